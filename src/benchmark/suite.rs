//! Evaluation suites: frozen, named, versioned splits of what a policy is
//! evaluated on, as files (`suites/NAME.toml`, built in like the tasks).
//!
//! A suite has at least a `train` and a `test` split; each split is a list
//! of rows (task, distribution, curriculum level, first seed, episodes).
//! The seeds of the train rows and the test rows never overlap (an overlap
//! is an error). A *validation suite* has a `train` and a `validation` split
//! instead of a test split: what recipes, epochs and blend weights are chosen
//! on. No task of its validation split may be one a built-in suite holds out
//! (compared by content, not by name), so that choosing on it never reads a
//! test split. A suite is identified by its name and the SHA-256 of its
//! text, which every result carries, so numbers from different versions of
//! a suite are never mixed. The evaluator is `crate::benchmark::evaluate::evaluate_suite`.
//!
//! ```toml
//! version = 1
//! name = "layout"
//! summary = "Train on the curriculum's last level, test on the challenge layouts (the paper's own test)."
//!
//! [[splits.train]]
//! task = "BlocksChoose-v0"
//! seed = 3000000
//! episodes = 200
//!
//! [[splits.test]]
//! task = "BlocksChoose-v0"
//! distribution = "challenge"
//! seed = 1000000
//! episodes = 200
//! ```

use crate::env::{registry, EnvError};
use crate::task::Task;
use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// The suite format this version reads.
pub const SUITE_VERSION: u32 = 1;

/// The built-in suites: (name, text).
pub const BUILTIN: &[(&str, &str)] = &[
    ("colour", include_str!("../../suites/colour.toml")),
    ("layout", include_str!("../../suites/layout.toml")),
    ("cross-task", include_str!("../../suites/cross-task.toml")),
    ("count", include_str!("../../suites/count.toml")),
    ("obstacles", include_str!("../../suites/obstacles.toml")),
    ("procgen", include_str!("../../suites/procgen.toml")),
    ("compose", include_str!("../../suites/compose.toml")),
    ("cross-task-v2", include_str!("../../suites/cross-task-v2.toml")),
    ("procgen-v2", include_str!("../../suites/procgen-v2.toml")),
    ("physics", include_str!("../../suites/physics.toml")),
];

/// The built-in suites' names, comma-separated (what help texts list).
pub fn builtin_names() -> String {
    BUILTIN.iter().map(|(n, _)| *n).collect::<Vec<_>>().join(", ")
}

/// A suite file as written.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
struct SuiteSpec {
    version: u32,
    name: String,
    summary: String,
    /// Named `[physics]` tables (`[physics.test]`) that rows give their tasks (`physics = "test"`).
    #[serde(default)]
    physics: BTreeMap<String, crate::task::physics::PhysicsSpec>,
    splits: BTreeMap<String, Vec<RowSpec>>,
}

/// One row as written: a task, or a family and a range of generator seeds (one row per task).
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
struct RowSpec {
    #[serde(default)]
    task: Option<String>,
    /// A shipped family's name or a family file (relative to the suite's folder).
    #[serde(default)]
    family: Option<String>,
    /// The generator seeds `[first, end)` whose tasks the row stands for.
    #[serde(default, deserialize_with = "crate::task::exact::option")]
    generator_seeds: Option<[u64; 2]>,
    /// Narrower choices than the family's (one rule variation alone, or a combination).
    #[serde(default)]
    choose: Option<crate::task::family::Narrowing>,
    /// Each seed's candidate, pinned (`task generate` records them): the rows are those draws,
    /// whatever the solver and the engine would choose today, and the suite loads without playing.
    #[serde(default)]
    candidates: Option<Vec<usize>>,
    /// The family file's `sha256:` when its candidates were pinned (`task generate` prints it): a
    /// family edited since is refused, as its pins may name other tasks now.
    #[serde(default)]
    family_sha256: Option<String>,
    distribution: Option<String>,
    level: Option<usize>,
    /// One of the suite's `[physics.NAME]` tables, given to the row's tasks (in place of theirs).
    #[serde(default)]
    physics: Option<String>,
    seed: u64,
    episodes: usize,
}

