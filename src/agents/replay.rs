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
    pub done: Vec<f32>,
    /// Extra per-transition value (e.g. the discounted return-to-go), `n`.
    pub extra: Vec<f32>,
    /// The bootstrap discount of each transition: γᵐ for an m-step return
    /// (γ for one step), applied to Q' of `next_obs` unless `done`.
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
}

impl ReplayBuffer {
    /// An empty buffer for `capacity` transitions (memory is allocated as it fills).
    pub fn new(obs_dim: usize, act_dim: usize, capacity: usize) -> Self {
        Self { obs_dim, act_dim, capacity: capacity.max(1), data: Batch::default(), next: 0, len: 0 }
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
        done: bool,
        extra: f32,
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
            self.data.done.push(f32::from(u8::from(done)));
            self.data.extra.push(extra);
            self.data.discount.push(discount);
            self.len += 1;
        } else {
            let i = self.next;
            self.data.obs[i * o..(i + 1) * o].copy_from_slice(obs);
            self.data.act[i * a..(i + 1) * a].copy_from_slice(act);
            self.data.rew[i] = rew;
            self.data.next_obs[i * o..(i + 1) * o].copy_from_slice(next_obs);
            self.data.done[i] = f32::from(u8::from(done));
            self.data.extra[i] = extra;
            self.data.discount[i] = discount;
        }
        self.next = (self.next + 1) % self.capacity;
    }

    /// `n` transitions drawn uniformly with replacement from all stored ones.
    /// Empty if nothing is stored.
    pub fn sample(&self, n: usize, rng: &mut impl Rng) -> Batch {
        let mut b = Batch::default();
        if self.len == 0 {
            return b;
        }
        let (o, a) = (self.obs_dim, self.act_dim);
        for _ in 0..n {
            let i = rng.gen_range(0..self.len);
            b.obs.extend_from_slice(&self.data.obs[i * o..(i + 1) * o]);
            b.act.extend_from_slice(&self.data.act[i * a..(i + 1) * a]);
            b.rew.push(self.data.rew[i]);
            b.next_obs.extend_from_slice(&self.data.next_obs[i * o..(i + 1) * o]);
            b.done.push(self.data.done[i]);
            b.extra.push(self.data.extra[i]);
            b.discount.push(self.data.discount[i]);
        }
        b
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
            && data.done.len() == n
            && data.extra.len() == n
            && data.discount.len() == n
            && (n == capacity.max(1) || next == n);
        if !ok {
            return Err(format!("replay arrays do not fit {n} transitions of {obs_dim}+{act_dim} values"));
        }
        Ok(Self { obs_dim, act_dim, capacity: capacity.max(1), data, next, len: n })
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
    fn samples_are_whole_transitions_and_include_the_newest() {
        let mut buf = ReplayBuffer::new(2, 1, 100);
        for k in 0..10 {
            push(&mut buf, k);
        }
        let b = buf.sample(2000, &mut ChaCha8Rng::seed_from_u64(0));
        assert_eq!(b.len(), 2000);
        for i in 0..b.len() {
            let v = b.rew[i];
            assert_eq!((b.obs[2 * i], b.act[i], b.next_obs[2 * i], b.extra[i]), (v, v, v + 1.0, -v));
            assert_eq!(b.done[i], if (v as usize) % 2 == 0 { 1.0 } else { 0.0 });
        }
        assert!(b.rew.contains(&9.0), "the newest transition is sampled");
        assert!(ReplayBuffer::new(2, 1, 4).sample(8, &mut ChaCha8Rng::seed_from_u64(0)).is_empty());
    }
}
