//! Task families: a family file (TOML, versioned) describes ranges over the framework — the
//! gripper's, table's and floor's colours, whether the gripper action is on, groups of blocks with
//! a colour, a count range, a size range and a placement rule — and [`Family::draw`] turns a
//! (generator seed, candidate) pair into one task, deterministically. Which candidates are kept
//! (the solver can play them, they are not decided at the first step) is decided above the
//! environment (`crate::episode::generate`); this module is data, like the rest of `task`.

use super::spec::{
    CurriculumSpec, Kind, ObjectSpec, PlacementSpec, RobotSpec, StartSpec, SurfaceSpec, TaskSpec, FORMAT_VERSION,
};
use super::{Task, TaskError, RESERVED_NAMES};
use crate::sim::rules::Colour;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use toml::Spanned;

/// The family file format version this build reads.
pub const FAMILY_VERSION: u32 = 1;

/// Most block groups and most blocks a generated task may have (the task format's own limit is
/// higher; generated tasks stay where the solver and the set networks are tested).
pub const MAX_FAMILY_BLOCKS: usize = 12;

/// The shipped families (`families/NAME.toml`, built in like the tasks): (name, text).
pub const BUILTIN_FAMILIES: &[(&str, &str)] = &[
    ("push", include_str!("../../families/push.toml")),
    ("gripper", include_str!("../../families/gripper.toml")),
    ("stack", include_str!("../../families/stack.toml")),
    ("gather", include_str!("../../families/gather.toml")),
    ("topple", include_str!("../../families/topple.toml")),
    ("avoid", include_str!("../../families/avoid.toml")),
    ("clutter", include_str!("../../families/clutter.toml")),
    ("choose", include_str!("../../families/choose.toml")),
];

/// A floor choice: no rule object, or one of the four colours.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum FloorChoice {
    /// The floor takes no part in the rules.
    None,
    /// Red.
    Red,
    /// Blue.
    Blue,
    /// Green.
    Green,
    /// Grey.
    Grey,
}

impl FloorChoice {
    /// The floor's colour as a rule object, if it is one.
    pub fn colour(self) -> Option<Colour> {
        match self {
            FloorChoice::None => None,
            FloorChoice::Red => Some(Colour::Red),
            FloorChoice::Blue => Some(Colour::Blue),
            FloorChoice::Green => Some(Colour::Green),
            FloorChoice::Grey => Some(Colour::Grey),
        }
    }
}

/// A family file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FamilySpec {
    /// Format version: 1.
    pub version: u32,
    /// The family's name: generated task ids are `NAME-SEED-v0` (e.g. `push-17-v0`).
    pub family: String,
    /// One line on what its tasks ask.
    #[serde(default)]
    pub summary: String,
    /// Steps before `truncated`, in every generated task.
    #[serde(default = "default_steps")]
    pub max_episode_steps: usize,
    /// The gripper colours to draw from (uniformly).
    pub gripper: Vec<Colour>,
    /// Whether the gripper action is on, to draw from (default: off).
    #[serde(default = "default_action")]
    pub gripper_action: Vec<bool>,
    /// The table colours to draw from.
    pub table: Vec<Colour>,
    /// The floor to draw from: "none" (no rule object) or a colour (default: "none").
    #[serde(default = "default_floor")]
    pub floor: Vec<FloorChoice>,
    /// What a generated task must pass to be kept.
    pub check: CheckSpec,
    /// Every generated task's `[placement]` (a task file's table, its defaults included): a family
    /// whose blocks start on others sets `settle_seconds`, as BlocksStack-v0 does.
    #[serde(default)]
    pub placement: PlacementSpec,
    /// Groups of block groups whose roles (colour and start) are dealt to the observation's slots
    /// at random every episode, as BlocksChooseShuffled-v0's are: each generated task's `shuffle`.
    /// A shuffled group is one block in every task (`count = [1, 1]`), and the groups of one
    /// shuffle have the same size range (one size is drawn for all of them), shape and mass.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub shuffle: Vec<Vec<String>>,
    /// The block groups, placed in this order.
    pub blocks: Vec<Spanned<BlockGroup>>,
    /// Every generated task's `[physics]` table: dynamics drawn per episode (absent: nominal).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub physics: Option<super::physics::PhysicsSpec>,
}

