//! DDPG training with the paper's curriculum, readable top to bottom.
//!
//! An epoch is `cycles` cycles; in a cycle every worker (one environment
//! each, stepped in its own thread) collects `rollouts` exploration episodes,
//! then the learner takes `batches` gradient steps on batches of
//! `batch_size × workers` transitions (the average of the workers' gradients,
//! as baselines' MPI Adam computes it) and the target networks follow. After
//! the cycles every worker plays `test_episodes` deterministic episodes at
//! the current level ("test") and at the maximum level ("finals"); when the
//! test success reaches `success_threshold` the curriculum moves up a level.
//!
//! The run directory holds `config.json`, `progress.csv` (one row per epoch),
//! `checkpoint.bin` (everything, written atomically every epoch),
//! `policy.json` (latest actor + normaliser), `best_policy.json` (best
//! finals success) and `success.png` (the success curves).

pub mod checkpoint;
pub mod plot;
mod rundir;

use rundir::write_progress;
pub use rundir::{load_policy, read_progress, write_json_atomic, RunDir, SavedPolicy};

use crate::agents::ddpg::{Ddpg, DdpgConfig, DdpgPolicy, UpdateStats};
use crate::agents::normalizer::Normalizer;
use crate::agents::replay::ReplayBuffer;
use crate::env::{registry, BlockEnv, EnvError};
use anyhow::{bail, Context, Result};
use checkpoint::RunState;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};
use std::path::Path;
use std::time::Instant;

