//! Runs: `blockpuzzle train` (one process or an MPI rank; resume and branch),
//! and `plot` and `report`, which read a run directory's files.

use anyhow::{bail, Context, Result};
use std::path::{Path, PathBuf};

use crate::env::registry;

#[derive(Debug, clap::Args)]
pub(super) struct TrainArgs {
    /// An experiment recipe: a TOML file of these flags (`epochs = 500`,
    /// `td3 = true`), e.g. experiments/ddpg3.toml; flags given here win over it.
    // Expanded before parsing (cli/experiment.rs): the field is here for --help.
    #[arg(long = "config", id = "recipe", value_name = "FILE")]
    _recipe: Option<PathBuf>,
    /// Run directory (config.json, progress.csv, checkpoints); default runs/TASK-METHOD-sSEED
    /// (e.g. runs/BlocksChoose-v0-pggd-aggrevated-s0; a task file's stem for TASK).
    #[arg(long)]
    run_dir: Option<PathBuf>,
    /// Continue the run in --run-dir from its last checkpoint. With no other flag but --epochs,
    /// --torch-threads and --snapshot-every, the run's own settings (its config.json) are used;
    /// with more (a recipe, say), they must match the run's.
    #[arg(long)]
    resume: bool,
    /// With --resume: continue a run whose replay log is not there (a run carried to another
    /// machine with its checkpoint, config.json and progress.csv). Where the solver played every
    /// stored transition at level 0 (behaviour cloning), the buffers are collected again from the
    /// run's seeds and the run continues exactly; otherwise they start empty and refill, and
    /// provenance.json records it.
    #[arg(long, requires = "resume")]
    rebuild_replay: bool,
    /// Start --run-dir (new) from this run directory's latest checkpoint, with
    /// the settings given here; only --level-replay, --challenge-share,
    /// --success-threshold, --batches, --random-eps, --noise-eps,
    /// --noise-correlation, --action-l2, --preact-l2, --preact-margin, --anchor-alpha and --ibrl may differ
    /// from the parent's (and --epochs, the total to reach). The parent stays as it is.
    #[arg(long, value_name = "RUN_DIR", conflicts_with = "resume", requires = "run_dir")]
    branch_from: Option<PathBuf>,
    #[command(flatten)]
    config: crate::learn::train::TrainConfig,
    /// The ids of the flags given on the command line (a recipe's included), filled in by `parse`.
    #[arg(skip)]
    pub(super) given: Vec<String>,
}

/// The flags `train --resume --run-dir DIR` may be given without restating the run's recipe: with
/// only these, the other settings come from the run's `config.json`.
const BARE_RESUME: &[&str] = &["run_dir", "resume", "rebuild_replay", "epochs", "torch_threads", "snapshot_every"];

/// The settings of `train --resume --run-dir DIR` given nothing but [`BARE_RESUME`]'s flags: the
/// run's recorded ones, with those flags' values. `None` for any other command line.
///
/// # Errors
/// A directory without a `config.json` or one that cannot be read as a run's settings; a resume
/// given other flags but not the run's task.
fn bare_resume(a: &TrainArgs) -> Result<Option<crate::learn::train::TrainConfig>> {
    let names_task = a.given.iter().any(|g| ["env", "suite", "families"].contains(&g.as_str()));
    if a.resume && a.run_dir.is_none() && !names_task {
        bail!(
            "train --resume continues the run in --run-dir: give --run-dir DIR (the run's settings then come \
             from DIR/config.json), or the run's own settings, --env included, to resume its default directory"
        );
    }
    let (true, Some(dir)) = (a.resume, &a.run_dir) else { return Ok(None) };
    if a.given.iter().any(|g| !BARE_RESUME.contains(&g.as_str())) {
        if !names_task {
            bail!(
                "train --resume given {} besides --run-dir must restate the run's settings, its task \
                 included: give its --env, --suite or --families (or its recipe, --config), or leave out \
                 every flag but --epochs, --torch-threads, --snapshot-every and --rebuild-replay to take the run's own",
                a.given
                    .iter()
                    .filter(|g| !BARE_RESUME.contains(&g.as_str()))
                    .map(|g| format!("--{}", g.replace('_', "-")))
                    .collect::<Vec<_>>()
                    .join(", ")
            );
        }
        return Ok(None);
    }
    let run = crate::learn::train::RunDir { dir: dir.clone() };
    if !run.config().exists() {
        bail!(
            "--resume: {} holds no run (no {}); start a new run without --resume, with its task and settings",
            dir.display(),
            run.config().display()
        );
    }
    let mut c = run.read_config()?;
    for g in &a.given {
        match g.as_str() {
            "epochs" => c.epochs = a.config.epochs,
            "torch_threads" => c.torch_threads = a.config.torch_threads,
            "snapshot_every" => c.snapshot_every = a.config.snapshot_every,
            _ => {}
        }
    }
    Ok(Some(c))
}