fn default_steps() -> usize {
    50
}
fn default_action() -> Vec<bool> {
    vec![false]
}
fn default_floor() -> Vec<FloorChoice> {
    vec![FloorChoice::None]
}

/// The checks a candidate task passes before it is kept.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CheckSpec {
    /// Episodes the solver plays on each candidate (seeds 0 .. episodes).
    #[serde(default = "default_episodes")]
    pub episodes: usize,
    /// The solver's success over those episodes must reach this (no impossible task).
    pub min_solver_success: f64,
    /// The share of episodes decided (success or failure) at the first step must stay below this
    /// (no trivial task; at most 1).
    #[serde(default = "default_decided")]
    pub max_decided_at_first_step: f64,
    /// Candidates tried per generator seed before the seed is given up.
    #[serde(default = "default_candidates")]
    pub max_candidates: usize,
}

fn default_episodes() -> usize {
    20
}
fn default_decided() -> f64 {
    0.5
}
fn default_candidates() -> usize {
    20
}

/// A group of blocks of one colour.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BlockGroup {
    /// Its name in the generated task (copies `NAME.0`, `NAME.1`, … where there are several);
    /// placement rules refer to groups by it.
    pub name: String,
    /// Their colour.
    pub colour: Colour,
    /// How many, `[min, max]`, drawn per task (0 leaves the group out).
    #[serde(default = "default_count", deserialize_with = "super::exact::array")]
    pub count: [usize; 2],
    /// Half side of the (cubic) blocks in metres, `[min, max]`, drawn per task (to the millimetre).
    #[serde(default = "default_size", deserialize_with = "super::exact::array")]
    pub size: [f64; 2],
    /// Fixed half extents (x, y, z) instead of drawn cubes (a wall, a pillar).
    #[serde(default, deserialize_with = "super::exact::option")]
    pub half_extents: Option<[f64; 3]>,
    /// Mass in kg (default: a task file's, 2).
    #[serde(default = "default_mass")]
    pub mass: f64,
    /// Where they start: a task file's `start` (references name groups, the gripper or the table).
    #[serde(default)]
    pub start: StartSpec,
}

fn default_count() -> [usize; 2] {
    [1, 1]
}
fn default_size() -> [f64; 2] {
    [0.025, 0.025]
}
fn default_mass() -> f64 {
    2.0
}

/// The family's `shuffle` can be dealt in every task it draws: each name a group, in one shuffle at
/// most, each group one block always there, and the groups of a shuffle alike in all but their
/// roles. The error says what to change.
fn check_shuffle(spec: &FamilySpec) -> Result<(), String> {
    let groups: Vec<&BlockGroup> = spec.blocks.iter().map(Spanned::get_ref).collect();
    let mut seen: Vec<&str> = Vec::new();
    for shuffle in &spec.shuffle {
        if shuffle.len() < 2 {
            return Err(format!("shuffle {shuffle:?}: a shuffle deals roles among at least two block groups"));
        }
        let mut members = Vec::new();
        for name in shuffle {
            let Some(g) = groups.iter().find(|g| &g.name == name) else {
                let names: Vec<&str> = groups.iter().map(|g| g.name.as_str()).collect();
                return Err(format!(
                    "shuffle names {name:?}, which is not a block group (the groups: {})",
                    names.join(", ")
                ));
            };
            if seen.contains(&name.as_str()) {
                return Err(format!("block group {name:?} is in two shuffles (or twice in one): name it once"));
            }
            seen.push(name);
            if g.count != [1, 1] {
                return Err(format!(
                    "shuffle: group {name:?} has count [{}, {}], so its roles cannot be dealt in every episode; a \
                     shuffled group is one block in every task: give it count = [1, 1], or leave it out of the shuffle",
                    g.count[0], g.count[1]
                ));
            }
            members.push(*g);
        }
        let first = members[0];
        let alike = |g: &BlockGroup| (g.size, g.half_extents, g.mass) == (first.size, first.half_extents, first.mass);
        if let Some(g) = members.iter().find(|g| !alike(g)) {
            return Err(format!(
                "shuffle {shuffle:?}: groups {:?} and {:?} differ in size, half_extents or mass, so their roles cannot \
                 be swapped (a shuffle moves colours and starts, not bodies): give them the same",
                first.name, g.name
            ));
        }
    }
    Ok(())
}

