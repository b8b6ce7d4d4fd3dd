//! Task streams: training tasks generated from families over a range of generator seeds, with no task
//! file written by hand (`train --families push,topple --generator-seeds 0..256`).
//!
//! A stream's pool is every task the families give for the seeds of the range (a seed whose candidates
//! all fail gives none), in family order, then seed order. Working a seed out costs the solver's check
//! ([`crate::episode::generate`]): up to `max_candidates × episodes` episodes. A disk cache keeps each seed's
//! kept candidate by family hash and engine, so a second run over the same pool draws its tasks
//! without playing (the kept candidate is drawn again and its hash compared with the cached one).
//! The cache is a help, never a source of truth: a missing, unreadable or stale entry, or one whose
//! seal does not match (an edit), is worked out again.
//!
//! A stream records itself ([`StreamRecord`]): its families by name and hash, its seed range and each
//! task by id, seed, candidate and hash. A run's `config.json` keeps that record; resume compares it.
//! Streams refuse seeds that a built-in suite holds out ([`crate::benchmark::suite::held_out_generator_seeds`]).

use crate::episode::generate::{generate_seed, SeedResult, GENERATOR_VERSION};
use crate::task::family::Family;
use crate::task::Task;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// The most generator seeds one stream may span (per family).
pub const MAX_STREAM_SEEDS: u64 = 100_000;

/// A range of generator seeds `[first, end)`, written `FIRST..END` on the command line.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct SeedRange(pub [u64; 2]);

impl SeedRange {
    /// The number of seeds in the range.
    pub fn len(&self) -> u64 {
        self.0[1].saturating_sub(self.0[0])
    }

    /// Whether the range holds no seed.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

impl std::fmt::Display for SeedRange {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}..{}", self.0[0], self.0[1])
    }
}

impl std::str::FromStr for SeedRange {
    type Err = String;

    /// `FIRST..END` (END excluded), e.g. `0..1024`.
    fn from_str(s: &str) -> Result<Self, String> {
        let usage = "write the generator seeds as FIRST..END (END excluded), e.g. 0..1024";
        let Some((a, b)) = s.trim().split_once("..") else {
            return Err(format!("{s:?} is not a seed range; {usage}"));
        };
        let num = |x: &str| x.trim().parse::<u64>().map_err(|_| format!("{x:?} in {s:?} is not a seed; {usage}"));
        let (first, end) = (num(a)?, num(b)?);
        if end <= first {
            return Err(format!("the seed range {s} is empty (END must be above FIRST); {usage}"));
        }
        if end - first > MAX_STREAM_SEEDS {
            return Err(format!(
                "the seed range {s} spans {} seeds; a stream spans at most {MAX_STREAM_SEEDS} seeds a family",
                end - first
            ));
        }
        Ok(SeedRange([first, end]))
    }
}

/// The largest weight `--family-weights` gives a family.
pub const MAX_FAMILY_WEIGHT: usize = 16;

/// How many times each named family's tasks stand in every pass over a stream's pool (the families
/// it does not name: once), written `avoid=3,gather=2` on the command line: so many times as often
/// its tasks have environments, and episodes.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(transparent)]
pub struct FamilyWeights(pub BTreeMap<String, usize>);

impl FamilyWeights {
    /// The weight of the family named `name` on the command line (1 where not given).
    pub fn weight(&self, name: &str) -> usize {
        self.0.get(name).copied().unwrap_or(1)
    }
}

impl std::fmt::Display for FamilyWeights {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let parts: Vec<String> = self.0.iter().map(|(name, w)| format!("{name}={w}")).collect();
        f.write_str(&parts.join(","))
    }
}

impl std::str::FromStr for FamilyWeights {
    type Err = String;

    /// `FAMILY=WEIGHT,...`, e.g. `avoid=3,gather=2`.
    fn from_str(s: &str) -> Result<Self, String> {
        let usage = format!(
            "write the weights as FAMILY=WEIGHT, comma-separated, each a whole number from 1 to {MAX_FAMILY_WEIGHT}, \
             e.g. avoid=3,gather=2"
        );
        let mut weights = BTreeMap::new();
        for part in s.split(',') {
            let Some((name, w)) = part.split_once('=').map(|(n, w)| (n.trim(), w.trim())) else {
                return Err(format!("{part:?} in {s:?} is not FAMILY=WEIGHT; {usage}"));
            };
            let weight = w.parse::<usize>().ok().filter(|w| (1..=MAX_FAMILY_WEIGHT).contains(w));
            let Some(weight) = weight.filter(|_| !name.is_empty()) else {
                return Err(format!("{part:?} in {s:?} is not FAMILY=WEIGHT; {usage}"));
            };
            if weights.insert(name.to_owned(), weight).is_some() {
                return Err(format!("{name} is weighted twice in {s:?}; give each family once"));
            }
        }
        Ok(Self(weights))
    }
}

