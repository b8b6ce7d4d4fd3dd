//! `blockpuzzle eval` (a policy on a task, or a policy or baseline on a suite) and `table` (the
//! paper's results table).

use super::episodes::policy_task;
use crate::env::registry;
use anyhow::{bail, Result};
use std::path::{Path, PathBuf};

#[derive(Debug, clap::Args)]
pub(super) struct EvalArgs {
    /// A policy file, a run directory (uses best_policy.json, else policy.json), a zoo name, or a
    /// baseline's name (as --baseline).
    #[arg(long)]
    checkpoint: Option<PathBuf>,
    /// Evaluate a policy that needs no training instead of a checkpoint, on --suite or on --env:
    /// `scripted` (each task's scripted controller) or `obs-hash` (pseudo-random actions from a hash
    /// of the observation, the same as Python's `blockpuzzle.policies.obs_hash`).
    #[arg(long, value_enum, conflicts_with = "checkpoint")]
    baseline: Option<crate::benchmark::evaluate::Baseline>,
    /// Evaluate on an evaluation suite instead: a built-in name or a suite file; writes
    /// eval-POLICY-suite-NAME.json and .md (docs/suites.md). The help lists the built-in names.
    #[arg(
        long,
        conflicts_with_all = ["env", "challenge", "level", "episodes", "seed"],
        help = format!(
            "Evaluate on an evaluation suite instead: a built-in name ({}) or a suite file; writes \
             eval-POLICY-suite-NAME.json and .md (docs/suites.md)",
            crate::benchmark::suite::builtin_names()
        )
    )]
    suite: Option<String>,
    /// With --suite: play at most N episodes of each row, a quick look. The result records it and
    /// is not the suite's score (`results` refuses it).
    #[arg(long, requires = "suite", value_name = "N", value_parser = crate::support::limits::EVAL_EPISODES.parser::<usize>())]
    episodes_per_row: Option<usize>,
    /// Environment id or task file (default: the one the policy was trained on).
    #[arg(long)]
    env: Option<String>,
    /// Use the task's challenge distribution (BlocksChoose-v0 and the tasks that define one).
    #[arg(long)]
    challenge: bool,
    /// Curriculum level (default: the maximum).
    #[arg(long, value_parser = crate::support::limits::COUNT.parser::<usize>())]
    level: Option<usize>,
    /// Episodes.
    #[arg(long, default_value_t = 100, value_parser = crate::support::limits::EVAL_EPISODES.parser::<usize>())]
    episodes: usize,
    /// Seed of the first episode (episode k uses seed + k).
    #[arg(long, default_value_t = crate::benchmark::evaluate::TEST_SEED, value_parser = crate::support::limits::SEED.parser::<u64>())]
    seed: u64,
    /// Where to write the JSON result (default: the run directory for a policy of a run,
    /// else the current folder, as eval-POLICY-TASK-DISTRIBUTION.json).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Threads playing episodes (default: all cores); the result does not depend on it.
    #[arg(long, value_parser = crate::support::limits::THREADS.parser::<usize>())]
    threads: Option<usize>,
}

#[derive(Debug, clap::Args)]
pub(super) struct TableArgs {
    /// The task: the paper's BlocksChoose-v0, or another id or task file with a challenge
    /// distribution (e.g. BlocksChooseShuffled-v0, to test generalisation).
    #[arg(long, default_value = crate::benchmark::table::ENV)]
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
    #[arg(long, default_value_t = 1000, value_parser = crate::support::limits::EVAL_EPISODES.parser::<usize>())]
    episodes: usize,
    /// Seed of the first episode (episode k uses seed + k).
    #[arg(long, default_value_t = crate::benchmark::evaluate::TEST_SEED, value_parser = crate::support::limits::SEED.parser::<u64>())]
    seed: u64,
    /// Write the Markdown table here too (atomically).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Write the table even when a row's policy cannot be loaded or evaluated
    /// (the row then says why); without it such a row is an error.
    #[arg(long)]
    allow_missing: bool,
    /// Threads playing episodes (default: all cores); the result does not depend on it.
    #[arg(long, value_parser = crate::support::limits::THREADS.parser::<usize>())]
    threads: Option<usize>,
}