/// A checked suite.
#[derive(Debug, Clone)]
pub struct Suite {
    /// Its name.
    pub name: String,
    /// One line on what it measures.
    pub summary: String,
    /// SHA-256 of the file's text (hex).
    pub sha256: String,
    /// The splits, `train` and `test` first, then any others by name.
    pub splits: Vec<Split>,
    /// Set by [`Suite::first_episodes`]: at most this many episodes per row, a quick look whose
    /// numbers are not the suite's score (results record it in their [`SuiteId`]).
    pub episodes_per_row: Option<usize>,
}

/// A named list of rows.
#[derive(Debug, Clone)]
pub struct Split {
    /// `train`, `test`, or another name.
    pub name: String,
    /// Its rows.
    pub rows: Vec<Row>,
}

/// What one row evaluates.
#[derive(Debug, Clone)]
pub struct Row {
    /// The task.
    pub task: Task,
    /// The id or resolved file path the task was made from (what `registry::task` takes), or for a
    /// generated task `FAMILY-SEED-v0 (family F, seed S, candidate C)` (its text is `task.source.toml`).
    pub source: String,
    /// Whether the task was generated from a family (no file holds it).
    pub generated: bool,
    /// The candidate the suite pins, for a generated task drawn without the solver's check
    /// ([`Suite::check_pinned`] plays what does not depend on the engine).
    pub pinned: Option<usize>,
    /// A named distribution of the task (None: the curriculum's, at `level`).
    pub distribution: Option<String>,
    /// Curriculum level (None: the maximum).
    pub level: Option<usize>,
    /// First seed (episode k plays seed + k).
    pub seed: u64,
    /// Episodes.
    pub episodes: usize,
}

impl Row {
    /// The row's task with `table` as its `[physics]` table (the suite's `[physics.LABEL]`): another
    /// task by content, so its hash and every result that records it say so.
    fn with_physics(&mut self, table: &crate::task::physics::PhysicsSpec, label: &str) -> Result<(), String> {
        let mut spec = self.task.spec.clone();
        spec.physics = Some(table.clone());
        self.task = Task::from_spec(spec).map_err(|e| e.to_string())?;
        self.source = format!("{} with the suite's [physics.{label}]", self.source);
        Ok(())
    }
}

impl Suite {
    /// Checks each pinned candidate of `split` (every split where None): the suite loads it without
    /// playing, so that a pin holds on every engine and build, but one the generator would never keep
    /// (its scene does not build, its layout cannot be drawn, the solver cannot play it) would score 0
    /// for every policy. The checks that play no episode to its end
    /// ([`crate::episode::generate::solver_can_play`]) run here, on `threads` threads: whatever evaluates,
    /// records or trains on a suite's rows calls this first.
    ///
    /// # Errors
    /// [`SuiteError::Invalid`] naming the row and its candidate, and the fix.
    pub fn check_pinned(&self, split: Option<&str>, threads: usize) -> Result<(), SuiteError> {
        use rayon::prelude::*;
        let rows: Vec<(&str, usize, &Row)> = self
            .splits
            .iter()
            .filter(|s| split.map_or(true, |name| s.name == name))
            .flat_map(|s| s.rows.iter().enumerate().map(move |(k, r)| (s.name.as_str(), k, r)))
            .filter(|(_, _, r)| r.pinned.is_some())
            .collect();
        let invalid = |message: String| SuiteError::Invalid { origin: self.name.clone(), message };
        let pool = crate::env::vector::model_threads(threads).map_err(invalid)?;
        pool.install(|| {
            rows.par_iter().try_for_each(|(split, k, r)| {
                crate::episode::generate::solver_can_play(&r.task).map_err(|why| {
                    invalid(format!(
                        "split {split}, row {k}: {} is a candidate the generator would not keep ({why}); pin the \
                         candidate `task generate FAMILY --seed SEED --count 1` keeps for that seed, or leave the seed \
                         out of the row",
                        r.source
                    ))
                })
            })
        })
    }
}

