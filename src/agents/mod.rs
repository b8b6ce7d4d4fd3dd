//! Learning agents: DDPG and PGGD (with their networks, optimiser,
//! normaliser and replay buffer), and AggreVaTeD's expert view and mixture.

pub mod ddpg;
pub mod expert;
pub mod mlp;
pub mod nets;
pub mod normalizer;
pub mod pggd;
pub mod replay;

use serde::{Deserialize, Serialize};

/// A trained policy of either algorithm, as saved in `policy.json`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum AnyPolicy {
    /// PGGD (tried first: a DDPG policy lacks its `act_dim` and `sigma_min`).
    Pggd(pggd::PggdPolicy),
    /// DDPG.
    Ddpg(ddpg::DdpgPolicy),
}

impl AnyPolicy {
    /// The deterministic action (DDPG: π(s); PGGD: clip(μ(s), ±1)).
    pub fn act(&self, obs: &[f32]) -> Vec<f32> {
        match self {
            Self::Pggd(p) => p.act(obs),
            Self::Ddpg(p) => p.act(obs),
        }
    }

    /// Observation size the policy expects.
    pub fn obs_dim(&self) -> usize {
        match self {
            Self::Pggd(p) => p.norm.dim(),
            Self::Ddpg(p) => p.norm.dim(),
        }
    }

    /// "ddpg" or "pggd".
    pub fn algo(&self) -> &'static str {
        match self {
            Self::Pggd(_) => "pggd",
            Self::Ddpg(_) => "ddpg",
        }
    }
}
