//! Starting a run from a trained policy, and demonstrations (issue 62): `--init-from` takes the
//! actor and normaliser from a policy (a zoo entry, a run directory or a policy file) and the
//! critics start fresh; `--critic-warmup` holds the actor still while they fit; `--anchor-alpha`
//! (TD3+BC) and `--ibrl` (IBRL's action proposal) keep the starting policy beside the learner;
//! `--start-at-top` begins the curriculum at its top; `--demos` puts a demos file's transitions in
//! a buffer of their own, from which every batch draws `--demos-ratio` (RLPD).
//!
//! Everything is loaded and checked before anything is written: the policy's observation must be
//! the run's, its actor deterministic and (once the run's layout is known) its network the run's
//! own ([`crate::learn::agents::algorithm::fit_actor`]); the demonstrations must be of the run's
//! tasks and observation. The run records the policy (name and hash) and the demos file (hash) in
//! `config.json`, and a resumed run refuses others.

use super::rollouts::Episode;
use super::{ConfigError, Context, Result, TrainConfig};
use crate::benchmark::demos::{Demos, DemosError};
use crate::benchmark::provenance::PolicyId;
use crate::benchmark::saved::SavedPolicy;
use crate::env::ObsSpec;
use crate::policy::actor::{AnyPolicy, DeterministicPolicy};
use crate::task::Task;
use serde::{Deserialize, Serialize};
use std::path::PathBuf;

/// How a run starts from a trained policy (all off: from scratch).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, clap::Args)]
#[serde(default)]
#[command(next_help_heading = "Starting from a trained policy, and demonstrations")]
pub struct FinetuneConfig {
    /// Start the actor and the observation normaliser from this trained policy (a zoo name, a run
    /// directory or a policy file) instead of random weights; the critics start fresh. DDPG/TD3,
    /// SAC, BC and DAgger; the run's network settings must be the policy's (e.g. `--net entity
    /// --set-width 64` for the zoo's `generalist-bc-entity`).
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
    /// Keep the actor near the policy it started from: TD3+BC's actor loss (Fujimoto & Gu 2021)
    /// with that policy's action as the target, −α·Q(s, π(s))/mean|Q| + mean ‖π(s) − π₀(s)‖²
    /// (TD3+BC's α is 2.5; larger: more of the critic). DDPG and TD3 (0: off).
    #[arg(long, default_value_t = 0.0, value_name = "ALPHA", requires = "init_from")]
    #[serde(skip_serializing_if = "is_zero_f64")]
    pub anchor_alpha: f64,
    /// IBRL's action proposal (Hu et al. 2023): the policy the run started from, frozen, proposes
    /// an action beside the actor's; exploration takes whichever the critic values more, and the
    /// critic's target bootstraps from the better of the two. The saved policy is the actor alone.
    /// DDPG and TD3.
    #[arg(long, requires = "init_from")]
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub ibrl: bool,
    /// Begin every task's curriculum at its top level (the distribution a policy is tested on),
    /// not at level 0.
    #[arg(long)]
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub start_at_top: bool,
    /// Demonstrations beside the run's own experience (RLPD, Ball et al. 2023): a demos file of
    /// the run's tasks (`blockpuzzle demos`), whose transitions fill a buffer of their own; every
    /// batch draws `--demos-ratio` of its transitions from it. Entities observations (`--net entity`).
    #[arg(long, value_name = "FILE")]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub demos: Option<PathBuf>,
    /// The share of each batch drawn from `--demos` (RLPD's is one half).
    #[arg(long, default_value_t = DEMOS_RATIO, value_name = "SHARE", requires = "demos")]
    #[serde(skip_serializing_if = "is_default_ratio")]
    pub demos_ratio: f64,
    /// `sha256:` of the `--demos` file's bytes, recorded when the run starts (a resumed run refuses
    /// another file).
    #[arg(skip)]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub demos_sha256: Option<String>,
}

/// The share of a batch drawn from the demonstrations, unless `--demos-ratio` says otherwise.
pub const DEMOS_RATIO: f64 = 0.5;

fn is_default_ratio(r: &f64) -> bool {
    *r == DEMOS_RATIO
}