#[derive(Debug, clap::Args)]
#[command(group(clap::ArgGroup::new("what").required(true).args(["run_dir", "overlay", "scaling", "curve"])))]
pub(super) struct PlotArgs {
    /// Run directory whose success.png to redraw.
    #[arg(long)]
    run_dir: Option<PathBuf>,
    /// Run directories whose finals success to draw in one figure (needs --out);
    /// a CSV file instead of a directory is another trainer's log with the
    /// columns epoch, time/env_steps and finals/success (python -m blockpuzzle.examples.sb3_td3).
    #[arg(long, num_args = 1.., requires = "out")]
    overlay: Vec<PathBuf>,
    /// Legend labels of the --overlay curves, in order (default: from each run's config, or the file name).
    #[arg(long, num_args = 1..)]
    labels: Vec<String>,
    /// Suite results (JSON of `eval --suite`) as `X:FILE`, drawn as train and test success against
    /// X on a logarithmic axis (needs --out), e.g. `--scaling 21:curve-21-s0.json 70:curve-70-s0.json`
    /// for success against the number of training tasks; a table of the points goes to stdout.
    #[arg(long, num_args = 1.., requires = "out", conflicts_with = "overlay")]
    scaling: Vec<String>,
    /// Suite results (JSON of `eval --suite`, e.g. of a run's snapshots) as `--curve LABEL FILE...`,
    /// drawn as one curve of test success against the env steps each policy had trained for, with
    /// 95% Wilson intervals; repeat for more curves (needs --out). Every result and --level must be
    /// of the same suite and engine.
    #[arg(long, num_args = 2.., value_names = ["LABEL", "RESULT"], action = clap::ArgAction::Append,
          requires = "out", conflicts_with_all = ["overlay", "scaling"])]
    curve: Vec<String>,
    /// --curve's values, one list per occurrence (LABEL, then its results), filled in by `parse`.
    #[arg(skip)]
    pub(super) curves: Vec<Vec<String>>,
    /// With --curve: `LABEL:RESULT`, the policy the curve LABEL's run started from (`train
    /// --init-from`), as its suite result: drawn as the curve's first point (split at the last colon:
    /// the label may hold colons, the file name may not). Where that policy was
    /// trained on the curve's task (e.g. DAgger's snapshot), its env steps are added to the curve's;
    /// where not (the generalist, trained on other tasks), the curve starts at 0.
    #[arg(long, num_args = 1.., requires = "curve")]
    start: Vec<String>,
    /// With --overlay or --curve: suite results (JSON of `eval --suite`) as `LABEL:FILE` (split at
    /// the last colon), each drawn as a dashed line at its test score, e.g. `--level solver:results/generalization/mujoco-2.2.2/baseline-scripted.beyond-ToppleTower-v0.json`.
    #[arg(long, num_args = 1..)]
    level: Vec<String>,
    /// With --scaling: a suite result (e.g. the solver's) drawn as dashed train and test lines.
    #[arg(long, requires = "scaling")]
    reference: Option<PathBuf>,
    /// With --scaling: what X counts.
    #[arg(long, default_value = "distinct training tasks", requires = "scaling")]
    x_label: String,
    /// Output PNG of --overlay or --scaling.
    #[arg(long)]
    out: Option<PathBuf>,
    /// Title of the --overlay figure (default: "Finals success (maximum level)") or of the --scaling
    /// one (default: "Success against X on SUITE").
    #[arg(long)]
    title: Option<String>,
}

