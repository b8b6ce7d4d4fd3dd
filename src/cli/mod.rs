//! The `blockpuzzle` command line. With the `cli` feature alone, the commands that need no
//! libtorch (the Python package's `blockpuzzle`); with `train`, every command.

use anyhow::{bail, Context, Result};
use clap::{Parser, Subcommand};
use std::path::{Path, PathBuf};

use crate::env::{registry, BlockEnv};
use crate::outcome::{Outcome, Outcomes};
use crate::policy::{Policy, RandomPolicy, ScriptedPolicy};
use crate::rollout::{run_episode, DumpWriter};

#[cfg(feature = "train")]
mod experiment;
#[cfg(feature = "train")]
mod runs;
mod zoo;
#[cfg(feature = "train")]
pub use runs::train_config;
#[cfg(feature = "train")]
use runs::{PlotArgs, TrainArgs};
use zoo::ZooCommand;

/// BlockPuzzle: coloured-block puzzles for the Fetch robot in MuJoCo.
#[derive(Debug, Parser)]
#[command(name = "blockpuzzle", version, about)]
pub struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
#[allow(clippy::large_enum_variant)] // parsed once per process
enum Command {
    /// List the registered environment ids.
    Envs,
    /// The engine and numeric libraries this process runs with (MuJoCo
    /// version, OpenBLAS kernels, OpenMP wait policy, cores, bf16 support).
    Info,
    /// Roll out a policy and write a trajectory dump (JSON Lines, one episode per line).
    Rollout(RolloutArgs),
    #[cfg(feature = "train")]
    /// Measure environment steps/s and raw mj_step/s.
    Bench(BenchArgs),
    /// Render a recorded episode headless (EGL): an animated GIF, a folder of PNGs, or a filmstrip PNG.
    Render(RenderArgs),
    #[cfg(feature = "train")]
    /// Train an agent with the task's curriculum: DDPG, PGGD, or PGGD with AggreVaTeD (--expert).
    Train(TrainArgs),
    /// Evaluate a trained policy: success rate with a 95% confidence interval.
    Eval(EvalArgs),
    #[cfg(feature = "train")]
    /// The paper's results table on BlocksChoose-v0 (Normal and Challenge), beside the paper's numbers.
    Table(TableArgs),
    #[cfg(feature = "train")]
    /// Redraw a run's success curves (success.png) from its progress.csv, or
    /// overlay the finals success of several runs (--overlay) in one PNG.
    Plot(PlotArgs),
    #[cfg(feature = "train")]
    /// The time to a result of a run: when test and finals success first
    /// reached --target (epoch, env steps, hours) and the epoch's time split.
    Report {
        /// Run directories.
        #[arg(required = true)]
        run_dirs: Vec<PathBuf>,
        /// Success to report the first epoch of (0 to 1).
        #[arg(long, default_value_t = 0.95, value_parser = crate::limits::parse_fraction)]
        target: f64,
    },
    /// Task files: `task check FILE` validates a task and samples its layouts.
    #[command(subcommand)]
    Task(TaskCommand),
    /// The model zoo (trained policies shipped in zoo/): list, check, export, evaluate.
    #[command(subcommand)]
    Zoo(ZooCommand),
    /// Suite results side by side (`compare`) or as a leaderboard (`leaderboard`); numbers of
    /// different engines, suites or task contents are never put in one column.
    #[command(subcommand)]
    Results(ResultsCommand),
    /// Print the generated MuJoCo XML of an environment's scene (save it in
    /// models/ to load it in other MuJoCo tools).
    Scene {
        /// Environment id or task file (.toml).
        #[arg(long)]
        env: String,
    },
    #[cfg(feature = "train")]
    /// Replay gymnasium-robotics FetchPush-v4 episodes (recorded by
    /// bench/align_fetchpush.py) in the FetchPush-like environment on this
    /// build's MuJoCo and print, per episode, the largest distance between
    /// the two gripper and block trajectories.
    Align {
        /// The reference file bench/align_fetchpush.py wrote.
        #[arg(long)]
        reference: PathBuf,
        /// Also draw the per-step distances (log scale) into this PNG.
        #[arg(long)]
        plot: Option<PathBuf>,
        /// Instead, measure env steps/s of the FetchPush-like scene with random
        /// actions, every episode starting from the reference's first state
        /// (the same scene as FetchPush-v4; its JSON as `bench --json` prints it).
        #[arg(long, value_parser = crate::limits::BENCH_STEPS.parser::<usize>())]
        bench_steps: Option<usize>,
        /// Threads of --bench-steps, each stepping its own environment.
        #[arg(long, default_value_t = 1, value_parser = crate::limits::THREADS.parser::<usize>())]
        threads: usize,
    },
}

#[derive(Debug, Subcommand)]
enum ResultsCommand {
    /// Suite results (JSON of `eval --suite` or Python's `evaluate`) side by side, one column per
    /// file; refused, naming the field, when their engines, suites or task contents differ.
    Compare {
        /// The result files.
        #[arg(required = true)]
        files: Vec<PathBuf>,
    },
    /// A Markdown leaderboard of suite results: one table per suite and engine, rows per policy
    /// by score with 95% intervals and gaps, the provenance in footnotes.
    Leaderboard {
        /// Result files, or folders of them (`*.json`).
        #[arg(required = true)]
        paths: Vec<PathBuf>,
        /// Write it here (atomically) instead of printing it.
        #[arg(long)]
        out: Option<PathBuf>,
        /// Instead of writing --out, check that it holds exactly what the files give (exit 1 if stale).
        #[arg(long, requires = "out")]
        check: bool,
    },
}

