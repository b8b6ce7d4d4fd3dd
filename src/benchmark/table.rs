//! The paper's results table ("Final evaluation of different agents on the
//! 3 blocks environment"): each agent on BlocksChoose-v0 at full difficulty
//! (Normal) and in the challenge distribution, with 95% intervals and the
//! paper's numbers beside them. Rows without a trained policy say so.

use crate::benchmark::evaluate::{evaluate, EvalError, EvalSpec, Evaluation};
use crate::benchmark::load::{load_policy, LoadError};
use crate::benchmark::saved::Trainer;
use crate::policy::actor::PolicyKind;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// Why a row of the table has no numbers: its policy cannot be loaded, is not the row's kind, or
/// cannot be evaluated (the table shows the message in the row's place).
#[derive(Debug, thiserror::Error)]
pub enum TableError {
    /// The policy is not the kind the row stands for (the message names the row, the policy and the fix).
    #[error("{0}")]
    Misfit(String),
    /// The policy could not be loaded.
    #[error(transparent)]
    Load(#[from] LoadError),
    /// The policy could not be evaluated.
    #[error(transparent)]
    Eval(#[from] EvalError),
}

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
    /// The algorithms the row stands for, as policy files record them, all of one kind of policy
    /// ([`Row::takes`]).
    pub algos: &'static [Trainer],
    /// The task the row's agent is trained on (or the task the table plays, `table --env`).
    pub trained_on: &'static str,
}

impl Row {
    /// The kind of policy the row stands for (its algorithms'): a row takes only that kind.
    pub fn takes(&self) -> PolicyKind {
        self.algos.first().map_or(PolicyKind::Deterministic, |a| a.trains())
    }

    /// Whether `saved` is the kind of policy this row stands for: the row's kind (deterministic or
    /// PGGD), trained from scratch by the row's algorithm (where the file records it: files written
    /// before they recorded it rest on being named as the row asks) on one task, the row's own or
    /// `played`, the task the table plays (`table --env`).
    ///
    /// # Errors
    /// The mismatch, naming the row, the policy and the fix.
    pub fn check(&self, saved: &crate::benchmark::saved::SavedPolicy, played: &str) -> Result<(), TableError> {
        let name = self.policy.as_deref().map_or_else(String::new, |p| p.display().to_string());
        let takes = self.takes();
        let wanted = match takes {
            PolicyKind::Deterministic => "a deterministic (DDPG) actor",
            PolicyKind::Gaussian => "a PGGD policy",
        };
        if saved.policy.kind() != takes {
            return Err(TableError::Misfit(format!(
                "the row \"{}\" takes {wanted}, and {name} is a {} policy; give that row a policy of its kind",
                self.method,
                saved.policy.algo()
            )));
        }
        if saved.is_multi_task() {
            return Err(TableError::Misfit(format!(
                "the row \"{}\" takes a single-task agent, and {name} was trained on several tasks ({}); give that \
                 row a policy trained on one task (the paper's rows are single-task agents)",
                self.method, saved.env_id
            )));
        }
        if let Some(algo) = saved.algo.filter(|a| !self.algos.contains(a)) {
            return Err(TableError::Misfit(format!(
                "the row \"{}\" stands for {}, and {name} was trained by {algo}; give that row a policy its method \
                 trained",
                self.method,
                self.algos.iter().map(|a| a.name()).collect::<Vec<_>>().join(" or ")
            )));
        }
        if let Some(start) = &saved.started_from {
            return Err(TableError::Misfit(format!(
                "the row \"{}\" stands for an agent trained from scratch, and {name} was fine-tuned from {}; give \
                 that row a policy trained from scratch (the paper's rows are)",
                self.method, start.name
            )));
        }
        if saved.env_id != self.trained_on && saved.env_id != played {
            return Err(TableError::Misfit(format!(
                "the row \"{}\" stands for an agent trained on {}{}, and {name} was trained on {}; give that row a \
                 policy trained there",
                self.method,
                self.trained_on,
                if played == self.trained_on { String::new() } else { format!(" (or on {played}, the task played)") },
                saved.env_id
            )));
        }
        Ok(())
    }
}

/// The policy of each row (a file, run directory or zoo name; None: not given).
#[derive(Debug, Clone, Default)]
pub struct Policies {
    /// DDPG trained on BlocksTouch-v0: "DDPG (2 blocks)", AggreVaTeD's expert.
    pub expert: Option<PathBuf>,
    /// DDPG trained on BlocksChoose-v0 with the paper's configuration.
    pub ddpg: Option<PathBuf>,
    /// DDPG trained on BlocksChoose-v0 with this project's changes.
    pub ddpg_ours: Option<PathBuf>,
    /// PGGD trained by AggreVaTeD.
    pub pggd: Option<PathBuf>,
    /// PGGD trained alone.
    pub pggd_alone: Option<PathBuf>,
}

impl Policies {
    /// The shipped zoo's entries for the rows (`table --zoo`).
    pub fn zoo() -> Self {
        let name = |n: &str| Some(PathBuf::from(n));
        Self {
            expert: name(ZOO_EXPERT),
            ddpg: name("BlocksChoose-v0-ddpg"),
            ddpg_ours: name("BlocksChoose-v0-ddpg-ours"),
            pggd: name("BlocksChoose-v0-pggd-aggrevated"),
            pggd_alone: name("BlocksChoose-v0-pggd"),
        }
    }