/// A stream's family, as recorded.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct FamilyRecord {
    /// As named on the command line (a shipped family's name or a file).
    pub name: String,
    /// The family's own name (`family = ...` in its file): generated ids are `FAMILY-SEED-v0`.
    pub family: String,
    /// `sha256:` of the family's content.
    pub hash: String,
    /// The family file's text, so that the pool can be drawn again anywhere ([`StreamRecord::draw`]):
    /// with no family file, cache or solver. Empty in records written before it was kept.
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub text: String,
}

/// One task of a stream's pool.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct PoolTask {
    /// `FAMILY-SEED-v0`.
    pub id: String,
    /// Index into [`StreamRecord::families`].
    pub family: usize,
    /// Its generator seed.
    pub seed: u64,
    /// The seed's kept candidate.
    pub candidate: usize,
    /// `sha256:` of the task's canonical form.
    pub hash: String,
}

impl PoolTask {
    /// What differs from `other`, field by field, in words (each as "this against that").
    fn differences(&self, other: &PoolTask) -> Vec<String> {
        let mut out = Vec::new();
        let mut differ = |what: &str, a: String, b: String| {
            if a != b {
                out.push(format!("{what} {a} against {b}"));
            }
        };
        differ("id", self.id.clone(), other.id.clone());
        differ("family", self.family.to_string(), other.family.to_string());
        differ("seed", self.seed.to_string(), other.seed.to_string());
        differ("candidate", self.candidate.to_string(), other.candidate.to_string());
        differ("hash", short(&self.hash).to_owned(), short(&other.hash).to_owned());
        out
    }
}

/// What a stream is: enough to draw its tasks again and to compare two runs' pools.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct StreamRecord {
    /// The families, in the order given.
    pub families: Vec<FamilyRecord>,
    /// The generator seeds `[first, end)` of every family.
    pub generator_seeds: [u64; 2],
    /// The pool's tasks, in family order, then seed order.
    pub tasks: Vec<PoolTask>,
    /// Seeds (over all families) whose candidates all failed: they give no task.
    pub seeds_without_task: usize,
    /// Seeds (over all families) left out because their task is, by content, one a built-in suite
    /// holds out ([`crate::benchmark::suite::held_out_tasks`]): a family whose draws repeat (gather's
    /// are 36 tasks in all) gives some suite's test task under another seed. Records written before
    /// this field left out none, and a record that left out none is written without it (so that
    /// zoo entries sealed before it read and seal the same).
    #[serde(default, skip_serializing_if = "is_zero")]
    pub seeds_held_out: usize,
    /// The most blocks any of the families can draw (the sum of its groups' largest counts): a stream
    /// run's observation layout has so many block slots, whichever seeds its pool holds, so that runs
    /// over pools of the same families read the same layout.
    pub max_blocks: usize,
}

impl StreamRecord {
    /// Whether `other` has the same families (by hash) over the same seeds: where two such pools
    /// differ, the solver's check chose otherwise (another solver version or engine), not the files.
    pub fn same_families(&self, other: &StreamRecord) -> bool {
        self.generator_seeds == other.generator_seeds
            && self.families.iter().map(|f| &f.hash).eq(other.families.iter().map(|f| &f.hash))
    }

    /// What differs between this pool and `other`, in words (empty: the same pool).
    pub fn differences(&self, other: &StreamRecord) -> Vec<String> {
        let mut out = Vec::new();
        if self.generator_seeds != other.generator_seeds {
            out.push(format!(
                "generator seeds {} against {}",
                SeedRange(self.generator_seeds),
                SeedRange(other.generator_seeds)
            ));
        }
        for (a, b) in self.families.iter().zip(&other.families) {
            if a.hash != b.hash {
                out.push(format!("family {} ({} against {})", a.name, short(&a.hash), short(&b.hash)));
            }
        }
        if self.families.len() != other.families.len() {
            out.push(format!("{} families against {}", self.families.len(), other.families.len()));
        }
        if out.is_empty() && self.tasks != other.tasks {
            let first = self.tasks.iter().zip(&other.tasks).find(|(a, b)| a != b);
            out.push(match first {
                Some((a, b)) => format!("task {} ({})", a.id, a.differences(b).join(", ")),
                None => format!("{} tasks against {}", self.tasks.len(), other.tasks.len()),
            });
        }
        out
    }

