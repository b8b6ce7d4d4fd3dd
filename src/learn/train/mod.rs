//! Training with the paper's curriculum, readable top to bottom: DDPG, PGGD,
//! and PGGD by AggreVaTeD from a DDPG expert (`learner.rs`).
//!
//! An epoch is `cycles` cycles; in a cycle every worker (one environment
//! each, stepped in its own thread) collects `rollouts` exploration episodes
//! (DDPG: actor + noise; PGGD: Gaussian samples; AggreVaTeD: per step the
//! expert with probability β, else the learner) into its own replay buffer,
//! then the learner takes `batches` gradient steps, each the mean of the
//! workers' gradients on a batch of `batch_size` from their own buffers (as
//! the paper's MPI workers and baselines' MPI Adam do), and DDPG's target
//! networks follow. After the cycles every worker plays `test_episodes`
//! deterministic episodes at the current level ("test") and at the maximum
//! level ("finals"); when the test success reaches `success_threshold` the
//! curriculum moves up a level. Under `mpirun` the workers are spread over
//! ranks (`comm.rs`); the loop itself is `trainer.rs`. A run may start from a trained policy, warm
//! its critics up first and draw part of every batch from demonstrations (`finetune.rs`).
//!
//! The run directory holds `config.json`, `progress.csv` (one row per epoch),
//! `checkpoint.bin` (everything but the replay buffers, every epoch),
//! `replay/` (the buffers' append-only log),
//! `policy.json` (latest actor + normaliser), `best_policy.json` (best
//! finals success), `success.png` (the success curves) and, for AggreVaTeD,
//! `expert_policy.json` (the run's copy of its expert); with `--snapshot-every
//! N`, `snapshots/epoch-NNNN.json` (the policy after every Nth epoch). A run carried to another
//! machine with its checkpoint, `config.json` and `progress.csv` alone gives its `policy.json` again
//! (`export.rs`).

/// Returns a [`TrainError::Refused`] with the formatted message: the problem and its fix.
macro_rules! refuse {
    ($($arg:tt)*) => {
        return Err($crate::learn::train::TrainError::Refused(format!($($arg)*)))
    };
}

mod branch;
mod export;
pub mod finetune;
pub mod checkpoint;
pub mod comm;
mod learner;
pub mod options;
pub mod plot;
pub mod report;
mod rollouts;
mod rundir;
mod tasks;
mod trainer;

use crate::learn::agents::registry::Algo;
pub use branch::{branch, BranchedFrom, BRANCHABLE_CHANGES};
pub use export::policy_from_checkpoint;
pub use learner::{AggrevatedConfig, PgWeight};
pub(crate) use rollouts::{play_all, stream_seed, Behaviour};
pub use rundir::{rank_engines, read_progress, LogError, RankBuild, ReplayRebuilt, RunDir, Span};
pub use trainer::{train, train_ranks, OnEpoch, Start};

use crate::env::registry;
use crate::learn::agents::arch::{NetConfig, NetKind, Pooling};
use crate::learn::agents::registry::AlgoConfigs;
use crate::learn::agents::shared::{Precision, SharedConfig};
use crate::support::limits::Bound;
use crate::task::Task;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// Workers of one training process (spread more over MPI ranks).
pub const WORKERS: Bound = Bound::new(
    "--workers",
    1,
    256,
    "per process: each is a thread with its own environment and replay buffer; run more as MPI ranks",
);
/// A stream run's tasks with environments per epoch (`train --active-tasks`).
pub const ACTIVE_TASKS: Bound = Bound::new(
    "--active-tasks",
    1,
    1_024,
    "each active task has an environment per worker, built anew every epoch (about a quarter of a second each)",
);
/// Transitions per batch and worker.
pub const BATCH_SIZE: Bound =
    Bound::new("--batch-size", 1, 65_536, "per worker; a batch's activations take batch × hidden × layers × 16 bytes");
/// Replay capacity per worker.
pub const BUFFER_SIZE: Bound =
    Bound::new("--buffer-size", 1, 100_000_000, "transitions per worker; the run's memory is checked too");
/// Epochs of a run.
pub const EPOCHS: Bound = Bound::new("--epochs", 1, 100_000, "");
/// Cycles per epoch.
pub const CYCLES: Bound = Bound::new("--cycles", 1, 10_000, "");
/// Exploration episodes per worker and cycle.
pub const ROLLOUTS: Bound = Bound::new("--rollouts", 1, 10_000, "");
/// Gradient steps per cycle.
pub const BATCHES: Bound = Bound::new("--batches", 0, 100_000, "");
/// Test and finals episodes per worker and epoch.
pub const TEST_EPISODES: Bound = Bound::new("--test-episodes", 1, 100_000, "");
/// Relabelled copies of an episode (hindsight colours).
pub const HINDSIGHT_COLOURS: Bound =
    Bound::new("--hindsight-colours", 0, 16, "an episode's blocks offer no more colourings");

/// Gradient steps per cycle in the paper's set-up (baselines' HER default).
pub const PAPER_BATCHES: usize = 40;

