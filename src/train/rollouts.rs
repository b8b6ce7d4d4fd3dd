//! Playing episodes for training: the behaviour policies (exploring DDPG,
//! sampling PGGD, AggreVaTeD's mixture, deterministic for tests), one
//! episode, and all workers' episodes in parallel threads.

use crate::agents::ddpg::DdpgPolicy;
use crate::agents::expert::{Actor, Mixture};
use crate::agents::normalizer::Normalizer;
use crate::agents::pggd::PggdPolicy;
use crate::agents::replay::ReplayBuffer;
use crate::agents::AnyPolicy;
use crate::env::{BlockEnv, EnvError};
use anyhow::Result;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use std::time::Instant;

/// Who acts in an episode.
#[derive(Debug, Clone)]
pub(crate) enum Behaviour<'a> {
    /// The deterministic policy (tests and finals).
    Greedy(&'a AnyPolicy),
    /// DDPG exploration: uniform with probability `random_eps`, else π(s) + N(0, noise_eps²).
    DdpgExplore { policy: &'a DdpgPolicy, random_eps: f64, noise_eps: f64 },
    /// PGGD sampling its Gaussian.
    PggdSample(&'a PggdPolicy),
    /// AggreVaTeD's roll-in mixture of expert and learner.
    Mixture(Mixture<'a>),
}

impl Behaviour<'_> {
    /// `(action to store, whether the expert chose it)`; the environment
    /// receives the stored action clipped to [−1, 1].
    fn act(&self, obs: &[f32], rng: &mut ChaCha8Rng) -> (Vec<f32>, bool) {
        match self {
            Self::Greedy(p) => (p.act(obs), false),
            Self::DdpgExplore { policy, random_eps, noise_eps } => {
                (policy.explore(obs, *random_eps, *noise_eps, rng), false)
            }
            Self::PggdSample(p) => (p.sample(obs, rng), false),
            Self::Mixture(m) => {
                let (who, a) = m.act(obs, rng);
                (a, who == Actor::Expert)
            }
        }
    }
}

/// A finished episode's transitions and outcome.
pub(crate) struct Episode {
    pub(crate) obs: Vec<Vec<f32>>,
    /// Actions as the behaviour produced them (PGGD: before clipping).
    pub(crate) act: Vec<Vec<f32>>,
    pub(crate) rew: Vec<f32>,
    pub(crate) terminated: bool,
    pub(crate) success: bool,
    /// Steps on which the expert acted.
    pub(crate) expert_steps: usize,
    /// Seconds spent in the policy (forward passes and noise).
    pub(crate) forward_seconds: f64,
}

impl Episode {
    /// Environment steps taken.
    pub(crate) fn len(&self) -> usize {
        self.rew.len()
    }

    /// Appends the transitions to `replay` (with each step's discounted
    /// return-to-go as the extra column) and feeds the observations to the
    /// normaliser.
    pub(crate) fn store(&self, replay: &mut ReplayBuffer, norm: &mut Normalizer, gamma: f64) {
        let n = self.rew.len();
        let mut ret = vec![0.0f32; n];
        let mut g = 0.0;
        for t in (0..n).rev() {
            g = self.rew[t] + gamma as f32 * g;
            ret[t] = g;
        }
        for (t, ret_t) in ret.iter().enumerate() {
            let done = self.terminated && t + 1 == n;
            replay.push(&self.obs[t], &self.act[t], self.rew[t], &self.obs[t + 1], done, *ret_t);
        }
        norm.update(&self.obs.concat());
    }
}

/// Mixes the run seed with counters into an independent stream seed.
pub(crate) fn stream_seed(seed: u64, parts: &[u64]) -> u64 {
    // SplitMix64 steps over the parts: cheap and well distributed.
    let mut z = seed ^ 0x9E37_79B9_7F4A_7C15;
    for &p in parts {
        z = z.wrapping_add(p).wrapping_add(0x9E37_79B9_7F4A_7C15);
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
    }
    z
}

/// Plays one episode with `behaviour` from the layout of `seed`.
fn play(env: &mut BlockEnv, behaviour: &Behaviour, seed: u64) -> Result<Episode, EnvError> {
    // The layout comes from `seed`; the exploration noise from a stream derived from it.
    let mut rng = ChaCha8Rng::seed_from_u64(stream_seed(seed, &[5]));
    let (mut obs, _) = env.reset(Some(seed))?;
    let mut ep = Episode {
        obs: vec![],
        act: vec![],
        rew: vec![],
        terminated: false,
        success: false,
        expert_steps: 0,
        forward_seconds: 0.0,
    };
    loop {
        let t = Instant::now();
        let (act, by_expert) = behaviour.act(&obs, &mut rng);
        ep.forward_seconds += t.elapsed().as_secs_f64();
        ep.expert_steps += by_expert as usize;
        let clipped: Vec<f32> = act.iter().map(|a| a.clamp(-1.0, 1.0)).collect();
        let s = env.step(&clipped)?;
        ep.obs.push(obs);
        ep.act.push(act);
        ep.rew.push(s.reward);
        ep.success |= s.info.is_success;
        obs = s.obs;
        if s.terminated || s.truncated {
            ep.terminated = s.terminated;
            ep.obs.push(obs);
            return Ok(ep);
        }
    }
}

/// Runs `per_worker` episodes on every worker's environment in parallel.
pub(crate) fn play_all(
    envs: &mut [BlockEnv],
    behaviour: &Behaviour,
    per_worker: usize,
    seed_of: impl Fn(usize, usize) -> u64 + Sync,
) -> Result<Vec<Episode>> {
    let results: Vec<Result<Vec<Episode>, EnvError>> = std::thread::scope(|s| {
        let handles: Vec<_> = envs
            .iter_mut()
            .enumerate()
            .map(|(w, env)| {
                let seed_of = &seed_of;
                s.spawn(move || (0..per_worker).map(|k| play(env, behaviour, seed_of(w, k))).collect())
            })
            .collect();
        handles
            .into_iter()
            .map(|h| h.join().unwrap_or_else(|_| Err(EnvError::Config("worker panicked".into()))))
            .collect()
    });
    let mut out = Vec::new();
    for r in results {
        out.extend(r?);
    }
    Ok(out)
}

/// Share of successful episodes (0 for none).
pub(crate) fn success_rate(eps: &[Episode]) -> f64 {
    if eps.is_empty() {
        return 0.0;
    }
    eps.iter().filter(|e| e.success).count() as f64 / eps.len() as f64
}
