//! `blockpuzzle task check`: a task file is compiled (every error with its
//! file and line), then reset many times at every level and in every named
//! distribution, and the cost of its layouts is reported: how often the
//! sampler redrew (a constraint failed) and how often the physics checks
//! redrew (objects overlapping, a stack falling over while settling, red
//! touching blue, the task already solved at reset). A reset that cannot be
//! made at all is reported with its reason.

use crate::env::{BlockEnv, EnvError, ResetStats};
use crate::task::Task;

/// What resetting one level (or distribution) cost.
#[derive(Debug, Clone, PartialEq)]
pub struct LevelReport {
    /// `level 3` or `distribution challenge`.
    pub label: String,
    /// Resets asked for.
    pub samples: u64,
    /// The counters of those resets.
    pub stats: ResetStats,
    /// Why resetting failed, if it did.
    pub error: Option<String>,
}

impl LevelReport {
    /// Share of the sampler's draws it rejected.
    pub fn sampler_rejection(&self) -> f64 {
        1.0 - self.stats.layouts as f64 / (self.stats.draws.max(1)) as f64
    }
    /// Share of the layouts the physics checks rejected.
    pub fn physics_rejection(&self) -> f64 {
        self.stats.rejected.total() as f64 / self.stats.layouts.max(1) as f64
    }
    /// One line for the terminal.
    pub fn line(&self) -> String {
        let mut s = format!(
            "{:<26} {:>4}/{} resets  sampler rejected {:>5.1}% of {} draws  physics rejected {:>5.1}% of {} layouts",
            self.label,
            self.stats.resets,
            self.samples,
            100.0 * self.sampler_rejection(),
            self.stats.draws,
            100.0 * self.physics_rejection(),
            self.stats.layouts
        );
        for (reason, n) in self.stats.rejected.iter() {
            s.push_str(&format!("\n{:<28}{n} x {reason}", ""));
        }
        if let Some(e) = &self.error {
            s.push_str(&format!("\n{:<28}FAILED: {e}", ""));
        }
        s
    }
}

/// Every level's and distribution's report.
#[derive(Debug, Clone, PartialEq)]
pub struct CheckReport {
    /// The task, compiled.
    pub task: Task,
    /// Reports in order: levels 0..=max, then the distributions.
    pub levels: Vec<LevelReport>,
}

impl CheckReport {
    /// Whether every level could be reset every time.
    pub fn ok(&self) -> bool {
        self.levels.iter().all(|l| l.error.is_none())
    }
}

/// The settings of each level and distribution: `(label, level, distribution)`.
pub fn settings(task: &Task) -> Vec<(String, usize, Option<String>)> {
    let mut out: Vec<_> = (0..=task.max_level()).map(|l| (format!("level {l}"), l, None)).collect();
    for d in task.distribution_names() {
        out.push((format!("distribution {d}"), task.max_level(), Some(d.to_owned())));
    }
    out
}

/// Resets `task` `samples` times (seeds `seed`, `seed + 1`, …) at every
/// level and in every distribution, calling `on_reset` after each reset (a
/// progress bar's tick).
///
/// # Errors
/// Seeds that would pass 2⁶⁴ − 1, or a scene MuJoCo refuses.
pub fn check(task: Task, samples: u64, seed: u64, on_reset: &mut dyn FnMut()) -> Result<CheckReport, EnvError> {
    crate::support::limits::seed_range(seed, samples).map_err(EnvError::Config)?;
    let config = crate::env::EnvConfig::new(task);
    let settings = settings(&config.task);
    let mut levels = Vec::new();
    for (label, level, distribution) in settings {
        let mut env = BlockEnv::new(config.clone())?;
        env.set_level(level)?;
        env.set_distribution(distribution.as_deref())?;
        let mut error = None;
        for k in 0..samples {
            let reset = env.reset(Some(seed + k));
            on_reset();
            if let Err(e) = reset {
                error = Some(e.to_string());
                break;
            }
        }
        levels.push(LevelReport { label, samples, stats: env.reset_stats().clone(), error });
    }
    Ok(CheckReport { task: config.task, levels })
}