/// A narrowing of a family (a suite row's `choose`): fewer choices for the gripper, the table,
/// the floor or the gripper action, and narrower count ranges for named groups, each within the
/// family's own.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Narrowing {
    /// Gripper colours (each one of the family's).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub gripper: Option<Vec<Colour>>,
    /// Whether the gripper action is on (each one of the family's).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub gripper_action: Option<Vec<bool>>,
    /// Table colours.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub table: Option<Vec<Colour>>,
    /// Floor choices.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub floor: Option<Vec<FloorChoice>>,
    /// Count ranges by group name (within the group's range).
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty", deserialize_with = "super::exact::map")]
    pub counts: BTreeMap<String, [usize; 2]>,
}

/// A checked family: its spec, its text's hash, and where it came from.
#[derive(Debug, Clone)]
pub struct Family {
    /// The spec.
    pub spec: FamilySpec,
    /// `sha256:` of the file's text (suites that name the family record it).
    pub hash: String,
    /// Where the text came from, for errors.
    pub origin: String,
    /// The file's text (None for a narrowed family: its text and the narrowing make it), so that a
    /// stream can carry its families ([`crate::benchmark::stream::FamilyRecord::text`]).
    pub text: Option<String>,
}

/// The most simulation steps the solver's check of one seed may take (check.episodes ×
/// check.max_candidates × max_episode_steps): a few minutes of one core.
pub const MAX_CHECK_STEPS: u64 = 1_000_000;

/// What [`Family::draw`] chose for one candidate, besides the task.
#[derive(Debug, Clone, PartialEq)]
pub struct Drawn {
    /// The task file's text.
    pub toml: String,
    /// The compiled task.
    pub task: Task,
}