    /// How many times each pool task stands in a pass over the pool ([`active_tasks`]): its family's
    /// weight in `weights` (by the name the command line gave the family), 1 without weights.
    pub fn copies(&self, weights: Option<&FamilyWeights>) -> Vec<usize> {
        let weight = |t: &PoolTask| weights.map_or(1, |w| self.families.get(t.family).map_or(1, |f| w.weight(&f.name)));
        self.tasks.iter().map(weight).collect()
    }
}

impl StreamRecord {
    /// The pool's tasks drawn again from the families' recorded texts, each checked against its recorded
    /// id and hash: a stream's tasks anywhere (a policy file, a zoo entry), with no family file, cache or
    /// solver (each task is its seed's recorded candidate).
    ///
    /// # Errors
    /// [`RecordError`]: a family recorded without its text (by a blockpuzzle before it kept
    /// them), a text whose hash is not the recorded one, a task of no recorded family, a task that draws
    /// otherwise than recorded (the record was edited, or another generator drew it).
    pub fn draw(&self) -> Result<Vec<Task>, RecordError> {
        let bad = RecordError;
        let mut families = Vec::with_capacity(self.families.len());
        for f in &self.families {
            if f.text.is_empty() {
                return Err(bad(format!(
                    "the stream's family {} is recorded by hash alone (written before stream records kept their \
                     families' texts): its tasks cannot be drawn from the record; train the policy again",
                    f.name
                )));
            }
            let family = Family::from_toml(&f.text, &f.name).map_err(|e| bad(format!("the stream's family: {e}")))?;
            if family.hash != f.hash || family.spec.family != f.family {
                return Err(bad(format!(
                    "the stream's family {} is recorded as {} ({}), its text is {} ({}): the record was edited; \
                     restore it",
                    f.name,
                    f.family,
                    short(&f.hash),
                    family.spec.family,
                    short(&family.hash)
                )));
            }
            families.push(family);
        }
        self.tasks
            .iter()
            .map(|t| {
                let family = families.get(t.family).ok_or_else(|| {
                    bad(format!(
                        "the stream's task {} names family {} of {}: the record was edited; restore it",
                        t.id,
                        t.family,
                        families.len()
                    ))
                })?;
                let drawn = family
                    .draw(t.seed, t.candidate)
                    .map_err(|e| {
                        bad(format!(
                            "the stream's task {} (seed {}, candidate {}) no longer draws: {e}; the record was edited, \
                             or this blockpuzzle's generator draws otherwise than the one that recorded it",
                            t.id, t.seed, t.candidate
                        ))
                    })?;
                if drawn.task.id() != t.id || drawn.task.source.hash != t.hash {
                    return Err(bad(format!(
                        "the stream's task {} (seed {}, candidate {}) is recorded as {}, but draws as {} {}: the \
                         record was edited, or this blockpuzzle's generator draws otherwise than the one that recorded it",
                        t.id,
                        t.seed,
                        t.candidate,
                        short(&t.hash),
                        drawn.task.id(),
                        short(&drawn.task.source.hash)
                    )));
                }
                Ok(drawn.task)
            })
            .collect()
    }
}

fn is_zero(n: &usize) -> bool {
    *n == 0
}

fn short(hash: &str) -> &str {
    // By characters: an edited record may hold any text.
    hash.char_indices().nth(19).map_or(hash, |(i, _)| &hash[..i])
}

/// A stream's tasks and its record.
#[derive(Debug, Clone)]
pub struct Pool {
    /// The tasks, compiled, in the record's order.
    pub tasks: Vec<Task>,
    /// The record.
    pub record: StreamRecord,
    /// Seeds taken from the disk cache.
    pub cached: usize,
    /// Seeds worked out by the solver's check in this call.
    pub checked: usize,
}

/// A recorded stream whose tasks do not draw again as recorded ([`StreamRecord::draw`]), named with the fix.
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub struct RecordError(pub String);

/// A stream that cannot be drawn; each names the problem and the fix.
#[derive(Debug, thiserror::Error)]
pub enum StreamError {
    /// No families given.
    #[error("--families is empty: name one or more families, comma-separated (shipped: {0})")]
    NoFamilies(String),
    /// A family that cannot be loaded (unknown name, bad file).
    #[error("--families: {0}")]
    Family(String),
    /// The same family twice.
    #[error("--families names the family {0:?} twice; name each once")]
    Repeated(String),
    /// The range overlaps a built-in suite's held-out seeds.
    #[error(
        "--generator-seeds {}: the suite {} holds out the {} family's seeds {} (its {} split); choose seeds outside \
         them, e.g. {}",
        .0.range, .0.suite, .0.family, .0.held, .0.split, .0.suggest
    )]
    HeldOut(Box<SeedsHeldOut>),
    /// Every seed of every family failed.
    #[error(
        "no task in the stream: every candidate of the {seeds} seeds was rejected ({reasons}); loosen the families' \
         ranges or [check], or choose other families"
    )]
    Empty { seeds: u64, reasons: String },
    /// A thread pool that cannot be made.
    #[error("{0}")]
    Threads(String),
}

