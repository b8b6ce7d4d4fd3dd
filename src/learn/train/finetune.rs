//! Starting a run from a trained policy (`train --init-from`): the actor and normaliser come from
//! the policy (a zoo entry, a run directory or a policy file), the critics start fresh and may
//! first warm up with the actor held still (`--critic-warmup`), and the curriculum may begin at
//! its top (`--start-at-top`), where a competent policy has nothing left to learn below.
//!
//! The policy is loaded and checked before anything is written: its observation must be the
//! run's, its actor deterministic, and (once the run's layout is known) its network the run's own
//! ([`crate::learn::agents::algorithm::fit_actor`]). The run records which policy it started from,
//! by name and hash, in `config.json`.

use super::{ConfigError, TrainConfig};
use crate::benchmark::provenance::PolicyId;
use crate::benchmark::saved::SavedPolicy;
use crate::policy::actor::{AnyPolicy, DeterministicPolicy};
use anyhow::{bail, Context, Result};
use serde::{Deserialize, Serialize};
use std::path::PathBuf;

/// How a run starts from a trained policy (all off: from scratch).
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize, clap::Args)]
#[serde(default)]
#[command(next_help_heading = "Starting from a trained policy")]
pub struct FinetuneConfig {
    /// Start the actor and the observation normaliser from this trained policy (a zoo name, a run
    /// directory or a policy file) instead of random weights; the critics start fresh. DDPG/TD3
    /// and SAC; the run's network settings must be the policy's (e.g. `--net entity --set-width 64`
    /// for the zoo's `generalist-bc-entity`).
    #[arg(long, value_name = "POLICY")]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub init_from: Option<PathBuf>,
    /// The policy `--init-from` named, as results name it (its hash), recorded when the run starts.
    #[arg(skip)]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub init_policy: Option<PolicyId>,
    /// Critic warm-up: the run's first N gradient updates step the critics alone, the actor held
    /// still, so that a fresh critic does not drag a trained actor off its skill (0: none).
    #[arg(long, default_value_t = 0, value_name = "UPDATES", requires = "init_from")]
    #[serde(skip_serializing_if = "is_zero")]
    pub critic_warmup: u64,
    /// Begin every task's curriculum at its top level (the distribution a policy is tested on),
    /// not at level 0.
    #[arg(long)]
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub start_at_top: bool,
}

fn is_zero(n: &u64) -> bool {
    *n == 0
}

impl FinetuneConfig {
    /// Whether every setting is off (a run from scratch; its `config.json` then omits them).
    pub fn is_off(&self) -> bool {
        *self == Self::default()
    }

    /// Whether the settings fit the run: an algorithm that can start from a policy, and a warm-up
    /// shorter than the run's updates.
    ///
    /// # Errors
    /// The first that does not, with its fix.
    pub fn validate(&self, run: &TrainConfig) -> Result<(), ConfigError> {
        let algo = run.algo.registration().info;
        if self.init_from.is_some() && !algo.starts_from_policy {
            return Err(ConfigError(format!(
                "--init-from: {} cannot start from a trained policy; use --algo ddpg (with --td3 for TD3) or --algo sac",
                algo.name
            )));
        }
        let updates = (run.epochs as u64).saturating_mul(run.cycles as u64).saturating_mul(run.batches as u64);
        if self.critic_warmup > 0 && self.critic_warmup >= updates {
            return Err(ConfigError(format!(
                "--critic-warmup {} is as long as the run or longer: {} epochs × {} cycles × {} batches make {updates} \
                 updates, so the actor would never learn; give fewer warm-up updates (e.g. {}) or more --epochs",
                self.critic_warmup,
                run.epochs,
                run.cycles,
                run.batches,
                (run.cycles as u64 * run.batches as u64).min(updates / 2)
            )));
        }
        Ok(())
    }

    /// The policy `--init-from` names, loaded and checked against the run's observation (None
    /// without `--init-from`).
    ///
    /// # Errors
    /// A missing or unreadable policy, a Gaussian one, or one of another observation.
    pub fn load(&self, run: &TrainConfig) -> Result<Option<(PolicyId, DeterministicPolicy)>> {
        let Some(path) = &self.init_from else { return Ok(None) };
        let saved: SavedPolicy = crate::benchmark::load::load_policy(path).with_context(|| {
            format!(
                "--init-from {}: cannot load the policy (give a zoo name, a run directory or a policy file)",
                path.display()
            )
        })?;
        let (theirs, ours) = (saved.obs_mode(), run.net.obs_mode());
        if theirs != ours {
            bail!(
                "--init-from {}: the policy reads the `{theirs}` observation, and this run's network (--net {}) reads \
                 `{ours}`; train with the policy's network (--net {})",
                path.display(),
                run.net.net.name(),
                crate::learn::agents::arch::NetKind::reading(theirs).name()
            );
        }
        let id = saved.policy_id(&path.display().to_string());
        match saved.policy {
            AnyPolicy::Deterministic(p) => Ok(Some((id, p))),
            AnyPolicy::Pggd(_) => bail!(
                "--init-from {}: a PGGD (Gaussian) policy; the actor of DDPG, TD3 and SAC starts from a deterministic \
                 one (trained by ddpg, td3, sac, bc or dagger)",
                path.display()
            ),
        }
    }
}