impl Family {
    /// Parses and checks a family file's text; `origin` names it in errors.
    ///
    /// # Errors
    /// [`TaskError`] with the line: malformed TOML, an unknown key or colour, an empty choice, an
    /// impossible range (min above max, a size outside 5 mm – 10 cm), too many blocks, a group
    /// named like the gripper or another group, a threshold outside [0, 1].
    pub fn from_toml(text: &str, origin: &str) -> Result<Family, TaskError> {
        let spec: FamilySpec = toml::from_str(text).map_err(|e| TaskError {
            origin: origin.to_owned(),
            line: e.span().map(|s| super::diagnostics::line_of(text, s.start)),
            message: e.message().trim_end().to_owned(),
        })?;
        let at = |span: Option<std::ops::Range<usize>>, message: String| TaskError {
            origin: origin.to_owned(),
            line: span.map(|s| super::diagnostics::line_of(text, s.start)),
            message,
        };
        let err = |message: String| at(None, message);
        if spec.version != FAMILY_VERSION {
            return Err(err(format!(
                "family format version {} is not one this build reads (it reads version {FAMILY_VERSION})",
                spec.version
            )));
        }
        if let Some(physics) = &spec.physics {
            physics.check().map_err(err)?;
        }
        // A group's block shape is `size` (cubes) or `half_extents` (boxes): both would drop one silently.
        if let Ok(raw) = text.parse::<toml::Table>() {
            let groups = raw.get("blocks").and_then(toml::Value::as_array).map_or(&[][..], Vec::as_slice);
            for g in groups.iter().filter_map(toml::Value::as_table) {
                if g.contains_key("size") && g.contains_key("half_extents") {
                    let name = g.get("name").and_then(toml::Value::as_str).unwrap_or("?");
                    return Err(err(format!(
                        "group {name} gives both `size` (a cube's half side) and `half_extents` (a box's); give one"
                    )));
                }
            }
        }
        let plain = |c: char| c.is_ascii_alphanumeric() || c == '-' || c == '_';
        if !spec.family.starts_with(|c: char| c.is_ascii_alphabetic())
            || spec.family.len() > 32
            || !spec.family.chars().all(plain)
        {
            return Err(err(format!(
                "family name {:?}: a letter, then letters, digits, '-' or '_', at most 32 (generated ids are NAME-SEED-v0)",
                spec.family
            )));
        }
        for (what, empty) in [
            ("gripper", spec.gripper.is_empty()),
            ("gripper_action", spec.gripper_action.is_empty()),
            ("table", spec.table.is_empty()),
            ("floor", spec.floor.is_empty()),
            ("blocks", spec.blocks.is_empty()),
        ] {
            if empty {
                return Err(err(format!("`{what}` lists nothing to draw from: give at least one choice")));
            }
        }
        if spec.max_episode_steps == 0 {
            return Err(err("max_episode_steps must be at least 1".into()));
        }
        let c = &spec.check;
        if !(0.0..=1.0).contains(&c.min_solver_success) {
            return Err(err(format!("check.min_solver_success {} must be in [0, 1]", c.min_solver_success)));
        }
        if !(c.max_decided_at_first_step > 0.0 && c.max_decided_at_first_step <= 1.0) {
            return Err(err(format!(
                "check.max_decided_at_first_step {} must be in (0, 1]",
                c.max_decided_at_first_step
            )));
        }
        if c.episodes == 0 || c.episodes > 1000 || c.max_candidates == 0 || c.max_candidates > 1000 {
            return Err(err(format!(
                "check.episodes ({}) and check.max_candidates ({}) must be 1 to 1000",
                c.episodes, c.max_candidates
            )));
        }
        // The solver's check of one seed may play episodes × candidates whole episodes: bounded, so that no
        // family makes `task generate` work for hours on one seed without a word.
        let work = (c.episodes * c.max_candidates) as u64 * spec.max_episode_steps as u64;
        if work > MAX_CHECK_STEPS {
            return Err(err(format!(
                "check.episodes × check.max_candidates × max_episode_steps = {} × {} × {} = {work} steps may go \
                 into one seed's check; at most {MAX_CHECK_STEPS} (the shipped families use 20 × 20 × 50–100): \
                 lower one of them",
                c.episodes, c.max_candidates, spec.max_episode_steps
            )));
        }
        let mut most = 0;
        let mut names: Vec<&str> = Vec::new();
        for g in &spec.blocks {
            let span = Some(g.span());
            let g = g.get_ref();
            if RESERVED_NAMES.contains(&g.name.as_str()) || names.contains(&g.name.as_str()) || g.name.is_empty() {
                return Err(at(span, format!("block group name {:?} is empty, reserved or used twice", g.name)));
            }
            names.push(&g.name);
            if g.count[0] > g.count[1] {
                return Err(at(
                    span,
                    format!("group {}: count [{}, {}] has min above max", g.name, g.count[0], g.count[1]),
                ));
            }
            if !(g.size[0] <= g.size[1] && g.size[0] >= 0.005 && g.size[1] <= 0.1) {
                return Err(at(
                    span,
                    format!(
                        "group {}: size [{}, {}] must be a range within 0.005 to 0.1 m",
                        g.name, g.size[0], g.size[1]
                    ),
                ));
            }
            if let Some(h) = g.half_extents.filter(|h| h.iter().any(|&v| !(0.005..=0.2).contains(&v))) {
                return Err(at(
                    span,
                    format!("group {}: half_extents {h:?} must each be within 0.005 to 0.2 m", g.name),
                ));
            }
            if !(g.mass > 0.0 && g.mass <= 100.0) {
                return Err(at(span, format!("group {}: mass {} must be above 0 and at most 100 kg", g.name, g.mass)));
            }
            most += g.count[1];
        }
        if most > MAX_FAMILY_BLOCKS {
            return Err(err(format!("the groups may draw {most} blocks; a family draws at most {MAX_FAMILY_BLOCKS}")));
        }
        check_shuffle(&spec).map_err(|m| at(super::diagnostics::field_span(text, "shuffle"), m))?;
        let hash = super::compile::sha256_id(text.as_bytes());
        Ok(Family { spec, hash, origin: origin.to_owned(), text: Some(text.to_owned()) })
    }