/// Training hyperparameters (defaults: the paper's set-up): the trainer's
/// own (workers, epochs, cycles, replay, batches, curriculum), the networks,
/// the settings the algorithms share, and each algorithm's own.
///
/// A run's `config.json` holds it; files written before the algorithms had
/// settings of their own read as they did ([`crate::learn::agents::shared::upgrade_legacy`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, clap::Args)]
#[serde(remote = "Self")]
pub struct TrainConfig {
    /// Algorithm (one of `agents::registry::Algo::ALL`).
    #[arg(long, default_value = "ddpg", value_parser = Algo::parser())]
    #[serde(default)]
    pub algo: Algo,
    /// Environment id or task file (.toml); several, comma-separated (`BlocksTouch-v0,BlocksChoose-v0`),
    /// train one policy on all of them: a task drawn per exploration episode, each with its own
    /// curriculum level, every observation in one layout (the most block slots of any task).
    #[arg(long, default_value = "", hide_default_value = true, required_unless_present_any = ["suite", "families", "resume"])]
    pub env: String,
    /// Train on the tasks of a suite's split instead of `--env` (a suite name or file, e.g.
    /// `procgen`; generated tasks included), as for an `--env` list.
    #[arg(long, conflicts_with = "env")]
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub suite: Option<String>,
    /// Train on a stream of generated tasks instead of `--env`: the tasks that these families
    /// (shipped names or family files, comma-separated, e.g. `push,gripper,stack,gather,topple`) give
    /// for every seed of `--generator-seeds`. Seeds a built-in suite holds out are refused.
    #[arg(long, conflicts_with_all = ["env", "suite"], requires = "generator_seeds")]
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub families: Option<String>,
    /// The generator seeds of `--families`, `FIRST..END` (END excluded): each family's tasks of
    /// those seeds form the run's pool.
    #[arg(long, requires = "families")]
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub generator_seeds: Option<crate::benchmark::stream::SeedRange>,
    /// A stream run's tasks with environments in one epoch: so many of the pool, taken in turn from
    /// a permutation drawn anew every pass over it (building a task's environments costs about a
    /// quarter of a second each).
    #[arg(long, default_value_t = DEFAULT_ACTIVE_TASKS, value_parser = ACTIVE_TASKS.parser::<usize>())]
    #[serde(default = "default_active_tasks", skip_serializing_if = "is_default_active_tasks")]
    pub active_tasks: usize,
    /// Draw some of a stream's families more often: `avoid=3,gather=2` puts every avoid task three
    /// times and every gather task twice into each pass over the pool (the other families' once),
    /// so that they have environments, and episodes, about so many times as often. Whole numbers
    /// from 1 to 16, for families of `--families` (as named there).
    #[arg(long, requires = "families")]
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub family_weights: Option<crate::benchmark::stream::FamilyWeights>,
    /// The split of `--suite` to train on.
    #[arg(long, default_value = "train")]
    #[serde(default = "train_split")]
    pub split: String,
    /// Count ranges for the task's entries with a count, in every training
    /// episode (every level, challenge episodes included), e.g. `grey=0-2`
    /// or `red=0` (comma-separated for several): the count suite's train
    /// counts on BlocksChooseN-v0, the obstacles suite's on BlocksAvoid-v0.
    /// The scene and the observation layout stay the task's. Default: the
    /// task's own ranges.
    #[arg(long)]
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub counts: Option<crate::task::counts::Counts>,
    /// Parallel workers (the paper's MPI workers), one environment each.
    #[arg(long, default_value_t = 2, value_parser = WORKERS.parser::<usize>())]
    pub workers: usize,
    /// Epochs to train (a resumed run continues up to this many).
    #[arg(long, default_value_t = 200, value_parser = EPOCHS.parser::<usize>())]
    pub epochs: usize,
    /// Cycles per epoch.
    #[arg(long, default_value_t = 50, value_parser = CYCLES.parser::<usize>())]
    pub cycles: usize,
    /// Exploration episodes per worker per cycle.
    #[arg(long, default_value_t = 2, value_parser = ROLLOUTS.parser::<usize>())]
    pub rollouts: usize,
    /// Gradient steps per cycle.
    #[arg(long, default_value_t = PAPER_BATCHES, value_parser = BATCHES.parser::<usize>())]
    pub batches: usize,
    /// Transitions per batch and worker.
    #[arg(long, default_value_t = 256, value_parser = BATCH_SIZE.parser::<usize>())]
    pub batch_size: usize,
    /// Replay buffer capacity in transitions, per worker (`--replay shared`: per process).
    #[arg(long, default_value_t = 1_000_000, value_parser = BUFFER_SIZE.parser::<usize>())]
    pub buffer_size: usize,
    /// How workers share replay: `per-worker` (the paper's MPI workers: each
    /// worker keeps its buffer, samples its batch and computes its gradient,
    /// and the update is the mean of the workers' gradients, whatever the
    /// split into processes) or `shared` (one buffer per process, one batch
    /// of batch-size × workers; runs started before per-worker replay).
    /// Default: per-worker for a new run; a resumed run keeps its own.
    #[arg(long, value_enum)]
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub replay: Option<ReplayLayout>,
    /// Test and finals episodes per worker per epoch.
    #[arg(long, default_value_t = 10, value_parser = TEST_EPISODES.parser::<usize>())]
    pub test_episodes: usize,
    /// Test success rate that moves the curriculum up a level (default: the
    /// task file's `curriculum.success_threshold`, 0.7 for the paper's tasks).
    #[arg(long)]
    pub success_threshold: Option<f64>,
    /// Seed of everything (weights, layouts, exploration, batches).
    #[arg(long, default_value_t = 0, value_parser = crate::support::limits::SEED.parser::<u64>())]
    pub seed: u64,
    /// Threads libtorch may use for updates (0: all cores; at most the number of cores).
    #[arg(long, default_value_t = 0, value_parser = crate::support::limits::COUNT.parser::<usize>())]
    pub torch_threads: usize,
    /// Probability that an exploration episode plays a uniformly drawn lower
    /// level instead of the current one (0: the paper's curriculum).
    #[arg(long, default_value_t = 0.0)]
    #[serde(default)]
    pub level_replay: f64,
    /// At the maximum level, probability that an exploration episode plays the
    /// task's challenge distribution (0: the paper's curriculum).
    #[arg(long, default_value_t = 0.0)]
    #[serde(default)]
    pub challenge_share: f64,
    /// Also keep the policy of every Nth epoch as `snapshots/epoch-NNNN.json`
    /// (0: never); earlier policies for AggreVaTeD experts or learning-curve studies.
    #[arg(long, default_value_t = 0, value_parser = crate::support::limits::COUNT.parser::<usize>())]
    #[serde(default)]
    pub snapshot_every: usize,
    /// Hindsight colour relabelling: besides each exploration episode, store
    /// up to K copies in which a block that blue touched is green (the green
    /// blocks taking its colour), observations recoloured and rewards and
    /// terminations replayed by the colour rules over the recorded contacts
    /// (0: off, the paper's).
    #[arg(long, default_value_t = 0, value_parser = HINDSIGHT_COLOURS.parser::<usize>())]
    #[serde(default)]
    pub hindsight_colours: usize,
    /// Which tasks hindsight relabelling proposes: `blue-touched` (a block blue touched becomes
    /// green) or `pairs` (also: a block that touched green becomes blue).
    #[arg(long, value_enum, default_value_t = crate::env::hindsight::Strategy::BlueTouched)]
    #[serde(default)]
    pub hindsight_strategy: crate::env::hindsight::Strategy,
    /// The networks: an MLP over the flat observation, or a set network over the `objects` one.
    #[command(flatten)]
    #[serde(default)]
    pub net: NetConfig,
    /// The settings the algorithms share (each reads those its registration lists).
    #[command(flatten)]
    #[serde(default)]
    pub shared: SharedConfig,
    /// Each algorithm's own settings (`config.json`: one group per algorithm, by name).
    #[command(flatten)]
    #[serde(flatten)]
    pub algos: AlgoConfigs,
    /// AggreVaTeD settings (PGGD with an expert).
    #[command(flatten)]
    #[serde(default)]
    pub aggrevated: AggrevatedConfig,
    /// Starting from a trained policy (`--init-from`, `--critic-warmup`, `--start-at-top`).
    #[command(flatten)]
    #[serde(default, skip_serializing_if = "finetune::FinetuneConfig::is_off")]
    pub finetune: finetune::FinetuneConfig,
    /// The task, by id and content, recorded when the run starts: a resumed
    /// run refuses a task file that changed, and survives one that moved.
    #[arg(skip)]
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub task: Option<crate::task::TaskSource>,
    /// A multi-task run's tasks, by id and content, recorded when the run starts (a resumed run
    /// refuses tasks that changed).
    #[arg(skip)]
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub tasks: Vec<crate::task::TaskSource>,
    /// A stream run's pool (`--families`), recorded when the run starts: its families by hash, its
    /// seeds and each task by hash (a resumed run refuses another pool).
    #[arg(skip)]
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stream: Option<crate::benchmark::stream::StreamRecord>,
    /// The run this one branched from (`train --branch-from`), recorded in
    /// its `config.json`.
    #[arg(skip)]
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub branched_from: Option<BranchedFrom>,
}

