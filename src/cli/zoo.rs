//! `blockpuzzle zoo`: list, check and export the shipped policies (src/benchmark/zoo.rs has the format).

use crate::benchmark::saved::Trainer;
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
    /// Rewrite entries of an older format in this one (format 7: what the policy is, its
    /// observation, the algorithm that trained it), sealed with their metadata's hash, after
    /// checking that they load; the tensors stay as they are.
    Upgrade {
        /// Entries to upgrade (default: all).
        names: Vec<String>,
        /// The zoo folder.
        #[arg(long)]
        zoo: Option<PathBuf>,
        /// Record the algorithm that trained them (bc, dagger, ddpg, td3, sac, pggd) where they
        /// record none (older entries say `unrecorded`).
        #[arg(long)]
        algo: Option<Trainer>,
        /// Record the policy they were fine-tuned from (a zoo name, run directory or policy file),
        /// where they record none (entries exported before `train --init-from` recorded it); it
        /// must have their network's layers.
        #[arg(long, value_name = "POLICY")]
        started_from: Option<PathBuf>,
        /// Record the version of the solver whose actions they learned from (BC, DAgger, runs with
        /// `--demos`), where they record none (entries exported before policy files recorded it).
        #[arg(long, value_name = "VERSION")]
        solver: Option<u32>,
    },
    /// Replace an entry's description (one line on what it is; figures belong in its evaluations
    /// and results/, and are refused), resealed.
    Describe {
        /// The entry.
        name: String,
        /// The new description.
        #[arg(long)]
        description: String,
        /// The zoo folder.
        #[arg(long)]
        zoo: Option<PathBuf>,
    },
    /// Write a trained policy as a zoo entry (NAME.safetensors + NAME.json).
    #[cfg(feature = "train")]
    Export(ZooExportArgs),
    /// Evaluate entries on this build's engine and record the results in their metadata: each
    /// evaluation the entry records (task, distribution, episodes, seeds) is played again here
    /// and kept beside the other engines' records (`zoo list` shows this engine's).
    Evaluate {
        /// Entries to evaluate (default: all).
        names: Vec<String>,
        /// The zoo folder.
        #[arg(long)]
        zoo: Option<PathBuf>,
        /// Threads playing episodes (default: all cores); the result does not depend on it.
        #[arg(long, value_parser = crate::support::limits::THREADS.parser::<usize>())]
        threads: Option<usize>,
    },
}

#[cfg(feature = "train")]
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
    /// The algorithm that trained it (bc, dagger, ddpg, td3, sac, pggd), where the policy file does
    /// not record it (runs before it was recorded).
    #[arg(long)]
    algo: Option<Trainer>,
    /// Evaluation results (JSON written by `blockpuzzle eval`) to record with it.
    #[arg(long = "eval")]
    evals: Vec<PathBuf>,
    /// Evaluate it first on this many episodes (seeds 1,000,000 on) at the
    /// maximum level and, where the task has one, in the challenge distribution,
    /// and record the results (0: no evaluation).
    #[arg(long, default_value_t = 0, value_parser = crate::support::limits::EXPORT_EPISODES.parser::<usize>())]
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
    let folder = |z: Option<PathBuf>| z.unwrap_or_else(crate::benchmark::zoo::dir);
    match c {
        ZooCommand::List { zoo } => list(&folder(zoo)),
        ZooCommand::Check { names, zoo } => check(&folder(zoo), names),
        ZooCommand::Upgrade { names, zoo, algo, started_from, solver } => {
            upgrade(&folder(zoo), names, Records { algo, started_from: started_from.as_deref(), solver })
        }
        ZooCommand::Evaluate { names, zoo, threads } => evaluate_entries(&folder(zoo), names, threads),
        ZooCommand::Describe { name, description, zoo } => describe(&folder(zoo), &name, &description),
        // The training stack's (it reads checkpoints with libtorch): `blockpuzzle-train` runs it.
        #[cfg(feature = "train")]
        ZooCommand::Export(_) => anyhow::bail!("`zoo export` runs in {}", super::TRAINING_BINARY),
    }
}

/// Runs `blockpuzzle zoo export` (the training stack's part of `zoo`).
#[cfg(feature = "train")]
pub(super) fn run_export(a: ZooExportArgs) -> Result<()> {
    export(&a.zoo.clone().unwrap_or_else(crate::benchmark::zoo::dir), a)
}

