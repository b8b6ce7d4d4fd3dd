//! `blockpuzzle zoo`: list, check and export the shipped policies (src/zoo.rs has the format).

use anyhow::{bail, Context, Result};
use clap::Subcommand;
use std::path::{Path, PathBuf};

#[derive(Debug, Subcommand)]
pub(super) enum ZooCommand {
    /// The entries: name, task, algorithm, epoch, environment steps, evaluations.
    List {
        /// The zoo folder (default: $BLOCKPUZZLE_ZOO, else zoo/ of this repository).
        #[arg(long)]
        zoo: Option<PathBuf>,
    },
    /// Load every entry (or the named ones) and check checksums, layouts and values.
    Check {
        /// Entries to check (default: all).
        names: Vec<String>,
        /// The zoo folder.
        #[arg(long)]
        zoo: Option<PathBuf>,
    },
    /// Write a trained policy as a zoo entry (NAME.safetensors + NAME.json).
    Export(ZooExportArgs),
}

#[derive(Debug, clap::Args)]
pub(super) struct ZooExportArgs {
    /// The policy: a policy file, a snapshot, or a run directory.
    #[arg(long)]
    from: PathBuf,
    /// The entry's name (file stem), e.g. BlocksChoose-v0-ddpg.
    #[arg(long)]
    name: String,
    /// One line on what it is.
    #[arg(long)]
    description: String,
    /// The command that trained it (recorded as given).
    #[arg(long)]
    trained_with: String,
    /// Evaluation results (JSON written by `blockpuzzle eval`) to record with it.
    #[arg(long = "eval")]
    evals: Vec<PathBuf>,
    /// Evaluate it first on this many episodes (seeds 1,000,000 on) at the
    /// maximum level and, where the task has one, in the challenge distribution,
    /// and record the results (0: no evaluation).
    #[arg(long, default_value_t = 0, value_parser = crate::limits::EXPORT_EPISODES.parser::<usize>())]
    evaluate: usize,
    /// The tasks to evaluate on, repeatable (default: the one it was trained on;
    /// e.g. BlocksChoose-v0 for the 2-block expert, which then sees no grey block).
    #[arg(long = "evaluate-env")]
    evaluate_envs: Vec<String>,
    /// Keep DDPG's critic too (for AggreVaTeD's --pg-weight expert-advantage).
    #[arg(long)]
    critic: bool,
    /// The zoo folder.
    #[arg(long)]
    zoo: Option<PathBuf>,
    /// Replace an existing entry of the same name.
    #[arg(long)]
    force: bool,
}