impl Row {
    /// "normal", or the distribution's name.
    pub fn distribution_label(&self) -> &str {
        self.distribution.as_deref().unwrap_or("normal")
    }
}

/// A suite that cannot be read or checked; each names the file and the fix.
#[derive(Debug, thiserror::Error)]
pub enum SuiteError {
    /// No such built-in suite and no such file.
    #[error("unknown suite {name:?}: the built-in suites are {}; or give the path of a suite file (.toml)", known.join(", "))]
    Unknown { name: String, known: Vec<String> },
    /// The file could not be read.
    #[error("cannot read suite file {path}")]
    Read { path: PathBuf, source: std::io::Error },
    /// Malformed TOML, a missing or unknown key.
    #[error("suite {origin}: {message}")]
    Parse { origin: String, message: String },
    /// A check failed.
    #[error("suite {origin}: {message}")]
    Invalid { origin: String, message: String },
}

/// Generator seeds that a built-in suite holds out: a family's seeds in a split other than `train`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct HeldOut {
    /// The suite.
    pub suite: String,
    /// The split that holds them.
    pub split: String,
    /// The family's name (as the suite row names it).
    pub family: String,
    /// The seeds `[first, end)`.
    pub seeds: [u64; 2],
}

/// Every built-in suite's held-out generator seeds (its rows that draw from a family, in every split
/// but `train`): a training stream must not draw them (`train --families`).
pub fn held_out_generator_seeds() -> Vec<HeldOut> {
    let mut out = Vec::new();
    for (name, text) in BUILTIN {
        // The built-in suites parse (a test loads every one); a row's file name is its family's.
        let Ok(spec) = toml::from_str::<SuiteSpec>(text) else { continue };
        for (split, rows) in spec.splits.iter().filter(|(s, _)| s.as_str() != "train") {
            for r in rows {
                if let (Some(family), Some(seeds)) = (&r.family, r.generator_seeds) {
                    let family =
                        Path::new(family).file_stem().map_or(family.clone(), |s| s.to_string_lossy().into_owned());
                    out.push(HeldOut { suite: (*name).to_owned(), split: split.clone(), family, seeds });
                }
            }
        }
    }
    out
}

/// The built-in suite `name`, or the suite file at that path.
///
/// # Errors
/// [`SuiteError`] naming what is wrong.
pub fn load(name_or_path: &str) -> Result<Suite, SuiteError> {
    if let Some((_, text)) = BUILTIN.iter().find(|(n, _)| *n == name_or_path) {
        return parse(text, name_or_path, None);
    }
    let path = Path::new(name_or_path);
    if path.extension().is_some_and(|e| e == "toml") || path.exists() {
        let text = crate::support::io::read_text(path, "suite file", crate::support::limits::TEXT_FILE_BYTES)
            .map_err(|source| SuiteError::Read { path: path.to_owned(), source })?;
        return parse(&text, &path.display().to_string(), path.parent());
    }
    Err(SuiteError::Unknown {
        name: name_or_path.to_owned(),
        known: BUILTIN.iter().map(|(n, _)| (*n).to_owned()).collect(),
    })
}