/// The most blocks `family` can draw: the sum of its groups' largest counts.
pub fn max_blocks(family: &Family) -> usize {
    family.spec.blocks.iter().map(|g| g.get_ref().count[1]).sum()
}

/// What [`StreamError::HeldOut`] names: the range asked for, the suite and split that hold out some
/// of its seeds, the family, those seeds, and a range to use instead.
#[derive(Debug)]
pub struct SeedsHeldOut {
    /// The range asked for.
    pub range: SeedRange,
    /// The suite that holds seeds of it out.
    pub suite: String,
    /// Its split.
    pub split: String,
    /// The family.
    pub family: String,
    /// The seeds held out.
    pub held: SeedRange,
    /// A range of as many seeds outside them.
    pub suggest: String,
}

/// The names of a comma-separated `--families` list, as written there (shipped names or files),
/// blanks dropped: the one reading of the list that loading and `--family-weights` share.
pub fn family_names(list: &str) -> Vec<&str> {
    list.split(',').map(str::trim).filter(|s| !s.is_empty()).collect()
}

/// Loads the families of a comma-separated list (shipped names or files).
///
/// # Errors
/// An empty list, an unknown family or bad file, a family named twice.
pub fn families(list: &str) -> Result<Vec<(String, Family)>, StreamError> {
    families_with(list, |name| Family::load(name, None))
}

/// [`families`], each name loaded by `load`.
fn families_with(
    list: &str,
    load: impl Fn(&str) -> Result<Family, crate::task::TaskError>,
) -> Result<Vec<(String, Family)>, StreamError> {
    let names = family_names(list);
    if names.is_empty() {
        let shipped: Vec<&str> = crate::task::family::BUILTIN_FAMILIES.iter().map(|(n, _)| *n).collect();
        return Err(StreamError::NoFamilies(shipped.join(", ")));
    }
    let mut out: Vec<(String, Family)> = Vec::new();
    for name in names {
        let family = load(name).map_err(|e| StreamError::Family(e.to_string()))?;
        if out.iter().any(|(_, f)| f.spec.family == family.spec.family) {
            return Err(StreamError::Repeated(family.spec.family.clone()));
        }
        out.push((name.to_owned(), family));
    }
    Ok(out)
}

/// The families of a resumed run's list (`record`: the pool its `config.json` records): each read
/// again where it can be (an edited file is then refused by the pool's comparison), and a family
/// file that is no longer there (a checkout moved to another folder or machine: recorded paths are
/// absolute) drawn from the text the run recorded, which the pool's comparison checks by hash like
/// any other. Each such family is named on stderr.
///
/// # Errors
/// As [`families`]; a missing file the record holds no text of (a record written before texts were
/// kept) is the error reading it.
pub fn recorded_families(list: &str, record: &StreamRecord) -> Result<Vec<(String, Family)>, StreamError> {
    families_with(list, |name| {
        let missing =
            !Path::new(name).exists() && !crate::task::family::BUILTIN_FAMILIES.iter().any(|(n, _)| *n == name);
        let recorded = record.families.iter().find(|f| f.name == name && !f.text.is_empty());
        match recorded.filter(|_| missing) {
            Some(f) => {
                eprintln!(
                    "note: the family file {name} is not there: the run's recorded copy of it ({}) is used",
                    short(&f.hash)
                );
                Family::from_toml(&f.text, name)
            }
            None => Family::load(name, None),
        }
    })
}

/// Refuses a range that overlaps seeds a built-in suite holds out for any of `families`.
///
/// # Errors
/// [`StreamError::HeldOut`] naming the suite, the split and its seeds.
pub fn check_held_out(families: &[(String, Family)], range: SeedRange) -> Result<(), StreamError> {
    let held = crate::benchmark::suite::held_out_generator_seeds();
    for (_, family) in families {
        for h in held.iter().filter(|h| h.family == family.spec.family) {
            let [a, b] = h.seeds;
            if range.0[0] < b && a < range.0[1] {
                // The largest held-out end of any family here: a range above it overlaps nothing.
                let above = held
                    .iter()
                    .filter(|x| families.iter().any(|(_, f)| f.spec.family == x.family))
                    .map(|x| x.seeds[1])
                    .max()
                    .unwrap_or(b);
                let below = range.0[0] < a;
                let suggest = if below {
                    SeedRange([range.0[0], a.min(range.0[1])]).to_string()
                } else {
                    SeedRange([above, above.saturating_add(range.len())]).to_string()
                };
                return Err(StreamError::HeldOut(Box::new(SeedsHeldOut {
                    range,
                    suite: h.suite.clone(),
                    split: h.split.clone(),
                    family: family.spec.family.clone(),
                    held: SeedRange([a, b]),
                    suggest,
                })));
            }
        }
    }
    Ok(())
}

