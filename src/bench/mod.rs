//! Throughput measurement: environment steps per second, MuJoCo `mj_step`
//! calls per second on the same trajectories, and the environment's overhead
//! (the share of a step spent outside `mj_step`); DDPG collection and
//! update rates in [`ddpg`].

pub mod ddpg;

use crate::env::{registry, BlockEnv, EnvError};
use crate::policy::{Policy, RandomPolicy};
use serde::Serialize;
use std::time::Instant;

/// Result of a benchmark run.
#[derive(Debug, Clone, Serialize)]
pub struct BenchReport {
    /// Environment id.
    pub env: String,
    /// Threads, each stepping its own environment.
    pub threads: usize,
    /// Steps per thread.
    pub steps: usize,
    /// Wall-clock seconds of the whole run.
    pub seconds: f64,
    /// Whether the robot collision filter was on.
    pub collision_filter: bool,
    /// Aggregate environment steps per second (all threads).
    pub env_steps_per_s: f64,
    /// Aggregate `mj_step` calls per second, counting only time inside `mj_step`.
    pub mj_steps_per_s: f64,
    /// Share of environment-step time spent outside `mj_step` (contact scans,
    /// action, observation, the end-of-step forward pass).
    pub overhead_fraction: f64,
}

struct ThreadResult {
    collision_filter: bool,
    seconds: f64,
    physics_seconds: f64,
    substeps: usize,
}

/// Makes a thread's environment.
type MakeEnv<'a> = &'a (dyn Fn() -> Result<BlockEnv, EnvError> + Sync);
/// Starts an episode (the environment and an episode seed) and returns its first observation.
type StartEpisode<'a> = &'a (dyn Fn(&mut BlockEnv, Option<u64>) -> Result<Vec<f32>, EnvError> + Sync);

fn one_thread(make: MakeEnv, start: StartEpisode, steps: usize, seed: u64) -> Result<ThreadResult, EnvError> {
    let mut env = make()?;
    let mut policy = RandomPolicy::new(seed);
    let mut obs = start(&mut env, Some(seed))?;
    // Warm-up outside the timing.
    for _ in 0..100 {
        let s = env.step(&policy.act(&obs))?;
        obs = if s.terminated || s.truncated { start(&mut env, None)? } else { s.obs };
    }
    let physics0 = env.physics_seconds();
    let t = Instant::now();
    for _ in 0..steps {
        let s = env.step(&policy.act(&obs))?;
        obs = if s.terminated || s.truncated { start(&mut env, None)? } else { s.obs };
    }
    Ok(ThreadResult {
        collision_filter: env.config().collision_filter,
        seconds: t.elapsed().as_secs_f64(),
        physics_seconds: env.physics_seconds() - physics0,
        substeps: steps * env.config().n_substeps,
    })
}

/// Steps `threads` independent environments of `id` in parallel, `steps`
/// random-action steps each (resets included in the timing), with or
/// without the robot collision filter.
///
/// # Errors
/// [`EnvError`] if an environment cannot be built or stepped.
pub fn run(id: &str, steps: usize, threads: usize, collision_filter: bool) -> Result<BenchReport, EnvError> {
    let make = || {
        let mut config = registry::config(id)?;
        config.collision_filter = collision_filter;
        BlockEnv::new(config)
    };
    let start = |env: &mut BlockEnv, seed: Option<u64>| Ok(env.reset(seed)?.0);
    run_with(id, &make, &start, steps, threads)
}

/// [`run`] over any environment: `make` builds each thread's, `start`
/// begins each episode (a reset, or a state set with `BlockEnv::set_state`).
///
/// # Errors
/// No steps or no threads, or [`EnvError`] if an environment cannot be
/// built, started or stepped.
pub fn run_with(
    label: &str,
    make: MakeEnv,
    start: StartEpisode,
    steps: usize,
    threads: usize,
) -> Result<BenchReport, EnvError> {
    if steps == 0 || threads == 0 {
        return Err(EnvError::Config(
            "--steps and --threads must be at least 1 (for `align`: --bench-steps and --threads)".into(),
        ));
    }
    let t = Instant::now();
    let results: Vec<Result<ThreadResult, EnvError>> = std::thread::scope(|s| {
        let handles: Vec<_> = (0..threads).map(|k| s.spawn(move || one_thread(make, start, steps, k as u64))).collect();
        handles
            .into_iter()
            .map(|h| h.join().unwrap_or_else(|_| Err(EnvError::Config("benchmark thread panicked".into()))))
            .collect()
    });
    let results = results.into_iter().collect::<Result<Vec<_>, _>>()?;
    let seconds = t.elapsed().as_secs_f64();
    let total_env: f64 = results.iter().map(|r| r.seconds).sum();
    let total_phys: f64 = results.iter().map(|r| r.physics_seconds).sum();
    let substeps: usize = results.iter().map(|r| r.substeps).sum();
    let collision_filter = results.first().is_some_and(|r| r.collision_filter);
    Ok(BenchReport {
        env: label.to_owned(),
        threads,
        steps,
        seconds,
        collision_filter,
        env_steps_per_s: (steps * threads) as f64 / seconds,
        mj_steps_per_s: substeps as f64 / total_phys * threads as f64,
        overhead_fraction: 1.0 - total_phys / total_env,
    })
}
