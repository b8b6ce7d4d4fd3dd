//! Experience replay: a ring buffer of transitions, sampled uniformly from
//! everything stored (the newest transitions included).

use rand::Rng;

/// A batch of transitions as flat row-major arrays.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Batch {
    /// Observations, `n × obs_dim`.
    pub obs: Vec<f32>,
    /// Actions, `n × act_dim`.
    pub act: Vec<f32>,
    /// Rewards, `n`.
    pub rew: Vec<f32>,
    /// Next observations, `n × obs_dim`.
    pub next_obs: Vec<f32>,
    /// 1.0 where the episode terminated (no bootstrap), else 0.0. Truncation
    /// at the time limit is not termination.
    pub terminated: Vec<f32>,
    /// The discounted return-to-go from each transition to the episode's end
    /// (PGGD's per-transition weight), `n`.
    pub return_to_go: Vec<f32>,
    /// The bootstrap discount of each transition: γᵐ for an m-step return
    /// (γ for one step), applied to Q' of `next_obs` unless `terminated`.
    pub discount: Vec<f32>,
}

impl Batch {
    /// Number of transitions.
    pub fn len(&self) -> usize {
        self.rew.len()
    }

    /// True when empty.
    pub fn is_empty(&self) -> bool {
        self.rew.is_empty()
    }
}

/// The replay buffer.
#[derive(Debug, Clone)]
pub struct ReplayBuffer {
    obs_dim: usize,
    act_dim: usize,
    capacity: usize,
    data: Batch,
    next: usize,
    len: usize,
    /// Index of the next transition in the buffer's whole history (the
    /// oldest stored one is `pushed - len`; transition i sits in slot i mod
    /// capacity). Checkpoints append the transitions since the last one.
    pushed: u64,
}

impl ReplayBuffer {
    /// An empty buffer for `capacity` transitions (memory is allocated as it fills).
    pub fn new(obs_dim: usize, act_dim: usize, capacity: usize) -> Self {
        Self { obs_dim, act_dim, capacity: capacity.max(1), data: Batch::default(), next: 0, len: 0, pushed: 0 }
    }

    /// Stored transitions.
    pub fn len(&self) -> usize {
        self.len
    }

    /// True when nothing is stored.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Capacity in transitions.
    pub fn capacity(&self) -> usize {
        self.capacity
    }

    /// Stores one transition, overwriting the oldest when full.
    #[allow(clippy::too_many_arguments)]
    pub fn push(
        &mut self,
        obs: &[f32],
        act: &[f32],
        rew: f32,
        next_obs: &[f32],
        terminated: bool,
        return_to_go: f32,
        discount: f32,
    ) {
        debug_assert_eq!(obs.len(), self.obs_dim);
        debug_assert_eq!(act.len(), self.act_dim);
        let (o, a) = (self.obs_dim, self.act_dim);
        if self.len < self.capacity {
            self.data.obs.extend_from_slice(obs);
            self.data.act.extend_from_slice(act);
            self.data.rew.push(rew);
            self.data.next_obs.extend_from_slice(next_obs);
            self.data.terminated.push(f32::from(u8::from(terminated)));
            self.data.return_to_go.push(return_to_go);
            self.data.discount.push(discount);
            self.len += 1;
        } else {
            let i = self.next;
            self.data.obs[i * o..(i + 1) * o].copy_from_slice(obs);
            self.data.act[i * a..(i + 1) * a].copy_from_slice(act);
            self.data.rew[i] = rew;
            self.data.next_obs[i * o..(i + 1) * o].copy_from_slice(next_obs);
            self.data.terminated[i] = f32::from(u8::from(terminated));
            self.data.return_to_go[i] = return_to_go;
            self.data.discount[i] = discount;
        }
        self.next = (self.next + 1) % self.capacity;
        self.pushed += 1;
    }

    /// Index of the next transition in the buffer's history (see the field).
    pub fn pushed(&self) -> u64 {
        self.pushed
    }

    /// Transitions `from..to` of the buffer's history, oldest first; `None`
    /// unless all of them are still stored.
    pub fn history(&self, from: u64, to: u64) -> Option<Batch> {
        if from > to || to > self.pushed || from < self.pushed - self.len as u64 {
            return None;
        }
        let mut b = Batch::default();
        for i in from..to {
            self.append_slot((i % self.capacity as u64) as usize, &mut b);
        }
        Some(b)
    }