/// The training settings of a `blockpuzzle train ...` command line (`args`
/// from the program name on, recipes expanded), without running it.
///
/// # Errors
/// A recipe that cannot be read, or flags clap refuses (its message).
pub fn train_config(args: Vec<std::ffi::OsString>) -> Result<crate::learn::train::TrainConfig> {
    match super::parse(args)?.command {
        super::Command::Train(a) => Ok(a.config),
        _ => bail!("not a `train` command line"),
    }
}

/// `blockpuzzle train`: one process, or one rank of an MPI job.
pub(super) fn train(a: TrainArgs) -> Result<()> {
    if !crate::learn::train::comm::Comm::launched_by_mpirun() {
        return train_in(&crate::learn::train::comm::Comm::local(), a);
    }
    #[cfg(feature = "mpi")]
    {
        // Only this thread talks to MPI (the workers are plain threads).
        let Some((universe, _)) = mpi::initialize_with_threading(mpi::Threading::Funneled) else {
            bail!("MPI was initialised twice");
        };
        let comm = crate::learn::train::comm::Comm::mpi(universe.world());
        if let Err(e) = train_in(&comm, a) {
            // Other ranks may wait in a collective: stop the whole job.
            eprintln!("error (rank {} of {}): {e:#}", comm.rank(), comm.size());
            comm.abort(1);
        }
        Ok(())
    }
    #[cfg(not(feature = "mpi"))]
    bail!("started by mpirun, but this blockpuzzle was built without the `mpi` feature; rebuild with --features mpi")
}