#[derive(Debug, Subcommand)]
enum TaskCommand {
    /// Validate a task file (errors with file and line), reset it --samples
    /// times at every level and in every distribution, and print how often
    /// layouts were redrawn and why; --render writes a filmstrip of one reset
    /// state per level and distribution.
    Check(TaskCheckArgs),
}

#[derive(Debug, clap::Args)]
struct TaskCheckArgs {
    /// Task file (.toml) or registered id.
    file: String,
    /// Resets per level and distribution.
    #[arg(long, default_value_t = 100, value_parser = crate::limits::CHECK_SAMPLES.parser::<u64>())]
    samples: u64,
    /// Seed of the first reset (reset k uses seed + k).
    #[arg(long, default_value_t = 0, value_parser = crate::limits::SEED.parser::<u64>())]
    seed: u64,
    /// Filmstrip PNG of one reset state per level and distribution.
    #[arg(long)]
    render: Option<PathBuf>,
    #[command(flatten)]
    view: ViewArgs,
}

#[cfg(feature = "train")]
#[derive(Debug, clap::Args)]
struct TableArgs {
    /// The task: the paper's BlocksChoose-v0, or another id or task file with a challenge
    /// distribution (e.g. BlocksChooseShuffled-v0, to test generalisation).
    #[arg(long, default_value = crate::table::ENV)]
    env: String,
    /// The 2-block DDPG expert (run directory, policy file or zoo name); evaluated with grey blocks removed from its view.
    #[arg(long)]
    expert: Option<PathBuf>,
    /// DDPG trained on BlocksChoose-v0 (run directory, policy file or zoo name; so are the rows below).
    #[arg(long)]
    ddpg: Option<PathBuf>,
    /// PGGD trained with AggreVaTeD on BlocksChoose-v0.
    #[arg(long)]
    pggd: Option<PathBuf>,
    /// PGGD trained alone on BlocksChoose-v0.
    #[arg(long)]
    pggd_alone: Option<PathBuf>,
    /// DDPG on BlocksChoose-v0 with this project's changes (the row "DDPG (3 blocks), ours").
    #[arg(long)]
    ddpg_ours: Option<PathBuf>,
    /// Every row from the shipped zoo (its standard entry names); --expert etc. override single rows.
    #[arg(long)]
    zoo: bool,
    /// Episodes per cell.
    #[arg(long, default_value_t = 1000, value_parser = crate::limits::EVAL_EPISODES.parser::<usize>())]
    episodes: usize,
    /// Seed of the first episode (episode k uses seed + k).
    #[arg(long, default_value_t = crate::evaluate::TEST_SEED, value_parser = crate::limits::SEED.parser::<u64>())]
    seed: u64,
    /// Write the Markdown table here too (atomically).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Write the table even when a row's policy cannot be loaded or evaluated
    /// (the row then says why); without it such a row is an error.
    #[arg(long)]
    allow_missing: bool,
    /// Threads playing episodes (default: all cores); the result does not depend on it.
    #[arg(long, value_parser = crate::limits::THREADS.parser::<usize>())]
    threads: Option<usize>,
}

#[derive(Debug, clap::Args)]
struct EvalArgs {
    /// A policy file, a run directory (uses best_policy.json, else policy.json) or a zoo name.
    #[arg(long)]
    checkpoint: Option<PathBuf>,
    /// Evaluate a policy that needs no training on the suite instead of a checkpoint: `scripted`
    /// (each task's scripted controller) or `obs-hash` (pseudo-random actions from a hash of the
    /// observation, the same as Python's `blockpuzzle.policies.obs_hash`).
    #[arg(long, value_enum, requires = "suite", conflicts_with = "checkpoint")]
    baseline: Option<crate::evaluate::Baseline>,
    /// Evaluate on an evaluation suite instead: a built-in name (colour, layout, cross-task, count,
    /// obstacles) or a suite file; writes eval-POLICY-suite-NAME.json and .md (docs/suites.md).
    #[arg(long, conflicts_with_all = ["env", "challenge", "level", "episodes", "seed"])]
    suite: Option<String>,
    /// With --suite: play at most N episodes of each row, a quick look. The result records it and
    /// is not the suite's score (`results` refuses it).
    #[arg(long, requires = "suite", value_name = "N", value_parser = crate::limits::EVAL_EPISODES.parser::<usize>())]
    episodes_per_row: Option<usize>,
    /// Environment id or task file (default: the one the policy was trained on).
    #[arg(long)]
    env: Option<String>,
    /// Use the task's challenge distribution (BlocksChoose-v0 and the tasks that define one).
    #[arg(long)]
    challenge: bool,
    /// Curriculum level (default: the maximum).
    #[arg(long, value_parser = crate::limits::COUNT.parser::<usize>())]
    level: Option<usize>,
    /// Episodes.
    #[arg(long, default_value_t = 100, value_parser = crate::limits::EVAL_EPISODES.parser::<usize>())]
    episodes: usize,
    /// Seed of the first episode (episode k uses seed + k).
    #[arg(long, default_value_t = crate::evaluate::TEST_SEED, value_parser = crate::limits::SEED.parser::<u64>())]
    seed: u64,
    /// Where to write the JSON result (default: the run directory for a policy of a run,
    /// else the current folder, as eval-POLICY-TASK-DISTRIBUTION.json).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Threads playing episodes (default: all cores); the result does not depend on it.
    #[arg(long, value_parser = crate::limits::THREADS.parser::<usize>())]
    threads: Option<usize>,
}

