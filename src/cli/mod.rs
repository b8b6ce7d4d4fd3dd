//! Layer 11, cli (the `cli` feature): the `blockpuzzle` command line.
//!
//! | module | what |
//! |---|---|
//! | this file | the commands, their dispatch, `envs`, `info`, `scene`, the list of training commands |
//! | `episodes` | `rollout`, `render`, `demos` |
//! | `eval` | `eval` (a task or a suite) and `table` |
//! | `blend` | `blend` (WiSE-FT interpolation of a fine-tuned policy) |
//! | `results` | `results compare` and `results leaderboard` |
//! | `task` | `task check` and `task generate` |
//! | `zoo` | `zoo list`, `check`, `evaluate`, `describe`, `upgrade`, `export` |
//! | `runs` (`train`) | `train` (one process or an MPI rank), `plot`, `report` |
//! | `experiment` (`train`) | `train --config FILE` recipes |
//! | `bench` (`train`) | `bench` and `align` |
//! | `serve` (`serve`) | `serve`, the browser app |
//! | `halves` (`train`) | `blockpuzzle` hands the training commands to `blockpuzzle-train` |
//!
//! With the `cli` feature alone, the commands that need no
//! libtorch (the Python package's `blockpuzzle`); with `train`, every command, in two binaries
//! (`halves`): `blockpuzzle` runs those [`run_core`] runs and starts `blockpuzzle-train` for the rest.

use anyhow::{bail, Result};
use clap::{Parser, Subcommand};
#[cfg(feature = "train")]
use std::path::PathBuf;

use crate::env::registry;

#[cfg(feature = "train")]
mod bench;
mod blend;
mod episodes;
mod eval;
#[cfg(feature = "train")]
mod experiment;
#[cfg(feature = "train")]
mod halves;
mod results;
#[cfg(feature = "train")]
mod runs;
#[cfg(feature = "serve")]
mod serve;
mod task;
mod zoo;
#[cfg(feature = "train")]
use bench::BenchArgs;
use episodes::{policy_task, DemosArgs, RenderArgs, RolloutArgs};
use eval::EvalArgs;
use eval::TableArgs;
#[cfg(feature = "train")]
pub use halves::{check_front, exec_training_half, runs_in_training_half, BUILD_ID, TRAINING_BINARY, TRAINING_HALF};
use results::ResultsCommand;
#[cfg(feature = "train")]
pub use runs::train_config;
#[cfg(feature = "train")]
use runs::{PlotArgs, TrainArgs};
use task::TaskCommand;
use zoo::ZooCommand;

/// The commands only the training build has (the `train` feature: libtorch, plots, benchmarks). A
/// build without it (the Python package's command, or `--no-default-features --features cli`) says
/// so when given one, rather than clap's "unrecognized subcommand".
pub const TRAINING_COMMANDS: &[&str] = &["train", "bench", "plot", "report", "align", "zoo export"];

/// The command a command line `args` (from the program name on) runs, before clap parses it: its
/// first two words after the program that are not options (a command and its subcommand).
fn command_words(args: &[std::ffi::OsString]) -> Vec<&str> {
    args.iter().skip(1).filter_map(|a| a.to_str()).filter(|a| !a.starts_with('-')).take(2).collect()
}

/// The entry of [`TRAINING_COMMANDS`] the command line `args` (from the program name on) runs, if
/// any.
pub fn training_command(args: &[std::ffi::OsString]) -> Option<&'static str> {
    command_in(TRAINING_COMMANDS, args)
}

