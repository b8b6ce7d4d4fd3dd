//! The learning agent of a run, whichever algorithm: what a checkpoint
//! saves and what the training loop updates (gradient, then a step with the
//! mean of the shards' gradients).

use super::ddpg::{Ddpg, DdpgConfig, UpdateStats};
use super::mlp::TanhMlp;
use super::normalizer::Normalizer;
use super::pggd::{Pggd, PggdConfig};
use super::replay::Batch;
use super::AnyPolicy;
use rand::Rng;
use serde::{Deserialize, Serialize};

/// Training algorithm.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum Algo {
    /// Deep deterministic policy gradient (OpenAI baselines' HER DDPG, no HER).
    #[default]
    Ddpg,
    /// Policy gradient with a Gaussian policy (the paper's PGGD); with
    /// `--expert`, trained by AggreVaTeD.
    Pggd,
}

/// A learner's networks, optimisers and normaliser: what a checkpoint holds.
/// (One lives per run, so the variants' size difference does not matter.)
#[allow(clippy::large_enum_variant)]
pub enum Agent {
    /// DDPG.
    Ddpg(Ddpg),
    /// PGGD.
    Pggd(Pggd),
}

impl Agent {
    /// A fresh agent of `algo`; PGGD takes its network shape and normaliser settings from `ddpg`.
    pub fn new(
        algo: Algo,
        ddpg: &DdpgConfig,
        pggd: &PggdConfig,
        obs_dim: usize,
        act_dim: usize,
        rng: &mut impl Rng,
    ) -> Self {
        let d = ddpg;
        match algo {
            Algo::Ddpg => Self::Ddpg(Ddpg::new(obs_dim, act_dim, d.clone(), rng)),
            Algo::Pggd => Self::Pggd(Pggd::new(
                obs_dim,
                act_dim,
                (d.layers, d.hidden),
                (d.norm_eps, d.norm_clip),
                pggd.clone(),
                rng,
            )),
        }
    }

    /// Takes the settings a branch may change (`train --branch-from`) from
    /// `ddpg`: DDPG's action penalties. Everything else stays as loaded.
    pub fn take_branch_settings(&mut self, ddpg: &DdpgConfig) {
        if let Self::Ddpg(a) = self {
            a.config.action_l2 = ddpg.action_l2;
            a.config.preact_l2 = ddpg.preact_l2;
        }
    }

    /// Which algorithm.
    pub fn algo(&self) -> Algo {
        match self {
            Self::Ddpg(_) => Algo::Ddpg,
            Self::Pggd(_) => Algo::Pggd,
        }
    }

    /// The deterministic policy, frozen.
    pub fn policy(&self) -> AnyPolicy {
        match self {
            Self::Ddpg(a) => AnyPolicy::Ddpg(a.policy()),
            Self::Pggd(a) => AnyPolicy::Pggd(a.policy()),
        }
    }

    /// DDPG's critic as a plain network (saved beside the policy); none for PGGD.
    pub fn critic(&self) -> Option<TanhMlp> {
        match self {
            Self::Ddpg(a) => Some(a.critic.to_plain()),
            Self::Pggd(_) => None,
        }
    }

    /// The observation normaliser.
    pub fn norm_mut(&mut self) -> &mut Normalizer {
        match self {
            Self::Ddpg(a) => &mut a.norm,
            Self::Pggd(a) => &mut a.norm,
        }
    }

    /// The flattened gradient of the next update on `batch` and its
    /// statistics (nothing changes). DDPG: `shard` picks TD3's smoothing
    /// noise; PGGD: each transition's weight is `weights` (e.g. an expert's
    /// advantage) or else the stored return-to-go.
    pub fn gradient(&mut self, batch: &Batch, shard: u64, weights: Option<&[f32]>) -> (Vec<f32>, UpdateStats) {
        match self {
            Self::Ddpg(a) => a.gradient(batch, shard),
            Self::Pggd(a) => a.gradient(batch, weights.unwrap_or(&batch.extra)),
        }
    }

    /// One optimiser step with a gradient laid out as [`Agent::gradient`]'s (e.g. a mean of several).
    pub fn apply_gradient(&mut self, gradient: &[f32]) {
        match self {
            Self::Ddpg(a) => a.apply_gradient(gradient),
            Self::Pggd(a) => a.apply_gradient(gradient),
        }
    }

    /// The length of the longest gradient [`Agent::gradient`] returns (DDPG:
    /// critics and actor; TD3 skips the actor on delayed updates).
    pub fn gradient_len(&self) -> usize {
        let count = |params: &[tch::Tensor]| params.iter().map(|p| p.numel()).sum::<usize>();
        match self {
            Self::Ddpg(a) => {
                count(&a.critic.params)
                    + a.twin.as_ref().map_or(0, |t| count(&t.critic.params))
                    + count(&a.actor.params)
            }
            Self::Pggd(a) => count(&a.net.params),
        }
    }

    /// End of a cycle of updates: DDPG's target networks follow (PGGD has none).
    pub fn end_cycle(&mut self) {
        if let Self::Ddpg(a) = self {
            a.update_targets();
        }
    }
}
