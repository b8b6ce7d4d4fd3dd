//! Learning algorithms (DDPG, PGGD, SAC: one file each, listed in
//! `algorithm::ALGORITHMS`), their networks, optimiser, normaliser and
//! replay buffer, and AggreVaTeD's expert view and mixture.

pub mod algorithm;
pub mod arch;
pub mod ddpg;
pub mod expert;
pub mod mlp;
pub mod nets;
pub mod normalizer;
pub mod pggd;
pub mod replay;
pub mod sac;

use serde::{Deserialize, Serialize};

/// The largest weight, bias or normaliser statistic a loaded policy may hold
/// (trained ones stay far below; larger values mean a damaged or diverged
/// file, which would act on overflowed numbers).
pub const MAX_ABS_WEIGHT: f32 = 1e6;

/// A trained policy, as saved in `policy.json`: a deterministic tanh actor
/// (DDPG, TD3, and SAC's mean action) or PGGD's Gaussian.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum AnyPolicy {
    /// PGGD (tried first: a DDPG policy lacks its `act_dim` and `sigma_min`).
    Pggd(pggd::PggdPolicy),
    /// A deterministic tanh actor (DDPG, TD3, SAC).
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

    /// The policy's network.
    pub fn net(&self) -> &mlp::TanhMlp {
        match self {
            Self::Pggd(p) => &p.net,
            Self::Ddpg(p) => &p.net,
        }
    }

    /// The observation the policy reads: flat, or `objects` for a set network.
    pub fn obs_mode(&self) -> crate::env::ObsMode {
        match self.net().set {
            None => crate::env::ObsMode::Flat,
            Some(_) => crate::env::ObsMode::Objects,
        }
    }

    /// A set network's policy on observations with `slots` object slots: the
    /// same weights, the normaliser's shared row statistics in every slot
    /// (a set network's weights do not depend on the number of objects). An
    /// MLP's policy is returned as it is.
    pub fn with_slots(&self, slots: usize) -> Self {
        let Some(layout) = self.net().set else { return self.clone() };
        let layout = layout.with_slots(slots);
        let mut out = self.clone();
        let (net, norm) = match &mut out {
            Self::Pggd(p) => (&mut p.net, &mut p.norm),
            Self::Ddpg(p) => (&mut p.net, &mut p.norm),
        };
        net.set = Some(layout);
        *norm = norm.with_slots(layout);
        out
    }

    /// Observation size the policy expects.
    pub fn obs_dim(&self) -> usize {
        match self {
            Self::Pggd(p) => p.norm.dim(),
            Self::Ddpg(p) => p.norm.dim(),
        }
    }

    /// Whether the policy can act: [`MAX_ABS_WEIGHT`] bounds every weight and
    /// normaliser statistic, the network maps the normaliser's size to the
    /// action size (PGGD: twice that, for μ and σ), σ's floor is sane.
    ///
    /// # Errors
    /// The first problem, named.
    pub fn check(&self) -> Result<(), String> {
        let (net, norm, outputs) = match self {
            Self::Ddpg(p) => (&p.net, &p.norm, crate::env::ACTION_DIM),
            Self::Pggd(p) => {
                if p.act_dim != crate::env::ACTION_DIM {
                    return Err(format!(
                        "the policy has {} actions, the environments {}",
                        p.act_dim,
                        crate::env::ACTION_DIM
                    ));
                }
                if !p.sigma_min.is_finite() || p.sigma_min < 0.0 || p.sigma_min > 1e3 {
                    return Err(format!("sigma_min is {}", p.sigma_min));
                }
                (&p.net, &p.norm, 2 * p.act_dim)
            }
        };
        norm.check(MAX_ABS_WEIGHT)?;
        net.check(norm.dim(), outputs, MAX_ABS_WEIGHT).map_err(|e| format!("actor: {e}"))
    }

    /// The policy's kind as files record it: "ddpg" (a deterministic tanh
    /// actor, whichever algorithm trained it) or "pggd".
    pub fn algo(&self) -> &'static str {
        match self {
            Self::Pggd(_) => "pggd",
            Self::Ddpg(_) => "ddpg",
        }
    }
}