    /// Each row's policy from `self`, else from `other`.
    pub fn or(self, other: Self) -> Self {
        Self {
            expert: self.expert.or(other.expert),
            ddpg: self.ddpg.or(other.ddpg),
            ddpg_ours: self.ddpg_ours.or(other.ddpg_ours),
            pggd: self.pggd.or(other.pggd),
            pggd_alone: self.pggd_alone.or(other.pggd_alone),
        }
    }
}

/// The zoo entry of the 2-block expert (DDPG on BlocksTouch-v0).
pub const ZOO_EXPERT: &str = "BlocksTouch-v0-ddpg";

/// The paper's rows for the given policies, in the paper's order, this
/// project's DDPG after the paper's (where given), and PGGD alone.
pub fn rows(p: Policies) -> Vec<Row> {
    // This project's row is shown only when it has a policy (it is not the paper's).
    // This project's DDPG may carry TD3's changes; the paper's rows are its own methods.
    let ours = p.ddpg_ours.map(|policy| Row {
        method: "DDPG (3 blocks), ours",
        policy: Some(policy),
        paper: (Some(0.97), Some(0.90)),
        algos: &[Trainer::Ddpg, Trainer::Td3],
        trained_on: ENV,
    });
    let mut rows = vec![
        Row {
            method: "DDPG (2 blocks), grey removed from its view",
            policy: p.expert,
            paper: (Some(0.44), Some(0.24)),
            algos: &[Trainer::Ddpg],
            trained_on: "BlocksTouch-v0",
        },
        Row {
            method: "DDPG (3 blocks)",
            policy: p.ddpg,
            paper: (Some(0.97), Some(0.90)),
            algos: &[Trainer::Ddpg],
            trained_on: ENV,
        },
        Row {
            method: "PGGD + AggreVaTeD",
            policy: p.pggd,
            paper: (Some(0.64), Some(0.40)),
            algos: &[Trainer::Pggd],
            trained_on: ENV,
        },
        // The paper gives no number: "barely passes the first difficulty level after 200 epochs".
        Row {
            method: "PGGD alone",
            policy: p.pggd_alone,
            paper: (None, None),
            algos: &[Trainer::Pggd],
            trained_on: ENV,
        },
    ];
    if let Some(ours) = ours {
        rows.insert(2, ours);
    }
    rows
}

/// A row's result.
#[derive(Debug)]
pub enum RowResult {
    /// No policy was given for the row.
    NotGiven,
    /// The policy could not be loaded or evaluated (the message says why).
    Missing(String),
    /// Evaluated: (Normal, Challenge), the policy's epoch and env steps (where recorded).
    Done {
        normal: Box<Evaluation>,
        challenge: Box<Evaluation>,
        epoch: usize,
        env_steps: Option<u64>,
        /// The policy by content.
        policy: crate::benchmark::provenance::PolicyId,
    },
}

/// Evaluates one row.
pub fn evaluate_row(row: &Row, task: &crate::task::Task, episodes: usize, seed: u64, threads: usize) -> RowResult {
    let Some(path) = &row.policy else { return RowResult::NotGiven };
    // A zoo name without an entry: the row's policy has not been shipped yet.
    if crate::benchmark::zoo::is_name(path)
        && crate::benchmark::zoo::find(&crate::benchmark::zoo::dir(), &path.to_string_lossy()).is_err()
    {
        return RowResult::Missing("not in the zoo yet (train it, then `blockpuzzle zoo export`)".into());
    }
    // The policy file is read once; each evaluation gets its own copy.
    let run = || -> Result<RowResult, TableError> {
        let saved = load_policy(path)?;
        row.check(&saved, task.id())?;
        let (epoch, env_steps) = (saved.epoch, saved.env_steps);
        let policy = saved.policy_id(&path.display().to_string());
        let spec = |challenge| EvalSpec { task, challenge, distribution: None, level: None, episodes, seed, threads };
        let normal = evaluate(path, saved.clone(), &spec(false))?;
        let challenge = evaluate(path, saved, &spec(true))?;
        Ok(RowResult::Done { normal: Box::new(normal), challenge: Box::new(challenge), epoch, env_steps, policy })
    };
    match run() {
        Ok(done) => done,
        Err(e) => RowResult::Missing(crate::support::error::chain(&e)),
    }
}

fn cell(e: &Evaluation, paper: Option<f64>) -> String {
    let paper = paper.map_or("paper: no number".to_owned(), |p| format!("paper {p:.2}"));
    format!("{:.3} ({:.3}–{:.3}); {paper}", e.success_rate, e.ci95.0, e.ci95.1)
}

/// The table as Markdown.
pub fn markdown(rows: &[(Row, RowResult)], env: &str, episodes: usize, seed: u64) -> String {
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
            RowResult::NotGiven => {
                let _ = writeln!(
                    s,
                    "| {} | not trained (paper {}) | not trained (paper {}) | none given |",
                    row.method,
                    paper(row.paper.0),
                    paper(row.paper.1)
                );
            }
            RowResult::Missing(why) => {
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
            RowResult::Done { normal, challenge, epoch, env_steps, .. } => {
                let steps = env_steps.map_or(String::new(), |n| format!(", {:.2} M env steps", n as f64 / 1e6));
                let _ = writeln!(
                    s,
                    "| {} | {} | {} | {} (epoch {epoch}{steps}{}) |",
                    row.method,
                    cell(normal, row.paper.0),
                    cell(challenge, row.paper.1),
                    row.policy.as_deref().map(shown).unwrap_or_default(),
                    if normal.grey_blind { ", grey removed" } else { "" }
                );
            }
        }
    }
    let done: Vec<_> = rows
        .iter()
        .filter_map(|(row, r)| match r {
            RowResult::Done { normal, challenge, .. } => Some((row.method, normal, challenge)),
            _ => None,
        })
        .collect();
    if !done.is_empty() {
        let _ = writeln!(
            s,
            "\nHow the other episodes ended, as shares of all episodes (`failure`: red touched blue; \
             `no_contact`: the gripper touched no block; `off_table`: a blue or green block left the table; \
             `blue_met_grey`: blue touched grey; `timeout`: anything else):\n"
        );
        for (method, normal, challenge) in done {
            let _ = writeln!(
                s,
                "- {method}: Normal {}; Challenge {}",
                normal.outcomes.summary(),
                challenge.outcomes.summary()
            );
        }
    }
    // What made the numbers (crate::benchmark::provenance): the engine above all.
    let _ = writeln!(s, "\nMade on {}, harness cli.", crate::benchmark::provenance::Build::current().describe());
    let done: Vec<String> = rows
        .iter()
        .filter_map(|(row, r)| match r {
            RowResult::Done { policy, .. } => {
                Some(format!("{}: `{}` {}", row.method, policy.name, policy.sha256.as_deref().unwrap_or("none")))
            }
            _ => None,
        })
        .collect();
    let task = rows.iter().find_map(|(_, r)| match r {
        RowResult::Done { normal, .. } => Some(format!("{} {}", normal.env, normal.task_sha256)),
        _ => None,
    });
    if let Some(task) = task {
        let _ = writeln!(s, "Task {task}. Policies by content: {}.", done.join("; "));
    }
    s
}