#[derive(Debug, clap::Args)]
struct RolloutArgs {
    /// Environment id (see `blockpuzzle envs`) or task file (.toml).
    #[arg(long)]
    env: String,
    /// Which policy acts: `random`, `scripted`, or a trained policy (file, run directory or zoo name).
    #[arg(long, default_value = "scripted")]
    policy: String,
    /// Number of episodes.
    #[arg(long, default_value_t = 10, value_parser = crate::limits::ROLLOUT_EPISODES.parser::<usize>())]
    episodes: usize,
    /// Seed of the first episode (episode k uses seed + k).
    #[arg(long, default_value_t = 0, value_parser = crate::limits::SEED.parser::<u64>())]
    seed: u64,
    /// Curriculum level (default: the maximum, i.e. the evaluation distribution).
    #[arg(long, conflicts_with_all = ["challenge", "distribution"], value_parser = crate::limits::COUNT.parser::<usize>())]
    level: Option<usize>,
    /// Use the challenge distribution (the same as --distribution challenge).
    #[arg(long, conflicts_with = "distribution")]
    challenge: bool,
    /// Use a named evaluation distribution of the task file ([distributions.NAME]).
    #[arg(long)]
    distribution: Option<String>,
    /// Output file (JSON Lines); written atomically.
    #[arg(long)]
    out: PathBuf,
    /// Also render the first episode: FILE.gif, FILE.png with --filmstrip N, or a folder.
    #[arg(long)]
    render: Option<PathBuf>,
    #[command(flatten)]
    view: ViewArgs,
    #[command(flatten)]
    movie: MovieArgs,
}

/// Frame size and camera (the Fetch viewer's by default).
#[derive(Debug, Clone, clap::Args)]
struct ViewArgs {
    /// Frame width in pixels.
    #[arg(long, default_value_t = 480, value_parser = crate::limits::FRAME_PIXELS.parser::<usize>())]
    width: usize,
    /// Frame height in pixels.
    #[arg(long, default_value_t = 480, value_parser = crate::limits::FRAME_PIXELS.parser::<usize>())]
    height: usize,
    /// Camera distance from the point it looks at (m).
    #[arg(long, default_value_t = 2.5)]
    distance: f64,
    /// Camera azimuth (degrees).
    #[arg(long, default_value_t = 132.0)]
    azimuth: f64,
    /// Camera elevation (degrees, negative looks down).
    #[arg(long, default_value_t = -14.0, allow_negative_numbers = true)]
    elevation: f64,
}

/// What a rendered episode is written as (`rollout --render`, `render`).
#[derive(Debug, Clone, clap::Args)]
struct MovieArgs {
    /// Frames per second of a GIF.
    #[arg(long, default_value_t = 10, value_parser = crate::limits::FPS.parser::<u32>())]
    fps: u32,
    /// Write a filmstrip PNG of this many evenly spaced frames (--out FILE.png).
    #[arg(long, value_parser = crate::limits::FILMSTRIP.parser::<usize>())]
    filmstrip: Option<usize>,
}

impl ViewArgs {
    /// The camera, checked (a command checks it before any work).
    fn view(&self) -> Result<crate::render::View> {
        let view = crate::render::View {
            width: self.width,
            height: self.height,
            distance: self.distance,
            azimuth: self.azimuth,
            elevation: self.elevation,
            ..Default::default()
        };
        view.check().map_err(anyhow::Error::msg)?;
        Ok(view)
    }
}

#[derive(Debug, clap::Args)]
#[command(group(clap::ArgGroup::new("source").required(true).args(["traj", "policy"])))]
struct RenderArgs {
    /// Trajectory dump written by `rollout` (JSON Lines).
    #[arg(long)]
    traj: Option<PathBuf>,
    /// Which episode of the dump (0-based).
    #[arg(long, default_value_t = 0, requires = "traj", value_parser = crate::limits::COUNT.parser::<usize>())]
    episode: usize,
    /// Or play one episode of a trained policy (file, run directory or zoo name) and render it.
    #[arg(long)]
    policy: Option<PathBuf>,
    /// With --policy: the task (default: the one the policy was trained on).
    #[arg(long, requires = "policy")]
    env: Option<String>,
    /// With --policy: the episode's seed.
    #[arg(long, default_value_t = crate::evaluate::TEST_SEED, requires = "policy", value_parser = crate::limits::SEED.parser::<u64>())]
    seed: u64,
    /// With --policy: the challenge distribution.
    #[arg(long, requires = "policy")]
    challenge: bool,
    /// Output: FILE.gif (animation), FILE.png with --filmstrip N, or a folder (one PNG per frame).
    #[arg(long)]
    out: PathBuf,
    #[command(flatten)]
    view: ViewArgs,
    #[command(flatten)]
    movie: MovieArgs,
}