/// The stream of `families` over `range`: every seed's task, from the disk cache in `cache` (a folder;
/// [`cache_dir`] is the usual one, None: no cache) where it holds the seed (drawn again and checked by
/// hash), else by the solver's check on `threads` threads (the cache then records it). `progress`
/// draws a bar on a terminal.
///
/// # Errors
/// Held-out seeds, no task at all, a thread pool that cannot be made. A seed whose task is, by
/// content, one a built-in suite holds out is left out and counted ([`StreamRecord::seeds_held_out`]).
pub fn pool(
    families: &[(String, Family)],
    range: SeedRange,
    threads: usize,
    cache: Option<&Path>,
    progress: bool,
) -> Result<Pool, StreamError> {
    check_held_out(families, range)?;
    // Each held-out task by content, with the suite, split and row id that hold it out.
    let held_out: BTreeMap<String, String> = crate::benchmark::suite::held_out_tasks()
        .map_err(|e| StreamError::Family(e.to_string()))?
        .into_iter()
        .map(|h| (h.content, format!("{}, held out by {}'s {} split", h.id, h.suite, h.split)))
        .collect();
    let mut first_held_out: Option<String> = None;
    let engine = crate::sim::mj::version();
    let mut record = StreamRecord {
        families: families
            .iter()
            .map(|(name, f)| FamilyRecord {
                name: name.clone(),
                family: f.spec.family.clone(),
                hash: f.hash.clone(),
                text: f.text.clone().unwrap_or_default(),
            })
            .collect(),
        generator_seeds: range.0,
        tasks: Vec::new(),
        seeds_without_task: 0,
        seeds_held_out: 0,
        max_blocks: families.iter().map(|(_, f)| max_blocks(f)).max().unwrap_or(0),
    };
    let (mut tasks, mut cached, mut checked) = (Vec::new(), 0, 0);
    let (mut rejected, mut examples) = (BTreeMap::<String, usize>::new(), BTreeMap::<String, String>::new());
    let threadpool = crate::env::vector::model_threads(threads).map_err(StreamError::Threads)?;
    let total = range.len() * families.len() as u64;
    let bar = if progress {
        crate::support::progress::bar(total, "stream pool: generator seeds")
    } else {
        crate::support::progress::hidden()
    };
    // Off a terminal: a line per family besides the periodic ones.
    let lines = bar.is_plain();
    for (index, (_, family)) in families.iter().enumerate() {
        let family_started = std::time::Instant::now();
        let checked_before = checked;
        let mut cache_file = Cache::read(cache, family, &engine);
        let seeds: Vec<u64> = (range.0[0]..range.0[1]).collect();
        let results = threadpool.install(|| seed_outcomes(family, &seeds, &cache_file, &bar));
        let mut changed = false;
        for (seed, kept, worked) in results {
            match &worked {
                Some(r) => {
                    checked += 1;
                    for (why, n) in &r.rejected {
                        *rejected.entry(why.clone()).or_insert(0) += n;
                    }
                    for (why, detail) in &r.examples {
                        examples
                            .entry(why.clone())
                            .or_insert_with(|| format!("{} seed {seed}: {detail}", family.spec.family));
                    }
                    let entry = kept.as_ref().map(|(c, t)| Pinned { candidate: *c, hash: t.source.hash.clone() });
                    cache_file.insert(seed, entry);
                    changed = true;
                }
                None => cached += 1,
            }
            match kept {
                Some((_, task)) if held_out.contains_key(&task.content_hash()) => {
                    record.seeds_held_out += 1;
                    if first_held_out.is_none() {
                        let which = &held_out[&task.content_hash()];
                        first_held_out = Some(format!("{} seed {seed} draws {which}", family.spec.family));
                    }
                }
                Some((candidate, task)) => {
                    record.tasks.push(PoolTask {
                        id: task.id().to_owned(),
                        family: index,
                        seed,
                        candidate,
                        hash: task.source.hash.clone(),
                    });
                    tasks.push(task);
                }
                None => record.seeds_without_task += 1,
            }
        }
        if changed {
            cache_file.write(cache, family, &engine);
        }
        if cache_file.unsealed > 0 {
            eprintln!(
                "warning: {} of the stream cache's entries for family {} do not match their seals (the file was \
                 edited or damaged): those seeds were worked out again by the solver",
                cache_file.unsealed, family.spec.family
            );
        }
        if lines {
            eprintln!(
                "stream pool: family {} ({} of {}): {} generator seeds, {} checked by the solver, in {:.1} s",
                family.spec.family,
                index + 1,
                families.len(),
                range.len(),
                checked - checked_before,
                family_started.elapsed().as_secs_f64()
            );
        }
    }
    bar.finish_and_clear();
    if tasks.is_empty() {
        let reasons = empty_reasons(&record, first_held_out.as_deref(), &rejected, &examples);
        return Err(StreamError::Empty { seeds: total, reasons });
    }
    Ok(Pool { tasks, record, cached, checked })
}