/// Runs a `blockpuzzle zoo` subcommand.
pub(super) fn run(c: ZooCommand) -> Result<()> {
    let folder = |z: Option<PathBuf>| z.unwrap_or_else(crate::zoo::dir);
    match c {
        ZooCommand::List { zoo } => {
            let zoo = folder(zoo);
            crate::zoo::existing(&zoo)?;
            let names = crate::zoo::names(&zoo);
            if names.is_empty() {
                println!("the zoo in {} has no entries", zoo.display());
            }
            for name in names {
                let meta = crate::zoo::read_meta(&zoo.join(format!("{name}.json")))?;
                let steps = meta.env_steps.map_or("?".into(), |s| format!("{:.2}M", s as f64 / 1e6));
                println!("{name:<36} {:<24} {} epoch {:>3}, {steps} env steps", meta.task.id, meta.algo, meta.epoch);
                println!("    {}", meta.description);
                for e in &meta.evaluations {
                    println!(
                        "    {} {}{}: {:.3} ({:.3}-{:.3}), {} episodes from seed {}",
                        e.env,
                        e.distribution,
                        if e.grey_blind { ", grey removed" } else { "" },
                        e.success_rate,
                        e.ci95.0,
                        e.ci95.1,
                        e.episodes,
                        e.seed
                    );
                    if let Some(o) = &e.outcomes {
                        println!("        the others: {}", o.summary());
                    }
                }
            }
            Ok(())
        }
        ZooCommand::Check { names, zoo } => {
            let zoo = folder(zoo);
            crate::zoo::existing(&zoo)?;
            let names = if names.is_empty() { crate::zoo::names(&zoo) } else { names };
            if names.is_empty() {
                bail!("no zoo entries in {}", zoo.display());
            }
            for name in &names {
                let (meta, _) = crate::zoo::load(&crate::zoo::find(&zoo, name)?)?;
                println!("{name}: ok ({} {}, epoch {})", meta.task.id, meta.algo, meta.epoch);
            }
            Ok(())
        }
        ZooCommand::Export(a) => {
            if a.evaluate == 0 && !a.evaluate_envs.is_empty() {
                bail!("--evaluate-env needs --evaluate N (the episodes per evaluation)");
            }
            let zoo = folder(a.zoo);
            // Before the evaluations, which may take long.
            crate::zoo::entry_free(&zoo, &a.name, a.force)?;
            let saved = crate::load::load_policy(&a.from)?;
            let mut evaluations = Vec::new();
            for path in &a.evals {
                evaluations.push(read_eval(path)?);
            }
            let envs: Vec<Option<&str>> = if a.evaluate_envs.is_empty() {
                vec![None]
            } else {
                a.evaluate_envs.iter().map(|e| Some(e.as_str())).collect()
            };
            for env in envs.into_iter().filter(|_| a.evaluate > 0) {
                let task = super::policy_task(env, &saved)?;
                let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
                let has_challenge = task.distribution("challenge").is_some();
                for challenge in [false, true].into_iter().filter(|&c| !c || has_challenge) {
                    let spec = crate::evaluate::EvalSpec {
                        distribution: None,
                        task: &task,
                        challenge,
                        level: None,
                        episodes: a.evaluate,
                        seed: crate::evaluate::TEST_SEED,
                        threads,
                    };
                    let r = crate::zoo::ZooEvaluation::from(crate::evaluate::evaluate(&a.from, saved.clone(), &spec)?);
                    eprintln!("{} {}: {:.3}", r.env, r.distribution, r.success_rate);
                    evaluations.push(r);
                }
            }
            let info = crate::zoo::ExportInfo {
                name: a.name.clone(),
                description: a.description,
                trained_with: a.trained_with,
                exported_from: a.from.display().to_string(),
                env_steps: saved.env_steps.or_else(|| env_steps_of(&a.from, saved.epoch)),
                evaluations,
                keep_critic: a.critic,
                overwrite: a.force,
            };
            let out = crate::zoo::export(&zoo, &saved, &info)?;
            let size = std::fs::metadata(&out).map_or(0, |m| m.len());
            println!("wrote {} ({:.0} kB) and its .json", out.display(), size as f64 / 1e3);
            Ok(())
        }
    }
}

/// An evaluation written by `blockpuzzle eval`, as a zoo record.
fn read_eval(path: &Path) -> Result<crate::zoo::ZooEvaluation> {
    #[derive(serde::Deserialize)]
    struct Written {
        env: String,
        challenge: bool,
        episodes: usize,
        seed: u64,
        success_rate: f64,
        ci95: (f64, f64),
        grey_blind: bool,
        #[serde(default)]
        outcomes: Option<crate::outcome::Outcomes>,
    }
    let text = std::fs::read_to_string(path).with_context(|| format!("cannot read evaluation {}", path.display()))?;
    let w: Written = serde_json::from_str(&text)
        .with_context(|| format!("{} is not an evaluation written by `blockpuzzle eval`", path.display()))?;
    Ok(crate::zoo::ZooEvaluation {
        env: w.env,
        distribution: if w.challenge { "challenge" } else { "normal" }.into(),
        grey_blind: w.grey_blind,
        episodes: w.episodes,
        seed: w.seed,
        success_rate: w.success_rate,
        ci95: w.ci95,
        outcomes: w.outcomes,
    })
}

/// Environment steps behind a policy of `epoch` epochs: from the
/// `progress.csv` of its run (the policy's folder, or the run of a snapshot).
fn env_steps_of(policy: &Path, epoch: usize) -> Option<u64> {
    let dir = if policy.is_dir() { policy.to_path_buf() } else { policy.parent()?.to_path_buf() };
    [dir.clone(), dir.parent()?.to_path_buf()].into_iter().find_map(|d| {
        let rows = crate::train::read_progress(&d.join("progress.csv")).ok()?;
        rows.iter().find(|r| r.epoch + 1 == epoch).map(|r| r.env_steps)
    })
}