/// `zoo list`: every entry, with its evaluations on this build's engine.
fn list(zoo: &Path) -> Result<()> {
    crate::benchmark::zoo::existing(zoo)?;
    let names = crate::benchmark::zoo::names(zoo);
    if names.is_empty() {
        println!("the zoo in {} has no entries", zoo.display());
    }
    for name in names {
        let meta = crate::benchmark::zoo::read_meta(&zoo.join(format!("{name}.json")))?;
        let steps = meta.env_steps.map_or("?".into(), |s| format!("{:.2}M", s as f64 / 1e6));
        let solver = meta.solver.map_or_else(String::new, |v| format!(" of solver version {v}"));
        println!(
            "{name:<36} {:<24} {}{solver} epoch {:>3}, {steps} env steps",
            meta.trained_on(),
            meta.trained_by().map_or("(algorithm unrecorded)", Trainer::name),
            meta.epoch
        );
        println!("    {}", meta.description);
        // Numbers of different engines differ: this build's engine's only, the others counted.
        let engine = crate::sim::mj::version();
        let others: std::collections::BTreeSet<String> = meta
            .evaluations
            .iter()
            .filter(|e| e.mujoco() != Some(engine.as_str()))
            .map(|e| e.mujoco().map_or_else(|| "ones that name no engine".to_owned(), |m| format!("MuJoCo {m}")))
            .collect();
        if !others.is_empty() {
            println!(
                "    (evaluations on MuJoCo {engine} below; {name}.json also has {})",
                others.into_iter().collect::<Vec<_>>().join(", ")
            );
        }
        for e in meta.evaluations.iter().filter(|e| e.mujoco() == Some(engine.as_str())) {
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

/// `zoo check`: each named entry (every one by default) loads with all its checks.
fn check(zoo: &Path, names: Vec<String>) -> Result<()> {
    crate::benchmark::zoo::existing(zoo)?;
    let names = if names.is_empty() { crate::benchmark::zoo::names(zoo) } else { names };
    if names.is_empty() {
        bail!("no zoo entries in {}", zoo.display());
    }
    for name in &names {
        let (meta, _) = crate::benchmark::zoo::load(&crate::benchmark::zoo::find_named(zoo, name, "check")?)?;
        println!(
            "{name}: ok ({} {}, epoch {})",
            meta.trained_on(),
            meta.trained_by().map_or("(algorithm unrecorded)", Trainer::name),
            meta.epoch
        );
    }
    Ok(())
}

/// What `zoo upgrade` records where an entry records none.
struct Records<'a> {
    algo: Option<Trainer>,
    started_from: Option<&'a Path>,
    solver: Option<u32>,
}

/// `zoo upgrade`: entries rewritten in this format and sealed, with the records given.
fn upgrade(zoo: &Path, names: Vec<String>, records: Records<'_>) -> Result<()> {
    crate::benchmark::zoo::existing(zoo)?;
    if records.started_from.is_some() && names.is_empty() {
        bail!("--started-from records one start: name the entries fine-tuned from it");
    }
    if records.solver.is_some() && names.is_empty() {
        bail!("--solver records the solver one policy learned from: name the entries that learned from it");
    }
    let start = match records.started_from {
        Some(p) => {
            let saved =
                crate::benchmark::load::load_policy(p).with_context(|| format!("--started-from {}", p.display()))?;
            let id = saved.policy_id(&p.display().to_string());
            Some((saved, id))
        }
        None => None,
    };
    let names = if names.is_empty() { crate::benchmark::zoo::names(zoo) } else { names };
    for name in &names {
        let path = crate::benchmark::zoo::find_named(zoo, name, "upgrade")?;
        let before = crate::benchmark::zoo::read_meta(&path)?.format;
        let started_from = start.as_ref().map(|(saved, id)| (saved, id.clone()));
        crate::benchmark::zoo::upgrade(
            &path,
            crate::benchmark::zoo::Upgrade { algo: records.algo, solver: records.solver, started_from },
        )?;
        let after = crate::benchmark::zoo::read_meta(&path)?;
        let by = after.algo.map_or(crate::benchmark::zoo::UNRECORDED, Trainer::name);
        println!("{name}: {before} -> {}, sealed, trained by {by}", after.format);
    }
    Ok(())
}

/// `zoo describe`: an entry's description replaced, resealed.
fn describe(zoo: &Path, name: &str, description: &str) -> Result<()> {
    crate::benchmark::zoo::existing(zoo)?;
    let path = crate::benchmark::zoo::find_named(zoo, name, "describe")?;
    crate::benchmark::zoo::describe(&path, description)?;
    println!("{name}: described, sealed");
    Ok(())
}

#[cfg(feature = "train")]
/// `zoo export`: a trained policy written as an entry, with its evaluations.
fn export(zoo: &Path, a: ZooExportArgs) -> Result<()> {
    if a.evaluate == 0 && !a.evaluate_envs.is_empty() {
        bail!("--evaluate-env needs --evaluate N (the episodes per evaluation)");
    }
    // Before the evaluations, which may take long.
    crate::benchmark::zoo::entry_free(zoo, &a.name, a.force)?;
    if let Some(figure) = crate::benchmark::zoo::figure_in(&a.description) {
        return Err(crate::benchmark::zoo::ZooError::FigureInDescription { figure }.into());
    }
    let saved = exported_policy(&a.from)?;
    let mut evaluations = Vec::new();
    for path in &a.evals {
        evaluations.push(read_eval(path)?);
    }
    if a.evaluate > 0 && a.evaluate_envs.is_empty() && saved.is_multi_task() {
        bail!(
            "{} was trained on several tasks ({}) and holds no one task to evaluate on: name them with \
             --evaluate-env ID (repeatable)",
            a.from.display(),
            saved.env_id
        );
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
            let spec = crate::benchmark::evaluate::EvalSpec {
                distribution: None,
                task: &task,
                challenge,
                level: None,
                episodes: a.evaluate,
                seed: crate::benchmark::evaluate::TEST_SEED,
                threads,
            };
            let provenance = crate::benchmark::provenance::Provenance::new(
                crate::benchmark::provenance::Harness::Cli,
                saved.policy_id(&a.name),
                None,
            );
            let e = crate::benchmark::evaluate::evaluate(&a.from, saved.clone(), &spec)?;
            let r = crate::benchmark::zoo::ZooEvaluation::new(e, provenance);
            eprintln!("{} {}: {:.3}", r.env, r.distribution, r.success_rate);
            evaluations.push(r);
        }
    }
    let info = crate::benchmark::zoo::ExportInfo {
        name: a.name.clone(),
        description: a.description,
        trained_with: a.trained_with,
        exported_from: a.from.display().to_string(),
        env_steps: saved.env_steps.or_else(|| env_steps_of(&a.from, saved.epoch)),
        evaluations,
        keep_critic: a.critic,
        overwrite: a.force,
        algo: a.algo,
    };
    let out = crate::benchmark::zoo::export(zoo, &saved, &info)?;
    let size = std::fs::metadata(&out).map_or(0, |m| m.len());
    println!("wrote {} ({:.0} kB) and its .json", out.display(), size as f64 / 1e3);
    Ok(())
}

#[cfg(feature = "train")]
/// An evaluation written by `blockpuzzle eval`, as a zoo record.
fn read_eval(path: &Path) -> Result<crate::benchmark::zoo::ZooEvaluation> {
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
        outcomes: Option<crate::episode::outcome::Outcomes>,
        #[serde(default)]
        task_sha256: Option<String>,
        #[serde(default)]
        provenance: Option<crate::benchmark::provenance::Provenance>,
    }
    let text = crate::support::io::read_text(path, "evaluation file", crate::support::limits::RESULT_FILE_BYTES)
        .with_context(|| format!("cannot read evaluation {}", path.display()))?;
    let w: Written = serde_json::from_str(&text).with_context(|| {
        // A suite's result is the likeliest other file: say what --eval takes instead.
        let suite = serde_json::from_str::<serde_json::Value>(&text).is_ok_and(|v| v.get("suite").is_some());
        let what = if suite { " (it is a suite's result, `eval --suite`)" } else { "" };
        format!(
            "{} is not the result of one task's evaluation{what}; --eval takes the file `blockpuzzle eval \
             --checkpoint POLICY --env TASK --episodes N` writes",
            path.display()
        )
    })?;
    Ok(crate::benchmark::zoo::ZooEvaluation {
        env: w.env,
        distribution: if w.challenge { "challenge" } else { "normal" }.into(),
        grey_blind: w.grey_blind,
        episodes: w.episodes,
        seed: w.seed,
        success_rate: w.success_rate,
        ci95: w.ci95,
        outcomes: w.outcomes,
        task_sha256: w.task_sha256,
        provenance: w.provenance,
    })
}