/// What a pool's seed gave: the seed, the task it keeps (its candidate), and the solver's work where
/// the seed was worked out rather than taken from the cache.
type SeedOutcome = (u64, Option<(usize, Task)>, Option<SeedResult>);

/// Each seed of `family`: from the cache where it holds the seed (drawn again, cheap, and kept where
/// the hash still matches), else worked out by the solver; in parallel on the calling thread pool.
fn seed_outcomes(
    family: &Family,
    seeds: &[u64],
    cache_file: &Cache,
    bar: &crate::support::progress::Progress,
) -> Vec<SeedOutcome> {
    use rayon::prelude::*;
    seeds
        .par_iter()
        .map(|&seed| {
            let from_cache = cache_file.entry(seed).and_then(|kept| match kept {
                None => Some(None),
                Some(p) => family
                    .draw(seed, p.candidate)
                    .ok()
                    .filter(|d| d.task.source.hash == p.hash)
                    .map(|d| Some((p.candidate, d.task))),
            });
            let out = match from_cache {
                Some(hit) => (seed, hit, None),
                None => {
                    let r = generate_seed(family, seed);
                    let kept =
                        r.task.as_ref().and_then(|g| Task::from_toml(&g.toml, None).ok().map(|t| (g.candidate, t)));
                    (seed, kept, Some(r))
                }
            };
            bar.inc(1);
            out
        })
        .collect()
}

/// Why a stream has no task: its seeds draw held-out tasks, the cache records none, or the solver
/// rejected every candidate (each reason counted, with its first example).
fn empty_reasons(
    record: &StreamRecord,
    first_held_out: Option<&str>,
    rejected: &BTreeMap<String, usize>,
    examples: &BTreeMap<String, String>,
) -> String {
    if record.seeds_held_out > 0 {
        format!(
            "{} of them draw a task a built-in suite holds out (by content, whatever the family is called; \
             first: {}); give generator seeds that no suite holds out",
            record.seeds_held_out,
            first_held_out.unwrap_or_default()
        )
    } else if rejected.is_empty() {
        "the cache records no task for any of them".to_owned()
    } else {
        let example = |why: &String| examples.get(why).map_or(String::new(), |e| format!(", first: {e}"));
        rejected.iter().map(|(why, n)| format!("{n} {why}{}", example(why))).collect::<Vec<_>>().join("; ")
    }
}

/// The pool indices that have environments in `epoch` of a run of `seed`: `k` tasks a time, taken in
/// turn from a permutation of the pool drawn anew for every pass, without repeats within an epoch.
/// Task `t` stands `copies[t]` times in every pass (its family's weight, [`FamilyWeights`]; 1 for
/// every task of an unweighted stream, whose every task is then seen once a pass). All of them when
/// `k` reaches the pool's size.
pub fn active_tasks(seed: u64, epoch: usize, copies: &[usize], k: usize) -> Vec<usize> {
    use rand::seq::SliceRandom;
    use rand::SeedableRng;
    let tasks = copies.len();
    if k >= tasks {
        return (0..tasks).collect();
    }
    // One pass: every task as many times as its copies.
    let entries: Vec<usize> = (0..tasks).flat_map(|t| std::iter::repeat(t).take(copies[t].max(1))).collect();
    let pass_len = entries.len();
    let pass_of = |p: usize| {
        let mut order = entries.clone();
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed ^ 0x5354_5245_414D);
        rng.set_stream(p as u64);
        order.shuffle(&mut rng);
        order
    };
    let start = epoch * k;
    let (mut pass, mut at) = (start / pass_len, start % pass_len);
    let mut order = pass_of(pass);
    let mut out = Vec::with_capacity(k);
    while out.len() < k {
        if at == pass_len {
            (pass, at) = (pass + 1, 0);
            order = pass_of(pass);
        }
        if !out.contains(&order[at]) {
            out.push(order[at]);
        }
        at += 1;
    }
    out
}