/// Parses and checks a suite's text; `origin` names it in errors, `dir` is
/// where task file paths in it are relative to.
///
/// # Errors
/// [`SuiteError::Parse`] or [`SuiteError::Invalid`].
pub fn parse(text: &str, origin: &str, dir: Option<&Path>) -> Result<Suite, SuiteError> {
    let spec: SuiteSpec =
        toml::from_str(text).map_err(|e| SuiteError::Parse { origin: origin.to_owned(), message: e.to_string() })?;
    let invalid = |message: String| SuiteError::Invalid { origin: origin.to_owned(), message };
    if spec.version != SUITE_VERSION {
        return Err(invalid(format!("version {} is not one this build reads ({SUITE_VERSION})", spec.version)));
    }
    let plain = |c: char| c.is_ascii_alphanumeric() || matches!(c, '-' | '_' | '.');
    if spec.name.is_empty() || spec.name.len() > 64 || spec.name.starts_with('.') || !spec.name.chars().all(plain) {
        return Err(invalid(format!(
            "name {:?}: a suite's name goes into file names, so it is 1 to 64 letters, digits, '-', '_' or '.' \
             (not first); for example \"my-suite\"",
            crate::support::limits::cut_long_lines(&spec.name)
        )));
    }
    for (label, table) in &spec.physics {
        table.check().map_err(|e| invalid(format!("[physics.{label}]: {e}")))?;
    }
    let kind = SuiteKind::of(|n| spec.splits.contains_key(n));
    for required in ["train", kind.scored_split()] {
        if !spec.splits.contains_key(required) {
            return Err(invalid(format!(
                "it has no {required} split: add [[splits.{required}]] rows (a suite has train and test splits, a \
                 validation suite train and validation splits)"
            )));
        }
    }
    let mut names: Vec<&String> = spec.splits.keys().collect();
    names.sort_by_key(|n| (n.as_str() != "train", n.as_str() != kind.scored_split(), n.as_str().to_owned()));
    let mut splits = Vec::new();
    let mut families = Vec::new();
    for name in names {
        let rows = &spec.splits[name];
        if rows.is_empty() {
            return Err(invalid(format!("split {name} is empty")));
        }
        let mut out = Vec::new();
        for (i, r) in rows.iter().enumerate() {
            let what = r.task.as_deref().or(r.family.as_deref()).unwrap_or("?");
            let at = |m: String| invalid(format!("splits.{name}[{i}] ({what}): {m}"));
            let physics = match &r.physics {
                None => None,
                Some(p) => Some(spec.physics.get(p).ok_or_else(|| {
                    let known: Vec<&str> = spec.physics.keys().map(String::as_str).collect();
                    at(format!(
                        "physics = {p:?} names no [physics.{p}] table of the suite (it has: {}); add the table or name \
                         one it has",
                        if known.is_empty() { "none".to_owned() } else { known.join(", ") }
                    ))
                })?),
            };
            let first = out.len();
            match (&r.task, &r.family, r.generator_seeds) {
                (Some(_), None, None) if r.choose.is_none() && r.candidates.is_none() && r.family_sha256.is_none() => {
                    out.push(row(r, dir).map_err(at)?)
                }
                (None, Some(f), Some(seeds)) => {
                    let mut family = crate::task::family::Family::load(f, dir).map_err(|e| at(e.to_string()))?;
                    if let Some(pinned) = r.family_sha256.as_deref().filter(|&h| h != family.hash) {
                        return Err(at(format!(
                            "the family is not the one its candidates were pinned from (family_sha256 = {pinned:?}, \
                             the file now {:?}): restore the family, or pin again from `task generate {f}` and set \
                             family_sha256 to the hash it prints",
                            family.hash
                        )));
                    }
                    if let Some(n) = &r.choose {
                        family = family.narrowed(n).map_err(|e| at(e.message))?;
                    }
                    families.push(family.hash.clone());
                    out.extend(generated_rows(r, &family, seeds).map_err(at)?);
                }
                _ => {
                    return Err(at(
                        "a row names a `task`, or a `family` with `generator_seeds = [first, end]` (and `choose`, `candidates`, `family_sha256`), not both"
                            .into(),
                    ))
                }
            }
            if let (Some(table), Some(label)) = (physics, &r.physics) {
                for row in &mut out[first..] {
                    row.with_physics(table, label).map_err(at)?;
                }
            }
        }
        splits.push(Split { name: name.clone(), rows: out });
    }
    check_disjoint(&splits).map_err(invalid)?;
    check_no_repeats(&splits).map_err(invalid)?;
    if splits.iter().any(|s| s.name == "validation") {
        check_validation_held_out(&splits, kind).map_err(invalid)?;
    }
    // The suite's identity covers the families its rows draw from.
    let mut h = Sha256::new();
    h.update(text.as_bytes());
    for f in &families {
        h.update(f.as_bytes());
    }
    Ok(Suite { name: spec.name, summary: spec.summary, sha256: hex(&h.finalize()), splits, episodes_per_row: None })
}