    /// The buffer whose history ends at `pushed` and whose stored
    /// transitions are `data` (oldest first): what [`ReplayBuffer::history`]
    /// of all stored transitions returned, so the rebuilt buffer is exact.
    ///
    /// # Errors
    /// A message if the arrays do not fit the sizes or the capacity.
    pub fn from_history(
        obs_dim: usize,
        act_dim: usize,
        capacity: usize,
        pushed: u64,
        data: Batch,
    ) -> Result<Self, String> {
        let n = data.rew.len();
        let capacity = capacity.max(1);
        let fits = data.obs.len() == n * obs_dim
            && data.next_obs.len() == n * obs_dim
            && data.act.len() == n * act_dim
            && [data.terminated.len(), data.return_to_go.len(), data.discount.len()] == [n; 3]
            && n as u64 <= pushed
            && (n == capacity || n as u64 == pushed);
        if !fits {
            return Err(format!(
                "replay history of {n} transitions does not fit {obs_dim}+{act_dim} values, capacity {capacity} and \
                 {pushed} pushed"
            ));
        }
        let mut buf = Self::new(obs_dim, act_dim, capacity);
        // Push in history order from the slot the oldest one occupies.
        let first = pushed - n as u64;
        buf.next = (first % capacity as u64) as usize;
        if n == capacity {
            buf.data = data.clone();
            buf.len = n;
            // Rotate so that transition i sits in slot i mod capacity.
            let shift = buf.next;
            let (o, a) = (obs_dim, act_dim);
            buf.data.obs.rotate_right(shift * o);
            buf.data.next_obs.rotate_right(shift * o);
            buf.data.act.rotate_right(shift * a);
            for v in [&mut buf.data.rew, &mut buf.data.terminated, &mut buf.data.return_to_go, &mut buf.data.discount] {
                v.rotate_right(shift);
            }
        } else {
            buf.data = data;
            buf.len = n;
            buf.next = n % capacity;
        }
        buf.pushed = pushed;
        Ok(buf)
    }

    /// `n` transitions drawn uniformly with replacement from all stored ones.
    /// Empty if nothing is stored.
    pub fn sample(&self, n: usize, rng: &mut impl Rng) -> Batch {
        let mut b = Batch::default();
        self.sample_into(n, rng, &mut b);
        b
    }

    /// As [`ReplayBuffer::sample`], appending to `b` (a batch drawn from several buffers).
    pub fn sample_into(&self, n: usize, rng: &mut impl Rng, b: &mut Batch) {
        if self.len == 0 {
            return;
        }
        for _ in 0..n {
            self.append_slot(rng.gen_range(0..self.len), b);
        }
    }

    /// Appends the transition stored in slot `j` to `b`.
    #[inline]
    fn append_slot(&self, j: usize, b: &mut Batch) {
        let (o, a) = (self.obs_dim, self.act_dim);
        b.obs.extend_from_slice(&self.data.obs[j * o..(j + 1) * o]);
        b.act.extend_from_slice(&self.data.act[j * a..(j + 1) * a]);
        b.rew.push(self.data.rew[j]);
        b.next_obs.extend_from_slice(&self.data.next_obs[j * o..(j + 1) * o]);
        b.terminated.push(self.data.terminated[j]);
        b.return_to_go.push(self.data.return_to_go[j]);
        b.discount.push(self.data.discount[j]);
    }

    /// The stored arrays in storage order and the next write position (for
    /// checkpoints: [`ReplayBuffer::from_parts`] restores the exact buffer).
    pub fn parts(&self) -> (&Batch, usize) {
        (&self.data, self.next)
    }

