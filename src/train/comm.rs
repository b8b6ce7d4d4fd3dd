//! The ranks of a training job: one process (the default) or the processes
//! of an MPI job started by `mpirun -np P blockpuzzle train …` (cargo
//! feature `mpi`). Everything the training loop exchanges between ranks goes
//! through here, always reduced in rank order so that a result does not
//! depend on how MPI schedules its messages.
//!
//! A rank's `--workers` are its *shards*; the global shard index `g = rank ×
//! workers + w` keys every random stream, so P ranks of W workers compute
//! what one process of P × W workers computes.

/// The job's communicator.
pub struct Comm {
    inner: Inner,
}

enum Inner {
    Local,
    #[cfg(feature = "mpi")]
    Mpi(mpi::topology::SimpleCommunicator),
}

#[cfg(feature = "mpi")]
use mpi::traits::*;

impl Comm {
    /// A job of one process.
    pub fn local() -> Self {
        Self { inner: Inner::Local }
    }

    /// The world of an initialised MPI job.
    #[cfg(feature = "mpi")]
    pub fn mpi(world: mpi::topology::SimpleCommunicator) -> Self {
        Self { inner: Inner::Mpi(world) }
    }

    /// True when this process was started by `mpirun` (Open MPI or a PMI launcher).
    pub fn launched_by_mpirun() -> bool {
        ["OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_RANK"].iter().any(|v| std::env::var_os(v).is_some())
    }

    /// This process's rank (0 for one process).
    pub fn rank(&self) -> usize {
        match &self.inner {
            Inner::Local => 0,
            #[cfg(feature = "mpi")]
            Inner::Mpi(w) => w.rank() as usize,
        }
    }

    /// The number of ranks.
    pub fn size(&self) -> usize {
        match &self.inner {
            Inner::Local => 1,
            #[cfg(feature = "mpi")]
            Inner::Mpi(w) => w.size() as usize,
        }
    }

    /// True on the rank that writes the run's shared files (rank 0).
    pub fn is_root(&self) -> bool {
        self.rank() == 0
    }

    /// Every rank's `local` values concatenated in rank order (lengths may differ).
    pub fn gather_f32(&self, local: &[f32]) -> Vec<f32> {
        match &self.inner {
            Inner::Local => local.to_vec(),
            #[cfg(feature = "mpi")]
            Inner::Mpi(w) => {
                let counts = self.gather_counts(w, local.len());
                let displs: Vec<i32> =
                    counts.iter().scan(0, |acc, &c| Some(std::mem::replace(acc, *acc + c))).collect();
                let mut out = vec![0.0f32; counts.iter().map(|&c| c as usize).sum()];
                let mut part = mpi::datatype::PartitionMut::new(&mut out[..], counts, displs);
                w.all_gather_varcount_into(local, &mut part);
                out
            }
        }
    }

    /// Every rank's `local` values (all of the same length), one vector per rank.
    pub fn gather_f64(&self, local: &[f64]) -> Vec<Vec<f64>> {
        match &self.inner {
            Inner::Local => vec![local.to_vec()],
            #[cfg(feature = "mpi")]
            Inner::Mpi(w) => {
                let mut out = vec![0.0f64; local.len() * self.size()];
                w.all_gather_into(local, &mut out[..]);
                out.chunks(local.len().max(1)).map(<[f64]>::to_vec).take(self.size()).collect()
            }
        }
    }

    /// Every rank's `local` value, one per rank.
    pub fn gather_u64(&self, local: u64) -> Vec<u64> {
        match &self.inner {
            Inner::Local => vec![local],
            #[cfg(feature = "mpi")]
            Inner::Mpi(w) => {
                let mut out = vec![0u64; self.size()];
                w.all_gather_into(&local, &mut out[..]);
                out
            }
        }
    }

    /// The mean of every shard's vector over all ranks: each rank passes its
    /// shards' vectors (the same number on every rank, all of one length);
    /// the sum runs over the global shard order (rank, then shard), one
    /// addition after another, so it is bit-identical for any split of the
    /// same shards into ranks.
    pub fn shard_mean(&self, local: &[Vec<f32>]) -> Vec<f32> {
        let len = local.first().map_or(0, Vec::len);
        let all: Vec<f32> = match &self.inner {
            Inner::Local => local.concat(),
            #[cfg(feature = "mpi")]
            Inner::Mpi(w) => {
                let mine = local.concat();
                let mut out = vec![0.0f32; mine.len() * self.size()];
                w.all_gather_into(&mine[..], &mut out[..]);
                out
            }
        };
        let mut shards = all.chunks_exact(len.max(1));
        let mut sum = shards.next().map(<[f32]>::to_vec).unwrap_or_default();
        let mut n = 1usize;
        for s in shards {
            for (a, b) in sum.iter_mut().zip(s) {
                *a += b;
            }
            n += 1;
        }
        if n > 1 {
            let n = n as f32;
            for a in &mut sum {
                *a /= n;
            }
        }
        sum
    }

    /// Rank 0's bytes on every rank.
    pub fn broadcast_bytes(&self, bytes: &mut Vec<u8>) {
        #[cfg(feature = "mpi")]
        if let Inner::Mpi(w) = &self.inner {
            let root = w.process_at_rank(0);
            let mut len = bytes.len() as u64;
            root.broadcast_into(&mut len);
            bytes.resize(len as usize, 0);
            root.broadcast_into(&mut bytes[..]);
        }
        let _ = bytes;
    }

    /// Stops every rank of the job with `code` (one process: exits).
    pub fn abort(&self, code: i32) -> ! {
        match &self.inner {
            Inner::Local => std::process::exit(code),
            #[cfg(feature = "mpi")]
            Inner::Mpi(w) => w.abort(code),
        }
    }

    #[cfg(feature = "mpi")]
    fn gather_counts(&self, w: &mpi::topology::SimpleCommunicator, n: usize) -> Vec<i32> {
        let mut counts = vec![0i32; self.size()];
        w.all_gather_into(&(n as i32), &mut counts[..]);
        counts
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shard_mean_adds_in_order_and_divides_once() {
        let c = Comm::local();
        assert_eq!(c.shard_mean(&[vec![1.0, 2.0]]), vec![1.0, 2.0]);
        assert_eq!(c.shard_mean(&[vec![1.0, 2.0], vec![3.0, 6.0]]), vec![2.0, 4.0]);
        // Sequential order: (1e8 + 1) - 1e8 = 0 in f32, (1e8 - 1e8) + 1 = 1.
        let m = c.shard_mean(&[vec![1e8], vec![1.0], vec![-1e8]]);
        assert_eq!(m, vec![((1e8f32 + 1.0) - 1e8) / 3.0]);
        assert_eq!(c.gather_f32(&[1.0, 2.0]), vec![1.0, 2.0]);
        assert_eq!((c.rank(), c.size(), c.is_root()), (0, 1, true));
    }
}