/// Most generator seeds one row may name (each is a task checked by the solver when the suite loads).
pub const MAX_GENERATED_ROWS: u64 = 200;

/// The rows of a family's generator seeds: one per seed, each its generated task (a seed without
/// one is an error naming it).
fn generated_rows(
    r: &RowSpec,
    family: &crate::task::family::Family,
    [first, end]: [u64; 2],
) -> Result<Vec<Row>, String> {
    if first >= end || end - first > MAX_GENERATED_ROWS {
        return Err(format!(
            "generator_seeds = [{first}, {end}] must be a range [first, end) of 1 to {MAX_GENERATED_ROWS} seeds"
        ));
    }
    let as_row = |task: Task, id: &str, seed: u64, candidate: usize| -> Result<Row, String> {
        let source = format!("{id} (family {}, seed {seed}, candidate {candidate})", family.spec.family);
        let mut row = row_of(task, source, r)?;
        row.generated = true;
        Ok(row)
    };
    if let Some(pins) = &r.candidates {
        if pins.len() as u64 != end - first {
            return Err(format!(
                "candidates lists {} entries for the {} generator seeds [{first}, {end}): give one per seed",
                pins.len(),
                end - first
            ));
        }
        let most = family.spec.check.max_candidates;
        let drawn = (first..end)
            .zip(pins)
            .map(|(seed, &c)| {
                if c >= most {
                    return Err(format!(
                        "candidates: {c} for seed {seed} is beyond the family's max_candidates = {most} (0 to {})",
                        most - 1
                    ));
                }
                let drawn = family.draw(seed, c).map_err(|e| format!("seed {seed}, candidate {c}: {}", e.message))?;
                Ok((seed, c, drawn.task))
            })
            .collect::<Result<Vec<_>, String>>()?;
        return drawn
            .into_iter()
            .map(|(seed, c, task)| {
                let mut row = as_row(task, &family.task_id(seed), seed, c)?;
                row.pinned = Some(c);
                Ok(row)
            })
            .collect();
    }
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    let results = crate::episode::generate::generate(family, first, (end - first) as usize, threads)
        .map_err(|e| e.to_string())?;
    results
        .into_iter()
        .map(|g| {
            let Some(t) = g.task else {
                return Err(format!(
                    "generator seed {} of family {} gives no task within {} candidates; leave it out of the range",
                    g.seed, family.spec.family, family.spec.check.max_candidates
                ));
            };
            let task = Task::from_toml(&t.toml, None).map_err(|e| e.to_string())?;
            as_row(task, &t.id, g.seed, t.candidate)
        })
        .collect()
}

/// One row compiled and checked.
fn row(r: &RowSpec, dir: Option<&Path>) -> Result<Row, String> {
    let name = r.task.as_deref().unwrap_or_default();
    let id = if registry::is_path(name) {
        dir.map_or_else(|| PathBuf::from(name), |d| d.join(name)).display().to_string()
    } else {
        name.to_owned()
    };
    let task = registry::task(&id).map_err(|e: EnvError| e.to_string())?;
    row_of(task, id, r)
}