/// `zoo evaluate`: every recorded measurement of the entries, played on this build's engine.
fn evaluate_entries(zoo: &Path, names: Vec<String>, threads: Option<usize>) -> Result<()> {
    crate::benchmark::zoo::existing(zoo)?;
    let names = if names.is_empty() { crate::benchmark::zoo::names(zoo) } else { names };
    if names.is_empty() {
        bail!("no zoo entries in {}", zoo.display());
    }
    let threads = threads.unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
    for name in &names {
        let path = crate::benchmark::zoo::find_named(zoo, name, "evaluate")?;
        let (meta, saved) = crate::benchmark::zoo::load(&path)?;
        // Each measurement once (an entry may hold it for several engines).
        let mut wanted: Vec<&crate::benchmark::zoo::ZooEvaluation> = Vec::new();
        let key =
            |r: &crate::benchmark::zoo::ZooEvaluation| (r.env.clone(), r.distribution.clone(), r.episodes, r.seed);
        for e in &meta.evaluations {
            if !wanted.iter().any(|w| key(w) == key(e)) {
                wanted.push(e);
            }
        }
        let mut fresh = Vec::new();
        for w in wanted {
            let env = (w.env != saved.env_id).then_some(w.env.as_str());
            let task = super::policy_task(env, &saved)?;
            if !matches!(w.distribution.as_str(), "normal" | "challenge") {
                bail!(
                    "{name}: evaluation on distribution {:?}: zoo evaluations are normal or challenge",
                    w.distribution
                );
            }
            let spec = crate::benchmark::evaluate::EvalSpec {
                task: &task,
                challenge: w.distribution == "challenge",
                distribution: None,
                level: None,
                episodes: w.episodes,
                seed: w.seed,
                threads,
            };
            let provenance = crate::benchmark::provenance::Provenance::new(
                crate::benchmark::provenance::Harness::Cli,
                saved.policy_id(name),
                None,
            );
            let e = crate::benchmark::evaluate::evaluate(Path::new(name), saved.clone(), &spec)?;
            let r = crate::benchmark::zoo::ZooEvaluation::new(e, provenance);
            println!(
                "{name} {} {} on MuJoCo {}: {:.3} ({}/{})",
                r.env,
                r.distribution,
                crate::sim::mj::version(),
                r.success_rate,
                r.outcomes.map_or(0, |o| o.success),
                r.episodes
            );
            fresh.push(r);
        }
        let what = crate::benchmark::zoo::record_evaluations(&path, fresh)?;
        for w in what.iter().filter(|w| **w == crate::benchmark::zoo::Recorded::Disagrees) {
            println!("    {w:?}: a record naming no engine has other numbers; it is kept beside this engine's");
        }
    }
    Ok(())
}

