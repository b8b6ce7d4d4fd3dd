#![allow(dead_code)]
//! Helpers shared by the integration tests.

use blockpuzzle::env::{BlockEnv, EnvConfig, EnvError, ResetOptions, VectorEnv, ACTION_DIM};
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

/// The variable naming the command line built without the `train` feature, which `make test`
/// builds: the core's commands run on it, started without loading libtorch (about 0.15 s of CPU
/// here against 0.9 s, most of it libtorch's start-up, for each of the few hundred commands the
/// tests run). Unset, every command runs on this build's `blockpuzzle`.
pub const CORE_CLI_VAR: &str = "BLOCKPUZZLE_CORE_CLI";

/// This build's `blockpuzzle`, which has every command.
#[cfg(feature = "cli")]
pub const FULL_CLI: &str = env!("CARGO_BIN_EXE_blockpuzzle");

/// The program that runs the command line `args` (from the subcommand on): the command line without
/// the training stack where [`CORE_CLI_VAR`] names one and `args` is not a training command, this
/// build's otherwise. Tests of what only the training build prints (`info`'s libtorch settings) use
/// [`FULL_CLI`].
#[cfg(feature = "cli")]
pub fn cli_for<S: AsRef<std::ffi::OsStr>>(args: &[S]) -> std::path::PathBuf {
    let mut line = vec![std::ffi::OsString::from("blockpuzzle")];
    line.extend(args.iter().map(|a| a.as_ref().to_owned()));
    let training = blockpuzzle::cli::training_command(&line).is_some();
    match std::env::var_os(CORE_CLI_VAR) {
        Some(core) if !training => core.into(),
        _ => FULL_CLI.into(),
    }
}

/// A `blockpuzzle` command with `args`, on the program [`cli_for`] picks.
#[cfg(feature = "cli")]
pub fn blockpuzzle<S: AsRef<std::ffi::OsStr>>(args: &[S]) -> std::process::Command {
    let mut c = std::process::Command::new(cli_for(args));
    c.args(args);
    c
}