/// The row of `task` (made from `source`) with `r`'s distribution, level, seed and episodes, checked.
fn row_of(task: Task, id: String, r: &RowSpec) -> Result<Row, String> {
    let distribution = match r.distribution.as_deref() {
        None | Some("normal") => None,
        Some(name) => {
            if task.distribution(name).is_none() {
                let known: Vec<&str> = task.spec.distributions.keys().map(String::as_str).collect();
                return Err(format!(
                    "the task has no distribution {name:?} (it has: normal{}{})",
                    if known.is_empty() { "" } else { ", " },
                    known.join(", ")
                ));
            }
            Some(name.to_owned())
        }
    };
    if let Some(l) = r.level {
        if l > task.max_level() {
            return Err(format!("level {l} is beyond the task's maximum level {}", task.max_level()));
        }
    }
    crate::support::limits::Bound { name: "episodes", ..crate::support::limits::EVAL_EPISODES }
        .check_usize(r.episodes)?;
    crate::support::limits::seed_range(r.seed, r.episodes as u64)?;
    Ok(Row {
        task,
        source: id,
        generated: false,
        pinned: None,
        distribution,
        level: r.level,
        seed: r.seed,
        episodes: r.episodes,
    })
}

/// What a suite measures, by its splits.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SuiteKind {
    /// A benchmark suite: `train` and `test`; its score is the test split's.
    Benchmark,
    /// A validation suite: `train` and `validation`, no `test`; what recipes are chosen on.
    Validation,
}

impl SuiteKind {
    /// The kind of a suite whose split names `has` says it has: a validation split and no test
    /// split make a validation suite.
    pub fn of(has: impl Fn(&str) -> bool) -> SuiteKind {
        if has("validation") && !has("test") {
            SuiteKind::Validation
        } else {
            SuiteKind::Benchmark
        }
    }

    /// The split its score is read from: `test`, or `validation`.
    pub fn scored_split(self) -> &'static str {
        match self {
            SuiteKind::Benchmark => "test",
            SuiteKind::Validation => "validation",
        }
    }
}

/// The seeds of every train row and every test or validation row must not overlap.
fn check_disjoint(splits: &[Split]) -> Result<(), String> {
    let rows =
        |name: &'static str| splits.iter().filter(move |s| s.name == name).flat_map(|s| s.rows.iter().enumerate());
    for held in ["test", "validation"] {
        for (i, a) in rows("train") {
            for (j, b) in rows(held) {
                if let Some((a_end, b_end)) = seeds_overlap(a, b) {
                    return Err(format!(
                        "the seeds of splits.train[{i}] ({}..{a_end}) and splits.{held}[{j}] ({}..{b_end}) overlap; \
                         train and {held} seeds must be disjoint",
                        a.seed, b.seed
                    ));
                }
            }
        }
    }
    Ok(())
}

/// A task a built-in suite holds out: a row of a split other than `train`.
#[derive(Debug, Clone)]
pub struct HeldOutTask {
    /// The suite.
    pub suite: String,
    /// The split.
    pub split: String,
    /// The task's id, as the suite's row gives it.
    pub id: String,
    /// The task's content hash, id and summary set aside ([`Task::content_hash`]).
    pub content: String,
}

/// Every task a built-in suite holds out (its rows in every split but `train`), by content.
///
/// # Errors
/// A built-in suite that does not load (a test loads every one).
pub fn held_out_tasks() -> Result<Vec<HeldOutTask>, SuiteError> {
    let mut out = Vec::new();
    for (name, text) in BUILTIN {
        let suite = parse(text, name, None)?;
        for split in suite.splits.iter().filter(|s| s.name != "train") {
            out.extend(split.rows.iter().map(|r| HeldOutTask {
                suite: suite.name.clone(),
                split: split.name.clone(),
                id: r.task.id().to_owned(),
                content: r.task.content_hash(),
            }));
        }
    }
    Ok(out)
}