fn train_in(comm: &crate::learn::train::comm::Comm, a: TrainArgs) -> Result<()> {
    let recorded = bare_resume(&a)?;
    // A bare resume has the run's recorded settings; others are resolved as a new run records them.
    let given = match recorded {
        Some(_) => None,
        None => Some(a.config.clone().with_absolute_paths()?),
    };
    let c = recorded.as_ref().or(given.as_ref()).unwrap_or(&a.config);
    let run_dir = a.run_dir.clone().unwrap_or_else(|| c.default_run_dir());
    let bar =
        if comm.is_root() { indicatif::ProgressBar::new(c.epochs as u64) } else { indicatif::ProgressBar::hidden() };
    bar.set_style(
        indicatif::ProgressStyle::with_template("{bar:30} epoch {pos}/{len} {msg} [{elapsed_precise} < {eta_precise}]")
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    let plain = comm.is_root() && !std::io::IsTerminal::is_terminal(&std::io::stderr());
    let mut last: Option<crate::learn::train::EpochRow> = None;
    let mut on_epoch = |row: &crate::learn::train::EpochRow, cfg: &crate::learn::train::TrainConfig| {
        let (steps, updates, secs) = match &last {
            Some(p) => (row.env_steps - p.env_steps, row.updates - p.updates, row.wall_seconds - p.wall_seconds),
            None => (row.env_steps, row.updates, row.wall_seconds),
        };
        bar.set_position(row.epoch as u64 + 1);
        let beta = if cfg.aggrevated.expert.is_some() { format!(" beta {:.2}", row.beta) } else { String::new() };
        let message = format!(
            "level {}{beta} success train {:.2} test {:.2} finals {:.2} | {:.0} env steps/s {:.1} updates/s",
            row.level,
            row.train_success,
            row.test_success,
            row.finals_success,
            steps as f64 / secs.max(1e-9),
            updates as f64 / secs.max(1e-9)
        );
        // Off a terminal (a log file, a batch job) the bar draws nothing: a plain line per epoch.
        if plain {
            eprintln!("epoch {}/{} {message} ({:.0} s)", row.epoch + 1, cfg.epochs, row.wall_seconds);
        }
        bar.set_message(message);
        last = Some(row.clone());
    };
    if let Some(parent) = &a.branch_from {
        branch_run(comm, parent, &run_dir, c)?;
    }
    use crate::learn::train::Start;
    let start = match (a.resume, a.rebuild_replay, a.branch_from.is_some()) {
        (true, true, _) => Start::ResumeRebuildingReplay,
        (true, false, _) | (false, _, true) => Start::Resume,
        (false, _, false) => Start::New,
    };
    let trained = crate::learn::train::train_ranks(comm, c, &run_dir, start, &mut on_epoch);
    // A branch that fails before its first epoch is removed: this command made it, and it holds
    // nothing but the parent's copy (issue 74: it was left behind, a complete run directory).
    if let (Err(_), Some(_), None) = (&trained, &a.branch_from, &last) {
        if comm.is_root() {
            if let Err(e) = std::fs::remove_dir_all(&run_dir) {
                eprintln!("warning: cannot remove the failed branch {}: {e}", run_dir.display());
            }
        }
    }
    let rows = trained?;
    bar.finish();
    if let Some(r) = rows.last() {
        println!(
            "{}: {} epochs, level {}, finals success {:.3}, {} env steps, {:.0} s; run directory {}",
            c.task_id(),
            r.epoch + 1,
            r.level,
            r.finals_success,
            r.env_steps,
            r.wall_seconds,
            run_dir.display()
        );
    }
    Ok(())
}

/// `train --branch-from`: rank 0 makes the branch, every rank learns whether it worked.
fn branch_run(
    comm: &crate::learn::train::comm::Comm,
    parent: &Path,
    child: &Path,
    c: &crate::learn::train::TrainConfig,
) -> Result<()> {
    Ok(comm.root_check(|| {
        let b = crate::learn::train::branch(parent, child, c)?;
        eprintln!(
            "{}: branched from {} at epoch {} ({} env steps){}",
            child.display(),
            parent.display(),
            b.epoch,
            b.env_steps,
            if b.changed.is_empty() { String::new() } else { format!("; changed {}", b.changed.join(", ")) }
        );
        Ok(())
    })?)
}

/// A run directory's config and progress rows.
/// The maximum curriculum level of a run's task (its recorded copy, else its id).
fn run_max_level(config: &crate::learn::train::TrainConfig) -> Result<usize> {
    // A stream's tasks come from families, which draw them with no curriculum (level 0 only).
    if config.stream.is_some() {
        return Ok(0);
    }
    // A multi-task run's level is the sum of its tasks' levels.
    if !config.tasks.is_empty() {
        return config.tasks.iter().map(|s| Ok(registry::recorded(s)?.max_level())).sum();
    }
    Ok(match &config.task {
        Some(source) => registry::recorded(source)?.max_level(),
        None => registry::task(&config.env)?.max_level(),
    })
}

fn read_run(dir: &Path) -> Result<(crate::learn::train::TrainConfig, Vec<crate::learn::train::EpochRow>)> {
    if std::fs::metadata(dir).is_ok_and(|m| !m.is_dir()) {
        let parent = dir.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
        bail!(
            "{} is a file; give its run directory (the folder with config.json and progress.csv), e.g. {}",
            dir.display(),
            parent.display()
        );
    }
    let run = crate::learn::train::RunDir { dir: dir.to_owned() };
    Ok((run.read_config()?, crate::learn::train::read_progress(&run.progress())?))
}

/// `blockpuzzle plot`: a run's success.png, or an overlay of several runs.
pub(super) fn plot(a: PlotArgs) -> Result<()> {
    if !a.level.is_empty() && a.overlay.is_empty() && a.curve.is_empty() {
        bail!("--level draws a reference line across curves: give it with --overlay or --curve");
    }
    if let Some(out) = &a.out {
        crate::learn::train::plot::png_only(out)?;
    }
    if let Some(dir) = a.run_dir.clone() {
        let (config, rows) = read_run(&dir)?;
        let max_level = run_max_level(&config)?;
        let run = crate::learn::train::RunDir { dir };
        crate::learn::train::plot::success_curves(&run.plot(), &config.title(), &rows, max_level)?;
        println!("wrote {}", run.plot().display());
    }
    if let (Some(out), false) = (&a.out, a.scaling.is_empty()) {
        return scaling(&a, out);
    }
    if let (Some(out), false) = (&a.out, a.curve.is_empty()) {
        return curves(&a, out);
    }
    if let Some(out) = a.out {
        if !a.labels.is_empty() && a.labels.len() != a.overlay.len() {
            bail!(
                "--labels gives {} labels for {} --overlay runs: give one per run, or none",
                a.labels.len(),
                a.overlay.len()
            );
        }
        let mut runs = Vec::new();
        for (i, path) in a.overlay.iter().enumerate() {
            let (label, points) = if path.is_file() {
                let name =
                    path.file_name().map_or_else(|| path.display().to_string(), |n| n.to_string_lossy().into_owned());
                (name, crate::learn::train::plot::read_finals(path)?)
            } else {
                let (config, rows) = read_run(path)?;
                let workers =
                    if config.workers == 1 { "1 worker".into() } else { format!("{} workers", config.workers) };
                (format!("{} ({workers})", config.title()), rows.iter().map(Into::into).collect())
            };
            runs.push((a.labels.get(i).cloned().unwrap_or(label), points));
        }
        let levels = levels(&a.level)?.into_iter().map(|(label, test, _)| (label, test)).collect::<Vec<_>>();
        let title = a.title.as_deref().unwrap_or("Finals success (maximum level)");
        crate::learn::train::plot::overlay(&out, title, &runs, &levels)?;
        println!("wrote {}", out.display());
    }
    Ok(())
}

/// `LABEL:FILE` of `--level` and `--start`, split at the last colon: a label may hold colons
/// ("TD3: from DAgger"), a file name may not.
fn label_file(given: &str) -> Option<(&str, &str)> {
    given.rsplit_once(':')
}

/// `plot --level LABEL:FILE...`: each result's test score, labelled with it, and its provenance.
fn levels(given: &[String]) -> Result<Vec<(String, f64, crate::benchmark::provenance::Provenance)>> {
    let mut levels = Vec::new();
    for given in given {
        let Some((label, file)) = label_file(given) else {
            bail!(
                "--level {given}: give LABEL:FILE, e.g. solver:results/generalization/mujoco-2.2.2/baseline-scripted.beyond-ToppleTower-v0.json"
            );
        };
        let r = crate::benchmark::results::read(Path::new(file))
            .map_err(|e| anyhow::Error::from(e).context(format!("--level {given}")))?
            .result;
        let Some(test) = r.splits.iter().find(|s| s.name == "test").and_then(|s| s.mean_success) else {
            bail!("--level {given}: {file} has no `test` split evaluated");
        };
        levels.push((format!("{label} ({test:.3})"), test, r.provenance));
    }
    Ok(levels)
}

/// The env steps the policy of `r` (read from `file`) had trained for: as the result records them,
/// or, for a result written before results did, from the policy file it names, if that file is
/// still the policy evaluated (the same policy hash).
fn policy_env_steps(file: &Path, r: &crate::benchmark::evaluate::SuiteResult) -> Result<u64> {
    if let Some(steps) = r.policy_env_steps {
        return Ok(steps);
    }
    let again = format!(
        "evaluate the policy again with this build (`blockpuzzle eval --suite ... --checkpoint POLICY --out {}`), \
         which records them",
        file.display()
    );
    let policy = Path::new(&r.policy);
    if r.provenance.policy.sha256.is_none() || !policy.is_file() {
        bail!(
            "{}: records no env steps of its policy (`{}`, a baseline or a file not here); {again}",
            file.display(),
            r.policy
        );
    }
    let saved = crate::benchmark::saved::read(policy)?;
    if saved.policy_id(&r.policy).sha256 != r.provenance.policy.sha256 {
        bail!(
            "{}: records no env steps of its policy, and {} is no longer the policy it evaluated (another \
             policy hash); {again}",
            file.display(),
            r.policy
        );
    }
    saved.env_steps.ok_or_else(|| anyhow::anyhow!("{}: its policy {} records no env steps", file.display(), r.policy))
}

/// A suite result's test score, and its 95% Wilson interval where the test split is one row.
fn test_score(r: &crate::benchmark::evaluate::SuiteResult) -> Result<(f64, Option<(f64, f64)>)> {
    let test = r.splits.iter().find(|s| s.name == "test");
    let Some((test, Some(success))) = test.map(|t| (t, t.mean_success)) else {
        bail!("no `test` split evaluated");
    };
    let ci95 = match &test.rows[..] {
        [one] => one.evaluation.as_ref().map(|e| e.ci95),
        _ => None,
    };
    Ok((success, ci95))
}

/// `plot --curve`: test success of evaluated policies against their env steps, and the points'
/// table (Markdown) on stdout.
fn curves(a: &PlotArgs, out: &Path) -> Result<()> {
    use crate::learn::train::plot::EvalPoint;
    let mut first: Option<(String, crate::benchmark::provenance::Provenance)> = None;
    let mut same = |what: &str, p: &crate::benchmark::provenance::Provenance| -> Result<()> {
        match &first {
            None => first = Some((what.to_owned(), p.clone())),
            Some((name, q)) => q.comparable(p).map_err(|m| {
                anyhow::anyhow!(
                    "{what} and {name} cannot be drawn in one figure: {m}; plot each suite and engine apart"
                )
            })?,
        }
        Ok(())
    };
    // A result of the figure: read, checked against the others, and its test score.
    let mut read = |file: &str, what: &str| -> Result<(crate::benchmark::evaluate::SuiteResult, EvalPoint)> {
        let r = crate::benchmark::results::read(Path::new(file))
            .map_err(|e| anyhow::Error::from(e).context(what.to_owned()))?
            .result;
        same(file, &r.provenance)?;
        let (success, ci95) = test_score(&r).with_context(|| format!("{what}: {file}"))?;
        Ok((r, EvalPoint { env_steps: 0, success, ci95 }))
    };
    let mut curves = Vec::new();
    let mut table = String::from("| curve | env steps | test success [95% Wilson] | result |\n|---|---:|---|---|\n");
    for given in &a.curves {
        let Some((label, files)) = given.split_first() else { continue };
        if label.ends_with(".json") && Path::new(label).is_file() {
            bail!(
                "--curve {label} ...: a curve starts with its label, then its results, e.g. \
                 --curve \"fine-tuned s0\" run-epoch2.json run-epoch4.json"
            );
        }
        // Each point with the file it came from, for the table.
        let mut points: Vec<(EvalPoint, &str)> = Vec::new();
        let mut curve_task = None;
        for file in files {
            let (r, point) = read(file, &format!("--curve {label}"))?;
            points.push((EvalPoint { env_steps: policy_env_steps(Path::new(file), &r)?, ..point }, file));
            curve_task = r.policy_task;
        }
        // This curve's starts, each as given (for messages) and its file.
        let starts: Vec<(&String, &str)> = a
            .start
            .iter()
            .filter_map(|s| label_file(s).filter(|(l, _)| *l == label.as_str()).map(|(_, f)| (s, f)))
            .collect();
        match starts[..] {
            [] => {}
            [(given, file)] => {
                let (r, point) = read(file, &format!("--start {given}"))?;
                // Env steps on this curve's own task count; a policy trained elsewhere starts it at 0.
                let own = r.policy_task.is_some() && r.policy_task == curve_task;
                let offset = if own { policy_env_steps(Path::new(file), &r)? } else { 0 };
                for (p, _) in &mut points {
                    p.env_steps += offset;
                }
                points.push((EvalPoint { env_steps: offset, ..point }, file));
            }
            _ => bail!("--start: {} starts given for the curve {label}; give one", starts.len()),
        }
        points.sort_by_key(|(p, _)| p.env_steps);
        for (p, file) in &points {
            let ci = p.ci95.map_or(String::new(), |(lo, hi)| format!(" [{lo:.3}, {hi:.3}]"));
            table.push_str(&format!("| {label} | {} | {:.3}{ci} | `{file}` |\n", p.env_steps, p.success));
        }
        curves.push((label.clone(), points.into_iter().map(|(p, _)| p).collect()));
    }
    if let Some(s) = a.start.iter().find(|s| !label_file(s).is_some_and(|(l, _)| a.curves.iter().any(|c| c[0] == l))) {
        bail!("--start {s}: give LABEL:RESULT with the LABEL of a --curve");
    }
    let mut lines = Vec::new();
    for (label, test, provenance) in levels(&a.level)? {
        same(&format!("--level {label}"), &provenance)?;
        lines.push((label, test));
    }
    let title = a.title.as_deref().unwrap_or("Test success against env steps");
    crate::learn::train::plot::evaluated(out, title, &curves, &lines)?;
    print!("{table}");
    println!("wrote {}", out.display());
    Ok(())
}

/// `plot --scaling`: the points' figure, and their table (Markdown) on stdout.
fn scaling(a: &PlotArgs, out: &Path) -> Result<()> {
    use crate::learn::train::plot::ScalingPoint;
    // A result's train and test means, its suite and its policy's name; every file read, to be
    // checked comparable (one engine, one suite version, the same task contents) as `results compare` does.
    let mut read = Vec::new();
    let mut means = |path: &Path| -> Result<(f64, f64, String, String)> {
        let file = crate::benchmark::results::read(path)?;
        let r = file.result.clone();
        read.push(file);
        let mean = |name: &str| {
            r.splits.iter().find(|s| s.name == name).and_then(|s| s.mean_success).ok_or_else(|| {
                anyhow::anyhow!(
                    "{}: no `{name}` split evaluated; --scaling takes suite results of both splits",
                    path.display()
                )
            })
        };
        Ok((mean("train")?, mean("test")?, r.suite.name.clone(), r.policy.clone()))
    };
    let mut points = Vec::new();
    let mut table = String::from("| x | train | test | gap | result |\n|---:|---:|---:|---:|---|\n");
    let mut suites = Vec::new();
    for arg in &a.scaling {
        let Some((x, file)) = arg.split_once(':') else {
            bail!("--scaling {arg}: write each point as X:FILE, e.g. 64:results/curve-64.json");
        };
        let x: f64 = x.trim().parse().map_err(|_| anyhow::anyhow!("--scaling {arg}: {x:?} is not a number"))?;
        let (train, test, suite, _) = means(Path::new(file))?;
        suites.push(suite);
        table.push_str(&format!("| {x} | {train:.3} | {test:.3} | {:.3} | `{file}` |\n", train - test));
        points.push(ScalingPoint { x, train, test });
    }
    let reference = match &a.reference {
        Some(path) => {
            let (train, test, suite, name) = means(path)?;
            suites.push(suite);
            table.push_str(&format!(
                "| reference | {train:.3} | {test:.3} | {:.3} | `{}` |\n",
                train - test,
                path.display()
            ));
            Some((name, train, test))
        }
        None => None,
    };
    suites.sort();
    suites.dedup();
    if suites.len() > 1 {
        bail!("--scaling: the results are of several suites ({}); give results of one suite", suites.join(", "));
    }
    crate::benchmark::results::check_all(&read)
        .map_err(|e| anyhow::anyhow!("--scaling: {e}; draw results of one engine and suite version in one figure"))?;
    let title = a.title.clone().unwrap_or_else(|| format!("Success against {} on {}", a.x_label, suites[0]));
    crate::learn::train::plot::scaling(
        out,
        &title,
        &a.x_label,
        &points,
        reference.as_ref().map(|(n, tr, te)| (n.as_str(), *tr, *te)),
    )?;
    print!("{table}");
    println!("wrote {}", out.display());
    Ok(())
}

/// `blockpuzzle report`: time to a result, from each run's progress.csv.
pub(super) fn report(run_dirs: &[PathBuf], target: f64) -> Result<()> {
    for dir in run_dirs {
        let (config, rows) = read_run(dir)?;
        let title = format!("{} ({} workers, {})", config.title(), config.workers, dir.display());
        print!("{}", crate::learn::train::report::text(&title, &rows, run_max_level(&config)?, target));
        // What made the numbers: the builds and engines that ran the epochs.
        let spans = crate::learn::train::RunDir { dir: dir.clone() }.read_provenance()?;
        if spans.is_empty() {
            println!("  made by: not recorded (the run started before runs recorded their engine)");
        }
        for s in &spans {
            let replay = s.replay.map(|r| format!("; {}", r.describe())).unwrap_or_default();
            println!("  made by: from epoch {} on, {}{replay}", s.from_epoch + 1, s.describe());
        }
    }
    Ok(())
}