/// A stream run's tasks with environments per epoch, unless `--active-tasks` says otherwise.
pub const DEFAULT_ACTIVE_TASKS: usize = 32;

fn default_active_tasks() -> usize {
    DEFAULT_ACTIVE_TASKS
}

/// Runs of listed tasks (and streams at the default) keep `config.json` as it was before streams.
fn is_default_active_tasks(n: &usize) -> bool {
    *n == DEFAULT_ACTIVE_TASKS
}

fn train_split() -> String {
    "train".to_owned()
}

impl Serialize for TrainConfig {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        TrainConfig::serialize(self, s)
    }
}

impl<'de> Deserialize<'de> for TrainConfig {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let mut value = serde_json::Value::deserialize(d)?;
        crate::learn::agents::shared::upgrade_legacy(&mut value);
        TrainConfig::deserialize(value).map_err(serde::de::Error::custom)
    }
}

/// How the workers of a process share replay (see [`TrainConfig::replay`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "kebab-case")]
pub enum ReplayLayout {
    /// One buffer, batch and gradient per worker; the update averages them.
    PerWorker,
    /// One buffer per process; one batch of `batch_size × workers`.
    Shared,
}

/// A training configuration that cannot run ([`TrainConfig::validate`]): the setting and its fix,
/// in words (the command line names the flag, a recipe its file and key).
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{0}")]
pub struct ConfigError(pub String);

