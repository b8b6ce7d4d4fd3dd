//! AggreVaTeD's ingredients (paper, "Imitation Learning"): the expert's view
//! of the 3-block observation (the grey block removed), the annealed mixing
//! probability β, and the mixed roll-in policy.

use super::nets::{tensor_to_vec, Net};
use crate::policy::actor::mlp::PlainNet;
use crate::policy::actor::normalizer::Normalizer;
use crate::policy::actor::DeterministicPolicy;
use rand::Rng;
use rand_chacha::ChaCha8Rng;
use tch::Tensor;

use crate::policy::actor::without_grey;

/// β at `epoch`: β0 + (1 − β0)·exp(−epoch / t0) (t0 = 0: β0 from the start).
pub fn beta(epoch: usize, beta0: f64, t0: f64) -> f64 {
    if t0 <= 0.0 {
        return beta0;
    }
    beta0 + (1.0 - beta0) * (-(epoch as f64) / t0).exp()
}

/// Which policy chose a mixed roll-in step.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Actor {
    /// The expert (grey-blind DDPG).
    Expert,
    /// The learner (sampling its Gaussian).
    Learner,
}

/// The roll-in policy β·π* + (1 − β)·π_θ: per step the expert acts with
/// probability β on the grey-removed view, else the learner samples.
#[derive(Clone, Copy)]
pub struct Mixture<'a> {
    /// The expert.
    pub expert: &'a DeterministicPolicy,
    /// The learner, exploring (PGGD: sampling its Gaussian).
    pub learner: &'a dyn super::algorithm::Explorer,
    /// Probability that the expert acts.
    pub beta: f64,
}

impl Mixture<'_> {
    /// `(who, action before clipping)` for one step; `noise` is the learner's episode noise state.
    pub fn act(&self, obs: &[f32], noise: &mut Vec<f32>, rng: &mut ChaCha8Rng) -> (Actor, Vec<f32>) {
        if rng.gen_bool(self.beta.clamp(0.0, 1.0)) {
            (Actor::Expert, self.expert.act(&without_grey(obs)))
        } else {
            (Actor::Learner, self.learner.explore(obs, noise, rng))
        }
    }
}

/// The expert's actor and critic in libtorch, for batched advantages
/// A*(s̃, a) = Q*(s̃, a) − Q*(s̃, π*(s̃)) (AggreVaTeD's `expert-advantage`).
pub struct ExpertCritic {
    actor: Net,
    critic: Net,
    norm: Normalizer,
    act_dim: usize,
}

impl ExpertCritic {
    /// From a saved DDPG policy and the critic saved with it.
    ///
    /// # Errors
    /// A message when the critic does not take the policy's observation and
    /// action, or does not output one value.
    pub(crate) fn new(policy: &DeterministicPolicy, critic: &PlainNet) -> Result<Self, String> {
        let actor = Net::from_plain(&policy.net).map_err(|e| format!("actor: {e}"))?;
        let critic = Net::from_plain(critic).map_err(|e| format!("critic: {e}"))?;
        let (obs_dim, act_dim) = (actor.sizes()[0], *actor.sizes().last().unwrap_or(&0));
        if critic.sizes()[0] != obs_dim + act_dim || critic.sizes().last() != Some(&1) {
            return Err(format!(
                "the critic maps {} inputs to {:?} outputs; the actor's observation and action need {} inputs and 1 \
                 output",
                critic.sizes()[0],
                critic.sizes().last(),
                obs_dim + act_dim
            ));
        }
        if policy.norm.dim() != obs_dim {
            return Err(format!("the normaliser has {} entries, the actor {obs_dim} inputs", policy.norm.dim()));
        }
        Ok(Self { actor, critic, norm: policy.norm.clone(), act_dim })
    }

