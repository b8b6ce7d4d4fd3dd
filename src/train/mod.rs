//! Training with the paper's curriculum, readable top to bottom: DDPG, PGGD,
//! and PGGD by AggreVaTeD from a DDPG expert (`learner.rs`).
//!
//! An epoch is `cycles` cycles; in a cycle every worker (one environment
//! each, stepped in its own thread) collects `rollouts` exploration episodes
//! (DDPG: actor + noise; PGGD: Gaussian samples; AggreVaTeD: per step the
//! expert with probability β, else the learner), then the learner takes
//! `batches` gradient steps on batches of `batch_size × workers` transitions
//! (the average of the workers' gradients, as baselines' MPI Adam computes
//! it) and DDPG's target networks follow. After
//! the cycles every worker plays `test_episodes` deterministic episodes at
//! the current level ("test") and at the maximum level ("finals"); when the
//! test success reaches `success_threshold` the curriculum moves up a level.
//!
//! The run directory holds `config.json`, `progress.csv` (one row per epoch),
//! `checkpoint.bin` (everything, written atomically every epoch),
//! `policy.json` (latest actor + normaliser), `best_policy.json` (best
//! finals success), `success.png` (the success curves) and, for AggreVaTeD,
//! `expert_policy.json` (the run's copy of its expert); with `--snapshot-every
//! N`, `snapshots/epoch-NNNN.json` (the policy after every Nth epoch).

pub mod checkpoint;
mod learner;
pub mod plot;
pub mod report;
mod rollouts;
mod rundir;

pub use learner::{Agent, AggrevatedConfig, Algo, PgWeight};
pub(crate) use rollouts::{play_all, stream_seed, Behaviour, Draw};
pub use rundir::{load_policy, read_progress, write_atomic, write_json_atomic, RunDir, SavedPolicy};

use crate::agents::ddpg::{DdpgConfig, Precision, UpdateStats};
use crate::agents::pggd::PggdConfig;
use crate::agents::replay::ReplayBuffer;
use crate::env::{registry, BlockEnv, EnvConfig};
use crate::task::Task;
use anyhow::{bail, Context, Result};
use checkpoint::RunState;
use learner::{Expert, Learner};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rollouts::success_rate;
use rundir::write_progress;
use serde::{Deserialize, Serialize};
use std::path::Path;
use std::time::Instant;