/// `blockpuzzle table`.
pub(super) fn table(a: TableArgs) -> Result<()> {
    crate::support::limits::seed_range(a.seed, a.episodes as u64).map_err(anyhow::Error::msg)?;
    if let Some(out) = &a.out {
        crate::support::io::check_output(out)?;
    }
    let threads = a.threads.unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
    let task = registry::task(&a.env)?;
    if task.distribution("challenge").is_none() {
        bail!("the table's second column is the challenge distribution, which {} does not define", a.env);
    }
    let given = crate::benchmark::table::Policies {
        expert: a.expert,
        ddpg: a.ddpg,
        ddpg_ours: a.ddpg_ours,
        pggd: a.pggd,
        pggd_alone: a.pggd_alone,
    };
    let rows =
        crate::benchmark::table::rows(if a.zoo { given.or(crate::benchmark::table::Policies::zoo()) } else { given });
    let mut done = Vec::new();
    for row in rows {
        eprintln!("evaluating {} ...", row.method);
        let outcome = crate::benchmark::table::evaluate_row(&row, &task, a.episodes, a.seed, threads);
        done.push((row, outcome));
    }
    let missing: Vec<String> = done
        .iter()
        .filter_map(|(row, r)| match r {
            crate::benchmark::table::RowResult::Missing(why) => Some(format!(
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
    let md = crate::benchmark::table::markdown(&done, task.id(), a.episodes, a.seed);
    print!("{md}");
    if let Some(out) = &a.out {
        crate::support::io::write_file(out, md.as_bytes())?;
    }
    Ok(())
}

/// Where `eval` writes by default: `eval-POLICY-TASK-DISTRIBUTION.json` in the
/// policy's run directory (a run directory, or a policy file or snapshot in
/// one), else in the current folder; POLICY is the file's stem or zoo name
/// (`best_policy` for a run directory, whose best policy is evaluated).
fn eval_out(checkpoint: &Path, label: &str) -> PathBuf {
    use crate::benchmark::saved::{BEST_POLICY_FILE, CONFIG_FILE, POLICY_FILE};
    let is_run = |d: &Path| d.join(CONFIG_FILE).is_file();
    let stem = |file: &str| file.trim_end_matches(".json").to_owned();
    let (run, policy) = if checkpoint.is_dir() {
        let best = checkpoint.join(BEST_POLICY_FILE).exists();
        (Some(checkpoint.to_path_buf()), stem(if best { BEST_POLICY_FILE } else { POLICY_FILE }))
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
    use crate::benchmark::evaluate::Subject;
    use crate::benchmark::provenance::Harness;
    let mut suite = crate::benchmark::suite::load(name)?;
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
    let md = match crate::support::io::check_output(&out)? {
        crate::support::io::Target::File { .. } => Some(out.with_extension("md")),
        crate::support::io::Target::Stream => None,
    };
    if let Some(md) = &md {
        crate::support::io::check_output(md)?;
    }
    // The one resolver: a trained policy, or a baseline by name (`--checkpoint scripted` is `--baseline scripted`).
    let named;
    let subject = match (&a.checkpoint, a.baseline) {
        (_, Some(b)) => Subject::Baseline(b),
        (checkpoint, None) => {
            named = crate::benchmark::load::resolve(checkpoint.as_deref().unwrap_or(Path::new("")))?;
            named.subject().ok_or_else(|| {
                anyhow::anyhow!(
                    "--checkpoint random: random actions are not evaluated on suites; give a trained policy, or \
                     --baseline obs-hash (seeded pseudo-random actions, the same in Python)"
                )
            })?
        }
    };
    let r =
        crate::benchmark::evaluate::evaluate_suite(subject, &suite, threads, Harness::Cli, &mut |_, _, _, _| Ok(()))?;
    crate::support::io::write_json(&out, &r)?;
    if let Some(md) = &md {
        crate::support::io::write_file(md, r.to_markdown().as_bytes())?;
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
        "suite {}: score {} ({} mean success), gap {} -> {}{md}",
        suite.name,
        show(r.score),
        r.scored_split(),
        show(r.gap),
        out.display(),
    );
    Ok(())
}

/// `blockpuzzle eval`.
pub(super) fn eval(a: EvalArgs) -> Result<()> {
    if let Some(suite) = &a.suite {
        return eval_suite(&a, suite);
    }
    use crate::benchmark::evaluate::Subject;
    use crate::benchmark::load::Named;
    // One resolver: a policy file, run directory or zoo name, or a baseline by --checkpoint or --baseline.
    let named = match (&a.checkpoint, a.baseline) {
        (Some(c), _) => crate::benchmark::load::resolve(c)?,
        (None, Some(b)) => Named::Baseline(b),
        (None, None) => bail!("give --checkpoint POLICY (a policy file, run directory or zoo name) or --baseline NAME"),
    };
    let Some(subject) = named.subject() else {
        bail!("`random` is random actions, not a policy to evaluate; give a policy file, run directory, zoo name or baseline")
    };
    // Where a result goes by default: beside a run's policy, else `eval-NAME-...` here.
    let (task, named_as, policy_epoch) = match subject {
        Subject::Saved(path, saved) => (policy_task(a.env.as_deref(), saved)?, path.to_path_buf(), Some(saved.epoch)),
        Subject::Baseline(b) => {
            let Some(env) = a.env.as_deref() else {
                bail!(
                    "the baseline `{}` has no task of its own: give --env ID (or a task file), or evaluate a suite \
                     with --suite S",
                    b.name()
                )
            };
            (crate::env::registry::task(env)?, PathBuf::from(format!("baseline-{}", b.name())), None)
        }
    };
    let id = task.id().to_owned();
    let policy = subject.id();
    let provenance =
        crate::benchmark::provenance::Provenance::new(crate::benchmark::provenance::Harness::Cli, policy.clone(), None);
    let spec = crate::benchmark::evaluate::EvalSpec {
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
    let out = a.out.clone().unwrap_or_else(|| eval_out(&named_as, &format!("{id}-{distribution}")));
    crate::support::io::check_output(&out)?;
    let r = crate::benchmark::evaluate::evaluate_subject(subject, &spec)?;
    let result = serde_json::json!({
        "env": id, "challenge": a.challenge, "level": r.level, "episodes": a.episodes, "seed": a.seed,
        "successes": r.successes, "success_rate": r.success_rate, "ci95": [r.ci95.0, r.ci95.1],
        "grey_blind": r.grey_blind, "outcomes": r.outcomes, "policy": policy.name, "policy_epoch": policy_epoch,
        "task_sha256": task.source.hash, "provenance": provenance,
    });
    crate::support::io::write_json(&out, &result)?;
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