#[cfg(feature = "train")]
#[derive(Debug, clap::Args)]
struct BenchArgs {
    /// Environment id or task file (.toml).
    #[arg(long, default_value = "BlocksTouch-v0")]
    env: String,
    /// Steps per thread.
    #[arg(long, default_value_t = 20_000, value_parser = crate::limits::BENCH_STEPS.parser::<usize>())]
    steps: usize,
    /// Threads, each stepping its own environment.
    #[arg(long, default_value_t = 1, value_parser = crate::limits::THREADS.parser::<usize>())]
    threads: usize,
    /// Print one JSON line instead of text.
    #[arg(long)]
    json: bool,
    /// Turn the robot collision filter off (to measure what it saves).
    #[arg(long)]
    no_collision_filter: bool,
    /// Measure DDPG instead: env steps/s while collecting with the exploring
    /// actor (replay insert included) and gradient updates/s.
    #[arg(long, conflicts_with_all = ["threads", "no_collision_filter"])]
    ddpg: bool,
    /// DDPG: collection workers, each stepping its own environment.
    #[arg(long, default_value_t = 1, requires = "ddpg", value_parser = crate::limits::WORKERS.parser::<usize>())]
    workers: usize,
    /// DDPG: gradient updates to time.
    #[arg(long, default_value_t = 300, requires = "ddpg", value_parser = crate::limits::BENCH_UPDATES.parser::<usize>())]
    updates: usize,
    /// DDPG: transitions per update batch.
    #[arg(long, default_value_t = 256, requires = "ddpg", value_parser = crate::limits::BATCH_SIZE.parser::<usize>())]
    batch_size: usize,
    /// DDPG: threads libtorch may use for the updates (at most the number of cores).
    #[arg(long, default_value_t = 1, requires = "ddpg", value_parser = crate::limits::COUNT.parser::<usize>())]
    torch_threads: usize,
    /// DDPG: seed of networks, layouts and noise.
    #[arg(long, default_value_t = 0, requires = "ddpg", value_parser = crate::limits::SEED.parser::<u64>())]
    seed: u64,
    /// DDPG: arithmetic of the updates' hidden-layer products.
    #[arg(long, value_enum, default_value = "f32", requires = "ddpg")]
    precision: crate::agents::ddpg::Precision,
    /// With --ddpg: the algorithm whose collection and updates to time (any of `train --algo`).
    #[arg(long, default_value = "ddpg", requires = "ddpg", value_parser = crate::agents::algorithm::Algo::parser())]
    algo: crate::agents::algorithm::Algo,
    /// With --ddpg: the networks, `mlp` on the flat observation or `set` on the `objects` one (as `train --net`).
    #[arg(long, value_enum, default_value = "mlp", requires = "ddpg")]
    net: crate::agents::arch::NetKind,
    /// With --ddpg --net set: `mean-max` or `attention` (as `train --set-pooling`).
    #[arg(long, value_enum, default_value = "mean-max", requires = "ddpg")]
    set_pooling: crate::agents::arch::Pooling,
    /// With --ddpg --net set: layer-normalise the pooled features (as `train --set-norm`).
    #[arg(long, requires = "ddpg")]
    set_norm: bool,
    /// With --ddpg --net set: the critics are MLPs (as `train --flat-critic`).
    #[arg(long, requires = "ddpg")]
    flat_critic: bool,
}

/// The command line's definition, every value-taking flag accepting a
/// leading '-' so that `--episodes -3` reaches the flag's parser and its
/// range is named, rather than '-3' reading as an unknown flag.
fn command() -> clap::Command {
    fn negatives(cmd: clap::Command) -> clap::Command {
        cmd.mut_args(|a| if a.get_action().takes_values() { a.allow_negative_numbers(true) } else { a })
            .mut_subcommands(negatives)
    }
    let cmd = negatives(<Cli as clap::CommandFactory>::command());
    // A flag given twice takes its last value: `train --config FILE` puts the
    // file's flags first, so the command line's own win.
    #[cfg(feature = "train")]
    let cmd = cmd.mut_subcommand("train", |t| t.args_override_self(true));
    cmd
}

/// An error and its causes on one line, each cause once: a cause whose text
/// the message already holds (`cannot read X: No such file`) is not repeated.
pub fn error_text(e: &anyhow::Error) -> String {
    let mut text = String::new();
    for cause in e.chain() {
        let part = cause.to_string();
        if text.contains(&part) {
            continue;
        }
        if !text.is_empty() {
            text.push_str(": ");
        }
        text.push_str(&part);
    }
    crate::limits::cut_long_lines(&text)
}

/// The command line `args` (from the program name on), `train --config`
/// recipes expanded.
///
/// # Errors
/// An unreadable recipe, or clap's error (help and version included).
fn parse(args: Vec<std::ffi::OsString>) -> Result<Cli> {
    let cmd = command();
    #[cfg(feature = "train")]
    let args = {
        let train = cmd.find_subcommand("train").cloned().unwrap_or_default();
        experiment::expand(args, &train)?
    };
    let matches = cmd.try_get_matches_from(args)?;
    Ok(<Cli as clap::FromArgMatches>::from_arg_matches(&matches)?)
}

/// Whether the command line `args` (from the program name on) parses, without running it: the
/// docs' command lines are checked so (tests/it/docs.rs).
///
/// # Errors
/// clap's message, or an unreadable recipe.
pub fn check_args(args: Vec<std::ffi::OsString>) -> Result<()> {
    parse(args).map(|_| ())
}

/// Runs the command line `args` (from the program name on) and returns the process's exit
/// status: 0; 1 with the error on stderr; clap's status for help, version and usage errors,
/// printed as clap prints them. The `blockpuzzle` binary and the Python package's command call it.
pub fn run(args: Vec<std::ffi::OsString>) -> i32 {
    let failed = |e: anyhow::Error| {
        eprintln!("error: {}", error_text(&e));
        1
    };
    let cli = match parse(args) {
        Ok(cli) => cli,
        Err(e) => match e.downcast::<clap::Error>() {
            Ok(usage) => {
                let _ = usage.print();
                return usage.exit_code();
            }
            Err(e) => return failed(e),
        },
    };
    match dispatch(cli.command) {
        Ok(()) => 0,
        Err(e) => failed(e),
    }
}