/// The entry of `commands` (each a command, or a command and its subcommand) the command line
/// `args` (from the program name on) runs, if any.
fn command_in(commands: &[&'static str], args: &[std::ffi::OsString]) -> Option<&'static str> {
    let words = command_words(args);
    commands.iter().copied().find(|c| {
        let c: Vec<&str> = c.split(' ').collect();
        words.len() >= c.len() && words[..c.len()] == c[..]
    })
}

/// Whether the command line `args` (from the program name on) runs one of
/// [`crate::learn::blas::KERNEL_COMMANDS`], whose start [`crate::learn::blas::ensure_fast_kernels`] is for.
#[cfg(feature = "train")]
pub fn wants_fast_kernels(args: &[std::ffi::OsString]) -> bool {
    command_words(args).first().is_some_and(|w| crate::learn::blas::KERNEL_COMMANDS.contains(w))
}

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
    /// The engine this process runs with (MuJoCo version, cores) and, in the training build,
    /// libtorch's numeric libraries (OpenBLAS kernels, OpenMP wait policy, bf16 support).
    Info,
    /// Roll out a policy and write a trajectory dump (JSON Lines, one episode per line).
    Rollout(RolloutArgs),
    #[cfg(feature = "train")]
    /// Measure environment steps/s and raw mj_step/s.
    Bench(BenchArgs),
    /// Record the solver's episodes on a suite split (entities observations, actions, rewards,
    /// outcomes, each episode's task hash) as a safetensors file, for imitation and offline RL.
    Demos(DemosArgs),
    /// Render a recorded episode headless (EGL): an animated GIF, a folder of PNGs, or a filmstrip PNG.
    Render(RenderArgs),
    #[cfg(feature = "train")]
    /// Train an agent with the task's curriculum (--algo: ddpg (--td3 for TD3), sac, pggd (with --expert: AggreVaTeD), bc, dagger).
    Train(TrainArgs),
    /// Evaluate a trained policy: success rate with a 95% confidence interval.
    Eval(EvalArgs),
    /// Interpolate a fine-tuned policy towards the one it started from, weight by weight (WiSE-FT):
    /// (1 - w) x BASE + w x TUNED, written as a policy file with the blend recorded.
    Blend(blend::BlendArgs),
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
        #[arg(long, default_value_t = 0.95, value_parser = crate::support::limits::parse_fraction)]
        target: f64,
    },
    /// Task files: `task check FILE` validates a task and samples its layouts; `task generate
    /// FAMILY` writes tasks drawn from a task family (`tasks` is another name for it).
    #[command(subcommand, alias = "tasks")]
    Task(TaskCommand),
    /// The model zoo (trained policies shipped in zoo/): list, check, export, evaluate, describe, upgrade.
    #[command(subcommand)]
    Zoo(ZooCommand),
    /// Suite results side by side (`compare`) or as a leaderboard (`leaderboard`); numbers of
    /// different engines, suites or task contents are never put in one column.
    #[command(subcommand)]
    Results(ResultsCommand),
    #[cfg(feature = "serve")]
    /// The browser app on a local address: browse tasks, families, suites, the zoo and the
    /// leaderboard, watch any policy play, build tasks in an editor.
    Serve(serve::ServeArgs),
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
        #[arg(long, value_parser = crate::support::limits::BENCH_STEPS.parser::<usize>())]
        bench_steps: Option<usize>,
        /// Threads of --bench-steps, each stepping its own environment.
        #[arg(long, default_value_t = 1, value_parser = crate::support::limits::THREADS.parser::<usize>())]
        threads: usize,
    },
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

/// Makes a closed pipe end the program quietly, as it ends `cat` and `ls` (`blockpuzzle info |
/// head -1`), rather than as a panic in the next `println!`: Rust starts programs with SIGPIPE
/// ignored. Both binaries call it first thing in `main`. Sockets are unaffected: the standard
/// library sends with `MSG_NOSIGNAL`, so `serve` sees a closed connection as an error, not a signal.
pub fn default_sigpipe() {
    // SAFETY: restoring a signal's default disposition, which the binaries do at startup, before any
    // thread exists; no handler is installed.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
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
    crate::support::limits::cut_long_lines(&text)
}

