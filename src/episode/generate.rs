//! Generated tasks: a family ([`crate::task::family`]) and a generator seed give one task, the first
//! of the seed's candidates that passes the checks the family states: it compiles and resets, the
//! solver ([`ScriptedPolicy::solver`], which reads only the observation) can play it and succeeds
//! often enough over a fixed set of episodes (no impossible task), and few of those episodes are
//! decided at their first step (no trivial task), and its layouts are common enough that a reset
//! all but never runs out of draws ([`GENERATOR_VERSION`] 2). Every rejected candidate is counted by
//! reason.
//! Each seed is independent of the others, so a range of seeds gives the same tasks on any number
//! of threads.

use crate::env::{BlockEnv, EnvConfig, ObsMode};
use crate::episode::rollout::run_episode;
use crate::policy::ScriptedPolicy;
use crate::task::family::Family;
use serde::Serialize;
use std::collections::BTreeMap;

/// The version of the generator's checks: which candidate a family's seed keeps depends on it (as on
/// the family, the engine and the solver), so generated records and the stream's cache name it.
/// 1: compiles, resets, the solver can play it, its success and the share decided at the first step.
/// 2: and its layouts are common enough ([`LAYOUT_MARGIN`]).
pub const GENERATOR_VERSION: u32 = 2;

/// A kept task's layouts must be common enough that one reset runs out of attempts with a chance of
/// about e^-20 (2 in a billion) or less, estimated over the check episodes' resets: the sampler's mean
/// draws per layout at most `placement.max_attempts / LAYOUT_MARGIN` (draws are independent, so a
/// reset needs more than `max_attempts` with a chance of about e^-(max_attempts / mean)), and the
/// share of layouts the physics checks reject at most e^(-LAYOUT_MARGIN / max_reset_attempts).
/// Without it a dense family (11 blocks 7.5 cm apart, say) can yield a task whose resets fail once
/// in 100,000, hours into a training run or in the middle of an evaluation.
pub const LAYOUT_MARGIN: f64 = 20.0;

/// A kept task.
#[derive(Debug, Clone, Serialize)]
pub struct Generated {
    /// Its id (`FAMILY-SEED-v0`).
    pub id: String,
    /// The generator seed.
    pub seed: u64,
    /// Which of the seed's candidates it is.
    pub candidate: usize,
    /// `sha256:` of the task's canonical form (what results record).
    pub hash: String,
    /// The solver's behaviour on it.
    pub script: String,
    /// The solver's success over the family's check episodes.
    pub solver_success: f64,
    /// The share of those episodes decided at their first step.
    pub decided_at_first_step: f64,
    /// The sampler's mean draws per layout over those episodes' resets.
    pub draws_per_layout: f64,
    /// The share of those layouts the physics checks rejected.
    pub physics_rejected: f64,
    /// The task file's text.
    #[serde(skip)]
    pub toml: String,
}

/// What one generator seed gave: its task, or none within the family's candidates; and the
/// candidates rejected on the way, by reason.
#[derive(Debug, Clone, Serialize)]
pub struct SeedResult {
    /// The generator seed.
    pub seed: u64,
    /// The kept task, if a candidate passed.
    pub task: Option<Generated>,
    /// Rejected candidates by reason.
    pub rejected: BTreeMap<String, usize>,
    /// The first rejection's whole message for each reason (the compiler's or the solver's words).
    pub examples: BTreeMap<String, String>,
}

/// Why a candidate was not kept: the reason it is counted under, and the whole message.
struct Rejection {
    kind: String,
    detail: String,
}

/// A rejection of kind `kind` (counted), with `detail` (the first one of each kind is kept).
fn reason(kind: &str, detail: &str) -> Rejection {
    Rejection { kind: kind.to_owned(), detail: detail.to_owned() }
}