/// Runs one parsed command.
fn dispatch(command: Command) -> Result<()> {
    match command {
        Command::Envs => envs(),
        Command::Info => info(),
        Command::Rollout(a) => rollout(a),
        #[cfg(feature = "train")]
        Command::Train(a) => runs::train(a),
        Command::Eval(a) => eval(a),
        Command::Render(a) => render(a),
        Command::Zoo(c) => zoo::run(c),
        Command::Results(c) => results(c),
        #[cfg(feature = "train")]
        Command::Report { run_dirs, target } => runs::report(&run_dirs, target),
        #[cfg(feature = "train")]
        Command::Table(a) => table(a),
        Command::Task(TaskCommand::Check(a)) => task_check(a),
        #[cfg(feature = "train")]
        Command::Plot(a) => runs::plot(a),
        #[cfg(feature = "train")]
        Command::Align { reference, plot: None, bench_steps: Some(steps), threads } => {
            align_bench(&reference, steps, threads)
        }
        #[cfg(feature = "train")]
        Command::Align { plot: Some(_), bench_steps: Some(_), .. } => {
            bail!("--plot draws the replay; leave it out with --bench-steps")
        }
        #[cfg(feature = "train")]
        Command::Align { reference, plot, .. } => align(&reference, plot.as_deref()),
        Command::Scene { env } => {
            let c = registry::config(&env)?;
            // Its includes are relative to the assets folder: save it there to load it elsewhere.
            print!("{}", crate::scene::mjcf(&c.scene_spec())?.0);
            Ok(())
        }
        #[cfg(feature = "train")]
        Command::Bench(a) if a.ddpg => bench_ddpg(a),
        #[cfg(feature = "train")]
        Command::Bench(a) => bench(&a),
    }
}

/// `blockpuzzle envs`: one line per registered id.
fn envs() -> Result<()> {
    for r in registry::REGISTRY {
        let task = registry::task(r.id)?;
        println!(
            "{:<24} obs {:>3}  levels 0-{:<2}  {}",
            r.id,
            crate::env::ObsSpec::flat(task.object_count()).dim(),
            task.max_level(),
            task.spec.summary
        );
    }
    Ok(())
}

/// `blockpuzzle info`: the engine and numeric libraries of this process.
/// `blockpuzzle results compare | leaderboard`.
fn results(c: ResultsCommand) -> Result<()> {
    match c {
        ResultsCommand::Compare { files } => {
            let files = files.iter().map(|f| crate::results::read(f)).collect::<Result<Vec<_>>>()?;
            print!("{}", crate::results::compare(&files)?);
        }
        ResultsCommand::Leaderboard { paths, out, check } => {
            let md = crate::results::leaderboard(&crate::results::read_all(&paths)?)?;
            match (out, check) {
                (Some(out), true) => {
                    let now = crate::io::read_text(&out, "leaderboard", crate::limits::RESULT_FILE_BYTES)
                        .with_context(|| format!("cannot read {}", out.display()))?;
                    if now != md {
                        bail!("{} is stale: regenerate it with the same command without --check", out.display());
                    }
                    println!("{} is up to date", out.display());
                }
                (Some(out), false) => {
                    crate::io::write_file(&out, md.as_bytes())?;
                    println!("wrote {}", out.display());
                }
                (None, _) => print!("{md}"),
            }
        }
    }
    Ok(())
}

fn info() -> Result<()> {
    println!("blockpuzzle {}", env!("CARGO_PKG_VERSION"));
    if let Some(commit) = crate::provenance::commit() {
        println!("commit {commit}");
    }
    println!("MuJoCo {} (the engine every number this build writes is made on)", crate::mj::version());
    // What libtorch's updates run with (the training build's concern).
    #[cfg(feature = "train")]
    {
        let var = |k: &str| std::env::var(k).unwrap_or_else(|_| "(unset)".into());
        println!("OpenBLAS kernels {}", crate::blas::openblas_core().unwrap_or_else(|| "(not loaded)".into()));
        println!("OPENBLAS_CORETYPE={}", var("OPENBLAS_CORETYPE"));
        println!("OMP_WAIT_POLICY={}", var("OMP_WAIT_POLICY"));
    }
    println!("cores {}", std::thread::available_parallelism().map_or(1, |n| n.get()));
    #[cfg(feature = "train")]
    println!("bf16 updates {}", if crate::agents::ddpg::Precision::bf16_supported() { "yes" } else { "no" });
    Ok(())
}

#[cfg(feature = "train")]
/// `align --bench-steps`: env steps/s of the FetchPush-like scene from the reference's first state.
fn align_bench(reference: &Path, steps: usize, threads: usize) -> Result<()> {
    let r = crate::align::Reference::load(reference)?;
    let Some(ep) = r.episodes.first() else { bail!("{} holds no episodes", reference.display()) };
    let start = |env: &mut crate::env::BlockEnv, _: Option<u64>| {
        let (q, v) =
            crate::align::start_state(env, ep).map_err(|e| crate::env::EnvError::BadState { reason: e.to_string() })?;
        env.set_state(&q, &v)
    };
    let report = crate::bench::run_with("FetchPush-like", &crate::align::fetchpush_like, &start, steps, threads)?;
    println!("{}", serde_json::to_string(&report)?);
    Ok(())
}

#[cfg(feature = "train")]
/// `blockpuzzle align`: the replay's per-episode deviations, and their plot.
fn align(reference: &Path, plot: Option<&Path>) -> Result<()> {
    let r = crate::align::Reference::load(reference)?;
    let title = format!(
        "FetchPush-v4 (gymnasium-robotics {}, MuJoCo {}) against FetchPush-like on MuJoCo {}",
        r.gymnasium_robotics,
        r.mujoco,
        crate::mj::version()
    );
    println!("{title}");
    println!("| episode | steps | gripper max (m) | block max (m) | worst step |\n|---|---|---|---|---|");
    let all = crate::align::replay_all(&r)?;
    for d in &all {
        println!(
            "| {} {} | {} | {:.2e} | {:.2e} | {} |",
            d.kind, d.seed, d.steps, d.grip_max, d.object_max, d.worst_step
        );
    }
    if let Some(png) = plot {
        let episodes: Vec<(String, Vec<[f64; 2]>)> =
            all.iter().map(|d| (format!("{} {}", d.kind, d.seed), d.per_step.clone())).collect();
        crate::train::plot::deviations(png, &title, &episodes, crate::align::TOLERANCE)?;
        println!("wrote {}", png.display());
    }
    Ok(())
}