/// The command line `args` (from the program name on), `train --config`
/// recipes expanded.
///
/// # Errors
/// An unreadable recipe, or clap's error (help and version included).
fn parse(args: Vec<std::ffi::OsString>) -> Result<Cli> {
    #[cfg(not(feature = "train"))]
    if let Some(name) = training_command(&args) {
        bail!(
            "`{name}` is a command of the training build, which this one is not (it was built without \
             the `train` feature, as the Python package's command is): run it with the Rust command \
             line built with its default features (`cargo install --path .` in a checkout, or `make build`)"
        );
    }
    let cmd = command();
    #[cfg(feature = "train")]
    let (args, origins) = {
        let train = cmd.find_subcommand("train").cloned().unwrap_or_default();
        experiment::expand(args, &train)?
    };
    #[cfg(feature = "train")]
    let matches = cmd.try_get_matches_from(args).map_err(|e| experiment::name_recipe(e, &origins))?;
    #[cfg(not(feature = "train"))]
    let matches = cmd.try_get_matches_from(args)?;
    #[allow(unused_mut)]
    let mut cli = <Cli as clap::FromArgMatches>::from_arg_matches(&matches)?;
    #[cfg(feature = "train")]
    if let (Command::Train(a), Some(m)) = (&mut cli.command, matches.subcommand_matches("train")) {
        // What `train --resume` was given besides the run's directory (runs::bare_resume).
        a.given = m
            .ids()
            .filter(|id| m.value_source(id.as_str()) == Some(clap::parser::ValueSource::CommandLine))
            .map(|id| id.as_str().to_owned())
            .collect();
    }
    #[cfg(feature = "train")]
    if let (Command::Plot(a), Some(m)) = (&mut cli.command, matches.subcommand_matches("plot")) {
        // `plot --curve LABEL FILE...`, each occurrence its own curve.
        a.curves = m
            .get_occurrences::<String>("curve")
            .map(|o| o.map(|each| each.cloned().collect()).collect())
            .unwrap_or_default();
    }
    Ok(cli)
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
/// printed as clap prints them. Every command this build has: `blockpuzzle-train` and the Python
/// package's command call it.
pub fn run(args: Vec<std::ffi::OsString>) -> i32 {
    #[cfg(feature = "train")]
    return run_with(args, dispatch_training);
    #[cfg(not(feature = "train"))]
    run_with(args, |_| unreachable!("a build without `train` has no training command"))
}

/// [`run`] for the commands that need no training stack, which the `blockpuzzle` binary runs
/// itself (it links no libtorch, so it starts in milliseconds); it hands the others to
/// `blockpuzzle-train` ([`exec_training_half`]) before calling this.
#[cfg(feature = "train")]
pub fn run_core(args: Vec<std::ffi::OsString>) -> i32 {
    run_with(args, |command| {
        bail!("`{command:?}` runs in {TRAINING_BINARY}, not in this binary: start it through `blockpuzzle`")
    })
}

/// [`run`], the commands of the training stack run by `training` (what links the stack in).
fn run_with(args: Vec<std::ffi::OsString>, training: fn(Command) -> Result<()>) -> i32 {
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
    match dispatch(cli.command, training) {
        Ok(()) => 0,
        Err(e) => failed(e),
    }
}

/// Runs one parsed command: those of the training build that need libtorch
/// ([`halves::TRAINING_HALF`]: `info` reports its libraries) through `training`, every other one here.
fn dispatch(command: Command, training: fn(Command) -> Result<()>) -> Result<()> {
    #[cfg(not(feature = "train"))]
    let _ = training;
    match command {
        Command::Envs => envs(),
        #[cfg(not(feature = "train"))]
        Command::Info => info(),
        Command::Rollout(a) => episodes::rollout(a),
        Command::Demos(a) => episodes::demos(a),
        Command::Eval(a) => eval::eval(a),
        Command::Blend(a) => blend::run(a),
        Command::Render(a) => episodes::render(a),
        #[cfg(feature = "train")]
        Command::Zoo(c @ ZooCommand::Export(_)) => training(Command::Zoo(c)),
        Command::Zoo(c) => zoo::run(c),
        Command::Results(c) => results::run(c),
        Command::Table(a) => eval::table(a),
        Command::Task(TaskCommand::Check(a)) => task::check(a),
        Command::Task(TaskCommand::Generate(a)) => task::generate(a),
        #[cfg(feature = "serve")]
        Command::Serve(a) => serve::serve(a),
        Command::Scene { env } => {
            let c = registry::config(&env)?;
            // Its includes are relative to the assets folder: save it there to load it elsewhere.
            print!("{}", crate::sim::scene::mjcf(&c.scene_spec())?.0);
            Ok(())
        }
        // Commands of the training build that run no libtorch.
        #[cfg(feature = "train")]
        Command::Report { run_dirs, target } => runs::report(&run_dirs, target),
        #[cfg(feature = "train")]
        Command::Plot(a) => runs::plot(a),
        #[cfg(feature = "train")]
        Command::Align { reference, plot: None, bench_steps: Some(steps), threads } => {
            bench::align_bench(&reference, steps, threads)
        }
        #[cfg(feature = "train")]
        Command::Align { plot: Some(_), bench_steps: Some(_), .. } => {
            bail!("--plot draws the replay; leave it out with --bench-steps")
        }
        #[cfg(feature = "train")]
        Command::Align { reference, plot, .. } => bench::align(&reference, plot.as_deref()),
        #[cfg(feature = "train")]
        c @ (Command::Info | Command::Train(_) | Command::Bench(_)) => training(c),
    }
}

/// Runs a command of the training stack (what only `blockpuzzle-train` links).
#[cfg(feature = "train")]
fn dispatch_training(command: Command) -> Result<()> {
    match command {
        Command::Info => info(),
        Command::Train(a) => runs::train(a),
        Command::Zoo(ZooCommand::Export(a)) => zoo::run_export(a),
        Command::Bench(a) if a.train => bench::train(a),
        Command::Bench(a) => bench::run(&a),
        other => bail!("`{other:?}` is not a command of the training stack"),
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
fn info() -> Result<()> {
    println!("blockpuzzle {}", env!("CARGO_PKG_VERSION"));
    if let Some(commit) = crate::benchmark::provenance::commit() {
        println!("commit {commit}");
    }
    println!("MuJoCo {} (the engine every number this build writes is made on)", crate::sim::mj::version());
    // What libtorch's updates run with (the training build's concern).
    #[cfg(feature = "train")]
    {
        let var = |k: &str| std::env::var(k).unwrap_or_else(|_| "(unset)".into());
        println!("OpenBLAS kernels {}", crate::learn::blas::openblas_core().unwrap_or_else(|| "(not loaded)".into()));
        println!("OPENBLAS_CORETYPE={}", var("OPENBLAS_CORETYPE"));
        println!("OMP_WAIT_POLICY={}", var("OMP_WAIT_POLICY"));
    }
    println!("cores {}", std::thread::available_parallelism().map_or(1, |n| n.get()));
    #[cfg(feature = "train")]
    println!("bf16 updates {}", if crate::learn::agents::shared::Precision::bf16_supported() { "yes" } else { "no" });
    Ok(())
}
