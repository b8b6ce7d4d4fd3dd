//! `blockpuzzle task check`: a task file validated, its layouts sampled at every level and
//! distribution, optionally one reset state of each rendered; `task generate`: task files drawn
//! from a family and kept where the solver can play them.

use super::episodes::ViewArgs;
use crate::env::{registry, BlockEnv};
use anyhow::{bail, Context, Result};
use clap::Subcommand;
use std::path::PathBuf;

#[derive(Debug, Subcommand)]
pub(super) enum TaskCommand {
    /// Validate a task file (errors with file and line), reset it --samples
    /// times at every level and in every distribution, and print how often
    /// layouts were redrawn and why; --render writes a filmstrip of one reset
    /// state per level and distribution.
    Check(TaskCheckArgs),
    /// Generate task files from a task family file: --count tasks, one per generator seed from
    /// --seed on, each the first candidate the solver can play (success over the family's check
    /// episodes at least its threshold) and not decided at the first step; writes DIR/ID.toml per
    /// task and DIR/generated.json (hashes, the solver's success, rejections by reason).
    Generate(TaskGenerateArgs),
}

#[derive(Debug, clap::Args)]
pub(super) struct TaskGenerateArgs {
    /// A shipped family by name (push, gripper, stack, gather, topple, avoid, clutter, choose: `families/`) or a family file (.toml).
    family: String,
    /// The first generator seed (task k comes from seed + k, the same whatever --count).
    #[arg(long, default_value_t = 0, value_parser = crate::support::limits::SEED.parser::<u64>())]
    seed: u64,
    /// How many tasks (generator seeds).
    #[arg(long, default_value_t = 10, value_parser = crate::support::limits::GENERATE_COUNT.parser::<usize>())]
    count: usize,
    /// Output folder (made if missing).
    #[arg(long)]
    out: PathBuf,
    /// Threads checking candidates (default: one per core); the tasks do not depend on it.
    #[arg(long, value_parser = crate::support::limits::THREADS.parser::<usize>())]
    threads: Option<usize>,
}

#[derive(Debug, clap::Args)]
pub(super) struct TaskCheckArgs {
    /// Task file (.toml) or registered id.
    file: String,
    /// Resets per level and distribution.
    #[arg(long, default_value_t = 100, value_parser = crate::support::limits::CHECK_SAMPLES.parser::<u64>())]
    samples: u64,
    /// Seed of the first reset (reset k uses seed + k).
    #[arg(long, default_value_t = 0, value_parser = crate::support::limits::SEED.parser::<u64>())]
    seed: u64,
    /// Filmstrip PNG of one reset state per level and distribution.
    #[arg(long)]
    render: Option<PathBuf>,
    #[command(flatten)]
    view: ViewArgs,
}

/// `blockpuzzle task generate`.
pub(super) fn generate(a: TaskGenerateArgs) -> Result<()> {
    crate::support::limits::seed_range(a.seed, a.count as u64).map_err(anyhow::Error::msg)?;
    let family = crate::task::family::Family::load(&a.family, None)?;
    crate::episode::generate::check_outputs(&a.out, &family, a.seed, a.count).context("--out")?;
    let threads = a.threads.unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
    // The seeds as people read them, first to last (`seed + count` may pass the largest seed).
    let seeds = match a.count {
        1 => format!("seed {}", a.seed),
        n => format!("seeds {} to {}", a.seed, a.seed + (n as u64 - 1)),
    };
    let results = crate::episode::generate::generate(&family, a.seed, a.count, threads).map_err(anyhow::Error::msg)?;
    let kept: Vec<&crate::episode::generate::Generated> = results.iter().filter_map(|r| r.task.as_ref()).collect();
    let missing: Vec<u64> = results.iter().filter(|r| r.task.is_none()).map(|r| r.seed).collect();
    let rejected = crate::episode::generate::rejections(&results);
    if kept.is_empty() {
        // Nothing to write: an error, naming each reason with its first message, and nothing written.
        let examples = crate::episode::generate::examples(&results);
        let reasons: Vec<String> = rejected
            .iter()
            .map(|(why, n)| match examples.get(why) {
                Some(e) => format!("{n} {why} (first: {})", crate::support::limits::cut_long_lines(e)),
                None => format!("{n} {why}"),
            })
            .collect();
        bail!(
            "{}: no task from {seeds}, and nothing was written: every candidate was rejected ({}). Fix the family \
             where a candidate does not compile or build; else loosen its ranges or its [check]",
            a.family,
            reasons.join("; ")
        );
    }
    crate::episode::generate::write_folder(
        &a.out,
        &family,
        &a.family,
        a.seed,
        &results,
        &crate::benchmark::provenance::Build::current(),
    )?;
    println!(
        "{}: {} of {} seeds gave a task ({seeds}), written to {}",
        family.spec.family,
        kept.len(),
        a.count,
        a.out.display()
    );
    let tried: usize = rejected.values().sum::<usize>() + kept.len();
    println!("candidates tried {tried}, rejected {}:", tried - kept.len());
    let examples = crate::episode::generate::examples(&results);
    for (why, n) in &rejected {
        println!("  {n:>5}  {why}");
        if let Some(e) = examples.get(why) {
            println!("         e.g. {}", crate::support::limits::cut_long_lines(e));
        }
    }
    if !missing.is_empty() {
        println!(
            "no task within {} candidates for seeds {:?}: loosen the family's ranges or its check",
            family.spec.check.max_candidates, missing
        );
    } else if let Some(end) = a.seed.checked_add(a.count as u64) {
        // The suite row that holds these tasks on every engine and build (docs/suites.md).
        let pins: Vec<String> = kept.iter().map(|t| t.candidate.to_string()).collect();
        let quoted = |s: &str| toml::Value::String(s.to_owned()).to_string();
        println!(
            "a suite row holding these tasks on every engine and build (docs/suites.md):\n  family = {}\n  \
             generator_seeds = [{}, {end}]\n  candidates = [{}]\n  family_sha256 = {}",
            quoted(&a.family),
            a.seed,
            pins.join(", "),
            quoted(&family.hash)
        );
    }
    Ok(())
}

/// `blockpuzzle task check`.
pub(super) fn check(a: TaskCheckArgs) -> Result<()> {
    if let Some(out) = &a.render {
        if out.extension().map_or(true, |e| !e.eq_ignore_ascii_case("png")) {
            bail!("--render writes a filmstrip PNG: give a FILE.png");
        }
        crate::support::io::check_output(out)?;
        a.view.view()?;
    }
    let task = registry::task(&a.file)?;
    let bar = crate::support::progress::bar(crate::episode::check::settings(&task).len() as u64 * a.samples, "reset");
    let report = crate::episode::check::check(task, a.samples, a.seed, &mut || bar.inc(1))?;
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
        for (label, level, distribution) in crate::episode::check::settings(task) {
            env.set_level(level)?;
            env.set_distribution(distribution.as_deref())?;
            if env.reset(Some(a.seed)).is_err() {
                continue;
            }
            renderer.colour_env(&env)?;
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
