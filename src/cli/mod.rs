//! The `blockpuzzle` command line.

use anyhow::{bail, Context, Result};
use clap::{Parser, Subcommand, ValueEnum};
use std::path::PathBuf;

use crate::env::{registry, BlockEnv};
use crate::policy::{Policy, RandomPolicy, ScriptedPolicy};
use crate::rollout::{run_episode, DumpWriter};

/// BlockPuzzle: coloured-block puzzles for the Fetch robot in MuJoCo.
#[derive(Debug, Parser)]
#[command(name = "blockpuzzle", version, about)]
pub struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// List the registered environment ids.
    Envs,
    /// Roll out a policy and write a trajectory dump (JSON Lines, one episode per line).
    Rollout(RolloutArgs),
    /// Measure environment steps/s and raw mj_step/s.
    Bench(BenchArgs),
    /// Print the generated MuJoCo XML of an environment's scene (save it in
    /// models/ to load it in other MuJoCo tools).
    Scene {
        /// Environment id.
        #[arg(long)]
        env: String,
    },
}

#[derive(Debug, Clone, Copy, ValueEnum)]
enum PolicyKind {
    /// Uniform random actions.
    Random,
    /// The hand-written pushing controller.
    Scripted,
}

#[derive(Debug, clap::Args)]
struct RolloutArgs {
    /// Environment id (see `blockpuzzle envs`).
    #[arg(long)]
    env: String,
    /// Which policy acts.
    #[arg(long, value_enum, default_value = "scripted")]
    policy: PolicyKind,
    /// Number of episodes.
    #[arg(long, default_value_t = 10)]
    episodes: usize,
    /// Seed of the first episode (episode k uses seed + k).
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Curriculum level (default: the maximum, i.e. the evaluation distribution).
    #[arg(long, conflicts_with = "challenge")]
    level: Option<usize>,
    /// Use the challenge distribution (BlocksChoose-v0 only).
    #[arg(long)]
    challenge: bool,
    /// Output file (JSON Lines); written atomically.
    #[arg(long)]
    out: PathBuf,
}

#[derive(Debug, clap::Args)]
struct BenchArgs {
    /// Environment id.
    #[arg(long, default_value = "BlocksTouch-v0")]
    env: String,
    /// Steps per thread.
    #[arg(long, default_value_t = 20_000)]
    steps: usize,
    /// Threads, each stepping its own environment.
    #[arg(long, default_value_t = 1)]
    threads: usize,
    /// Print one JSON line instead of text.
    #[arg(long)]
    json: bool,
    /// Turn the robot collision filter off (to measure what it saves).
    #[arg(long)]
    no_collision_filter: bool,
}

/// Runs the command line.
///
/// # Errors
/// Any failure, with a message that names the problem.
pub fn main() -> Result<()> {
    let cli = Cli::parse();
    match cli.command {
        Command::Envs => {
            for r in registry::REGISTRY {
                let env = registry::config(r.id)?;
                println!(
                    "{:<16} obs {:>2}  levels 0-{:<2}  {}",
                    r.id,
                    crate::env::obs_dim(env.blocks.len()),
                    env.layout.max_level(),
                    r.summary
                );
            }
            Ok(())
        }
        Command::Rollout(a) => rollout(a),
        Command::Scene { env } => {
            let c = registry::config(&env)?;
            let spec = crate::scene::SceneSpec {
                blocks: c.blocks,
                gripper: c.gripper,
                table: c.table,
                collision_filter: c.collision_filter,
            };
            print!("{}", crate::scene::mjcf(&spec)?);
            Ok(())
        }
        Command::Bench(a) => {
            let r = crate::bench::run(&a.env, a.steps, a.threads, !a.no_collision_filter)?;
            if a.json {
                println!("{}", serde_json::to_string(&r)?);
            } else {
                println!(
                    "{}{}: {} thread(s) x {} steps in {:.2} s\n  env steps/s   {:>10.0}\n  mj_step/s     {:>10.0}\n  env overhead  {:>9.2}% of a step",
                    r.env,
                    if r.collision_filter { "" } else { " (no collision filter)" },
                    r.threads,
                    r.steps, r.seconds, r.env_steps_per_s, r.mj_steps_per_s, 100.0 * r.overhead_fraction
                );
            }
            Ok(())
        }
    }
}

fn rollout(a: RolloutArgs) -> Result<()> {
    let mut env: BlockEnv = registry::make(&a.env)?;
    if a.challenge {
        env.set_challenge(true)?;
    }
    let level = a.level.unwrap_or(env.max_level());
    env.set_level(level)?;
    if a.episodes == 0 {
        bail!("--episodes must be at least 1");
    }
    let mut writer = DumpWriter::create(&a.out)?;
    let mut policy: Box<dyn Policy> = match a.policy {
        PolicyKind::Random => Box::new(RandomPolicy::new(a.seed)),
        PolicyKind::Scripted => Box::new(ScriptedPolicy::for_env(env.config())),
    };
    let (mut successes, mut failures, mut steps) = (0usize, 0usize, 0usize);
    for k in 0..a.episodes {
        let seed = a.seed.wrapping_add(k as u64);
        let ep = run_episode(&mut env, policy.as_mut(), seed).with_context(|| format!("episode {k} (seed {seed})"))?;
        successes += ep.success as usize;
        failures += ep.failure as usize;
        steps += ep.steps.len();
        writer.write(&ep)?;
    }
    writer.finish()?;
    let n = a.episodes as f64;
    println!(
        "{} {:?} policy, level {}{}: success {:.3} ({}/{}), failure {:.3}, mean length {:.1}; wrote {}",
        a.env,
        a.policy,
        level,
        if a.challenge { " (challenge)" } else { "" },
        successes as f64 / n,
        successes,
        a.episodes,
        failures as f64 / n,
        steps as f64 / n,
        a.out.display()
    );
    Ok(())
}