/// Training hyperparameters (defaults: the paper's set-up).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, clap::Args)]
pub struct TrainConfig {
    /// Algorithm.
    #[arg(long, value_enum, default_value = "ddpg")]
    #[serde(default)]
    pub algo: Algo,
    /// Environment id.
    #[arg(long)]
    pub env: String,
    /// Parallel workers (the paper's MPI workers), one environment each.
    #[arg(long, default_value_t = 2)]
    pub workers: usize,
    /// Epochs to train (a resumed run continues up to this many).
    #[arg(long, default_value_t = 200)]
    pub epochs: usize,
    /// Cycles per epoch.
    #[arg(long, default_value_t = 50)]
    pub cycles: usize,
    /// Exploration episodes per worker per cycle.
    #[arg(long, default_value_t = 2)]
    pub rollouts: usize,
    /// Gradient steps per cycle.
    #[arg(long, default_value_t = 40)]
    pub batches: usize,
    /// Transitions per batch and worker.
    #[arg(long, default_value_t = 256)]
    pub batch_size: usize,
    /// Replay buffer capacity in transitions.
    #[arg(long, default_value_t = 1_000_000)]
    pub buffer_size: usize,
    /// Test and finals episodes per worker per epoch.
    #[arg(long, default_value_t = 10)]
    pub test_episodes: usize,
    /// Test success rate that moves the curriculum up a level (default: the
    /// task file's `curriculum.success_threshold`, 0.7 for the paper's tasks).
    #[arg(long)]
    pub success_threshold: Option<f64>,
    /// Seed of everything (weights, layouts, exploration, batches).
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Threads libtorch may use for updates (0: all cores).
    #[arg(long, default_value_t = 0)]
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
    #[arg(long, default_value_t = 0)]
    #[serde(default)]
    pub snapshot_every: usize,
    /// DDPG hyperparameters (PGGD uses its network shape, gamma and normaliser settings).
    #[command(flatten)]
    pub ddpg: DdpgConfig,
    /// PGGD hyperparameters.
    #[command(flatten)]
    #[serde(default)]
    pub pggd: PggdConfig,
    /// AggreVaTeD settings (PGGD with an expert).
    #[command(flatten)]
    #[serde(default)]
    pub aggrevated: AggrevatedConfig,
    /// The task, by id and content, recorded when the run starts: a resumed
    /// run refuses a task file that changed, and survives one that moved.
    #[arg(skip)]
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub task: Option<crate::task::TaskSource>,
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
    /// Wall seconds of the test and finals episodes (a part of `env_seconds`).
    #[serde(rename = "time/eval_seconds", default)]
    pub eval_seconds: f64,
    /// Wall seconds spent writing the previous epoch's files (progress, plot,
    /// policies, checkpoint); `wall_seconds` includes it.
    #[serde(rename = "time/persist_seconds", default)]
    pub persist_seconds: f64,
    /// AggreVaTeD: probability that the expert acts in this epoch's roll-ins (0 without an expert).
    #[serde(rename = "aggrevated/beta", default)]
    pub beta: f64,
    /// AggreVaTeD: share of this epoch's exploration steps taken by the expert.
    #[serde(rename = "aggrevated/expert_share", default)]
    pub expert_share: f64,
    /// CPU time of the process over the epoch / (wall time × cores).
    #[serde(rename = "time/cpu_utilisation", default)]
    pub cpu_utilisation: f64,
}

/// User + system CPU seconds of this process so far.
fn cpu_seconds() -> f64 {
    // SAFETY: getrusage writes one rusage struct into the zeroed value we
    // pass; RUSAGE_SELF is always valid.
    let usage = unsafe {
        let mut u: libc::rusage = std::mem::zeroed();
        if libc::getrusage(libc::RUSAGE_SELF, &mut u) != 0 {
            return 0.0;
        }
        u
    };
    let secs = |t: libc::timeval| t.tv_sec as f64 + t.tv_usec as f64 * 1e-6;
    secs(usage.ru_utime) + secs(usage.ru_stime)
}

/// Per-epoch callback for progress reporting.
pub type OnEpoch<'a> = &'a mut dyn FnMut(&EpochRow, &TrainConfig);

