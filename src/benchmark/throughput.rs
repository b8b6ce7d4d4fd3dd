//! Throughput measurement: environment steps per second, MuJoCo `mj_step`
//! calls per second on the same trajectories, and the environment's overhead
//! (the share of a step spent outside `mj_step`). Training's collection and
//! update rates, for any algorithm, are `learn::bench` (libtorch).

use crate::env::vector::VectorEnv;
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
    /// Wall-clock seconds of the timed stepping: from the moment every
    /// environment is built and warmed up to the last one's last step, the
    /// way `bench/fetchpush_steps.py` times FetchPush-v4's processes.
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

/// Makes an environment.
type MakeEnv<'a> = &'a (dyn Fn() -> Result<BlockEnv, EnvError> + Sync);
/// Starts an episode (the environment and an episode seed) and returns its first observation.
pub type StartEpisode<'a> = &'a (dyn Fn(&mut BlockEnv, Option<u64>) -> Result<Vec<f32>, EnvError> + Sync);

/// Steps `env` `n` times with random actions from `obs`, starting a new
/// episode with `start` whenever one ends; returns the last observation. The one stepping loop of
/// the throughput benchmarks (`blockpuzzle bench`, `align`, Python's `Env.bench_steps`).
///
/// # Errors
/// [`EnvError`] if a step or a new episode fails.
pub fn random_steps(
    env: &mut BlockEnv,
    start: StartEpisode,
    policy: &mut RandomPolicy,
    mut obs: Vec<f32>,
    n: usize,
) -> Result<Vec<f32>, EnvError> {
    for _ in 0..n {
        let s = env.step(&policy.act(&obs))?;
        obs = if s.terminated || s.truncated { start(env, None)? } else { s.obs };
    }
    Ok(obs)
}

/// One environment's timed stretch.
struct Timed {
    started: Instant,
    ended: Instant,
    physics_seconds: f64,
}

/// Steps `threads` independent environments of `id` in parallel, `steps`
/// random-action steps each (resets included in the timing; building the
/// environment and a 100-step warm-up are not), with or without the robot
/// collision filter.
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
    for (bound, v) in [(crate::support::limits::BENCH_STEPS, steps), (crate::support::limits::THREADS, threads)] {
        bound
            .check_usize(v)
            .map_err(|e| EnvError::Config(format!("{e} (for `align`: --bench-steps and --threads)")))?;
    }
    // Built outside the timing (a panic while building is an error, not an abort).
    let envs = (0..threads)
        .map(|_| {
            std::panic::catch_unwind(std::panic::AssertUnwindSafe(make))
                .unwrap_or_else(|_| Err(EnvError::Config("a benchmark environment panicked while building".into())))
        })
        .collect::<Result<Vec<_>, _>>()?;
    let mut vec = VectorEnv::from_envs(envs, threads)?;
    // A 100-step warm-up each, untimed; then `steps` timed steps each, every environment in its thread.
    let warm = vec.each(|k, env| -> Result<(RandomPolicy, Vec<f32>), EnvError> {
        let mut policy = RandomPolicy::new(k as u64);
        let obs = start(env, Some(k as u64))?;
        let obs = random_steps(env, start, &mut policy, obs, 100)?;
        Ok((policy, obs))
    });
    let mut states = warm.into_iter().collect::<Result<Vec<_>, _>>()?;
    let results = vec.each_with(&mut states, |_, env, (policy, obs)| -> Result<Timed, EnvError> {
        let physics0 = env.physics_seconds();
        let started = Instant::now();
        random_steps(env, start, policy, std::mem::take(obs), steps)?;
        Ok(Timed { started, ended: Instant::now(), physics_seconds: env.physics_seconds() - physics0 })
    });
    let results = results.into_iter().collect::<Result<Vec<_>, _>>()?;
    // From the first environment's start (all start within microseconds) to the last finisher.
    let first = results.iter().map(|r| r.started).min();
    let last = results.iter().map(|r| r.ended).max();
    let seconds = match (first, last) {
        (Some(first), Some(last)) => (last - first).as_secs_f64(),
        _ => 0.0,
    };
    let total_env: f64 = results.iter().map(|r| (r.ended - r.started).as_secs_f64()).sum();
    let total_phys: f64 = results.iter().map(|r| r.physics_seconds).sum();
    let config = vec.envs()[0].config();
    let substeps = steps * threads * config.n_substeps;
    let collision_filter = config.collision_filter;
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

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::atomic::{AtomicUsize, Ordering};
    use std::time::Duration;

    fn gripper_touch() -> Result<BlockEnv, EnvError> {
        BlockEnv::new(registry::config("GripperTouch-v0")?)
    }

    fn reset(env: &mut BlockEnv, seed: Option<u64>) -> Result<Vec<f32>, EnvError> {
        Ok(env.reset(seed)?.0)
    }

    #[test]
    fn building_the_environments_is_not_timed() {
        // A second of set-up per environment against two steps: the timed span must leave it out
        // (as FetchPush-v4's side never counts it).
        let slow = || {
            std::thread::sleep(Duration::from_secs(1));
            gripper_touch()
        };
        let r = run_with("GripperTouch-v0", &slow, &reset, 2, 2).unwrap();
        assert!(r.seconds < 1.0, "set-up counted: {r:?}");
        assert!(r.env_steps_per_s > 4.0, "{r:?}");
    }

    #[test]
    fn an_environment_that_cannot_be_built_fails_the_run_without_a_hang() {
        let built = AtomicUsize::new(0);
        let second_fails = || {
            if built.fetch_add(1, Ordering::SeqCst) == 1 {
                Err(EnvError::Config("no second environment".into()))
            } else {
                gripper_touch()
            }
        };
        let e = run_with("GripperTouch-v0", &second_fails, &reset, 5, 3).unwrap_err();
        assert!(e.to_string().contains("no second environment"), "{e}");
    }

    #[test]
    fn an_environment_that_panics_while_building_fails_the_run_without_a_hang() {
        let built = AtomicUsize::new(0);
        let second_panics = || {
            assert!(built.fetch_add(1, Ordering::SeqCst) != 1, "deliberate panic in the second set-up");
            gripper_touch()
        };
        let e = run_with("GripperTouch-v0", &second_panics, &reset, 5, 2).unwrap_err();
        assert!(e.to_string().contains("panicked while building"), "{e}");
    }
}