/// A seed's kept candidate, as cached.
#[derive(Debug, Clone, Serialize, Deserialize)]
struct Pinned {
    candidate: usize,
    hash: String,
}

/// A seed's cache entry: its kept candidate (None: the seed has no task) and a seal over it.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct Entry {
    kept: Option<Pinned>,
    seal: String,
}

/// One family's cache file: each worked-out seed's kept candidate (null: no task). Which candidate a
/// seed keeps depends on the family, the engine, the solver that plays the checks and the checks
/// themselves, so all four key it.
///
/// Each entry is sealed ([`Cache::seal`]: a hash over the family's hash, the engine, the solver's and
/// the generator's versions, the seed and what it keeps). The hash check at draw time catches an
/// entry whose task no longer draws; the seal catches an edit that keeps the draw consistent
/// (another candidate with its hash, or a seed marked as having no task), which would otherwise
/// change the pool silently. An entry whose seal does not match is worked out again, and the run
/// says so. The seal is a check against edits and damage, not a signature: anyone with this source
/// can compute one.
#[derive(Debug, Default, Serialize, Deserialize)]
struct Cache {
    family: String,
    hash: String,
    engine: String,
    /// The solver's version ([`crate::policy::SOLVER_VERSION`]).
    solver: u32,
    /// The generator's checks' version ([`GENERATOR_VERSION`]).
    generator: u32,
    seeds: BTreeMap<u64, Entry>,
    /// Entries read whose seal did not match (not written).
    #[serde(skip)]
    unsealed: usize,
}

/// The cache folder: `$BLOCKPUZZLE_CACHE_DIR`, else `$XDG_CACHE_HOME/blockpuzzle`, else
/// `~/.cache/blockpuzzle` (None: none of them set).
pub fn cache_dir() -> Option<PathBuf> {
    let var = |k: &str| std::env::var_os(k).filter(|v| !v.is_empty()).map(PathBuf::from);
    var("BLOCKPUZZLE_CACHE_DIR")
        .or_else(|| var("XDG_CACHE_HOME").map(|d| d.join("blockpuzzle")))
        .or_else(|| var("HOME").map(|d| d.join(".cache/blockpuzzle")))
}

impl Cache {
    /// The seal of `seed`'s entry `kept` in this cache.
    fn seal(&self, seed: u64, kept: Option<&Pinned>) -> String {
        let kept = kept.map_or_else(|| "none".to_owned(), |p| format!("{} {}", p.candidate, p.hash));
        let text = format!("{}\n{}\n{}\n{}\n{seed}\n{kept}", self.hash, self.engine, self.solver, self.generator);
        crate::benchmark::provenance::sha256(text.as_bytes())
    }

    /// `seed`'s kept candidate where its entry is there and sealed (None: not cached).
    fn entry(&self, seed: u64) -> Option<Option<&Pinned>> {
        let e = self.seeds.get(&seed)?;
        (e.seal == self.seal(seed, e.kept.as_ref())).then_some(e.kept.as_ref())
    }

    /// Records `seed`'s kept candidate, sealed.
    fn insert(&mut self, seed: u64, kept: Option<Pinned>) {
        let seal = self.seal(seed, kept.as_ref());
        self.seeds.insert(seed, Entry { kept, seal });
    }

    fn path(dir: Option<&Path>, family: &Family, engine: &str) -> Option<PathBuf> {
        let hex = family.hash.trim_start_matches("sha256:");
        let name = format!(
            "{}-{}-mujoco-{engine}-solver{}-generator{GENERATOR_VERSION}.json",
            family.spec.family,
            &hex[..hex.len().min(16)],
            crate::policy::SOLVER_VERSION
        );
        Some(dir?.join("generated").join(name))
    }

    /// The family's cache on this engine in `dir` (empty where there is none or it does not read).
    fn read(dir: Option<&Path>, family: &Family, engine: &str) -> Cache {
        let empty = Cache {
            family: family.spec.family.clone(),
            hash: family.hash.clone(),
            engine: engine.to_owned(),
            solver: crate::policy::SOLVER_VERSION,
            generator: GENERATOR_VERSION,
            ..Default::default()
        };
        let Some(path) = Self::path(dir, family, engine) else { return empty };
        let Ok(text) = crate::support::io::read_text(&path, "stream cache", crate::support::limits::TEXT_FILE_BYTES)
        else {
            return empty;
        };
        match serde_json::from_str::<Cache>(&text) {
            Ok(mut c)
                if c.hash == family.hash
                    && c.engine == engine
                    && c.solver == crate::policy::SOLVER_VERSION
                    && c.generator == GENERATOR_VERSION =>
            {
                c.unsealed = c.seeds.iter().filter(|(seed, e)| e.seal != c.seal(**seed, e.kept.as_ref())).count();
                c
            }
            Ok(_) => empty,
            Err(e) => {
                eprintln!(
                    "warning: the stream cache {} does not read ({e}; a file of an older blockpuzzle?): its seeds \
                     are worked out again and the file rewritten",
                    path.display()
                );
                empty
            }
        }
    }