/// Trains DDPG; with `resume`, continues from the run directory's checkpoint.
///
/// # Errors
/// Bad configuration, environment errors, I/O and checkpoint errors.
pub fn train(config: &TrainConfig, run_dir: &Path, resume: bool, on_epoch: OnEpoch) -> Result<Vec<EpochRow>> {
    // Every setting is checked before anything is written.
    if config.workers == 0 || config.cycles == 0 || config.batch_size == 0 || config.test_episodes == 0 {
        bail!("--workers, --cycles, --batch-size and --test-episodes must be at least 1");
    }
    config.ddpg.validate().map_err(anyhow::Error::msg)?;
    if !(0.0..=1.0).contains(&config.level_replay) || !(0.0..=1.0).contains(&config.challenge_share) {
        bail!("--level-replay and --challenge-share must be in [0, 1]");
    }
    if config.algo == Algo::Pggd && (config.ddpg.n_step != 1 || config.ddpg.td3) {
        bail!("--n-step and --td3 are DDPG options; PGGD uses the return-to-go");
    }
    if config.ddpg.precision == Precision::Bf16 && !Precision::bf16_supported() {
        bail!("--precision bf16 needs a CPU with AMX or AVX512-BF16 (this one has neither); use --precision f32");
    }
    if config.algo == Algo::Ddpg && config.aggrevated.expert.is_some() {
        bail!("--expert is for --algo pggd (AggreVaTeD); DDPG trains without an expert");
    }
    if config.algo == Algo::Ddpg && config.aggrevated.pg_weight != PgWeight::Return {
        bail!("--pg-weight is for --algo pggd");
    }
    let (lr, sigma_min) = (config.pggd.lr, config.pggd.sigma_min);
    if !lr.is_finite() || lr <= 0.0 || !sigma_min.is_finite() || sigma_min < 0.0 {
        bail!("--pg-lr must be a positive number and --pg-sigma-min a number ≥ 0");
    }
    let t0 = config.aggrevated.t0;
    if !(0.0..=1.0).contains(&config.aggrevated.beta0) || !t0.is_finite() || t0 < 0.0 {
        bail!("--beta0 must be in [0, 1] and --t0 at least 0");
    }
    let run = RunDir { dir: run_dir.to_owned() };
    std::fs::create_dir_all(&run.dir).with_context(|| format!("cannot create run directory {}", run.dir.display()))?;
    tch::set_num_threads(if config.torch_threads == 0 {
        std::thread::available_parallelism().map_or(1, |n| n.get()) as i32
    } else {
        config.torch_threads as i32
    });

    // The task (checked against the run's recorded copy on resume), then one environment per worker.
    let saved_config = if resume && run.config().exists() { Some(run.read_config()?) } else { None };
    let task = run_task(config, &run, saved_config.as_ref().and_then(|c| c.task.as_ref()))?;
    let mut config = config.clone();
    config.task = Some(task.source.clone());
    let config = &config;
    let threshold = config.success_threshold.unwrap_or(task.spec.curriculum.success_threshold);
    if !(0.0..=1.0).contains(&threshold) {
        bail!("--success-threshold must be in [0, 1]");
    }
    let mut envs: Vec<BlockEnv> =
        (0..config.workers).map(|_| BlockEnv::new(EnvConfig::new(task.clone()))).collect::<Result<_, _>>()?;
    let (obs_dim, act_dim) = (envs[0].observation_space().dim(), envs[0].action_space().dim());
    let max_level = envs[0].max_level();
    if config.challenge_share > 0.0 && task.distribution("challenge").is_none() {
        bail!("--challenge-share: the task {} has no challenge distribution", task.id());
    }

    // Agent, replay buffer, run state: fresh or from the checkpoint.
    let (agent, mut replay, mut state, mut rows) = if resume && run.checkpoint().exists() {
        let saved = match saved_config {
            Some(c) => c,
            None => run.read_config()?,
        };
        let changed = computation_differences(&saved, config);
        if !changed.is_empty() || (saved.task.is_none() && saved.env != config.env) {
            bail!(
                "--resume with settings that differ from {} ({}); resume with the run's settings or start a new run with another --run-dir",
                run.config().display(),
                if changed.is_empty() { "--env".to_owned() } else { changed.join(", ") }
            );
        }
        let loaded = checkpoint::load(&run.checkpoint(), task.id(), obs_dim, act_dim)?;
        let rows = read_progress(&run.progress())?.into_iter().filter(|r| r.epoch < loaded.state.epoch).collect();
        (loaded.agent, loaded.replay, loaded.state, rows)
    } else {
        if resume {
            bail!("--resume: no checkpoint in {}", run.dir.display());
        }
        if run.checkpoint().exists() {
            bail!(
                "{} already holds a run; pass --resume to continue it or choose another --run-dir",
                run.dir.display()
            );
        }
        let mut rng = ChaCha8Rng::seed_from_u64(stream_seed(config.seed, &[0]));
        let agent = Agent::new(config, obs_dim, act_dim, &mut rng);
        let state = RunState {
            env_id: task.id().to_owned(),
            obs_dim,
            act_dim,
            epoch: 0,
            level: 0,
            env_steps: 0,
            updates: 0,
            episodes_per_worker: 0,
            wall_seconds: 0.0,
            best_finals: -1.0,
        };
        (agent, ReplayBuffer::new(obs_dim, act_dim, config.buffer_size), state, Vec::new())
    };
    if agent.algo() != config.algo {
        bail!("{} holds a {:?} agent, not {:?}", run.checkpoint().display(), agent.algo(), config.algo);
    }
    let seen = crate::agents::expert::obs_dim_without_grey(&envs[0].config().blocks());
    let expert = Expert::load(&config.aggrevated, seen, &run.expert_policy(), resume)?;
    let mut learner = Learner { agent, expert };
    write_json_atomic(&run.config(), config)?;

    let mut persist_seconds = 0.0;
    while state.epoch < config.epochs {
        let epoch = state.epoch;
        let started = Instant::now();
        let cpu_started = cpu_seconds();
        for env in &mut envs {
            env.set_level(state.level.min(max_level))?;
        }
        let (mut env_seconds, mut update_seconds, mut forward_seconds) = (0.0, 0.0, 0.0);
        let (mut train_eps, mut train_wins, mut train_steps, mut expert_steps) = (0usize, 0usize, 0usize, 0usize);
        let mut stats = Vec::new();
        for cycle in 0..config.cycles {
            // Collect.
            let t = Instant::now();
            let policy = learner.agent.policy();
            let behaviour = learner.behaviour(&policy, epoch, config);
            let base = state.episodes_per_worker;
            let draw = Draw {
                level: state.level.min(max_level),
                max_level,
                level_replay: config.level_replay,
                challenge_share: config.challenge_share,
            };
            let draw = (draw.level_replay > 0.0 || draw.challenge_share > 0.0).then_some(draw);
            let eps = play_all(&mut envs, &behaviour, config.rollouts, draw.as_ref(), |w, k| {
                stream_seed(config.seed, &[1, w as u64, base + k as u64])
            })?;
            state.episodes_per_worker += config.rollouts as u64;
            env_seconds += t.elapsed().as_secs_f64();
            for ep in &eps {
                train_eps += 1;
                train_wins += ep.success as usize;
                train_steps += ep.len();
                expert_steps += ep.expert_steps;
                state.env_steps += ep.len() as u64;
                forward_seconds += ep.forward_seconds / config.workers as f64;
                ep.store(&mut replay, learner.agent.norm_mut(), config.ddpg.gamma, config.ddpg.n_step);
            }
            // Learn.
            let t = Instant::now();
            let mut rng = ChaCha8Rng::seed_from_u64(stream_seed(config.seed, &[2, epoch as u64, cycle as u64]));
            for _ in 0..config.batches {
                let batch = replay.sample(config.batch_size * config.workers, &mut rng);
                stats.push(learner.update(&batch, obs_dim));
                state.updates += 1;
            }
            learner.end_cycle();
            update_seconds += t.elapsed().as_secs_f64();
        }

        // Test at the current level, finals at the maximum level, both with
        // the deterministic policy.
        let t = Instant::now();
        let policy = learner.agent.policy();
        let greedy = Behaviour::Greedy(&policy);
        for env in &mut envs {
            env.set_level(state.level.min(max_level))?;
            env.set_distribution(None)?;
        }
        let test = play_all(&mut envs, &greedy, config.test_episodes, None, |w, k| {
            stream_seed(config.seed, &[3, epoch as u64, w as u64, k as u64])
        })?;
        for env in &mut envs {
            env.set_level(max_level)?;
        }
        let finals = play_all(&mut envs, &greedy, config.test_episodes, None, |w, k| {
            stream_seed(config.seed, &[4, epoch as u64, w as u64, k as u64])
        })?;
        env_seconds += t.elapsed().as_secs_f64();
        forward_seconds += test.iter().chain(&finals).map(|e| e.forward_seconds).sum::<f64>() / config.workers as f64;

        // The mean over the epoch's updates; the actor's over the updates that stepped it (TD3 skips some).
        let mean = |f: fn(&UpdateStats) -> f64| {
            let v: Vec<f64> = stats.iter().map(f).filter(|x| !x.is_nan()).collect();
            if v.is_empty() {
                0.0
            } else {
                v.iter().sum::<f64>() / v.len() as f64
            }
        };
        let eval_seconds = t.elapsed().as_secs_f64();
        let epoch_wall = started.elapsed().as_secs_f64();
        state.wall_seconds += epoch_wall;
        let cores = std::thread::available_parallelism().map_or(1, |n| n.get()) as f64;
        let row = EpochRow {
            epoch,
            level: state.level,
            train_success: if train_eps == 0 { 0.0 } else { train_wins as f64 / train_eps as f64 },
            test_success: success_rate(&test),
            finals_success: success_rate(&finals),
            mean_q: mean(|s| s.mean_q),
            critic_loss: mean(|s| s.critic_loss),
            actor_loss: mean(|s| s.actor_loss),
            env_steps: state.env_steps,
            updates: state.updates,
            wall_seconds: state.wall_seconds,
            env_seconds,
            forward_seconds,
            update_seconds,
            eval_seconds,
            persist_seconds,
            beta: learner.beta(epoch, config).unwrap_or(0.0),
            expert_share: if train_steps == 0 { 0.0 } else { expert_steps as f64 / train_steps as f64 },
            cpu_utilisation: (cpu_seconds() - cpu_started) / (epoch_wall * cores).max(1e-9),
        };
        if row.test_success >= threshold && state.level < max_level {
            state.level += 1;
        }
        state.epoch += 1;

        // Persist: progress, policies, then the checkpoint (last, so that a
        // crash before it repeats at most this epoch).
        let persist_started = Instant::now();
        rows.push(row.clone());
        write_progress(&run.progress(), &rows)?;
        plot::success_curves(&run.plot(), &config.title(), &rows, max_level)?;
        let saved = SavedPolicy {
            env_id: task.id().to_owned(),
            task: Some(task.source.clone()),
            epoch: state.epoch,
            env_steps: Some(state.env_steps),
            finals_success: row.finals_success,
            policy,
            critic: learner.agent.critic(),
        };
        write_json_atomic(&run.policy(), &saved)?;
        if config.snapshot_every > 0 && state.epoch % config.snapshot_every == 0 {
            let path = run.snapshot(state.epoch);
            std::fs::create_dir_all(run.snapshots())
                .with_context(|| format!("cannot create {}", run.snapshots().display()))?;
            write_json_atomic(&path, &saved)?;
        }
        // Ties go to the newer policy: same finals score, more training.
        if row.finals_success >= state.best_finals {
            state.best_finals = row.finals_success;
            write_json_atomic(&run.best_policy(), &saved)?;
        }
        checkpoint::save(&run.checkpoint(), &state, &learner.agent, &config.ddpg, &replay)?;
        // Counted from the next epoch's wall time on (the checkpoint already holds this epoch's).
        persist_seconds = persist_started.elapsed().as_secs_f64();
        state.wall_seconds += persist_seconds;
        on_epoch(&row, config);
    }
    Ok(rows)
}