impl Default for FinetuneConfig {
    fn default() -> Self {
        Self {
            init_from: None,
            init_policy: None,
            critic_warmup: 0,
            anchor_alpha: 0.0,
            ibrl: false,
            start_at_top: false,
            demos: None,
            demos_ratio: DEMOS_RATIO,
            demos_sha256: None,
        }
    }
}

fn is_zero(n: &u64) -> bool {
    *n == 0
}

fn is_zero_f64(x: &f64) -> bool {
    *x == 0.0
}

impl FinetuneConfig {
    /// Whether the run keeps the policy it started from beside its learner (`--anchor-alpha`,
    /// `--ibrl`): a resumed run loads it again.
    pub fn keeps_policy(&self) -> bool {
        self.start_uses().any()
    }

    /// What the learner keeps the starting policy for (`--anchor-alpha`, `--ibrl`).
    pub fn start_uses(&self) -> crate::learn::agents::algorithm::StartUses {
        crate::learn::agents::algorithm::StartUses { anchor_alpha: self.anchor_alpha, propose: self.ibrl }
    }

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
        let algo = run.algo.info();
        if self.init_from.is_some() && !algo.starts_from_policy {
            let can: Vec<&str> = crate::learn::agents::registry::Algo::ALL
                .iter()
                .filter(|a| a.info().starts_from_policy)
                .map(|a| a.name())
                .collect();
            return Err(ConfigError(format!(
                "--init-from: {} cannot start from a trained policy; use --algo {} (ddpg with --td3 for TD3)",
                algo.name(),
                can.join(", ")
            )));
        }
        if self.critic_warmup > 0 && algo.imitates {
            return Err(ConfigError(format!(
                "--critic-warmup {}: {} imitates the solver and has no critic to warm up; leave --critic-warmup out (or 0)",
                self.critic_warmup, algo.name()
            )));
        }
        if !self.anchor_alpha.is_finite() || self.anchor_alpha < 0.0 {
            return Err(ConfigError(format!(
                "--anchor-alpha {} must be a number ≥ 0 (0: off; TD3+BC's is 2.5)",
                self.anchor_alpha
            )));
        }
        if !(0.0..=1.0).contains(&self.demos_ratio) {
            return Err(ConfigError(format!(
                "--demos-ratio {} is a share of each batch: give a number from 0 to 1 (RLPD's is 0.5)",
                self.demos_ratio
            )));
        }
        if self.demos.is_some() && !run.net.obs_mode().is_entities() {
            return Err(ConfigError(format!(
                "--demos hold the solver's `entities` observation, and this run's network, {}, reads `{}`; \
                 train with --net entity",
                network(&run.net),
                run.net.obs_mode()
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
        // TD3 steps the actor on every `--policy-delay`-th update only: the first after the warm-up
        // must fall inside the run.
        let ddpg = &run.algos.ddpg;
        if self.critic_warmup > 0 && algo.name() == "ddpg" && ddpg.td3 {
            let delay = ddpg.policy_delay.max(1) as u64;
            let first = self.critic_warmup.div_ceil(delay) * delay;
            if first >= updates {
                return Err(ConfigError(format!(
                    "--critic-warmup {} with TD3's --policy-delay {delay}: the actor steps on every {delay}th update, \
                     and the first after the warm-up would be update {first}, past the run's {updates}, so the actor \
                     would never learn; give at most {} warm-up updates, or more --epochs",
                    self.critic_warmup,
                    (updates - 1) / delay * delay
                )));
            }
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
            refuse!(
                "--init-from {}: the policy reads the `{theirs}` observation, and this run's network, {}, reads \
                 `{ours}`; train with the policy's network (--net {})",
                path.display(),
                network(&run.net),
                crate::learn::agents::arch::NetKind::reading(theirs).name()
            );
        }
        let id = saved.policy_id(&path.display().to_string());
        match saved.policy {
            AnyPolicy::Deterministic(p) => Ok(Some((id, p))),
            AnyPolicy::Pggd(_) => refuse!(
                "--init-from {}: a PGGD (Gaussian) policy; the actor of DDPG, TD3 and SAC starts from a deterministic \
                 one (trained by ddpg, td3, sac, bc or dagger)",
                path.display()
            ),
        }
    }
}

/// A demos file read for a run: its bytes' hash and its contents.
pub struct DemoFile {
    /// `sha256:` of the file's bytes.
    pub sha256: String,
    /// What it holds.
    pub demos: Demos,
}

impl FinetuneConfig {
    /// The `--demos` file, read whole (None without `--demos`).
    ///
    /// # Errors
    /// A missing or malformed file, named with the flag.
    pub fn read_demos(&self) -> Result<Option<DemoFile>> {
        let Some(path) = &self.demos else { return Ok(None) };
        let (demos, sha256) = match Demos::read_hashed(path) {
            Ok(read) => read,
            Err(e @ DemosError::Read(_)) => Err(e).with_context(|| {
                format!("--demos {}: cannot read it (record one with `blockpuzzle demos`)", path.display())
            })?,
            Err(e) => Err(e).with_context(|| format!("--demos {}", path.display()))?,
        };
        let suite = demos.provenance.suite.as_ref().map_or("SUITE", |s| s.name.as_str());
        if demos.split == "test" {
            refuse!(
                "--demos {}: recorded on the test split of suite {suite}, which a run must not train on (as `train \
                 --split test` is refused); record demos of its train split (`blockpuzzle demos --suite {suite} \
                 --split train`)",
                path.display()
            );
        }
        let made_by = demos.provenance.build.solver_version();
        if made_by != crate::policy::SOLVER_VERSION {
            refuse!(
                "--demos {}: recorded by solver version {made_by}, and this build's solver is version {}: its actions \
                 are not the labels this build's solver gives; record the demos again with this build \
                 (`blockpuzzle demos --suite {suite} --split {}`)",
                path.display(),
                crate::policy::SOLVER_VERSION,
                demos.split
            );
        }
        Ok(Some(DemoFile { sha256, demos }))
    }
}

/// The demonstrations' episodes in the run's observation layout (`spec`): each episode's task must
/// be one of the run's `tasks` (by content hash); its block rows go to the first block slots (the
/// rest absent), its gripper, table and floor rows to the fixtures' rows.
///
/// # Errors
/// An episode of another task, or tensors of another layout, named with the fix.
pub(crate) fn demo_episodes(
    file: &DemoFile,
    path: &std::path::Path,
    spec: &ObsSpec,
    tasks: &[Task],
) -> Result<Vec<Episode>> {
    let d = &file.demos;
    let (r, f, rows) = (d.layout.robot.len(), d.layout.entity.len(), d.layout.rows);
    if !spec.mode.is_entities() || r != spec.robot_dim() || f != spec.object_dim() {
        refuse!(
            "--demos {}: its observations have {r} robot features and rows of {f}, and this run's have {} and {} \
             (the `{}` observation); record the demos with this build",
            path.display(),
            spec.robot_dim(),
            spec.object_dim(),
            spec.mode
        );
    }
    let fixtures = spec.mode.fixtures().len();
    let slots = spec.rows() - fixtures;
    let (mut obs_at, mut step_at) = (0, 0);
    let mut out = Vec::with_capacity(d.episodes.len());
    for (i, e) in d.episodes.iter().enumerate() {
        let Some(task) = tasks.iter().find(|t| t.source.hash == e.task_sha256) else {
            let ours: Vec<&str> = tasks.iter().map(|t| t.id()).collect();
            refuse!(
                "--demos {}: episode {i} is of task {} ({}), which this run does not train on ({}); record demos of \
                 the run's tasks (`blockpuzzle demos --suite S` with a suite whose rows are those tasks)",
                path.display(),
                e.task,
                e.task_sha256,
                ours.join(", ")
            );
        };
        if task.id() != e.task {
            refuse!(
                "--demos {}: episode {i} names task {}, and its hash {} is task {}'s: the file was edited; record the \
                 demos again with `blockpuzzle demos`",
                path.display(),
                e.task,
                e.task_sha256,
                task.id()
            );
        }
        let blocks = task.object_count();
        if blocks + fixtures > rows || blocks > slots {
            refuse!("--demos {}: episode {i} ({}) does not fit this run's {slots} block rows", path.display(), e.task);
        }
        // The demo row each of the run's rows takes (None: an absent block slot).
        let ours: Vec<Option<usize>> =
            (0..slots).map(|k| (k < blocks).then_some(k)).chain((0..fixtures).map(|j| Some(blocks + j))).collect();
        let obs = (obs_at..obs_at + e.steps + 1)
            .map(|o| {
                let row = |k: usize| &d.tensors.entities[(o * rows + k) * f..(o * rows + k + 1) * f];
                let mask = |k: usize| d.tensors.mask[o * rows + k];
                let mut v = d.tensors.robot[o * r..(o + 1) * r].to_vec();
                for k in &ours {
                    match k {
                        Some(k) => v.extend_from_slice(row(*k)),
                        None => v.extend(std::iter::repeat(0.0).take(f)),
                    }
                }
                v.extend(ours.iter().map(|k| k.map_or(0.0, mask)));
                v
            })
            .collect();
        let steps = step_at..step_at + e.steps;
        out.push(Episode {
            obs,
            act: steps.clone().map(|t| d.tensors.actions[t * 4..(t + 1) * 4].to_vec()).collect(),
            rew: d.tensors.rewards[steps.clone()].to_vec(),
            terminated: e.steps > 0 && d.tensors.terminations[step_at + e.steps - 1] > 0.5,
            success: e.outcome == crate::episode::outcome::Outcome::Success,
            expert_steps: e.steps,
            forward_seconds: 0.0,
            contacts: None,
        });
        obs_at += e.steps + 1;
        step_at += e.steps;
    }
    Ok(out)
}

/// The run's network as a message names it, without claiming a flag the user may not have given:
/// `mlp (--net's default)`, `entity (--net)`.
fn network(net: &crate::learn::agents::arch::NetConfig) -> String {
    let default = crate::learn::agents::arch::NetConfig::default().net;
    let how = if net.net == default { "--net's default" } else { "--net" };
    format!("{} ({how})", net.net.name())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::env::{BlockEnv, EnvConfig, ObsMode};

    /// A demonstration's observations, put in a run's layout, are what the run's own environment
    /// shows at the same task and seed: in the task's own layout, and in a wider one (a multi-task
    /// run's, more block slots before the fixtures' rows).
    #[test]
    fn demonstrations_read_as_the_runs_environment_shows_them() {
        let suite = crate::benchmark::suite::load(&format!(
            "{}/experiments/beyond-teacher/suites/ToppleTower-v0.toml",
            env!("CARGO_MANIFEST_DIR")
        ))
        .unwrap();
        let demos =
            crate::benchmark::demos::record(&suite, "train", Some(2), 1, crate::benchmark::provenance::Harness::Cli)
                .unwrap();
        let file = DemoFile { sha256: "sha256:test".into(), demos };
        let task = crate::env::registry::task("ToppleTower-v0").unwrap();
        for slots in [0, task.object_count() + 2] {
            let config = EnvConfig { obs_mode: ObsMode::Entities, slots, ..EnvConfig::new(task.clone()) };
            let mut env = BlockEnv::new(config).unwrap();
            env.set_level(env.max_level()).unwrap();
            let episodes =
                demo_episodes(&file, std::path::Path::new("d"), &env.obs_spec(), std::slice::from_ref(&task)).unwrap();
            assert_eq!(episodes.len(), 2);
            for (k, e) in episodes.iter().enumerate() {
                let (obs, _) = env.reset(Some(5_000_000 + k as u64)).unwrap();
                assert_eq!(e.obs[0], obs, "slots {slots}, episode {k}");
                assert_eq!(e.obs.len(), e.act.len() + 1);
                let step = env.step(&e.act[0]).unwrap();
                assert_eq!((&e.obs[1], e.rew[0]), (&step.obs, step.reward), "slots {slots}, episode {k}, step 1");
            }
        }
        // Demonstrations of another task are refused, naming it and the run's.
        let other = crate::env::registry::task("BlocksStack-v0").unwrap();
        let env = BlockEnv::new(EnvConfig { obs_mode: ObsMode::Entities, ..EnvConfig::new(other.clone()) }).unwrap();
        let e = demo_episodes(&file, std::path::Path::new("d"), &env.obs_spec(), &[other]).err().unwrap().to_string();
        assert!(e.contains("task ToppleTower-v0") && e.contains("(BlocksStack-v0)"), "{e}");
    }
}