    /// Rebuilds a buffer from [`ReplayBuffer::parts`].
    ///
    /// # Errors
    /// A message if the arrays do not fit the sizes.
    pub fn from_parts(
        obs_dim: usize,
        act_dim: usize,
        capacity: usize,
        data: Batch,
        next: usize,
    ) -> Result<Self, String> {
        let n = data.rew.len();
        let ok = n <= capacity.max(1)
            && next < capacity.max(1)
            && data.obs.len() == n * obs_dim
            && data.next_obs.len() == n * obs_dim
            && data.act.len() == n * act_dim
            && data.terminated.len() == n
            && data.return_to_go.len() == n
            && data.discount.len() == n
            && (n == capacity.max(1) || next == n);
        if !ok {
            return Err(format!("replay arrays do not fit {n} transitions of {obs_dim}+{act_dim} values"));
        }
        // The history index is virtual: any value that puts transition i in slot i mod capacity.
        let pushed = if n == capacity.max(1) { (capacity.max(1) + next) as u64 } else { n as u64 };
        Ok(Self { obs_dim, act_dim, capacity: capacity.max(1), data, next, len: n, pushed })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    fn push(buf: &mut ReplayBuffer, k: usize) {
        let v = k as f32;
        buf.push(&[v, v], &[v], v, &[v + 1.0, v + 1.0], k % 2 == 0, -v, 0.5 * v);
    }

    #[test]
    fn ring_overwrites_oldest_and_round_trips_through_parts() {
        let mut buf = ReplayBuffer::new(2, 1, 3);
        for k in 0..5 {
            push(&mut buf, k);
        }
        assert_eq!(buf.len(), 3);
        let (data, next) = buf.parts();
        assert_eq!((data.rew.clone(), next), (vec![3.0, 4.0, 2.0], 2));
        let mut copy = ReplayBuffer::from_parts(2, 1, 3, data.clone(), next).unwrap();
        push(&mut buf, 5);
        push(&mut copy, 5);
        assert_eq!(buf.parts().0, copy.parts().0);
        assert!(ReplayBuffer::from_parts(2, 1, 3, Batch { rew: vec![1.0], ..Batch::default() }, 1).is_err());
    }

    #[test]
    fn history_round_trips_at_every_fill_and_wrap() {
        for (capacity, total) in [(5, 3), (5, 5), (5, 7), (5, 10), (5, 13), (1, 4)] {
            let mut buf = ReplayBuffer::new(2, 1, capacity);
            for k in 0..total {
                push(&mut buf, k);
            }
            let start = buf.pushed() - buf.len() as u64;
            let data = buf.history(start, buf.pushed()).unwrap();
            assert_eq!(data.rew.first().copied(), Some(start as f32), "oldest first");
            let copy = ReplayBuffer::from_history(2, 1, capacity, buf.pushed(), data).unwrap();
            assert_eq!((copy.parts().0, copy.parts().1, copy.len()), (buf.parts().0, buf.parts().1, buf.len()));
            let mut a = buf.clone();
            let mut b = copy;
            for k in total..total + 3 {
                push(&mut a, k);
                push(&mut b, k);
            }
            assert_eq!(a.parts(), b.parts(), "capacity {capacity}, {total} pushed");
            assert!(buf.history(0, buf.pushed() + 1).is_none());
        }
        // Parts of an old checkpoint give a history index that keeps slots.
        let mut buf = ReplayBuffer::new(2, 1, 3);
        for k in 0..5 {
            push(&mut buf, k);
        }
        let (data, next) = buf.parts();
        let old = ReplayBuffer::from_parts(2, 1, 3, data.clone(), next).unwrap();
        let h = old.history(old.pushed() - 3, old.pushed()).unwrap();
        assert_eq!(h.rew, vec![2.0, 3.0, 4.0]);
        assert!(ReplayBuffer::from_history(2, 1, 3, 2, h).is_err(), "more stored than pushed");
    }

    #[test]
    fn samples_are_whole_transitions_and_include_the_newest() {
        let mut buf = ReplayBuffer::new(2, 1, 100);
        for k in 0..10 {
            push(&mut buf, k);
        }
        let b = buf.sample(2000, &mut ChaCha8Rng::seed_from_u64(0));
        assert_eq!(b.len(), 2000);
        for i in 0..b.len() {
            let v = b.rew[i];
            assert_eq!((b.obs[2 * i], b.act[i], b.next_obs[2 * i], b.return_to_go[i]), (v, v, v + 1.0, -v));
            assert_eq!(b.terminated[i], if (v as usize) % 2 == 0 { 1.0 } else { 0.0 });
        }
        assert!(b.rew.contains(&9.0), "the newest transition is sampled");
        assert!(ReplayBuffer::new(2, 1, 4).sample(8, &mut ChaCha8Rng::seed_from_u64(0)).is_empty());
    }
}