/// Why generated tasks cannot be made or written, naming the path.
#[derive(Debug, thiserror::Error)]
pub enum GenerateError {
    /// The thread pool cannot be made.
    #[error("{0}")]
    Threads(String),
    /// The output exists and is not a folder.
    #[error("{} is not a folder; give a folder for the task files", path.display())]
    NotAFolder {
        /// The output.
        path: std::path::PathBuf,
    },
    /// The output folder cannot be made.
    #[error("cannot make the folder {}: {reason}", path.display())]
    CannotMakeFolder {
        /// The folder.
        path: std::path::PathBuf,
        /// The OS's error.
        reason: std::io::Error,
    },
    /// A file cannot be written.
    #[error("cannot write {}: {reason}", path.display())]
    CannotWrite {
        /// The file.
        path: std::path::PathBuf,
        /// The OS's error.
        reason: std::io::Error,
    },
    /// An output that cannot be written ([`check_outputs`]).
    #[error(transparent)]
    Output(#[from] crate::support::io::WriteError),
    /// The manifest cannot be encoded.
    #[error(transparent)]
    Encode(#[from] serde_json::Error),
}

/// The checks of a candidate that play no episode to its end, and so give the same answer on every
/// engine and build: its scene builds, its first check episode's layout can be drawn, and the solver
/// can play it (it chooses its behaviour from that first observation). A pinned candidate
/// ([`crate::benchmark::suite`]) must pass them: the generator would not keep one that does not.
///
/// # Errors
/// The reason, in the words the generator counts it under, and the detail.
pub fn solver_can_play(task: &crate::task::Task) -> Result<(), String> {
    let mut env = BlockEnv::new(EnvConfig { obs_mode: ObsMode::Entities, ..EnvConfig::new(task.clone()) })
        .map_err(|e| format!("cannot build its scene: {e}"))?;
    let (obs, _) = env.reset(Some(0)).map_err(|e| format!("no layout at reset: {e}"))?;
    let mut solver = ScriptedPolicy::solver(env.obs_spec().max_objects);
    crate::policy::Policy::act(&mut solver, &obs);
    match solver.unsolvable() {
        Some(why) => Err(format!("the solver cannot play it: {why}")),
        None => Ok(()),
    }
}

/// Checks a drawn candidate; `Ok` with what the kept task records, or the reason it is rejected.
fn check(family: &Family, seed: u64, candidate: usize) -> Result<Generated, Rejection> {
    let drawn = family.draw(seed, candidate).map_err(|e| reason("does not compile", &e.message))?;
    let c = &family.spec.check;
    let mut env = BlockEnv::new(EnvConfig { obs_mode: ObsMode::Entities, ..EnvConfig::new(drawn.task.clone()) })
        .map_err(|e| reason("cannot build its scene", &e.to_string()))?;
    let mut solver = ScriptedPolicy::solver(env.obs_spec().max_objects);
    let (mut success, mut decided, mut script) = (0usize, 0usize, None);
    for episode in 0..c.episodes as u64 {
        let ep = match run_episode(&mut env, &mut solver, episode) {
            Ok(ep) => ep,
            // A task whose layouts cannot be drawn (the placement gives up) is not kept.
            Err(e) => return Err(reason("no layout at reset", &e.to_string())),
        };
        if let Some(why) = solver.unsolvable() {
            // Counted by what the solver cannot do (its words name no object of the task).
            return Err(reason(&format!("the solver cannot play it: {why}"), ""));
        }
        script = script.or(solver.script());
        success += ep.success as usize;
        decided += (ep.steps.len() <= 1 && (ep.success || ep.failure)) as usize;
    }
    let (draws_per_layout, physics_rejected) = layout_rates(env.reset_stats());
    let placement = &drawn.task.spec.placement;
    let most_draws = placement.max_attempts as f64 / LAYOUT_MARGIN;
    if draws_per_layout > most_draws {
        return Err(reason(
            "layouts too rare to draw",
            &format!(
                "{draws_per_layout:.0} draws per layout on average, above max_attempts / {LAYOUT_MARGIN} = {most_draws:.0}"
            ),
        ));
    }
    let most_rejected = (-LAYOUT_MARGIN / placement.max_reset_attempts as f64).exp();
    if physics_rejected > most_rejected {
        return Err(reason(
            "layouts too often rejected by the physics checks",
            &format!(
                "{:.0}% of layouts rejected, above {:.0}% for max_reset_attempts = {}",
                100.0 * physics_rejected,
                100.0 * most_rejected,
                placement.max_reset_attempts
            ),
        ));
    }
    let n = c.episodes as f64;
    let (solver_success, decided_share) = (success as f64 / n, decided as f64 / n);
    if decided_share >= c.max_decided_at_first_step {
        return Err(reason("decided at the first step too often", &format!("{decided} of {} episodes", c.episodes)));
    }
    if solver_success < c.min_solver_success {
        return Err(reason("solver success below the family's threshold", &format!("{solver_success:.2}")));
    }
    Ok(Generated {
        id: family.task_id(seed),
        seed,
        candidate,
        hash: drawn.task.source.hash.clone(),
        script: script.map_or("none", |s| s.name()).to_owned(),
        solver_success,
        decided_at_first_step: decided_share,
        draws_per_layout,
        physics_rejected,
        toml: drawn.toml,
    })
}

/// The sampler's mean draws per layout and the share of layouts the physics checks rejected, over the
/// resets `stats` counts.
fn layout_rates(stats: &crate::env::ResetStats) -> (f64, f64) {
    let layouts = stats.layouts.max(1) as f64;
    (stats.draws as f64 / layouts, stats.rejected.total() as f64 / layouts)
}

/// The task of generator seed `seed`: its candidates in order until one passes. A seed's result
/// depends on the family's content (its hash) and the seed alone, so a process keeps each one it
/// has worked out (suites that draw from families load again without checking again).
pub fn generate_seed(family: &Family, seed: u64) -> SeedResult {
    use std::collections::HashMap;
    use std::sync::{Mutex, OnceLock};
    type Memo = Mutex<HashMap<(String, u64), SeedResult>>;
    static MEMO: OnceLock<Memo> = OnceLock::new();
    let memo = MEMO.get_or_init(Default::default);
    let key = (family.hash.clone(), seed);
    if let Some(r) = memo.lock().ok().and_then(|m| m.get(&key).cloned()) {
        return r;
    }
    let r = check_seed(family, seed);
    if let Ok(mut m) = memo.lock() {
        m.insert(key, r.clone());
    }
    r
}

/// [`generate_seed`]'s work: the seed's candidates in order until one passes.
fn check_seed(family: &Family, seed: u64) -> SeedResult {
    let (mut rejected, mut examples) = (BTreeMap::new(), BTreeMap::new());
    for candidate in 0..family.spec.check.max_candidates {
        match check(family, seed, candidate) {
            Ok(task) => return SeedResult { seed, task: Some(task), rejected, examples },
            Err(why) => {
                *rejected.entry(why.kind.clone()).or_insert(0) += 1;
                if !why.detail.is_empty() {
                    examples.entry(why.kind).or_insert(why.detail);
                }
            }
        }
    }
    SeedResult { seed, task: None, rejected, examples }
}

/// The tasks of generator seeds `first .. first + count`, on `threads` threads (the same tasks for
/// any thread count).
///
/// # Errors
/// A thread pool that cannot be made.
pub fn generate(family: &Family, first: u64, count: usize, threads: usize) -> Result<Vec<SeedResult>, GenerateError> {
    use rayon::prelude::*;
    let pool = crate::env::vector::model_threads(threads).map_err(GenerateError::Threads)?;
    Ok(pool.install(|| (0..count as u64).into_par_iter().map(|k| generate_seed(family, first + k)).collect()))
}

/// The rejection counts of several seeds together, by reason.
pub fn rejections(results: &[SeedResult]) -> BTreeMap<String, usize> {
    let mut all = BTreeMap::new();
    for r in results {
        for (why, n) in &r.rejected {
            *all.entry(why.clone()).or_insert(0) += n;
        }
    }
    all
}

/// The first message of each rejection reason over several seeds (in seed order).
pub fn examples(results: &[SeedResult]) -> BTreeMap<String, String> {
    let mut all = BTreeMap::new();
    for r in results {
        for (why, detail) in &r.examples {
            all.entry(why.clone()).or_insert_with(|| format!("seed {}: {detail}", r.seed));
        }
    }
    all
}

/// Writes the kept tasks of `results` (generator seeds `first ..`, `family`'s) to `out` as ID.toml,
/// and `out/generated.json`: the family, its file and hash, `build` (what made them: the caller's
/// `provenance::Build`, which this module, below provenance, cannot name), each kept task's record,
/// the seeds without a task and the rejections by reason; returns that record. `out` is made if
/// missing.
///
/// # Errors
/// `out` is not a folder or cannot be made; a file cannot be written.
pub fn write_folder(
    out: &std::path::Path,
    family: &Family,
    family_source: &str,
    first: u64,
    results: &[SeedResult],
    build: &impl Serialize,
) -> Result<serde_json::Value, GenerateError> {
    use std::io::Write as _;
    // A folder made here goes again if anything fails.
    let created = match std::fs::metadata(out) {
        Ok(m) if !m.is_dir() => return Err(GenerateError::NotAFolder { path: out.to_owned() }),
        Ok(_) => None,
        Err(_) => Some(
            crate::support::io::CreatedDir::create(out)
                .map_err(|reason| GenerateError::CannotMakeFolder { path: out.to_owned(), reason })?,
        ),
    };
    let kept: Vec<&Generated> = results.iter().filter_map(|r| r.task.as_ref()).collect();
    let manifest = serde_json::json!({
        "family": family.spec.family,
        "family_file": family_source,
        "family_hash": family.hash,
        "generator": GENERATOR_VERSION,
        "first_seed": first,
        "count": results.len(),
        "build": build,
        "tasks": kept,
        "seeds_without_a_task": results.iter().filter(|r| r.task.is_none()).map(|r| r.seed).collect::<Vec<_>>(),
        "rejected": rejections(results),
        "rejection_examples": examples(results),
    });
    let json = serde_json::to_vec_pretty(&manifest)?;
    // Every output is written in full before any is put in place: a full disk, or an output that is a
    // folder, leaves nothing behind.
    let files = kept.iter().map(|t| (out.join(format!("{}.toml", t.id)), t.toml.as_bytes()));
    let mut outputs = Vec::new();
    for (path, bytes) in files.chain(std::iter::once((out.join(MANIFEST), &json[..]))) {
        let cannot = |reason: std::io::Error| GenerateError::CannotWrite { path: path.clone(), reason };
        let mut output = crate::support::io::Output::create(&path).map_err(cannot)?;
        output.write_all(bytes).and_then(|()| output.flush()).map_err(cannot)?;
        outputs.push((path, output));
    }
    for (path, output) in outputs {
        output.finish().map_err(|reason| GenerateError::CannotWrite { path, reason })?;
    }
    created.into_iter().for_each(crate::support::io::CreatedDir::keep);
    Ok(manifest)
}

/// The record `task generate` writes beside the task files.
pub const MANIFEST: &str = "generated.json";

/// Checks, before any candidate is played, that `out` is a folder (or can be made) and that every file
/// `task generate` may write into it (each seed's `FAMILY-SEED-v0.toml` and [`MANIFEST`]) can be written.
///
/// # Errors
/// `out` is not a folder, or the first output that cannot be written (a folder in its place, a read-only
/// file), named.
pub fn check_outputs(out: &std::path::Path, family: &Family, first: u64, count: usize) -> Result<(), GenerateError> {
    match std::fs::metadata(out) {
        Ok(m) if !m.is_dir() => return Err(GenerateError::NotAFolder { path: out.to_owned() }),
        Ok(_) => {}
        Err(_) => return Ok(()),
    }
    for seed in (0..count as u64).map(|k| first + k) {
        crate::support::io::check_output(&out.join(format!("{}.toml", family.task_id(seed))))?;
    }
    crate::support::io::check_output(&out.join(MANIFEST))?;
    Ok(())
}
