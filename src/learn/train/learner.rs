//! The learner being trained (any registered algorithm) and, for AggreVaTeD, the expert.

use super::comm::Comm;
use super::{Context, Result, TrainConfig, TrainError};
use crate::benchmark::load::load_policy;
use crate::benchmark::saved::SavedPolicy;
use crate::learn::agents::algorithm::Algorithm;
use crate::learn::agents::algorithm::{Explorer, UpdateStats};
use crate::learn::agents::expert::{beta, ExpertCritic, Mixture};
use crate::learn::agents::replay::Batch;
use crate::policy::actor::mlp::PlainNet;
use crate::policy::actor::without_grey;
use crate::policy::actor::AnyPolicy;
use crate::policy::actor::DeterministicPolicy;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// The descent direction of PGGD under AggreVaTeD.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "kebab-case")]
pub enum PgWeight {
    /// Each step's discounted return-to-go of the (mixed) roll-in.
    #[default]
    Return,
    /// The expert critic's advantage Q*(s̃, a) − Q*(s̃, π*(s̃)), s̃ the grey-removed observation.
    ExpertAdvantage,
}

/// AggreVaTeD settings (PGGD only).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, clap::Args)]
pub struct AggrevatedConfig {
    /// AggreVaTeD expert: a DDPG run directory, policy file or zoo name, trained on the
    /// grey-less layout; it sees the observation with grey blocks removed.
    #[arg(long)]
    pub expert: Option<PathBuf>,
    /// β0 of the mixing schedule β = β0 + (1 − β0)·exp(−epoch / t0).
    #[arg(long, default_value_t = 0.0)]
    pub beta0: f64,
    /// t0 of the mixing schedule, in epochs.
    #[arg(long, default_value_t = 50.0)]
    pub t0: f64,
    /// Weight of each step's log-probability gradient.
    #[arg(long, value_enum, default_value = "return")]
    pub pg_weight: PgWeight,
}

impl Default for AggrevatedConfig {
    fn default() -> Self {
        Self { expert: None, beta0: 0.0, t0: 50.0, pg_weight: PgWeight::Return }
    }
}

/// The AggreVaTeD expert: its policy and, for `expert-advantage`, its critic.
pub(crate) struct Expert {
    policy: DeterministicPolicy,
    critic: Option<ExpertCritic>,
}

impl Expert {
    /// Loads the expert named by `config` and checks that it takes `seen`
    /// observation components (the environment's, grey blocks removed). A resumed
    /// run takes the policy (and critic) from its copy `frozen` (when there is
    /// one); a new run takes them from the configured path and writes the copy.
    ///
    /// # Errors
    /// Missing or malformed files, a PGGD policy, a size mismatch, no critic
    /// of the policy's epoch for `expert-advantage`.
    pub(crate) fn load(config: &AggrevatedConfig, seen: usize, frozen: &Path, resume: bool) -> Result<Option<Self>> {
        let Some(path) = &config.expert else {
            if config.pg_weight == PgWeight::ExpertAdvantage {
                refuse!("--pg-weight expert-advantage needs an expert (--expert DIR)");
            }
            return Ok(None);
        };
        let from_copy = resume && frozen.exists();
        let mut saved = if from_copy {
            load_policy(frozen)
                .with_context(|| format!("loading this run's copy of the expert, {}", frozen.display()))?
        } else {
            load_policy(path).with_context(|| format!("loading the expert {}", path.display()))?
        };
        let AnyPolicy::Deterministic(policy) = saved.policy.clone() else {
            refuse!(
                "expert {} is a {} policy; AggreVaTeD needs a deterministic (DDPG or SAC) expert",
                path.display(),
                saved.policy.algo()
            );
        };
        if policy.norm.dim() != seen {
            refuse!(
                "expert {} expects {}-dimensional observations ({}), but this environment's observation without \
                 grey blocks has {seen}",
                path.display(),
                policy.norm.dim(),
                saved.env_id
            );
        }
        let critic = if config.pg_weight == PgWeight::ExpertAdvantage {
            let plain = match saved.critic.take() {
                Some(c) => c,
                None if from_copy => {
                    refuse!("this run's copy of the expert, {}, has no critic; start the run afresh", frozen.display())
                }
                None => critic_from_checkpoint(path, &saved, seen)?,
            };
            let critic = ExpertCritic::new(&policy, &plain).map_err(|e| {
                TrainError::Refused(format!("the critic saved with expert {} does not fit it: {e}", path.display()))
            })?;
            saved.critic = Some(plain);
            Some(critic)
        } else {
            None
        };
        // Only a valid expert is copied into the run (with its critic when used).
        if !from_copy {
            crate::support::io::write_json(frozen, &saved)?;
        }
        Ok(Some(Self { policy, critic }))
    }

