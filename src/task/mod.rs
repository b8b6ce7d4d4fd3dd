//! Layer 3, task: tasks as data, with no MuJoCo.
//!
//! | module | what |
//! |---|---|
//! | [`spec`] | the task file format (TOML, version 1), every default written once |
//! | `compile` | the compiler: a spec checked against its ranges and references, counts expanded |
//! | `diagnostics` | what a task file's errors say ([`TaskError`]): file, line, the fix |
//! | `exact` | fixed-length lists read strictly |
//! | [`expr`] | curriculum expressions over named values (`min(0.08 + 0.025 * level, 0.20)`) |
//! | [`sampler`] | layouts drawn from a task's start specs |
//! | [`counts`] | count ranges given from outside a file (`train --counts grey=0-2`) |
//! | [`family`] | task families: ranges over the framework that generate tasks |
//! | [`physics`] | a task's `[physics]` table: per-episode ranges of the dynamics, their bounds and the draw |
//!
//! Tasks as data: a task file (TOML, [`spec`]) describes the objects, their
//! colours and sizes, where each starts (samplers over the curriculum
//! level), the curriculum, named evaluation distributions, the gripper and
//! table colours, and the episode length. [`Task::from_toml`] checks a file
//! and compiles it; [`sampler`] draws layouts from it. The built-in
//! environments are task files too (`tasks/*.toml`, embedded in the binary)
//! and go through the same code.

mod compile;
pub mod counts;
mod diagnostics;
pub(crate) mod exact;
pub mod expr;
pub mod family;
pub mod physics;
pub mod sampler;
pub mod spec;

use spec::{ObjectSpec, TaskSpec};

use crate::sim::rules::{Colour, MAX_OBJECTS};
pub(crate) use compile::{draws_nothing, least_count, parse_value, Checker, Scope};
pub use diagnostics::TaskError;
use serde::{Deserialize, Serialize};
use std::path::PathBuf;

/// Names objects may not take: they name the robot and the surfaces.
pub const RESERVED_NAMES: [&str; 3] = ["gripper", "table", "floor"];
/// Most objects a task may place (the gripper, table and floor are rule objects too).
pub const MAX_TASK_OBJECTS: usize = MAX_OBJECTS - RESERVED_NAMES.len();
/// Highest curriculum level a task may have.
pub const MAX_LEVEL: usize = 1000;

/// Where a task came from and its exact text, so that runs, saved policies
/// and dumps can rebuild it after the file moved or changed.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct TaskSource {
    /// The task id.
    pub id: String,
    /// The file it was read from (absent for built-ins and tasks made in code).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub path: Option<PathBuf>,
    /// The task file's text.
    pub toml: String,
    /// `sha256:` of the canonical form of the spec (comments and layout do not count).
    pub hash: String,
}

impl TaskSource {
    /// The task of the recorded text, checked against the recorded hash: a
    /// copy whose text was edited (its hash left as it was) is refused rather
    /// than run as if it were the recorded task.
    ///
    /// # Errors
    /// Text that does not compile, or compiles to another task than `hash` names.
    pub fn compile(&self) -> Result<Task, TaskError> {
        let origin = format!("the recorded copy of {}", self.id);
        if !crate::support::limits::is_sha256(&self.hash) {
            return Err(TaskError {
                origin,
                line: None,
                message: format!(
                    "its hash {:?} is not a content hash (sha256: and 64 hex digits): the record was damaged or \
                     written by hand; restore the original file",
                    crate::support::limits::cut_long_lines(&self.hash)
                ),
            });
        }
        let mut task = Task::parse(&self.toml, &origin, None)?;
        if task.source.hash != self.hash {
            return Err(TaskError {
                origin,
                line: None,
                message: format!(
                    "its text is not the task its hash {} names (the text was edited, its hash was not); restore \
                     the original file",
                    self.hash
                ),
            });
        }
        task.source.path.clone_from(&self.path);
        Ok(task)
    }
}

/// A compiled named distribution: its level, parameter values, starts and
/// count ranges (one per [`CountGroup`]).
#[derive(Debug, Clone)]
pub(crate) struct Distribution {
    pub name: String,
    pub level: usize,
    pub values: Vec<f64>,
    pub starts: Vec<sampler::Placement>,
    pub counts: Vec<[usize; 2]>,
}

/// The copies of one object entry with a `count`: objects `first` ..
/// `first + max`, of which the first n, drawn from `range`, take part.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct CountGroup {
    /// The entry's name (its copies are `NAME.0`, `NAME.1`, …).
    pub entry: String,
    /// Index of `NAME.0` among the task's objects.
    pub first: usize,
    /// Copies in the scene.
    pub max: usize,
    /// The curriculum's count range.
    pub range: [usize; 2],
}