    /// Reads and checks a family file.
    ///
    /// # Errors
    /// An unreadable file, or what [`Family::from_toml`] refuses.
    pub fn read(path: &std::path::Path) -> Result<Family, TaskError> {
        let origin = path.display().to_string();
        let text = crate::support::io::read_text(path, "family file", crate::support::limits::TEXT_FILE_BYTES)
            .map_err(|e| TaskError { origin: origin.clone(), line: None, message: e.to_string() })?;
        Family::from_toml(&text, &origin)
    }

    /// A shipped family by name, or a family file (relative paths against `dir` where given).
    ///
    /// # Errors
    /// Neither a shipped family nor a readable file, or what [`Family::from_toml`] refuses.
    pub fn load(name_or_path: &str, dir: Option<&std::path::Path>) -> Result<Family, TaskError> {
        if let Some((name, text)) = BUILTIN_FAMILIES.iter().find(|(n, _)| *n == name_or_path) {
            return Family::from_toml(text, &format!("families/{name}.toml"));
        }
        // A file is looked for where it is read from: beside the suite that names it, if any.
        let given = std::path::Path::new(name_or_path);
        let path = dir.map_or_else(|| given.to_owned(), |d| d.join(given));
        if given.extension().is_some_and(|e| e == "toml") || path.exists() {
            return Family::read(&path);
        }
        let known: Vec<&str> = BUILTIN_FAMILIES.iter().map(|(n, _)| *n).collect();
        Err(TaskError {
            origin: name_or_path.to_owned(),
            line: None,
            message: format!(
                "no such family: the shipped ones are {}; or give a family file (.toml)",
                known.join(", ")
            ),
        })
    }

    /// The family narrowed as `n` says: a family of its own, whose hash covers this one's and the
    /// narrowing, whose tasks are drawn from the narrower choices and ranges.
    ///
    /// # Errors
    /// A choice the family does not offer, a group it does not have, a count range outside the
    /// group's, an empty list.
    pub fn narrowed(&self, n: &Narrowing) -> Result<Family, TaskError> {
        let err = |message: String| TaskError { origin: self.origin.clone(), line: None, message };
        fn subset<T: PartialEq + Copy + std::fmt::Debug>(
            what: &str,
            of: &[T],
            pick: &Option<Vec<T>>,
        ) -> Result<Vec<T>, String> {
            let Some(pick) = pick else { return Ok(of.to_vec()) };
            if pick.is_empty() {
                return Err(format!("choose.{what} is empty: give at least one of {of:?}"));
            }
            match pick.iter().find(|p| !of.contains(p)) {
                Some(p) => Err(format!("choose.{what}: {p:?} is not one of the family's {of:?}")),
                None => Ok(pick.clone()),
            }
        }
        let mut spec = self.spec.clone();
        spec.gripper = subset("gripper", &self.spec.gripper, &n.gripper).map_err(err)?;
        spec.gripper_action = subset("gripper_action", &self.spec.gripper_action, &n.gripper_action).map_err(err)?;
        spec.table = subset("table", &self.spec.table, &n.table).map_err(err)?;
        spec.floor = subset("floor", &self.spec.floor, &n.floor).map_err(err)?;
        for (name, range) in &n.counts {
            let Some(g) = spec.blocks.iter_mut().map(Spanned::get_mut).find(|g| &g.name == name) else {
                let names: Vec<&str> = self.spec.blocks.iter().map(|g| g.get_ref().name.as_str()).collect();
                return Err(err(format!(
                    "choose.counts: the family has no group {name:?} (it has {})",
                    names.join(", ")
                )));
            };
            if range[0] > range[1] || range[0] < g.count[0] || range[1] > g.count[1] {
                return Err(err(format!(
                    "choose.counts.{name} = [{}, {}] must be a range within the group's [{}, {}]",
                    range[0], range[1], g.count[0], g.count[1]
                )));
            }
            g.count = *range;
        }
        let narrowing = serde_json::to_string(n).unwrap_or_default();
        let hash = super::compile::sha256_id(format!("{}\n{narrowing}", self.hash).as_bytes());
        Ok(Family { spec, hash, origin: format!("{} (narrowed)", self.origin), text: None })
    }

