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
    seconds: f64,
    physics_seconds: f64,
    substeps: usize,
}

fn one_thread(id: &str, steps: usize, seed: u64, collision_filter: bool) -> Result<ThreadResult, EnvError> {
    let mut config = registry::config(id)?;
    config.collision_filter = collision_filter;
    let mut env = BlockEnv::new(config)?;
    let mut policy = RandomPolicy::new(seed);
    let mut obs = env.reset(Some(seed))?.0;
    // Warm-up outside the timing.
    for _ in 0..100 {
        let s = env.step(&policy.act(&obs))?;
        obs = if s.terminated || s.truncated { env.reset(None)?.0 } else { s.obs };
    }
    let physics0 = env.physics_seconds();
    let t = Instant::now();
    for _ in 0..steps {
        let s = env.step(&policy.act(&obs))?;
        obs = if s.terminated || s.truncated { env.reset(None)?.0 } else { s.obs };
    }
    Ok(ThreadResult {
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
    let threads = threads.max(1);
    let t = Instant::now();
    let results: Vec<Result<ThreadResult, EnvError>> = std::thread::scope(|s| {
        let handles: Vec<_> =
            (0..threads).map(|k| s.spawn(move || one_thread(id, steps, k as u64, collision_filter))).collect();
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
    Ok(BenchReport {
        env: id.to_owned(),
        threads,
        steps,
        seconds,
        collision_filter,
        env_steps_per_s: (steps * threads) as f64 / seconds,
        mj_steps_per_s: substeps as f64 / total_phys * threads as f64,
        overhead_fraction: 1.0 - total_phys / total_env,
    })
}