#[cfg(feature = "train")]
/// `bench --ddpg`: collection env steps/s and update rate.
fn bench_ddpg(a: BenchArgs) -> Result<()> {
    let r = crate::bench::ddpg::run(&crate::bench::ddpg::DdpgBenchConfig {
        env: a.env,
        workers: a.workers,
        steps: a.steps,
        updates: a.updates,
        batch_size: a.batch_size,
        torch_threads: a.torch_threads,
        seed: a.seed,
        precision: a.precision,
        algo: a.algo,
        net: crate::agents::arch::NetConfig {
            net: a.net,
            set_pooling: a.set_pooling,
            set_norm: a.set_norm,
            ..Default::default()
        },
        flat_critic: a.flat_critic,
    })?;
    if a.json {
        println!("{}", serde_json::to_string(&r)?);
    } else {
        println!(
            "{:?} ({}) on {}: {} worker(s), {} torch thread(s), batch {}, {:?}\n  env steps/s (collect) {:>8.0}  ({:.0}% in the actor)\n  updates/s             {:>8.1}",
            r.algo, r.net, r.env, r.workers, r.threads, r.batch_size, r.precision, r.env_steps_per_s, 100.0 * r.forward_fraction, r.updates_per_s
        );
    }
    Ok(())
}

#[cfg(feature = "train")]
/// `blockpuzzle bench`: env steps/s and mj_step/s.
fn bench(a: &BenchArgs) -> Result<()> {
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

fn rollout(a: RolloutArgs) -> Result<()> {
    // Check the --render output before spending time on the episodes.
    let render_kind = a
        .render
        .as_deref()
        .map(|out| crate::render::replay::Output::for_path(out, a.movie.filmstrip, a.movie.fps))
        .transpose()?;
    if a.render.is_some() {
        a.view.view()?;
    }
    let mut env: BlockEnv = registry::make(&a.env)?;
    if a.challenge {
        env.set_challenge(true)?;
    }
    env.set_distribution(a.distribution.as_deref().or(a.challenge.then_some("challenge")))?;
    let level = a.level.unwrap_or(env.max_level());
    env.set_level(level)?;
    crate::limits::seed_range(a.seed, a.episodes as u64).map_err(anyhow::Error::msg)?;
    let mut writer = DumpWriter::create(&a.out)?;
    let mut policy: Box<dyn Policy> = match a.policy.as_str() {
        "random" => Box::new(RandomPolicy::new(a.seed)),
        "scripted" => Box::new(ScriptedPolicy::for_env(env.config())),
        path => {
            let saved = crate::load::load_policy(Path::new(path))?;
            env.set_obs_mode(saved.policy.obs_mode());
            Box::new(crate::evaluate::trained_policy(Path::new(path), saved, &env)?)
        }
    };
    let (mut outcomes, mut steps) = (Outcomes::default(), 0usize);
    for k in 0..a.episodes {
        let seed = a.seed + k as u64;
        let ep = run_episode(&mut env, policy.as_mut(), seed).with_context(|| format!("episode {k} (seed {seed})"))?;
        outcomes.add(Outcome::of(&ep));
        steps += ep.steps.len();
        writer.write(&ep)?;
    }
    writer.finish()?;
    if let (Some(out), Some(kind)) = (&a.render, &render_kind) {
        // The dump is whole by now: a failed rendering keeps it and says so.
        let (frames, fps) =
            crate::render::replay::render_dump(&a.out, 0, &a.view.view()?, out, kind).with_context(|| {
                format!(
                    "the episodes are saved in {}, but --render failed; render them with \
                     `blockpuzzle render --traj {}` once rendering works",
                    a.out.display(),
                    a.out.display()
                )
            })?;
        println!("rendered episode 0: {frames} frames ({fps:.1} frames/s) -> {}", out.display());
    }
    let n = a.episodes as f64;
    println!(
        "{} {} policy, level {}{}: success {:.3} ({}/{}), mean length {:.1}; not successful: {}; wrote {}",
        a.env,
        a.policy,
        level,
        env.distribution_name().map_or(String::new(), |d| format!(" ({d})")),
        outcomes.success as f64 / n,
        outcomes.success,
        a.episodes,
        steps as f64 / n,
        outcomes.summary(),
        a.out.display()
    );
    Ok(())
}

fn task_check(a: TaskCheckArgs) -> Result<()> {
    if let Some(out) = &a.render {
        if out.extension().map_or(true, |e| !e.eq_ignore_ascii_case("png")) {
            bail!("--render writes a filmstrip PNG: give a FILE.png");
        }
        crate::io::check_output(out)?;
        a.view.view()?;
    }
    let task = registry::task(&a.file)?;
    let bar = crate::progress::bar(crate::check::settings(&task).len() as u64 * a.samples, "reset");
    let report = crate::check::check(task, a.samples, a.seed, &mut || bar.inc(1))?;
    bar.finish_and_clear();
    let task = &report.task;
    println!(
        "{}: task {} is valid: {} objects, levels 0-{}, distributions: {}",
        a.file,
        task.id(),
        task.object_count(),
        task.max_level(),
        if task.distribution_names().is_empty() { "none".to_owned() } else { task.distribution_names().join(", ") }
    );
    for l in &report.levels {
        println!("{}", l.line());
    }
    if let Some(out) = &a.render {
        let mut frames = Vec::new();
        let mut env = BlockEnv::new(crate::env::EnvConfig::new(task.clone()))?;
        let mut renderer = crate::render::Renderer::new(env.scene().model.as_ref(), &a.view.view()?)?;
        for (label, level, distribution) in crate::check::settings(task) {
            env.set_level(level)?;
            env.set_distribution(distribution.as_deref())?;
            if env.reset(Some(a.seed)).is_err() {
                continue;
            }
            let colours: Vec<_> = env.objects().iter().map(|o| o.colour).collect();
            renderer.colour_objects(env.scene(), &colours, &env.absent_objects())?;
            frames.push(renderer.render(env.data_mut(), Some((&format!("{}\n{label}", task.id()), ""))));
        }
        let n = frames.len();
        crate::render::output::filmstrip(out, &frames, n)?;
        println!("wrote {} ({n} reset states)", out.display());
    }
    if !report.ok() {
        bail!("{}: some levels could not be reset (see above)", a.file);
    }
    Ok(())
}

fn render(a: RenderArgs) -> Result<()> {
    let kind = crate::render::replay::Output::for_path(&a.out, a.movie.filmstrip, a.movie.fps)?;
    let view = a.view.view()?;
    let (frames, fps, what) = match (&a.traj, &a.policy) {
        (Some(traj), _) => {
            let (frames, fps) = crate::render::replay::render_dump(traj, a.episode, &view, &a.out, &kind)?;
            (frames, fps, format!("episode {}", a.episode))
        }
        (None, Some(path)) => {
            let saved = crate::load::load_policy(path)?;
            let task = policy_task(a.env.as_deref(), &saved)?;
            let mode = saved.policy.obs_mode();
            let mut env = BlockEnv::new(crate::env::EnvConfig { obs_mode: mode, ..crate::env::EnvConfig::new(task) })?;
            env.set_distribution(a.challenge.then_some("challenge"))?;
            let level = env.max_level();
            env.set_level(level)?;
            let mut policy = crate::evaluate::trained_policy(path, saved, &env)?;
            let ep = run_episode(&mut env, &mut policy, a.seed)?;
            let (frames, seconds) = crate::render::replay::episode_frames(&ep, &view)?;
            kind.write(&a.out, &frames)?;
            let outcome = if ep.success {
                "success"
            } else if ep.failure {
                "failure"
            } else {
                "neither"
            };
            (frames.len(), frames.len() as f64 / seconds.max(1e-9), format!("seed {} ({outcome})", a.seed))
        }
        (None, None) => bail!("give --traj DUMP or --policy POLICY"),
    };
    println!(
        "rendered {frames} frames of {what} at {}x{} ({fps:.1} frames/s) -> {}",
        a.view.width,
        a.view.height,
        a.out.display()
    );
    Ok(())
}

/// The task to run a policy on: the one named, else the one it was trained
/// on (its recorded copy if the file moved or changed).
fn policy_task(env: Option<&str>, saved: &crate::saved::SavedPolicy) -> Result<crate::task::Task> {
    Ok(match (env, &saved.task) {
        (Some(env), _) => registry::task(env)?,
        (None, Some(source)) => registry::recorded(source)?,
        (None, None) => registry::task(&saved.env_id)?,
    })
}

#[cfg(feature = "train")]
fn table(a: TableArgs) -> Result<()> {
    crate::limits::seed_range(a.seed, a.episodes as u64).map_err(anyhow::Error::msg)?;
    if let Some(out) = &a.out {
        crate::io::check_output(out)?;
    }
    let threads = a.threads.unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
    let task = registry::task(&a.env)?;
    if task.distribution("challenge").is_none() {
        bail!("the table's second column is the challenge distribution, which {} does not define", a.env);
    }
    let given = crate::table::Policies {
        expert: a.expert,
        ddpg: a.ddpg,
        ddpg_ours: a.ddpg_ours,
        pggd: a.pggd,
        pggd_alone: a.pggd_alone,
    };
    let rows = crate::table::rows(if a.zoo { given.or(crate::table::Policies::zoo()) } else { given });
    let mut done = Vec::new();
    for row in rows {
        eprintln!("evaluating {} ...", row.method);
        let outcome = crate::table::evaluate_row(&row, &task, a.episodes, a.seed, threads);
        done.push((row, outcome));
    }
    let missing: Vec<String> = done
        .iter()
        .filter_map(|(row, r)| match r {
            crate::table::RowResult::Missing(why) => Some(format!(
                "{} ({}): {why}",
                row.method,
                row.policy.as_deref().map_or(String::new(), |p| p.display().to_string())
            )),
            _ => None,
        })
        .collect();
    for m in &missing {
        eprintln!("missing row {m}");
    }
    if !missing.is_empty() && !a.allow_missing {
        bail!(
            "{} row(s) asked for could not be built (above); no table was written. Fix them, or pass \
             --allow-missing to write the table with those rows marked missing",
            missing.len()
        );
    }
    let md = crate::table::markdown(&done, task.id(), a.episodes, a.seed);
    print!("{md}");
    if let Some(out) = &a.out {
        crate::io::write_file(out, md.as_bytes())?;
    }
    Ok(())
}

/// Where `eval` writes by default: `eval-POLICY-TASK-DISTRIBUTION.json` in the
/// policy's run directory (a run directory, or a policy file or snapshot in
/// one), else in the current folder; POLICY is the file's stem or zoo name
/// (`best_policy` for a run directory, whose best policy is evaluated).
fn eval_out(checkpoint: &Path, label: &str) -> PathBuf {
    let is_run = |d: &Path| d.join("config.json").is_file();
    let (run, policy) = if checkpoint.is_dir() {
        let best = checkpoint.join("best_policy.json").exists();
        (Some(checkpoint.to_path_buf()), if best { "best_policy" } else { "policy" }.to_owned())
    } else {
        let stem = checkpoint.file_stem().map_or_else(|| "policy".into(), |s| s.to_string_lossy().into_owned());
        let folder = checkpoint.parent().filter(|p| !p.as_os_str().is_empty());
        // A policy file in a run directory, or a snapshot in its snapshots/ folder.
        let run = folder.and_then(|f| [Some(f), f.parent()].into_iter().flatten().find(|d| is_run(d)));
        (run.map(Path::to_path_buf), stem)
    };
    run.unwrap_or_default().join(format!("eval-{policy}-{label}.json"))
}

/// `eval --suite`: every row of the suite, the JSON result and its Markdown beside it.
fn eval_suite(a: &EvalArgs, name: &str) -> Result<()> {
    use crate::evaluate::Subject;
    use crate::provenance::Harness;
    let mut suite = crate::suite::load(name)?;
    if let Some(n) = a.episodes_per_row {
        suite = suite.first_episodes(n)?;
    }
    let threads = a.threads.unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
    // Where the results go, checked before any episode is played.
    let out = match (&a.out, &a.checkpoint, a.baseline) {
        (Some(out), _, _) => out.clone(),
        (None, _, Some(b)) => PathBuf::from(format!("eval-{}-suite-{}.json", b.name(), suite.name)),
        (None, Some(checkpoint), None) => eval_out(checkpoint, &format!("suite-{}", suite.name)),
        (None, None, None) => bail!("give --checkpoint POLICY or --baseline scripted|obs-hash"),
    };
    if out.extension().is_some_and(|e| e.eq_ignore_ascii_case("md")) {
        bail!(
            "--out {}: names the JSON result, whose Markdown goes beside it as NAME.md; give NAME.json",
            out.display()
        );
    }
    // Checked before any episode is played; the Markdown goes beside a file, a device or pipe gets the JSON alone.
    let md = match crate::io::check_output(&out)? {
        crate::io::Target::File { .. } => Some(out.with_extension("md")),
        crate::io::Target::Stream => None,
    };
    if let Some(md) = &md {
        crate::io::check_output(md)?;
    }
    let saved;
    let subject = match (&a.checkpoint, a.baseline) {
        (_, Some(b)) => Subject::Baseline(b),
        (checkpoint, None) => {
            let checkpoint = checkpoint.as_deref().unwrap_or(Path::new(""));
            saved = crate::load::load_policy(checkpoint)?;
            Subject::Saved(checkpoint, &saved)
        }
    };
    let r = crate::evaluate::evaluate_suite(subject, &suite, threads, Harness::Cli, &mut |_, _, _, _| Ok(()))?;
    crate::io::write_json(&out, &r)?;
    if let Some(md) = &md {
        crate::io::write_file(md, r.to_markdown().as_bytes())?;
    }
    for split in &r.splits {
        for row in &split.rows {
            match (&row.evaluation, &row.skipped) {
                (Some(e), _) => println!(
                    "{:<6} {} {}: success {:.3} (95% CI {:.3}-{:.3})",
                    split.name, row.task, row.distribution, e.success_rate, e.ci95.0, e.ci95.1
                ),
                (None, reason) => println!(
                    "{:<6} {} {}: skipped ({})",
                    split.name,
                    row.task,
                    row.distribution,
                    reason.as_deref().unwrap_or("")
                ),
            }
        }
    }
    let show = |v: Option<f64>| v.map_or_else(|| "none".to_owned(), |v| format!("{v:.3}"));
    let md = md.map_or_else(|| " (no Markdown beside a device or pipe)".to_owned(), |md| format!(", {}", md.display()));
    println!(
        "suite {}: score {} (test mean success), gap {} -> {}{md}",
        suite.name,
        show(r.score),
        show(r.gap),
        out.display(),
    );
    Ok(())
}

fn eval(a: EvalArgs) -> Result<()> {
    if let Some(suite) = &a.suite {
        return eval_suite(&a, suite);
    }
    let Some(checkpoint) = &a.checkpoint else {
        bail!("give --checkpoint POLICY (a policy file, run directory or zoo name; --baseline needs --suite)")
    };
    let saved = crate::load::load_policy(checkpoint)?;
    let task = policy_task(a.env.as_deref(), &saved)?;
    let id = task.id().to_owned();
    let policy_epoch = saved.epoch;
    let provenance = crate::provenance::Provenance::new(
        crate::provenance::Harness::Cli,
        saved.policy_id(&checkpoint.display().to_string()),
        None,
    );
    let spec = crate::evaluate::EvalSpec {
        task: &task,
        distribution: None,
        challenge: a.challenge,
        level: a.level,
        episodes: a.episodes,
        seed: a.seed,
        threads: a.threads.unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get())),
    };
    let distribution = match (a.challenge, a.level) {
        (true, _) => "challenge".to_owned(),
        (false, Some(l)) if l < task.max_level() => format!("level{l}"),
        _ => "normal".to_owned(),
    };
    let out = a.out.clone().unwrap_or_else(|| eval_out(checkpoint, &format!("{id}-{distribution}")));
    crate::io::check_output(&out)?;
    let r = crate::evaluate::evaluate(checkpoint, saved, &spec)?;
    let result = serde_json::json!({
        "env": id, "challenge": a.challenge, "level": r.level, "episodes": a.episodes, "seed": a.seed,
        "successes": r.successes, "success_rate": r.success_rate, "ci95": [r.ci95.0, r.ci95.1],
        "grey_blind": r.grey_blind, "outcomes": r.outcomes, "policy": checkpoint, "policy_epoch": policy_epoch,
        "task_sha256": task.source.hash, "provenance": provenance,
    });
    crate::io::write_json(&out, &result)?;
    println!(
        "{id}{}{}: success {:.3} (95% CI {:.3}-{:.3}, {}/{}); not successful: {} -> {}",
        if a.challenge { " challenge" } else { "" },
        if r.grey_blind { " (grey blocks removed from the policy's view)" } else { "" },
        r.success_rate,
        r.ci95.0,
        r.ci95.1,
        r.successes,
        a.episodes,
        r.outcomes.summary(),
        out.display()
    );
    Ok(())
}
