//! The ranks of a training job: one process (the default) or the processes
//! of an MPI job started by `mpirun -np P blockpuzzle train …` (cargo
//! feature `mpi`). Everything the training loop exchanges between ranks goes
//! through here, always reduced in rank order so that a result does not
//! depend on how MPI schedules its messages.
//!
//! A rank's `--workers` are its *shards*; the global shard index `g = rank ×
//! workers + w` keys every random stream, so P ranks of W workers compute
//! what one process of P × W workers computes.

use super::TrainError;

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

    /// Every rank's `local` bytes, one vector per rank in rank order (lengths may differ).
    pub fn gather_bytes(&self, local: &[u8]) -> Vec<Vec<u8>> {
        match &self.inner {
            Inner::Local => vec![local.to_vec()],
            #[cfg(feature = "mpi")]
            Inner::Mpi(w) => {
                let counts = self.gather_counts(w, local.len());
                let displs = displacements(&counts);
                let mut out = vec![0u8; counts.iter().map(|&c| c as usize).sum()];
                let mut part = mpi::datatype::PartitionMut::new(&mut out[..], &counts[..], &displs[..]);
                w.all_gather_varcount_into(local, &mut part);
                displs.iter().zip(&counts).map(|(&d, &c)| out[d as usize..(d + c) as usize].to_vec()).collect()
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
    /// shards' vectors (the same number on every rank, all of one length).
    /// Every element is summed over the global shard order (rank, then
    /// shard), one addition after another, so the result is bit-identical
    /// for any split of the same shards into ranks. Under MPI the sum is
    /// split like a ring all-reduce: rank c receives chunk c of every
    /// shard's vector (all-to-all), sums it in shard order, and the summed
    /// chunks are gathered (all-gather); each rank sends and receives about
    /// twice one shard's vector per local shard, whatever the number of ranks.
    pub fn shard_mean(&self, local: &[Vec<f32>]) -> Vec<f32> {
        let len = local.first().map_or(0, Vec::len);
        match &self.inner {
            Inner::Local => {
                let slices: Vec<&[f32]> = local.iter().map(Vec::as_slice).collect();
                mean_in_order(&slices, len)
            }
            #[cfg(feature = "mpi")]
            Inner::Mpi(w) => {
                let (p, shards) = (self.size(), local.len());
                let bounds: Vec<usize> = (0..=p).map(|c| c * len / p).collect();
                let chunk = |c: usize| bounds[c]..bounds[c + 1];
                // To rank c: chunk c of each of my shards, shard after shard.
                let mut send = Vec::with_capacity(shards * len);
                let mut send_counts = Vec::with_capacity(p);
                for c in 0..p {
                    for v in local {
                        send.extend_from_slice(&v[chunk(c)]);
                    }
                    send_counts.push((shards * chunk(c).len()) as i32);
                }
                let mine = chunk(self.rank()).len();
                let recv_counts = vec![(shards * mine) as i32; p];
                let mut recv = vec![0.0f32; shards * mine * p];
                {
                    let send_part =
                        mpi::datatype::Partition::new(&send[..], &send_counts[..], displacements(&send_counts));
                    let mut recv_part =
                        mpi::datatype::PartitionMut::new(&mut recv[..], &recv_counts[..], displacements(&recv_counts));
                    w.all_to_all_varcount_into(&send_part, &mut recv_part);
                }
                // Received rank by rank, each rank's shards in order: the global shard order.
                let slices: Vec<&[f32]> = recv.chunks_exact(mine.max(1)).take(shards * p).collect();
                let summed = if mine == 0 { Vec::new() } else { mean_in_order(&slices, mine) };
                let counts: Vec<i32> = (0..p).map(|c| chunk(c).len() as i32).collect();
                let mut out = vec![0.0f32; len];
                let mut part = mpi::datatype::PartitionMut::new(&mut out[..], &counts[..], displacements(&counts));
                w.all_gather_varcount_into(&summed[..], &mut part);
                out
            }
        }
    }

    /// Runs `check` on rank 0 and gives every rank its outcome: an error on
    /// rank 0 is the same error (its text) on every rank, so that all stop
    /// with rank 0's message instead of failing later each in its own way.
    ///
    /// # Errors
    /// Rank 0's error.
    pub fn root_check(&self, check: impl FnOnce() -> Result<(), TrainError>) -> Result<(), TrainError> {
        let mut status = Vec::new();
        if self.is_root() {
            if let Err(e) = check() {
                status = crate::support::error::chain(&e).into_bytes();
            }
        }
        if self.size() > 1 {
            self.broadcast_bytes(&mut status);
        }
        if status.is_empty() {
            Ok(())
        } else {
            Err(TrainError::Rank0(String::from_utf8_lossy(&status).into_owned()))
        }
    }

    /// Rank 0's bytes on every rank.
    pub fn broadcast_bytes(&self, bytes: &mut Vec<u8>) {
        #[cfg(feature = "mpi")]
        if let Inner::Mpi(w) = &self.inner {
            let root = w.process_at_rank(0);
            let mut len = bytes.len() as u64;
            root.broadcast_into(&mut len);
            bytes.resize(len as usize, 0);
            // MPI refuses an empty buffer; every rank knows the length by now.
            if len > 0 {
                root.broadcast_into(&mut bytes[..]);
            }
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

/// The element-wise mean of `slices` (each `len` long), summed in order,
/// one addition after another, and divided once.
fn mean_in_order(slices: &[&[f32]], len: usize) -> Vec<f32> {
    let mut it = slices.iter();
    let mut sum = it.next().map(|s| s[..len].to_vec()).unwrap_or_default();
    for s in it {
        for (a, b) in sum.iter_mut().zip(s.iter()) {
            *a += b;
        }
    }
    if slices.len() > 1 {
        let n = slices.len() as f32;
        for a in &mut sum {
            *a /= n;
        }
    }
    sum
}

/// Offsets of consecutive blocks of `counts`.
#[cfg(feature = "mpi")]
fn displacements(counts: &[i32]) -> Vec<i32> {
    counts.iter().scan(0, |acc, &c| Some(std::mem::replace(acc, *acc + c))).collect()
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
