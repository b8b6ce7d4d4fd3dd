//! `blockpuzzle task check`: a task file validated, its layouts sampled at every level and
//! distribution, optionally one reset state of each rendered.

use super::episodes::ViewArgs;
use crate::env::{registry, BlockEnv};
use anyhow::{bail, Result};
use clap::Subcommand;
use std::path::PathBuf;

#[derive(Debug, Subcommand)]
pub(super) enum TaskCommand {
    /// Validate a task file (errors with file and line), reset it --samples
    /// times at every level and in every distribution, and print how often
    /// layouts were redrawn and why; --render writes a filmstrip of one reset
    /// state per level and distribution.
    Check(TaskCheckArgs),
}

#[derive(Debug, clap::Args)]
pub(super) struct TaskCheckArgs {
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

/// `blockpuzzle task check`.
pub(super) fn check(a: TaskCheckArgs) -> Result<()> {
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