    /// The expert critic's advantage of each row's action, on grey-removed observations.
    fn advantage(&self, batch: &Batch, obs_dim: usize) -> Option<Vec<f32>> {
        let critic = self.critic.as_ref()?;
        let seen: Vec<f32> = batch.obs.chunks_exact(obs_dim).flat_map(without_grey).collect();
        Some(critic.advantage(&seen, &batch.act))
    }
}

/// The critic of an expert policy saved without one (older runs): from the
/// checkpoint of its run directory, which must be of the policy's epoch.
fn critic_from_checkpoint(path: &Path, saved: &SavedPolicy, seen: usize) -> Result<PlainNet> {
    let ckpt = if path.is_dir() { path.join("checkpoint.bin") } else { path.with_file_name("checkpoint.bin") };
    let no_critic = format!(
        "--pg-weight expert-advantage needs the expert's critic: {} (epoch {}) was saved without one",
        path.display(),
        saved.epoch
    );
    if !ckpt.exists() {
        refuse!("{no_critic}, and there is no {} beside it", ckpt.display());
    }
    let loaded = super::checkpoint::load(&ckpt, &saved.env_id, seen, crate::env::ACTION_DIM)
        .with_context(|| format!("{no_critic}; reading the critic from {}", ckpt.display()))?;
    if loaded.state.epoch != saved.epoch {
        refuse!(
            "{no_critic}, and {} is at epoch {}, so its critic belongs to another policy; use the policy.json \
             written with that checkpoint, or a policy saved by this version (it carries its critic)",
            ckpt.display(),
            loaded.state.epoch
        );
    }
    match loaded.agent.critic() {
        Some(critic) => Ok(critic),
        None => refuse!("{} is a {} checkpoint, which has no critic", ckpt.display(), loaded.agent.name()),
    }
}

/// What the training loop trains: the agent and, for AggreVaTeD, the expert.
pub(crate) struct Learner {
    pub(crate) agent: Box<dyn Algorithm>,
    pub(crate) expert: Option<Expert>,
    /// Wall seconds spent averaging gradients (under MPI: exchanging them) since last reset.
    pub(crate) reduce_seconds: f64,
}

impl Learner {
    /// One gradient step from one batch per shard of this rank: each
    /// shard's gradient, the mean over every rank's shards (in global shard
    /// order, `first_shard` being this rank's first), one optimiser step.
    /// Returns each local shard's statistics.
    pub(crate) fn update(
        &mut self,
        batches: &[Batch],
        first_shard: usize,
        comm: &Comm,
        obs_dim: usize,
    ) -> Vec<UpdateStats> {
        let mut gradients = Vec::with_capacity(batches.len());
        let mut stats = Vec::with_capacity(batches.len());
        for (i, batch) in batches.iter().enumerate() {
            let weights = self.expert.as_ref().and_then(|e| e.advantage(batch, obs_dim));
            let (g, s) = self.agent.gradient(batch, (first_shard + i) as u64, weights.as_deref());
            gradients.push(g);
            stats.push(s);
        }
        let t = std::time::Instant::now();
        let mean = comm.shard_mean(&gradients);
        self.reduce_seconds += t.elapsed().as_secs_f64();
        self.agent.apply_gradient(&mean);
        stats
    }

    /// End of a cycle (e.g. target networks follow).
    pub(crate) fn end_cycle(&mut self) {
        self.agent.end_cycle();
    }

    /// β at `epoch`: of the AggreVaTeD mixture, or an imitation learner's
    /// share of the solver (None for neither).
    pub(crate) fn beta(&self, epoch: usize, config: &TrainConfig) -> Option<f64> {
        match &self.expert {
            Some(_) => Some(beta(epoch, config.aggrevated.beta0, config.aggrevated.t0)),
            None => self.agent.solver_share(epoch),
        }
    }

    /// The roll-in of this cycle: AggreVaTeD's mixture of the expert and
    /// `explorer` (the learner's exploration, frozen) at `epoch`; None without an expert.
    pub(crate) fn mixture<'a>(
        &'a self,
        explorer: &'a dyn Explorer,
        epoch: usize,
        config: &TrainConfig,
    ) -> Option<Mixture<'a>> {
        let e = self.expert.as_ref()?;
        Some(Mixture { expert: &e.policy, learner: explorer, beta: self.beta(epoch, config).unwrap_or(0.0) })
    }
}