impl TrainConfig {
    /// The method as (display name, short name): DDPG, PGGD, or PGGD + AggreVaTeD.
    fn method(&self) -> (&'static str, &'static str) {
        match (self.algo, &self.aggrevated.expert) {
            (Algo::Ddpg, _) => ("DDPG", "ddpg"),
            (Algo::Pggd, None) => ("PGGD", "pggd"),
            (Algo::Pggd, Some(_)) => match self.aggrevated.pg_weight {
                PgWeight::Return => ("PGGD + AggreVaTeD", "pggd-aggrevated"),
                PgWeight::ExpertAdvantage => ("PGGD + AggreVaTeD (expert advantage)", "pggd-aggrevated-adv"),
            },
        }
    }

    /// The task's id: the recorded one, else `--env` (a task file's stem when it is a path).
    pub fn task_id(&self) -> String {
        match &self.task {
            Some(t) => t.id.clone(),
            None if registry::is_path(&self.env) => {
                Path::new(&self.env).file_stem().map_or(self.env.clone(), |s| s.to_string_lossy().into_owned())
            }
            None => self.env.clone(),
        }
    }

    /// This project's options in use beyond the paper's DDPG, e.g. "TD3, 3-step, bf16" (empty: none).
    pub fn options(&self) -> String {
        let d = &self.ddpg;
        let mut v = Vec::new();
        if d.td3 {
            v.push("TD3".to_owned());
        }
        if d.n_step > 1 {
            v.push(format!("{}-step", d.n_step));
        }
        if self.level_replay > 0.0 {
            v.push(format!("level replay {}", self.level_replay));
        }
        if self.challenge_share > 0.0 {
            v.push(format!("challenge share {}", self.challenge_share));
        }
        if d.precision == Precision::Bf16 {
            v.push("bf16".to_owned());
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
        format!("runs/{}-{}-s{}", self.task_id(), self.method().1, self.seed).into()
    }
}

/// The settings that change what a run computes and differ between `a`
/// and `b`, by flag name: every field of the configuration (nested ones
/// included, so a new setting is compared without being listed here) but
/// those in [`RESUMABLE_CHANGES`].
fn computation_differences(a: &TrainConfig, b: &TrainConfig) -> Vec<String> {
    let mut out = Vec::new();
    differing_fields("", &a, &b, &mut out);
    out
}

/// Fields that may change on `--resume`: the epoch target, thread count and
/// snapshots, and the task and its id (checked by content in [`run_task`]).
const RESUMABLE_CHANGES: &[&str] = &["epochs", "torch_threads", "snapshot_every", "task", "env"];

/// The fields of two configurations that differ, as `--PREFIXfield-name`;
/// nested configurations are compared field by field (PGGD's flags carry `pg-`).
fn differing_fields<T: Serialize>(prefix: &str, a: &T, b: &T, out: &mut Vec<String>) {
    let (a, b) = (serde_json::to_value(a).unwrap_or_default(), serde_json::to_value(b).unwrap_or_default());
    let (serde_json::Value::Object(a), serde_json::Value::Object(b)) = (a, b) else { return };
    for (k, v) in &a {
        if RESUMABLE_CHANGES.contains(&k.as_str()) {
            continue;
        }
        match (v, b.get(k)) {
            (serde_json::Value::Object(_), Some(w @ serde_json::Value::Object(_))) => {
                differing_fields(if k == "pggd" { "pg-" } else { prefix }, v, w, out)
            }
            (v, w) if w == Some(v) => {}
            _ => out.push(format!("--{prefix}{}", k.replace('_', "-"))),
        }
    }
}

/// The task of a run: `--env` resolved; on resume, checked against `recorded`,
/// the copy in the run's `config.json` (a changed task is an error naming
/// what changed; a task file that no longer exists is replaced by the copy).
///
/// # Errors
/// An unknown id or bad task file, or a task that changed since the run started.
fn run_task(config: &TrainConfig, run: &RunDir, recorded: Option<&crate::task::TaskSource>) -> Result<Task> {
    let Some(source) = recorded else {
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
    if current.source.hash != source.hash {
        let copy = Task::parse(&source.toml, &format!("the copy in {}", run.config().display()), None)?;
        let changed = copy.differences(&current);
        bail!(
            "--resume: the task {} has changed since the run started ({} differ from the copy in {}); \
             restore the file, or start a new run with another --run-dir",
            config.env,
            if changed.is_empty() { "its contents".to_owned() } else { changed.join(", ") },
            run.config().display()
        );
    }
    Ok(current)
}