/// A checked, compiled task.
#[derive(Debug, Clone)]
pub struct Task {
    /// The spec as written.
    pub spec: TaskSpec,
    /// The objects of the scene: the spec's, with every entry that has a
    /// count expanded into its copies (`NAME.0` …).
    objects: Vec<ObjectSpec>,
    /// The entries with a count, in file order.
    groups: Vec<CountGroup>,
    /// Where it came from.
    pub source: TaskSource,
    /// Parameter names, in evaluation order after `level`, `max_level`, `pi`.
    pub(crate) names: Vec<String>,
    /// Values of `names` at each level of the normal curriculum.
    pub(crate) values: Vec<Vec<f64>>,
    /// Compiled starts of the objects.
    pub(crate) starts: Vec<sampler::Placement>,
    /// Compiled named distributions.
    pub(crate) distributions: Vec<Distribution>,
    /// Object indices of each shuffle group.
    pub(crate) shuffle: Vec<Vec<usize>>,
    /// No random draw and no shuffle: every layout is the same.
    deterministic: bool,
}

impl PartialEq for Task {
    fn eq(&self, other: &Self) -> bool {
        self.spec == other.spec
    }
}

/// Counts of reasons (why layouts were redrawn), in order of first appearance.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Tally(Vec<(String, u64)>);

impl Tally {
    /// Counts one more `reason`.
    pub fn add(&mut self, reason: &str) {
        match self.0.iter_mut().find(|(r, _)| r == reason) {
            Some(e) => e.1 += 1,
            None => self.0.push((reason.to_owned(), 1)),
        }
    }
    /// Every reason and its count.
    pub fn iter(&self) -> impl Iterator<Item = (&str, u64)> {
        self.0.iter().map(|(r, n)| (r.as_str(), *n))
    }
    /// The sum of the counts.
    pub fn total(&self) -> u64 {
        self.0.iter().map(|e| e.1).sum()
    }
    /// "REASON in N of them" for the most frequent reason (empty when none).
    pub fn most(&self) -> String {
        self.0.iter().max_by_key(|e| e.1).map(|(r, n)| format!("{r} in {n} of them")).unwrap_or_default()
    }
}

/// Whether a task id is safe in file names: `Name-vN`, a letter first, then
/// letters, digits, '_' and '-', at most 64 characters.
pub fn is_safe_id(id: &str) -> bool {
    let Some((name, version)) = id.rsplit_once("-v") else { return false };
    id.len() <= 64
        && name.starts_with(|c: char| c.is_ascii_alphabetic())
        && name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-')
        && !version.is_empty()
        && version.chars().all(|c| c.is_ascii_digit())
}

impl Task {
    /// The id.
    pub fn id(&self) -> &str {
        &self.spec.id
    }
    /// Highest curriculum level.
    pub fn max_level(&self) -> usize {
        self.spec.curriculum.max_level
    }
    /// Names of the evaluation distributions.
    pub fn distribution_names(&self) -> Vec<&str> {
        self.distributions.iter().map(|d| d.name.as_str()).collect()
    }
    /// Index of a named distribution.
    pub fn distribution(&self, name: &str) -> Option<usize> {
        self.distributions.iter().position(|d| d.name == name)
    }
    /// Object colours as written (before any shuffle), in object order.
    pub fn colours(&self) -> Vec<Colour> {
        self.objects.iter().map(|o| o.colour).collect()
    }
    /// The scene's objects in order (an entry with a count stands for its
    /// copies `NAME.0` …, each listed here).
    pub fn objects(&self) -> impl Iterator<Item = &ObjectSpec> {
        self.objects.iter()
    }
    /// Number of objects in the scene (every copy of a counted entry
    /// included): the observation's object slots.
    pub fn object_count(&self) -> usize {
        self.objects.len()
    }
    /// The entries whose number of copies varies per episode.
    pub fn count_groups(&self) -> &[CountGroup] {
        &self.groups
    }
    /// The count range of `group` in `distribution` (or the curriculum's).
    pub fn count_range(&self, group: usize, distribution: Option<usize>) -> [usize; 2] {
        distribution.map_or(self.groups[group].range, |d| self.distributions[d].counts[group])
    }
    /// Which objects take part in an episode: for each entry with a count,
    /// n uniform in its range (one draw from `rng`, only where the range has
    /// more than one value), then its first n copies. Tasks without counts
    /// draw nothing (all present).
    ///
    /// # Panics
    /// A `distribution` index that [`Task::distribution`] did not give.
    pub fn draw_present(&self, distribution: Option<usize>, rng: &mut impl rand::Rng) -> Vec<bool> {
        let mut present = vec![true; self.objects.len()];
        for (g, group) in self.groups.iter().enumerate() {
            let [lo, hi] = self.count_range(g, distribution);
            let n = if lo == hi { lo } else { rng.gen_range(lo..=hi) };
            present[group.first + n..group.first + group.max].fill(false);
        }
        present
    }
    /// Whether every layout is the same: no random draw, no shuffle.
    pub fn is_deterministic(&self) -> bool {
        self.deterministic
    }
    /// Parameter values at `level` (or of a distribution), by name.
    pub fn params(&self, level: usize, distribution: Option<usize>) -> Vec<(String, f64)> {
        let vals = match distribution {
            Some(d) => &self.distributions[d].values,
            None => &self.values[level.min(self.max_level())],
        };
        self.names.iter().cloned().zip(vals.iter().copied()).collect()
    }
}