/// Why a run could not start, continue or be branched, or a file of it could not be read or written.
/// The messages name the problem and the fix; where a lower error has a context (the file being
/// read), the chain reads "context: error", as the command line prints it.
#[derive(Debug, thiserror::Error)]
pub enum TrainError {
    /// A setting that cannot run ([`TrainConfig::validate`]).
    #[error(transparent)]
    Config(#[from] ConfigError),
    /// A run, task or setting refused as given: the message names the problem and the fix.
    #[error("{0}")]
    Refused(String),
    /// A lower error, led by what was being done ("cannot read PATH").
    #[error("{what}")]
    Context {
        /// What was being done, naming the file or flag.
        what: String,
        /// What failed.
        #[source]
        source: Box<TrainError>,
    },
    /// Rank 0's error, as its text, on every rank of the job ([`comm::Comm::root_check`]).
    #[error("{0}")]
    Rank0(String),
    /// An episode of a rollout plan that no environment played (a bug of the plan).
    #[error("episode {0} of the plan names no environment")]
    Unplayed(usize),
    /// An environment could not be made, set or stepped.
    #[error(transparent)]
    Env(#[from] crate::env::EnvError),
    /// A task does not compile (`--counts`, a recorded copy).
    #[error(transparent)]
    Task(#[from] crate::task::TaskError),
    /// A suite or its split could not be loaded or checked (`--suite`).
    #[error(transparent)]
    Suite(#[from] crate::benchmark::suite::SuiteError),
    /// A stream of generated tasks could not be made (`--families`; boxed, as the largest lower errors are).
    #[error(transparent)]
    Stream(Box<crate::benchmark::stream::StreamError>),
    /// A trained policy could not be loaded (`--expert`, `--init-from`).
    #[error(transparent)]
    Load(#[from] crate::benchmark::load::LoadError),
    /// Demonstrations could not be read (`--demos`; boxed).
    #[error(transparent)]
    Demos(Box<crate::benchmark::demos::DemosError>),
    /// A checkpoint could not be read, written or used.
    #[error(transparent)]
    Checkpoint(#[from] checkpoint::CheckpointError),
    /// A run's log could not be read.
    #[error(transparent)]
    Log(#[from] LogError),
    /// The success curves could not be drawn.
    #[error(transparent)]
    Plot(#[from] plot::PlotError),
    /// An output is refused or its write failed.
    #[error(transparent)]
    Write(#[from] crate::support::io::WriteError),
    /// A file or folder operation failed.
    #[error(transparent)]
    Io(#[from] std::io::Error),
    /// JSON could not be read or written (a run's files, what ranks exchange).
    #[error(transparent)]
    Json(#[from] serde_json::Error),
}

impl From<crate::benchmark::stream::StreamError> for TrainError {
    fn from(e: crate::benchmark::stream::StreamError) -> Self {
        Self::Stream(Box::new(e))
    }
}

impl From<crate::benchmark::demos::DemosError> for TrainError {
    fn from(e: crate::benchmark::demos::DemosError) -> Self {
        Self::Demos(Box::new(e))
    }
}

/// The training layer's results.
pub(crate) type Result<T, E = TrainError> = std::result::Result<T, E>;

/// Leads an error with what was being done ([`TrainError::Context`]): its chain reads
/// "context: error".
pub(crate) trait Context<T> {
    /// The error of `self`, led by `what()`.
    fn with_context(self, what: impl FnOnce() -> String) -> Result<T>;
}

impl<T, E: Into<TrainError>> Context<T> for std::result::Result<T, E> {
    fn with_context(self, what: impl FnOnce() -> String) -> Result<T> {
        self.map_err(|e| TrainError::Context { what: what(), source: Box::new(e.into()) })
    }
}

/// One row of `progress.csv`.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct EpochRow {
    pub epoch: usize,
    #[serde(rename = "curriculum/level")]
    pub level: usize,
    #[serde(rename = "train/success")]
    pub train_success: f64,
    #[serde(rename = "test/success")]
    pub test_success: f64,
    #[serde(rename = "finals/success")]
    pub finals_success: f64,
    #[serde(rename = "train/mean_q")]
    pub mean_q: f64,
    #[serde(rename = "train/critic_loss")]
    pub critic_loss: f64,
    #[serde(rename = "train/actor_loss")]
    pub actor_loss: f64,
    #[serde(rename = "time/env_steps")]
    pub env_steps: u64,
    #[serde(rename = "time/updates")]
    pub updates: u64,
    #[serde(rename = "time/wall_seconds")]
    pub wall_seconds: f64,
    /// Wall seconds of collection and test episodes (policy and environment).
    #[serde(rename = "time/env_seconds")]
    pub env_seconds: f64,
    /// The policy's share of `env_seconds`: actor forward passes and noise,
    /// summed over workers and divided by their number.
    #[serde(rename = "time/forward_seconds", default)]
    pub forward_seconds: f64,
    /// Wall seconds of gradient updates and target updates.
    #[serde(rename = "time/update_seconds")]
    pub update_seconds: f64,
    /// Wall seconds of averaging the workers' gradients, a part of
    /// `update_seconds` (under MPI: gathering every rank's gradients and summing them).
    #[serde(rename = "time/reduce_seconds", default)]
    pub reduce_seconds: f64,
    /// Wall seconds of the test and finals episodes (a part of `env_seconds`).
    #[serde(rename = "time/eval_seconds", default)]
    pub eval_seconds: f64,
    /// Wall seconds spent writing the previous epoch's files (progress, plot,
    /// policies, checkpoint); `wall_seconds` includes it.
    #[serde(rename = "time/persist_seconds", default)]
    pub persist_seconds: f64,
    /// AggreVaTeD: probability that the expert acts in this epoch's roll-ins;
    /// BC and DAgger: that the solver acts (0 for the others).
    #[serde(rename = "aggrevated/beta", default)]
    pub beta: f64,
    /// AggreVaTeD: share of this epoch's exploration steps taken by the expert; BC and DAgger: by the solver.
    #[serde(rename = "aggrevated/expert_share", default)]
    pub expert_share: f64,
    /// Hindsight colours: relabelled episodes stored per exploration episode.
    #[serde(rename = "hindsight/relabelled", default)]
    pub relabelled: f64,
    /// Hindsight colours: share of the relabelled episodes that succeed under their colours.
    #[serde(rename = "hindsight/relabelled_success", default)]
    pub relabelled_success: f64,
    /// CPU time of the process over the epoch / (wall time × cores).
    #[serde(rename = "time/cpu_utilisation", default)]
    pub cpu_utilisation: f64,
}

impl TrainConfig {
    /// The settings with every relative file path made absolute (against the current folder):
    /// `--demos`, `--init-from` where it names a file or folder, the files of `--families` and of
    /// `--env`. `config.json` records them so, and a resume from another folder reads the same files.
    /// Names (a zoo entry, a shipped family, a task id) stay as given.
    ///
    /// # Errors
    /// A current folder that cannot be read, or whose path is not UTF-8 (the lists are text).
    pub fn with_absolute_paths(mut self) -> Result<Self> {
        let cwd = std::env::current_dir().map_err(|e| {
            TrainError::Refused(format!("cannot read the current folder to resolve the run's file paths: {e}"))
        })?;
        let absolute = |p: &Path| if p.is_relative() && p.exists() { cwd.join(p) } else { p.to_owned() };
        let text = |p: std::path::PathBuf, flag: &str| {
            p.into_os_string().into_string().map_err(|p| {
                TrainError::Refused(format!(
                    "{flag}: the file's full path {} is not UTF-8; run from a folder whose path is",
                    Path::new(&p).display()
                ))
            })
        };
        let finetune = &mut self.finetune;
        finetune.demos = finetune.demos.as_deref().map(absolute);
        if let Some(p) = finetune.init_from.as_deref() {
            let named =
                p.to_str().is_some_and(|s| s == "random" || crate::benchmark::evaluate::Baseline::named(s).is_some());
            if !named {
                finetune.init_from = Some(absolute(p));
            }
        }
        // A comma-separated list with each item that is a file (not a `name`) made absolute.
        let list = |list: &str, name: &dyn Fn(&str) -> bool, flag: &str| {
            let items = list
                .split(',')
                .map(|item| match item.trim() {
                    t if name(t) || !Path::new(t).exists() => Ok(item.to_owned()),
                    t => text(absolute(Path::new(t)), flag),
                })
                .collect::<Result<Vec<_>>>()?;
            Ok::<_, TrainError>(items.join(","))
        };
        if let Some(families) = &self.families {
            let builtin = |n: &str| crate::task::family::BUILTIN_FAMILIES.iter().any(|(b, _)| *b == n);
            self.families = Some(list(families, &builtin, "--families")?);
        }
        if !self.env.is_empty() {
            self.env = list(&self.env, &|t| !registry::is_path(t), "--env")?;
        }
        Ok(self)
    }

    /// Checks every setting before anything is written (`ranks`: the MPI processes of the run).
    ///
    /// # Errors
    /// The first setting that cannot run, named with its fix.
    pub fn validate(&self, ranks: usize) -> Result<(), ConfigError> {
        use self::{BATCHES, BATCH_SIZE, BUFFER_SIZE, CYCLES, EPOCHS, ROLLOUTS, TEST_EPISODES, WORKERS};
        let c = self;
        for (bound, v) in [
            (WORKERS, c.workers),
            (EPOCHS, c.epochs),
            (CYCLES, c.cycles),
            (ROLLOUTS, c.rollouts),
            (BATCHES, c.batches),
            (BATCH_SIZE, c.batch_size),
            (BUFFER_SIZE, c.buffer_size),
            (TEST_EPISODES, c.test_episodes),
        ] {
            bound.check_usize(v).map_err(ConfigError)?;
        }
        crate::learn::blas::torch_threads(self.torch_threads).map_err(ConfigError)?;
        Algo::validate(&self.shared, &self.algos).map_err(ConfigError)?;
        if !(0.0..=1.0).contains(&self.level_replay) || !(0.0..=1.0).contains(&self.challenge_share) {
            return Err(ConfigError("--level-replay and --challenge-share must be in [0, 1]".into()));
        }
        self.net.validate().map_err(ConfigError)?;
        if self.suite.is_none() && self.split != "train" {
            return Err(ConfigError(format!(
                "--split {} is only used with --suite (the split of a suite to train on)",
                self.split
            )));
        }
        if self.suite.is_none() && self.families.is_none() && self.env.trim().is_empty() {
            return Err(ConfigError(
                "no task: pass --env ID (several comma-separated), --suite S, or --families F --generator-seeds A..B"
                    .into(),
            ));
        }
        // A doubled or trailing comma names nothing: refused rather than dropped, since the list is
        // recorded as given and a run's label and pool come from it.
        // (An --env list is checked where its tasks are resolved.)
        if let Some(list) = self.families.as_deref().filter(|l| l.contains(',')) {
            if let Some(k) = list.split(',').position(|item| item.trim().is_empty()) {
                return Err(ConfigError(format!(
                    "--families {list:?}: item {} of the list is empty; list family names or files separated by \
                     single commas",
                    k + 1
                )));
            }
        }
        if self.families.is_some() != self.generator_seeds.is_some() {
            return Err(ConfigError("--families and --generator-seeds go together: give both (e.g. --families push,gripper --generator-seeds 0..256)".into()));
        }
        let (width, flag) = match self.net.set_width {
            0 => (self.shared.hidden, "--hidden"),
            w => (w, "--set-width"),
        };
        if self.net.set_transformer > 0 && width % crate::policy::actor::mlp::TRANSFORMER_HEADS != 0 {
            return Err(ConfigError(format!(
                "--set-transformer splits {flag} {width} into {} heads; give a multiple of {}",
                crate::policy::actor::mlp::TRANSFORMER_HEADS,
                crate::policy::actor::mlp::TRANSFORMER_HEADS
            )));
        }
        // Which algorithm takes an expert first: the network matters only to one that does, and an
        // imitator given one is told to drop it before anything about its network.
        let expert = self.aggrevated.expert.is_some();
        self.algo.check_expert(expert).map_err(ConfigError)?;
        options::check(&self.settings()).map_err(ConfigError)?;
        if expert && self.net.net != crate::learn::agents::arch::NetKind::Mlp {
            return Err(ConfigError(
                "--expert: AggreVaTeD's expert view is the flat observation without grey blocks; train with --net mlp"
                    .into(),
            ));
        }
        let t0 = self.aggrevated.t0;
        if !(0.0..=1.0).contains(&self.aggrevated.beta0) || !t0.is_finite() || t0 < 0.0 {
            return Err(ConfigError("--beta0 must be in [0, 1] and --t0 at least 0".into()));
        }
        if let Some(t) = self.success_threshold {
            if !(0.0..=1.0).contains(&t) {
                return Err(ConfigError("--success-threshold must be in [0, 1]".into()));
            }
        }
        if self.families.is_none() && self.active_tasks != DEFAULT_ACTIVE_TASKS {
            return Err(ConfigError(
                "--active-tasks applies to a stream of generated tasks (--families); leave it out here".into(),
            ));
        }
        if self.families.is_none() && self.family_weights.is_some() {
            return Err(ConfigError(
                "--family-weights weighs the families of a stream of generated tasks; give --families too, or \
                 leave the weights out"
                    .into(),
            ));
        }
        if let (Some(weights), Some(list)) = (&self.family_weights, &self.families) {
            let families = crate::benchmark::stream::family_names(list);
            if let Some(other) = weights.0.keys().find(|name| !families.contains(&name.as_str())) {
                return Err(ConfigError(format!(
                    "--family-weights names {other}, which is not a family of this stream ({}); weigh only families of \
                     --families, as named there",
                    families.join(", ")
                )));
            }
        }
        self.finetune.validate(self)?;
        if ranks > 1 && self.replay == Some(ReplayLayout::Shared) {
            return Err(ConfigError(format!(
                "--replay shared keeps one buffer per process, so {} ranks would not compute what one process \
                 computes; use --replay per-worker (the default) under mpirun",
                ranks
            )));
        }
        Ok(())
    }

    /// The choices and settings [`options::check`] reads.
    pub fn settings(&self) -> options::Options<'_> {
        options::Options {
            algo: self.algo,
            net: &self.net,
            shared: &self.shared,
            algos: &self.algos,
            aggrevated: &self.aggrevated,
            hindsight_colours: self.hindsight_colours,
            hindsight_strategy_given: self.hindsight_strategy != crate::env::hindsight::Strategy::default(),
        }
    }

    /// The replay layout of a run's recorded configuration (one recorded
    /// before the setting existed shared its replay).
    pub fn replay_layout(&self) -> ReplayLayout {
        self.replay.unwrap_or(ReplayLayout::Shared)
    }

    /// The method as (display name, short name): e.g. DDPG, or PGGD +
    /// AggreVaTeD (`pggd-aggrevated`).
    fn method(&self) -> (String, String) {
        let (title, name) = (self.algo.title(), self.algo.name());
        match (&self.aggrevated.expert, self.aggrevated.pg_weight) {
            (None, _) => (title.to_owned(), name.to_owned()),
            (Some(_), PgWeight::Return) => (format!("{title} + AggreVaTeD"), format!("{name}-aggrevated")),
            (Some(_), PgWeight::ExpertAdvantage) => {
                (format!("{title} + AggreVaTeD (expert advantage)"), format!("{name}-aggrevated-adv"))
            }
        }
    }

    /// Whether the run learns from the solver's actions (an imitation algorithm, or `--demos`): its
    /// policy records the solver version ([`crate::benchmark::saved::SavedPolicy::solver`]).
    pub fn learns_from_solver(&self) -> bool {
        self.algo.info().imitates || self.finetune.demos.is_some()
    }

    /// The algorithm as policy files and zoo entries record it (`ddpg` with `--td3` is `td3`).
    pub fn trainer(&self) -> crate::benchmark::saved::Trainer {
        match self.algo.info().trainer {
            crate::benchmark::saved::Trainer::Ddpg if self.algos.ddpg.td3 => crate::benchmark::saved::Trainer::Td3,
            trainer => trainer,
        }
    }

    /// The task's id: the recorded one, else `--env` (a task file's stem when it is a path); for a
    /// multi-task run, `SUITE-SPLIT` or the tasks' ids joined by `+`.
    pub fn task_id(&self) -> String {
        if tasks::is_multi(self) {
            return tasks::label(self);
        }
        match &self.task {
            Some(t) => t.id.clone(),
            None => tasks::env_name(&self.env),
        }
    }

    /// This project's options in use beyond the paper's set-up, e.g. "TD3, 3-step, bf16" (empty: none).
    pub fn options(&self) -> String {
        let s = &self.shared;
        let mut v = Vec::new();
        let net = self.net.describe();
        if !net.is_empty() {
            v.push(net);
        }
        if s.flat_critic {
            v.push("flat critics".into());
        }
        if let Some(c) = &self.counts {
            v.push(format!("counts {c}"));
        }
        if self.hindsight_colours > 0 {
            v.push(format!("hindsight colours {}", self.hindsight_colours));
            if self.hindsight_strategy == crate::env::hindsight::Strategy::Pairs {
                v.push("hindsight pairs".into());
            }
        }
        v.extend(self.algo.describe(&self.algos));
        if s.n_step > 1 {
            v.push(format!("{}-step", s.n_step));
        }
        if self.level_replay > 0.0 {
            v.push(format!("level replay {}", self.level_replay));
        }
        if self.challenge_share > 0.0 {
            v.push(format!("challenge share {}", self.challenge_share));
        }
        if s.precision == Precision::Bf16 {
            v.push("bf16".to_owned());
        }
        if self.batches != PAPER_BATCHES {
            v.push(format!("{} batches per cycle", self.batches));
        }
        if let Some(b) = &self.branched_from {
            v.push(format!("branched at epoch {}", b.epoch));
        }
        v.join(", ")
    }

    /// Plot title: method, options and environment, e.g. "PGGD + AggreVaTeD on
    /// BlocksChoose-v0" or "DDPG (TD3, 3-step) on BlocksChoose-v0".
    pub fn title(&self) -> String {
        let options = self.options();
        if options.is_empty() {
            format!("{} on {}", self.method().0, self.task_id())
        } else {
            format!("{} ({options}) on {}", self.method().0, self.task_id())
        }
    }

    /// The default run directory, `runs/TASK-METHOD-sSEED`.
    pub fn default_run_dir(&self) -> std::path::PathBuf {
        let net = match (self.net.net, self.net.set_pooling) {
            (NetKind::Mlp, _) => String::new(),
            (kind, Pooling::MeanMax) => format!("-{}", kind.name()),
            (kind, Pooling::Attention) => format!("-{}-attention", kind.name()),
            (kind, Pooling::Colour) => format!("-{}-colour", kind.name()),
            (kind, Pooling::Query) => format!("-{}-query", kind.name()),
        };
        let norm = [
            (self.net.set_robot_tokens, "-tokens"),
            (self.net.set_type_norm, "-typenorm"),
            (self.net.set_norm, "-norm"),
        ]
        .iter()
        .filter(|(on, _)| *on)
        .map(|(_, s)| *s)
        .collect::<String>();
        let norm = match self.net.set_transformer {
            0 => norm,
            n => format!("-transformer{n}{norm}"),
        };
        let norm = match self.net.set_width {
            0 => norm,
            w => format!("-w{w}{norm}"),
        };
        let critic = if self.shared.flat_critic { "-flatcritic" } else { "" };
        // `--counts grey=0-2,red=1` -> `-grey0-2-red1`.
        let counts = self
            .counts
            .as_ref()
            .map_or(String::new(), |c| format!("-{}", c.to_string().replace('=', "").replace(',', "-")));
        format!("runs/{}-{}{net}{norm}{critic}{counts}-s{}", self.task_id(), self.method().1, self.seed).into()
    }
}

/// The settings that change what a run computes and differ between `a`
/// and `b`, by flag name: every field of the configuration (nested ones
/// included, so a new setting is compared without being listed here) but
/// those in [`RESUMABLE_CHANGES`].
fn computation_differences(a: &TrainConfig, b: &TrainConfig) -> Vec<String> {
    let mut out = Vec::new();
    differing_fields(&a, &b, &mut out);
    out
}

/// The seal of a run's configuration, which its checkpoints record ([`checkpoint::RunState`]): the
/// `sha256:` of every setting but those a resume may change ([`RESUMABLE_CHANGES`]), with the
/// contents of its tasks (a task's, a list's or a stream's hashes). A resume whose `config.json` does
/// not give the checkpoint's seal is refused: the file was edited (a seed, a width, an anchor, a
/// dropped stream or fine-tuning record), or the checkpoint is another run's.
pub(crate) fn config_seal(c: &TrainConfig) -> String {
    let mut v = serde_json::to_value(c).unwrap_or_default();
    if let Some(o) = v.as_object_mut() {
        for k in RESUMABLE_CHANGES {
            o.remove(*k);
        }
    }
    let listed = c.task.iter().chain(&c.tasks).map(|t| t.hash.as_str());
    let streamed = c.stream.iter().flat_map(|s| s.tasks.iter().map(|t| t.hash.as_str()));
    let tasks: Vec<&str> = listed.chain(streamed).collect();
    crate::benchmark::provenance::sha256(format!("{v}\ntasks {}", tasks.join("+")).as_bytes())
}

/// Whether the checkpoint at `path` (its header's `state`) was written with `config`, the run's
/// `config.json`: its seal is the config's, or, at a branch's first resume, the parent's. `what` starts
/// the message (`--resume`, or the folder a policy is made from). Checkpoints written before seals
/// pass.
///
/// # Errors
/// Another run's checkpoint, or an edited `config.json`, with both seals and the fix.
pub(crate) fn check_config_seal(
    run: &RunDir,
    config: &TrainConfig,
    path: &std::path::Path,
    state: &checkpoint::RunState,
    what: &str,
) -> Result<()> {
    let Some(recorded) = &state.config_seal else { return Ok(()) };
    let ours = config_seal(config);
    let branch_start = config
        .branched_from
        .as_ref()
        .is_some_and(|b| b.epoch == state.epoch && b.parent_seal.as_ref() == Some(recorded));
    if ours != *recorded && !branch_start {
        refuse!(
            "{what}: {} is not the configuration {} was written with (its seal {ours}, the checkpoint's \
             {recorded}): the file was edited, or the checkpoint is another run's; restore the run's own config.json \
             and checkpoint together, or start a new run with another --run-dir",
            run.config().display(),
            path.display()
        );
    }
    Ok(())
}

/// Fields that may change on `--resume`: the epoch target, thread count and
/// snapshots, the task and its id (checked by content in [`run_task`]), and
/// the record of a branch (kept from the run's `config.json`).
const RESUMABLE_CHANGES: &[&str] =
    &["epochs", "torch_threads", "snapshot_every", "task", "tasks", "stream", "env", "branched_from"];

/// The fields of two configurations that differ, as the flags that set them
/// (`--PREFIXfield-name`), each once: the groups of flags (`net`, `shared`,
/// `aggrevated`, and each algorithm's, whose flags carry its registration's
/// prefix) field by field, any other value whole (`--counts`, not its
/// entries); [`RESUMABLE_CHANGES`] left out.
fn differing_fields<T: Serialize>(a: &T, b: &T, out: &mut Vec<String>) {
    use crate::learn::agents::registry::{flag, groups};
    const GROUPS: [&str; 4] = ["net", crate::learn::agents::shared::SHARED_KEY, "aggrevated", "finetune"];
    let (a, b) = (serde_json::to_value(a).unwrap_or_default(), serde_json::to_value(b).unwrap_or_default());
    for path in crate::support::diff::differences(&a, &b) {
        let Some(top) = path.key(0) else { continue };
        if RESUMABLE_CHANGES.contains(&top) {
            continue;
        }
        let prefix = GROUPS.iter().map(|g| (*g, "")).chain(groups()).find(|(g, _)| *g == top).map(|(_, p)| p);
        let name = match (prefix, path.key(1)) {
            (Some(prefix), Some(field)) => flag(prefix, field),
            _ => flag("", top),
        };
        if !out.contains(&name) {
            out.push(name);
        }
    }
}

/// The task of a run: `--env` resolved; on resume, checked against `recorded`,
/// the copy in the run's `config.json` (a changed task is an error naming
/// what changed; a task file that no longer exists is replaced by the copy).
///
/// # Errors
/// An unknown id or bad task file, or a task that changed since the run started.
fn run_task(config: &TrainConfig, run: &RunDir, saved: Option<&TrainConfig>) -> Result<Task> {
    let Some((saved, source)) = saved.and_then(|s| Some((s, s.task.as_ref()?))) else {
        return Ok(registry::task(&config.env)?);
    };
    if registry::is_path(&config.env) && !Path::new(&config.env).exists() {
        eprintln!(
            "{} is gone: resuming with the copy of {} recorded in {}",
            config.env,
            source.id,
            run.config().display()
        );
        return Ok(registry::recorded(source)?);
    }
    let current = registry::task(&config.env)?;
    if current.id() != source.id {
        refuse!(
            "--resume: {} was trained on {} (--env {}), this command asks for {}; pass --env {}",
            run.dir.display(),
            source.id,
            saved.env,
            current.id(),
            saved.env
        );
    }
    if current.source.hash != source.hash {
        let copy = Task::parse(&source.toml, &format!("the copy in {}", run.config().display()), None)?;
        let changed = copy.differences(&current);
        refuse!(
            "--resume: the task {} has changed since the run started ({} differ from the copy in {}); \
             restore the file, or start a new run with another --run-dir",
            config.env,
            if changed.is_empty() { "its contents".to_owned() } else { changed.join(", ") },
            run.config().display()
        );
    }
    Ok(current)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn training_bounds_name_the_flag_the_range_and_why() {
        assert_eq!(WORKERS.parse::<usize>("12"), Ok(12));
        let e = WORKERS.parse::<usize>("-3").unwrap_err();
        assert!(e.contains("whole number from 1 to 256"), "{e}");
        let e = WORKERS.parse::<usize>("100000").unwrap_err();
        assert!(e.contains("allowed are 1 to 256") && e.contains("MPI"), "{e}");
    }

    #[test]
    fn a_context_leads_the_lower_error_in_the_chain() {
        let e = Err::<(), _>(std::io::Error::other("gone")).with_context(|| "cannot read x".to_owned()).unwrap_err();
        assert_eq!(e.to_string(), "cannot read x");
        assert_eq!(crate::support::error::chain(&e), "cannot read x: gone");
    }
}