/// The policy `zoo export --from` names: a policy file, run directory or zoo name; or a run carried
/// without its policy files (checkpoint.bin, config.json and progress.csv, as
/// `experiments/generalist/state/` keeps them), whose checkpoint gives the policy it wrote then.
#[cfg(feature = "train")]
fn exported_policy(from: &std::path::Path) -> Result<crate::benchmark::saved::SavedPolicy> {
    use crate::benchmark::saved::{BEST_POLICY_FILE, POLICY_FILE};
    let carried = from.is_dir()
        && !from.join(BEST_POLICY_FILE).exists()
        && !from.join(POLICY_FILE).exists()
        && from.join("checkpoint.bin").is_file();
    if carried {
        return crate::learn::train::policy_from_checkpoint(from)
            .with_context(|| format!("--from {}: the policy of its checkpoint", from.display()));
    }
    Ok(crate::benchmark::load::load_policy(from)?)
}

#[cfg(feature = "train")]
/// Environment steps behind a policy of `epoch` epochs: from the
/// `progress.csv` of its run (the policy's folder, or the run of a snapshot).
fn env_steps_of(policy: &Path, epoch: usize) -> Option<u64> {
    let dir = if policy.is_dir() { policy.to_path_buf() } else { policy.parent()?.to_path_buf() };
    [dir.clone(), dir.parent()?.to_path_buf()].into_iter().find_map(|d| {
        let rows = crate::learn::train::read_progress(&d.join("progress.csv")).ok()?;
        rows.iter().find(|r| r.epoch + 1 == epoch).map(|r| r.env_steps)
    })
}

/// `--algo`'s values: the trainers' recorded names.
impl clap::ValueEnum for Trainer {
    fn value_variants<'a>() -> &'a [Self] {
        &Trainer::ALL
    }

    fn to_possible_value(&self) -> Option<clap::builder::PossibleValue> {
        Some(clap::builder::PossibleValue::new(self.name()))
    }
}