    /// The id of the task generator seed `seed` gives.
    pub fn task_id(&self, seed: u64) -> String {
        format!("{}-{seed}-v0", self.spec.family)
    }

    /// Candidate `candidate` of generator seed `seed`: every choice drawn from a generator seeded
    /// by the pair alone, so the same family, seed and candidate give the same task anywhere.
    ///
    /// # Errors
    /// A drawn task that does not compile (a placement rule naming a group drawn empty, say),
    /// with the compiler's message.
    pub fn draw(&self, seed: u64, candidate: usize) -> Result<Drawn, TaskError> {
        let s = &self.spec;
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        rng.set_stream(candidate as u64);
        let pick = |rng: &mut ChaCha8Rng, n: usize| rng.gen_range(0..n);
        let gripper = s.gripper[pick(&mut rng, s.gripper.len())];
        let action = s.gripper_action[pick(&mut rng, s.gripper_action.len())];
        let table = s.table[pick(&mut rng, s.table.len())];
        let floor = s.floor[pick(&mut rng, s.floor.len())].colour();
        let mut objects = Vec::new();
        let mut summary = Vec::new();
        let drawn: Vec<(usize, f64)> = s
            .blocks
            .iter()
            .map(|g| {
                let g = g.get_ref();
                let n = rng.gen_range(g.count[0]..=g.count[1]);
                (n, (rng.gen_range(g.size[0]..=g.size[1]) * 1000.0).round() / 1000.0)
            })
            .collect();
        // The groups of a shuffle take the size drawn for its first group (their ranges are one).
        let size_of = |name: &str| {
            let group = s.shuffle.iter().find(|sh| sh.iter().any(|n| n == name)).map_or(name, |sh| sh[0].as_str());
            s.blocks.iter().position(|g| g.get_ref().name == group).map(|i| drawn[i].1)
        };
        for (g, &(n, size)) in s.blocks.iter().zip(&drawn) {
            let g = g.get_ref();
            let size = size_of(&g.name).unwrap_or(size);
            if n == 0 {
                continue;
            }
            summary.push(format!("{n} {}", g.colour));
            objects.push(Spanned::new(
                0..0,
                ObjectSpec {
                    name: g.name.clone(),
                    colour: g.colour,
                    kind: Kind::Box,
                    half_extents: g.half_extents.unwrap_or([size; 3]),
                    mass: g.mass,
                    friction: None,
                    start: g.start.clone(),
                    count: (n > 1).then_some([n, n]),
                },
            ));
        }
        let id = self.task_id(seed);
        let spec = TaskSpec {
            version: FORMAT_VERSION,
            id: id.clone(),
            summary: format!(
                "{} family, seed {seed} (candidate {candidate}): {} gripper{}, {} table, {} floor; {}",
                s.family,
                gripper,
                if action { " with the gripper action" } else { "" },
                table,
                floor.map_or("neutral".to_owned(), |c| c.to_string()),
                summary.join(", ")
            ),
            max_episode_steps: s.max_episode_steps,
            shuffle: s.shuffle.clone(),
            robot: RobotSpec { gripper, gripper_action: action, ..RobotSpec::default() },
            table: SurfaceSpec { colour: table },
            floor: floor.map(|colour| SurfaceSpec { colour }),
            curriculum: CurriculumSpec::default(),
            placement: s.placement.clone(),
            objects,
            distributions: BTreeMap::new(),
            physics: s.physics.clone(),
        };
        let body = toml::to_string(&spec).map_err(|e| TaskError {
            origin: id.clone(),
            line: None,
            message: format!("cannot write the task: {e}"),
        })?;
        let toml = format!(
            "# Generated by `blockpuzzle task generate` from family {} ({}), seed {seed}, candidate {candidate}.\n{body}",
            s.family, self.hash
        );
        let task = Task::from_toml(&toml, None).map_err(|e| TaskError {
            origin: format!("{} (seed {seed}, candidate {candidate})", self.origin),
            line: None,
            message: e.to_string(),
        })?;
        Ok(Drawn { toml, task })
    }
}
