//! The paper's results table ("Final evaluation of different agents on the
//! 3 blocks environment"): each agent on BlocksChoose-v0 at full difficulty
//! (Normal) and in the challenge distribution, with 95% intervals and the
//! paper's numbers beside them. Rows without a trained policy say so.

use crate::evaluate::{evaluate, EvalSpec, Evaluation};
use crate::train::load_policy;
use anyhow::Result;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// The environment of the paper's table (the default of `table --env`).
pub const ENV: &str = "BlocksChoose-v0";

/// One row: a method, where its policy is, the paper's (Normal, Challenge).
#[derive(Debug, Clone)]
pub struct Row {
    /// Method name as in the paper.
    pub method: &'static str,
    /// Policy file or run directory (None: not given).
    pub policy: Option<PathBuf>,
    /// The paper's success rates, where it gives them.
    pub paper: (Option<f64>, Option<f64>),
}

/// The paper's rows for the given policies, in the paper's order, plus PGGD alone.
pub fn rows(
    expert: Option<PathBuf>,
    ddpg: Option<PathBuf>,
    pggd: Option<PathBuf>,
    pggd_alone: Option<PathBuf>,
) -> Vec<Row> {
    vec![
        Row { method: "DDPG (2 blocks), grey removed from its view", policy: expert, paper: (Some(0.44), Some(0.24)) },
        Row { method: "DDPG (3 blocks)", policy: ddpg, paper: (Some(0.97), Some(0.90)) },
        Row { method: "PGGD + AggreVaTeD", policy: pggd, paper: (Some(0.64), Some(0.40)) },
        // The paper gives no number: "barely passes the first difficulty level after 200 epochs".
        Row { method: "PGGD alone", policy: pggd_alone, paper: (None, None) },
    ]
}

/// A row's outcome.
#[derive(Debug)]
pub enum Outcome {
    /// No policy was given for the row.
    NotGiven,
    /// The policy could not be loaded or evaluated (the message says why).
    Missing(String),
    /// Evaluated: (Normal, Challenge) and the policy's epoch.
    Done { normal: Evaluation, challenge: Evaluation, epoch: usize },
}

/// Evaluates one row.
pub fn evaluate_row(row: &Row, task: &crate::task::Task, episodes: usize, seed: u64, threads: usize) -> Outcome {
    let Some(path) = &row.policy else { return Outcome::NotGiven };
    // The policy file is read once; each evaluation gets its own copy.
    let run = || -> Result<(Evaluation, Evaluation, usize)> {
        let saved = load_policy(path)?;
        let epoch = saved.epoch;
        let spec = |challenge| EvalSpec { task, challenge, level: None, episodes, seed, threads };
        let normal = evaluate(path, saved.clone(), &spec(false))?;
        Ok((normal, evaluate(path, saved, &spec(true))?, epoch))
    };
    match run() {
        Ok((normal, challenge, epoch)) => Outcome::Done { normal, challenge, epoch },
        Err(e) => Outcome::Missing(format!("{e:#}")),
    }
}

fn cell(e: &Evaluation, paper: Option<f64>) -> String {
    let paper = paper.map_or("paper: no number".to_owned(), |p| format!("paper {p:.2}"));
    format!("{:.3} ({:.3}–{:.3}); {paper}", e.success_rate, e.ci95.0, e.ci95.1)
}

/// The table as Markdown.
pub fn markdown(rows: &[(Row, Outcome)], env: &str, episodes: usize, seed: u64) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "Final evaluation on {env}: Normal = the maximum curriculum level, Challenge = the challenge");
    let _ = writeln!(
        s,
        "distribution. {episodes} episodes per cell (seeds {seed}–{}), success rate",
        seed + episodes as u64 - 1
    );
    if env == ENV {
        let _ = writeln!(s, "with its 95% Wilson interval, and the paper's number.\n");
    } else {
        let _ = writeln!(s, "with its 95% Wilson interval, and the paper's number on {ENV} for comparison.\n");
    }
    let _ = writeln!(s, "| Method | Normal | Challenge | Policy |");
    let _ = writeln!(s, "|---|---|---|---|");
    for (row, outcome) in rows {
        let paper = |p: Option<f64>| p.map_or("no number".to_owned(), |p| format!("{p:.2}"));
        let shown = |p: &Path| p.display().to_string();
        match outcome {
            Outcome::NotGiven => {
                let _ = writeln!(
                    s,
                    "| {} | not trained (paper {}) | not trained (paper {}) | none given |",
                    row.method,
                    paper(row.paper.0),
                    paper(row.paper.1)
                );
            }
            Outcome::Missing(why) => {
                let _ = writeln!(
                    s,
                    "| {} | missing (paper {}) | missing (paper {}) | {}: {} |",
                    row.method,
                    paper(row.paper.0),
                    paper(row.paper.1),
                    row.policy.as_deref().map(shown).unwrap_or_default(),
                    why.replace('|', "/").replace('\n', " ")
                );
            }
            Outcome::Done { normal, challenge, epoch } => {
                let _ = writeln!(
                    s,
                    "| {} | {} | {} | {} (epoch {epoch}{}) |",
                    row.method,
                    cell(normal, row.paper.0),
                    cell(challenge, row.paper.1),
                    row.policy.as_deref().map(shown).unwrap_or_default(),
                    if normal.grey_blind { ", grey removed" } else { "" }
                );
            }
        }
    }
    s
}