/// No row of a validation split may be a task a built-in suite holds out: choosing a recipe on it
/// would read that suite's test split. In a validation suite this holds for every split (its train
/// rows are chosen on too). Compared by content, so a family copied under another name, or a task
/// file copied from a built-in one, is caught.
fn check_validation_held_out(splits: &[Split], kind: SuiteKind) -> Result<(), String> {
    let held = held_out_tasks().map_err(|e| e.to_string())?;
    let checked = |s: &&Split| s.name == "validation" || kind == SuiteKind::Validation;
    for split in splits.iter().filter(checked) {
        for (i, row) in split.rows.iter().enumerate() {
            let content = row.task.content_hash();
            if let Some(h) = held.iter().find(|h| h.content == content) {
                return Err(format!(
                    "splits.{}[{i}] ({}) is {}, a task the built-in suite {} holds out in its {} split: \
                     choosing a recipe on it would read that split. Validate on tasks no suite holds out (for a \
                     family, generator seeds outside every suite's; procgen-v2 holds out 20000-20009, compose \
                     100-103 of push and gripper)",
                    split.name, row.source, h.id, h.suite, h.split
                ));
            }
        }
    }
    Ok(())
}

/// The ends of two rows' seed ranges (`seed..seed + episodes`) where the ranges overlap.
fn seeds_overlap(a: &Row, b: &Row) -> Option<(u64, u64)> {
    let (a_end, b_end) = (a.seed.saturating_add(a.episodes as u64), b.seed.saturating_add(b.episodes as u64));
    (a.seed < b_end && b.seed < a_end).then_some((a_end, b_end))
}

/// No two rows of a split may play the same episodes (the same task content,
/// distribution and level with overlapping seeds): the mean would count
/// them twice.
fn check_no_repeats(splits: &[Split]) -> Result<(), String> {
    for split in splits {
        for (i, a) in split.rows.iter().enumerate() {
            for (j, b) in split.rows.iter().enumerate().skip(i + 1) {
                let same = a.task.source.hash == b.task.source.hash
                    && a.distribution == b.distribution
                    && a.level.unwrap_or(a.task.max_level()) == b.level.unwrap_or(b.task.max_level());
                if let Some((a_end, b_end)) = seeds_overlap(a, b).filter(|_| same) {
                    return Err(format!(
                        "splits.{0}[{i}] and splits.{0}[{j}] play the same episodes ({1}, {2}, seeds {3}..{a_end} \
                         and {4}..{b_end}), which the mean would count twice; remove one or give it other seeds",
                        split.name,
                        a.task.id(),
                        a.distribution_label(),
                        a.seed,
                        b.seed
                    ));
                }
            }
        }
    }
    Ok(())
}

fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

/// What a result records of the suite it came from.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct SuiteId {
    /// Its name.
    pub name: String,
    /// SHA-256 of its text.
    pub sha256: String,
    /// Present when the run was shortened ([`Suite::first_episodes`]): at most this many episodes
    /// per row. Such a result is not the suite's score: `results` refuses it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub episodes_per_row: Option<usize>,
}

impl Suite {
    /// Its name and hash, as results record them.
    pub fn id(&self) -> SuiteId {
        SuiteId { name: self.name.clone(), sha256: self.sha256.clone(), episodes_per_row: self.episodes_per_row }
    }

    /// The suite shortened to the first `episodes` episodes of every row (rows with fewer keep
    /// theirs): a quick look at a policy, recorded as such in every result it makes.
    ///
    /// # Errors
    /// `episodes` is 0.
    pub fn first_episodes(mut self, episodes: usize) -> Result<Suite, SuiteError> {
        if episodes == 0 {
            return Err(SuiteError::Invalid {
                origin: self.name.clone(),
                message: "a shortened run needs at least 1 episode per row".into(),
            });
        }
        for row in self.splits.iter_mut().flat_map(|s| s.rows.iter_mut()) {
            row.episodes = row.episodes.min(episodes);
        }
        self.episodes_per_row = Some(episodes);
        Ok(self)
    }
}