    /// A*(s̃, a) for rows of grey-removed observations and actions (actions
    /// clipped to [−1, 1] as the environment does).
    pub fn advantage(&self, obs: &[f32], act: &[f32]) -> Vec<f32> {
        tch::no_grad(|| {
            let mut x = obs.to_vec();
            self.norm.normalize_in_place(&mut x);
            let o = Tensor::of_slice(&x).view([-1, self.norm.dim() as i64]);
            let a = Tensor::of_slice(act).view([-1, self.act_dim as i64]).clamp(-1.0, 1.0);
            let q = |a: &Tensor| self.critic.forward(&Tensor::cat(&[&o, a], 1));
            tensor_to_vec(&(q(&a) - q(&self.actor.forward(&o))))
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::env::{BLOCK_OBS, ROBOT_OBS};
    use crate::learn::agents::arch::Arch;

    #[test]
    fn beta_follows_the_schedule() {
        assert_eq!(beta(0, 0.0, 50.0), 1.0);
        assert!((beta(50, 0.0, 50.0) - (-1.0f64).exp()).abs() < 1e-12);
        assert!((beta(100, 0.2, 50.0) - (0.2 + 0.8 * (-2.0f64).exp())).abs() < 1e-12);
        assert!(beta(10_000, 0.2, 50.0) - 0.2 < 1e-12);
        assert_eq!(beta(7, 0.3, 0.0), 0.3);
        let mut last = f64::INFINITY;
        for e in 0..300 {
            let b = beta(e, 0.0, 50.0);
            assert!(b < last && b > 0.0);
            last = b;
        }
    }

    #[test]
    fn beta_one_is_all_expert_and_beta_zero_all_learner() {
        use crate::learn::agents::ddpg::{Ddpg, DdpgConfig};
        use crate::learn::agents::pggd::{Pggd, PggdConfig};
        use crate::learn::agents::shared::SharedConfig;
        use rand::SeedableRng;
        use rand_chacha::ChaCha8Rng;
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        let dim = ROBOT_OBS + 3 * BLOCK_OBS;
        let expert = Ddpg::new(
            dim - BLOCK_OBS,
            4,
            SharedConfig { hidden: 16, ..SharedConfig::default() },
            DdpgConfig::default(),
            &mut rng,
        )
        .policy();
        let learner = Pggd::new(Arch::mlp(dim), 4, (2, 16), (0.01, 5.0), PggdConfig::default(), &mut rng).policy();
        let mut obs: Vec<f32> = (0..dim).map(|k| (k as f32 * 0.7).sin()).collect();
        obs[dim - 4..].copy_from_slice(&[0.0, 0.0, 0.0, 1.0]); // the third block is grey
        for (beta, who) in [(1.0, Actor::Expert), (0.0, Actor::Learner)] {
            let m = Mixture { expert: &expert, learner: &learner, beta };
            let (mut r1, mut r2) = (ChaCha8Rng::seed_from_u64(9), ChaCha8Rng::seed_from_u64(9));
            for _ in 0..100 {
                let (w, a) = m.act(&obs, &mut Vec::new(), &mut r1);
                assert_eq!(w, who);
                let expected = if who == Actor::Expert {
                    let _ = r2.gen_bool(1.0); // the mixture's draw
                    expert.act(&without_grey(&obs))
                } else {
                    let _ = r2.gen_bool(0.0);
                    learner.sample(&obs, &mut r2)
                };
                assert_eq!(a, expected);
            }
        }
        // In between, both act, in proportion.
        let m = Mixture { expert: &expert, learner: &learner, beta: 0.3 };
        let mut r = ChaCha8Rng::seed_from_u64(2);
        let n = (0..10_000).filter(|_| m.act(&obs, &mut Vec::new(), &mut r).0 == Actor::Expert).count();
        assert!((2_700..3_300).contains(&n), "{n}");
    }

    #[test]
    fn saved_critic_gives_the_learners_advantage() {
        use crate::learn::agents::ddpg::{Ddpg, DdpgConfig};
        use crate::learn::agents::shared::SharedConfig;
        use rand::SeedableRng;
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        let mut ddpg = Ddpg::new(
            6,
            4,
            SharedConfig { hidden: 16, layers: 2, ..SharedConfig::default() },
            DdpgConfig::default(),
            &mut rng,
        );
        let obs: Vec<f32> = (0..18).map(|k| (k as f32 * 0.37).sin() * 3.0).collect();
        ddpg.norm.update(&obs);
        let act: Vec<f32> = (0..12).map(|k| (k as f32 * 0.91).cos() * 1.5).collect();
        let (policy, critic) = (ddpg.policy(), ddpg.critic.to_plain());
        let expert = ExpertCritic::new(&policy, &critic).unwrap();
        // The reference: the plain-Rust networks, row by row.
        let theirs: Vec<f32> = obs
            .chunks(6)
            .zip(act.chunks(4))
            .map(|(o, a)| {
                let mut x = o.to_vec();
                policy.norm.normalize_in_place(&mut x);
                let q = |a: &[f32]| {
                    let a: Vec<f32> = a.iter().map(|v| v.clamp(-1.0, 1.0)).collect();
                    critic.forward(&[x.as_slice(), &a].concat())[0]
                };
                q(a) - q(&policy.act(o))
            })
            .collect();
        let ours = expert.advantage(&obs, &act);
        assert_eq!(ours.len(), 3);
        for (a, b) in ours.iter().zip(&theirs) {
            assert!((a - b).abs() < 1e-5, "{ours:?} vs {theirs:?}");
        }
        assert!(ours.iter().any(|a| a.abs() > 1e-4), "a random critic gives non-zero advantages");
        // The expert's own action has zero advantage.
        let own: Vec<f32> = obs.chunks(6).flat_map(|o| ddpg.policy().act(o)).collect();
        assert!(expert.advantage(&obs, &own).iter().all(|a| a.abs() < 1e-5));
        // A critic of another shape is refused.
        let other = Ddpg::new(
            5,
            4,
            SharedConfig { hidden: 16, layers: 2, ..SharedConfig::default() },
            DdpgConfig::default(),
            &mut rng,
        );
        assert!(ExpertCritic::new(&ddpg.policy(), &other.critic.to_plain()).is_err());
    }
}