/// Training hyperparameters (defaults: the paper's DDPG set-up).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, clap::Args)]
pub struct TrainConfig {
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
    /// Test success rate that moves the curriculum up a level.
    #[arg(long, default_value_t = 0.7)]
    pub success_threshold: f64,
    /// Seed of everything (weights, layouts, exploration, batches).
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Threads libtorch may use for updates (0: all cores).
    #[arg(long, default_value_t = 0)]
    pub torch_threads: usize,
    /// DDPG hyperparameters.
    #[command(flatten)]
    pub ddpg: DdpgConfig,
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

/// A finished episode's transitions and outcome.
pub(crate) struct Episode {
    pub(crate) obs: Vec<Vec<f32>>,
    pub(crate) act: Vec<Vec<f32>>,
    pub(crate) rew: Vec<f32>,
    pub(crate) terminated: bool,
    pub(crate) success: bool,
    /// Seconds spent in the policy (actor forward pass and noise).
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

/// Plays one episode with `policy` (exploring when `explore` is Some((random_eps, noise_eps))).
fn play(env: &mut BlockEnv, policy: &DdpgPolicy, seed: u64, explore: Option<(f64, f64)>) -> Result<Episode, EnvError> {
    // The layout comes from `seed`; the exploration noise from a stream derived from it.
    let mut rng = ChaCha8Rng::seed_from_u64(stream_seed(seed, &[5]));
    let (mut obs, _) = env.reset(Some(seed))?;
    let mut ep =
        Episode { obs: vec![], act: vec![], rew: vec![], terminated: false, success: false, forward_seconds: 0.0 };
    loop {
        let t = Instant::now();
        let act = match explore {
            Some((r, n)) => policy.explore(&obs, r, n, &mut rng),
            None => policy.act(&obs),
        };
        ep.forward_seconds += t.elapsed().as_secs_f64();
        let s = env.step(&act)?;
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
    policy: &DdpgPolicy,
    per_worker: usize,
    seed_of: impl Fn(usize, usize) -> u64 + Sync,
    explore: Option<(f64, f64)>,
) -> Result<Vec<Episode>> {
    let results: Vec<Result<Vec<Episode>, EnvError>> = std::thread::scope(|s| {
        let handles: Vec<_> = envs
            .iter_mut()
            .enumerate()
            .map(|(w, env)| {
                let seed_of = &seed_of;
                s.spawn(move || (0..per_worker).map(|k| play(env, policy, seed_of(w, k), explore)).collect())
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

fn success_rate(eps: &[Episode]) -> f64 {
    if eps.is_empty() {
        return 0.0;
    }
    eps.iter().filter(|e| e.success).count() as f64 / eps.len() as f64
}

/// Per-epoch callback for progress reporting.
pub type OnEpoch<'a> = &'a mut dyn FnMut(&EpochRow, &TrainConfig);

/// Trains DDPG; with `resume`, continues from the run directory's checkpoint.
///
/// # Errors
/// Bad configuration, environment errors, I/O and checkpoint errors.
pub fn train(config: &TrainConfig, run_dir: &Path, resume: bool, on_epoch: OnEpoch) -> Result<Vec<EpochRow>> {
    if config.workers == 0 || config.cycles == 0 || config.batch_size == 0 || config.test_episodes == 0 {
        bail!("--workers, --cycles, --batch-size and --test-episodes must be at least 1");
    }
    if !(0.0..1.0).contains(&config.ddpg.gamma) {
        bail!("--gamma must be in [0, 1)");
    }
    let run = RunDir { dir: run_dir.to_owned() };
    std::fs::create_dir_all(&run.dir).with_context(|| format!("cannot create run directory {}", run.dir.display()))?;
    tch::set_num_threads(if config.torch_threads == 0 {
        std::thread::available_parallelism().map_or(1, |n| n.get()) as i32
    } else {
        config.torch_threads as i32
    });

    // Environments: one per worker.
    let mut envs: Vec<BlockEnv> = (0..config.workers).map(|_| registry::make(&config.env)).collect::<Result<_, _>>()?;
    let (obs_dim, act_dim) = (envs[0].observation_space().dim(), envs[0].action_space().dim());
    let max_level = envs[0].max_level();

    // Learner, replay buffer, run state: fresh or from the checkpoint.
    let (mut agent, mut replay, mut state, mut rows) = if resume && run.checkpoint().exists() {
        let saved: TrainConfig = serde_json::from_str(&std::fs::read_to_string(run.config())?)
            .with_context(|| format!("{} is not a training config", run.config().display()))?;
        if saved.env != config.env || saved.ddpg != config.ddpg || saved.workers != config.workers {
            bail!(
                "--resume with different settings than {} (env, workers or DDPG hyperparameters differ)",
                run.config().display()
            );
        }
        let loaded = checkpoint::load(&run.checkpoint(), &config.env, obs_dim, act_dim)?;
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
        let agent = Ddpg::new(obs_dim, act_dim, config.ddpg.clone(), &mut rng);
        let state = RunState {
            env_id: config.env.clone(),
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
    write_json_atomic(&run.config(), config)?;

    let explore = Some((config.ddpg.random_eps, config.ddpg.noise_eps));
    while state.epoch < config.epochs {
        let epoch = state.epoch;
        let started = Instant::now();
        let cpu_started = cpu_seconds();
        for env in &mut envs {
            env.set_level(state.level.min(max_level))?;
        }
        let (mut env_seconds, mut update_seconds, mut forward_seconds) = (0.0, 0.0, 0.0);
        let (mut train_eps, mut train_wins) = (0usize, 0usize);
        let mut stats = Vec::new();
        for cycle in 0..config.cycles {
            // Collect.
            let t = Instant::now();
            let policy = agent.policy();
            let base = state.episodes_per_worker;
            let eps = play_all(
                &mut envs,
                &policy,
                config.rollouts,
                |w, k| stream_seed(config.seed, &[1, w as u64, base + k as u64]),
                explore,
            )?;
            state.episodes_per_worker += config.rollouts as u64;
            env_seconds += t.elapsed().as_secs_f64();
            for ep in &eps {
                train_eps += 1;
                train_wins += ep.success as usize;
                state.env_steps += ep.len() as u64;
                forward_seconds += ep.forward_seconds / config.workers as f64;
                ep.store(&mut replay, &mut agent.norm, config.ddpg.gamma);
            }
            // Learn.
            let t = Instant::now();
            let mut rng = ChaCha8Rng::seed_from_u64(stream_seed(config.seed, &[2, epoch as u64, cycle as u64]));
            for _ in 0..config.batches {
                let batch = replay.sample(config.batch_size * config.workers, &mut rng);
                stats.push(agent.update(&batch));
                state.updates += 1;
            }
            agent.update_targets();
            update_seconds += t.elapsed().as_secs_f64();
        }

        // Test at the current level, finals at the maximum level.
        let t = Instant::now();
        let policy = agent.policy();
        let test = play_all(
            &mut envs,
            &policy,
            config.test_episodes,
            |w, k| stream_seed(config.seed, &[3, epoch as u64, w as u64, k as u64]),
            None,
        )?;
        for env in &mut envs {
            env.set_level(max_level)?;
        }
        let finals = play_all(
            &mut envs,
            &policy,
            config.test_episodes,
            |w, k| stream_seed(config.seed, &[4, epoch as u64, w as u64, k as u64]),
            None,
        )?;
        env_seconds += t.elapsed().as_secs_f64();
        forward_seconds += test.iter().chain(&finals).map(|e| e.forward_seconds).sum::<f64>() / config.workers as f64;

        let mean = |f: fn(&UpdateStats) -> f64| {
            if stats.is_empty() {
                0.0
            } else {
                stats.iter().map(f).sum::<f64>() / stats.len() as f64
            }
        };
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
            cpu_utilisation: (cpu_seconds() - cpu_started) / (epoch_wall * cores).max(1e-9),
        };
        if row.test_success >= config.success_threshold && state.level < max_level {
            state.level += 1;
        }
        state.epoch += 1;

        // Persist: progress, policies, then the checkpoint (last, so that a
        // crash before it repeats at most this epoch).
        rows.push(row.clone());
        write_progress(&run.progress(), &rows)?;
        plot::success_curves(&run.plot(), &format!("DDPG on {}", config.env), &rows, max_level)?;
        let saved =
            SavedPolicy { env_id: config.env.clone(), epoch: state.epoch, finals_success: row.finals_success, policy };
        write_json_atomic(&run.policy(), &saved)?;
        if row.finals_success > state.best_finals {
            state.best_finals = row.finals_success;
            write_json_atomic(&run.best_policy(), &saved)?;
        }
        checkpoint::save(&run.checkpoint(), &state, &agent, &replay)?;
        on_epoch(&row, config);
    }
    Ok(rows)
}
