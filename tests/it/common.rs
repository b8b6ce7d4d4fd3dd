#![allow(dead_code)]
//! Helpers shared by the integration tests.

use blockpuzzle::env::vector::{ResetOptions, VectorEnv};
use blockpuzzle::env::{BlockEnv, EnvConfig, EnvError, ACTION_DIM};
use blockpuzzle::policy::Policy;

/// One recorded step: (qpos, qvel, obs, reward, terminated, truncated).
pub type Frame = (Vec<f64>, Vec<f64>, Vec<f32>, f32, bool, bool);

/// Runs one episode; returns the reset frame and one frame per step.
pub fn trajectory(env: &mut BlockEnv, policy: &mut dyn Policy, seed: u64) -> Result<Vec<Frame>, EnvError> {
    let (mut obs, _) = env.reset(Some(seed))?;
    policy.reset();
    let mut out = vec![(env.data().qpos().to_vec(), env.data().qvel().to_vec(), obs.clone(), 0.0, false, false)];
    loop {
        let s = env.step(&policy.act(&obs))?;
        out.push((
            env.data().qpos().to_vec(),
            env.data().qvel().to_vec(),
            s.obs.clone(),
            s.reward,
            s.terminated,
            s.truncated,
        ));
        obs = s.obs;
        if s.terminated || s.truncated {
            return Ok(out);
        }
    }
}

/// Actions for `n` environments at step `t`: each depends on its environment's index and the step only.
pub fn vector_actions(n: usize, t: usize) -> Vec<f32> {
    (0..n * ACTION_DIM)
        .map(|k| (((k / ACTION_DIM) * 7919 + t * 104_729 + k % ACTION_DIM * 31) % 200) as f32 / 100.0 - 1.0)
        .collect()
}

/// Environment `index`'s observations, rewards and flags over `steps` steps of a vector engine
/// of `n` environments of `config` on `threads` threads, environment i reset with `first_seed + i`.
pub fn vector_trajectory(
    config: &EnvConfig,
    (n, threads): (usize, usize),
    index: usize,
    steps: usize,
    first_seed: u64,
) -> Vec<f32> {
    let mut v = VectorEnv::new(config, n, threads).unwrap();
    let d = v.obs_spec().dim();
    let mut obs = vec![0.0; n * d];
    let seeds: Vec<Option<u64>> = (0..n).map(|i| Some(first_seed + i as u64)).collect();
    v.reset(&seeds, None, &ResetOptions::default(), &mut obs).unwrap();
    let mut out = obs[index * d..(index + 1) * d].to_vec();
    for t in 0..steps {
        let r = v.step(&vector_actions(n, t), &mut obs).unwrap()[index].clone();
        out.extend_from_slice(&obs[index * d..(index + 1) * d]);
        out.extend([r.reward, r.terminated as u8 as f32, r.truncated as u8 as f32, r.autoreset as u8 as f32]);
    }
    out
}

/// Says that the running test skips `what` and why, where a run shows it: straight to the process's
/// standard error, past the test harness's capture (which keeps `eprintln!` of a passing test out of
/// sight), so a green run lists what it did not check.
pub fn skipped(what: &str) {
    use std::io::Write;
    let test = std::thread::current().name().unwrap_or("a test").to_owned();
    let _ = writeln!(std::io::stderr().lock(), "SKIPPED in {test}: {what}");
}

/// This build's `blockpuzzle`.
#[cfg(feature = "cli")]
pub const CLI: &str = env!("CARGO_BIN_EXE_blockpuzzle");

/// A `blockpuzzle` command with `args` (from the subcommand on): how every test starts the command line.
#[cfg(feature = "cli")]
pub fn blockpuzzle<S: AsRef<std::ffi::OsStr>>(args: &[S]) -> std::process::Command {
    let mut c = std::process::Command::new(CLI);
    c.args(args);
    c
}