    /// Writes the cache (a failure only costs the next run the check again: it is reported, not fatal).
    fn write(&self, dir: Option<&Path>, family: &Family, engine: &str) {
        let Some(path) = Self::path(dir, family, engine) else { return };
        let result = path
            .parent()
            .map_or(Ok(()), std::fs::create_dir_all)
            .map_err(|e| e.to_string())
            .and_then(|()| crate::support::io::write_json(&path, self).map_err(|e| e.to_string()));
        if let Err(e) = result {
            eprintln!("warning: cannot write the stream cache {}: {e}", path.display());
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn seed_ranges_read_and_refuse() {
        assert_eq!("0..1024".parse::<SeedRange>(), Ok(SeedRange([0, 1024])));
        assert!("5..5".parse::<SeedRange>().unwrap_err().contains("empty"));
        assert!("9..3".parse::<SeedRange>().unwrap_err().contains("empty"));
        assert!("0-8".parse::<SeedRange>().unwrap_err().contains("FIRST..END"));
        assert!("a..8".parse::<SeedRange>().unwrap_err().contains("not a seed"));
        assert!("0..100001".parse::<SeedRange>().unwrap_err().contains("at most"));
    }

    #[test]
    fn active_sets_cover_the_pool_once_a_pass_without_repeats() {
        let (pool, k) = (10, 4);
        let once = vec![1; pool];
        let mut seen = vec![0; pool];
        for epoch in 0..5 {
            let a = active_tasks(3, epoch, &once, k);
            assert_eq!(a.len(), k);
            let mut s = a.clone();
            s.sort_unstable();
            s.dedup();
            assert_eq!(s.len(), k, "{a:?}");
            a.iter().for_each(|&t| seen[t] += 1);
        }
        // 20 places over 2 passes of 10: every task twice (a repeat at a pass boundary is skipped).
        assert!(seen.iter().all(|&n| (1..=3).contains(&n)), "{seen:?}");
        assert_eq!(active_tasks(3, 2, &once, k), active_tasks(3, 2, &once, k));
        assert_ne!(active_tasks(3, 0, &once, k), active_tasks(4, 0, &once, k));
        assert_eq!(active_tasks(3, 7, &[1; 5], 8), vec![0, 1, 2, 3, 4]);
    }

    /// A family weighted 3 has its tasks active about three times as often as the others, never twice
    /// in one epoch; the weights parse as written and refuse what is not a weight.
    #[test]
    fn weighted_families_are_active_as_often_as_their_weight() {
        // Tasks 0-9 of a family weighted 3, tasks 10-19 of one weighted 1; 6 of 20 active an epoch.
        let copies: Vec<usize> = (0..20).map(|t| if t < 10 { 3 } else { 1 }).collect();
        let (mut heavy, mut light) = (0, 0);
        for epoch in 0..400 {
            let a = active_tasks(5, epoch, &copies, 6);
            let mut s = a.clone();
            s.sort_unstable();
            s.dedup();
            assert_eq!(s.len(), 6, "{a:?}");
            heavy += a.iter().filter(|&&t| t < 10).count();
            light += a.iter().filter(|&&t| t >= 10).count();
        }
        let ratio = heavy as f64 / light as f64;
        assert!((2.5..3.5).contains(&ratio), "{heavy} against {light}");
        let w: FamilyWeights = " avoid=3, gather = 2".parse().unwrap();
        assert_eq!((w.weight("avoid"), w.weight("gather"), w.weight("push")), (3, 2, 1));
        assert_eq!(w.to_string(), "avoid=3,gather=2");
        for (bad, says) in [
            ("avoid", "FAMILY=WEIGHT"),
            ("avoid=0", "from 1 to 16"),
            ("avoid=17", "from 1 to 16"),
            ("avoid=1.5", "whole number"),
            ("=2", "FAMILY=WEIGHT"),
            ("avoid=2,avoid=3", "weighted twice"),
        ] {
            let err = bad.parse::<FamilyWeights>().unwrap_err();
            assert!(err.contains(says), "{bad}: {err}");
        }
    }
}
