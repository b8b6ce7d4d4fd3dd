//! Demonstrations: the solver's episodes on a suite split, recorded for imitation (behaviour
//! cloning, DAgger's first data) and for offline RL (Python exports them as a Minari dataset).
//!
//! The solver ([`ScriptedPolicy::solver`]) reads only the `entities` observation, so what it is
//! shown is what a learner is shown. A demos file is one safetensors file of float32 tensors, every
//! observation padded to the split's largest row count (padding rows are zero with mask 0):
//!
//! | tensor | shape | |
//! |---|---|---|
//! | `robot` | [O, R] | the robot features of each observation |
//! | `entities` | [O, E, F] | the entity rows (blocks, then gripper, table, floor; then padding) |
//! | `mask` | [O, E] | 1 where a row is present |
//! | `actions` | [T, 4] | the solver's actions |
//! | `rewards`, `terminations`, `truncations` | [T] | per step (flags as 0 / 1) |
//!
//! Episode i has `steps` steps (its metadata) and `steps + 1` observations (the reset's, then each
//! step's), in episode order: episode i's steps start at the sum of the earlier episodes' steps, its
//! observations at that sum plus i. The file's `__metadata__` has one entry, `blockpuzzle-demos`, a
//! JSON object: `version`, `split`, `provenance` (build, engine, suite and its hash), `layout`
//! (feature names, rows) and `episodes` (per episode: task id and hash, row, seed, steps, return,
//! outcome). The same episodes give the same bytes.

use safetensors::tensor::{Dtype, SafeTensors, TensorView};
use serde::{Deserialize, Serialize};
use std::collections::HashMap;
use std::path::Path;

use crate::benchmark::evaluate::{make_env, EvalSpec};
use crate::benchmark::provenance::{Harness, PolicyId, Provenance};
use crate::benchmark::suite::Suite;
use crate::benchmark::suite::SuiteError;
use crate::env::vector::VectorEnv;
use crate::env::EnvError;
use crate::env::{ObsMode, ObsSpec};
use crate::episode::outcome::Outcome;
use crate::episode::rollout::RolloutError;
use crate::policy::ScriptedPolicy;
use crate::support::io::WriteError;

/// The format name in a demos file's metadata.
pub const FORMAT: &str = "blockpuzzle-demos";
/// The demos format version this build writes and reads.
pub const VERSION: u32 = 1;

/// One recorded episode's facts.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DemoEpisode {
    /// Task id.
    pub task: String,
    /// The task's content hash.
    pub task_sha256: String,
    /// The row of the split it was played on (0-based).
    pub row: usize,
    /// The seed passed to `reset`.
    pub seed: u64,
    /// Steps (its observations are one more).
    pub steps: usize,
    /// Sum of rewards.
    pub episode_return: f32,
    /// Why it ended.
    pub outcome: Outcome,
    /// The curriculum level it was played at: with `seed` and `distribution`, what `reset` takes to
    /// play it again (None in files written before levels were recorded).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub level: Option<usize>,
    /// The task file's distribution it was drawn from (None: the task's own draw).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub distribution: Option<String>,
}

/// What the observation tensors hold.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DemoLayout {
    /// The robot features' names (R of them).
    pub robot: Vec<String>,
    /// The features of an entity row (F of them).
    pub entity: Vec<String>,
    /// Rows per observation (E): the split's largest entities count.
    pub rows: usize,
}

/// Recorded demonstrations, in memory.
#[derive(Debug, Clone, PartialEq)]
pub struct Demos {
    /// The tensors' layout.
    pub layout: DemoLayout,
    /// What made them.
    pub provenance: Provenance,
    /// The split they were played on.
    pub split: String,
    /// The episodes, in order.
    pub episodes: Vec<DemoEpisode>,
    /// Their observations and steps.
    pub tensors: DemoTensors,
}

/// One recorded episode with its number in the row (the threads record them out of order).
type Numbered = (usize, (DemoEpisode, DemoTensors));

/// The episodes' observations (O of them) and steps (T), one after another.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct DemoTensors {
    /// [O, R] robot features.
    pub robot: Vec<f32>,
    /// [O, E, F] entity rows.
    pub entities: Vec<f32>,
    /// [O, E] row mask.
    pub mask: Vec<f32>,
    /// [T, 4] actions.
    pub actions: Vec<f32>,
    /// [T] rewards.
    pub rewards: Vec<f32>,
    /// [T] 1 where the episode ended under the rules.
    pub terminations: Vec<f32>,
    /// [T] 1 where the episode was cut (time limit, instability).
    pub truncations: Vec<f32>,
}

impl DemoTensors {
    fn append(&mut self, other: DemoTensors) {
        self.robot.extend(other.robot);
        self.entities.extend(other.entities);
        self.mask.extend(other.mask);
        self.actions.extend(other.actions);
        self.rewards.extend(other.rewards);
        self.terminations.extend(other.terminations);
        self.truncations.extend(other.truncations);
    }
}

/// Why demonstrations could not be recorded, written or read.
#[derive(Debug, thiserror::Error)]
pub enum DemosError {
    /// The suite has no such split.
    #[error("suite {suite} has no split {split:?} (it has {have})")]
    NoSplit {
        /// The suite's name.
        suite: String,
        /// The split asked for.
        split: String,
        /// The splits it has, comma-separated.
        have: String,
    },
    /// Episodes, seeds or the file's size beyond their bounds (the message names the flag to lower).
    #[error("{0}")]
    Bounds(String),
    /// The suite's pinned rows are not what its file says.
    #[error(transparent)]
    Suite(#[from] SuiteError),
    /// A row's environment could not be made.
    #[error(transparent)]
    Env(#[from] EnvError),
    /// A row's environment shows another layout than the split's.
    #[error("{task}: the environment shows {shown} entity rows, not {rows}")]
    Layout {
        /// The row's task.
        task: String,
        /// The rows it shows.
        shown: usize,
        /// The split's rows.
        rows: usize,
    },
    /// An episode failed in the simulator.
    #[error("{task} episode seed {seed}")]
    Episode {
        /// The row's task.
        task: String,
        /// Its seed.
        seed: u64,
        /// What failed.
        #[source]
        source: RolloutError,
    },
    /// The tensors could not be laid out as safetensors.
    #[error(transparent)]
    Encode(#[from] safetensors::SafeTensorError),
    /// The metadata could not be written as JSON.
    #[error(transparent)]
    Json(#[from] serde_json::Error),
    /// The output path is refused or the write failed.
    #[error(transparent)]
    Write(#[from] WriteError),
    /// The file could not be read.
    #[error(transparent)]
    Read(#[from] std::io::Error),
    /// The file is not a demos file this build reads.
    #[error("{path} is not a usable demos file: {why}; record one with `blockpuzzle demos`")]
    Unusable {
        /// The file.
        path: std::path::PathBuf,
        /// What is wrong with it.
        why: String,
    },
}

type Result<T, E = DemosError> = std::result::Result<T, E>;

/// The most bytes a demos file may hold (the tensors are built in memory first): 10,000 episodes
/// of 50 steps with 16 rows are about 0.9 GiB.
pub const MAX_BYTES: u64 = crate::support::limits::DUMP_FILE_BYTES;

/// Plays the solver on every row of `split` of `suite`, `episodes` per row (None: the row's own
/// count) from the row's seed on, on `threads` threads. The same episodes whatever `threads`.
///
/// # Errors
/// No such split; a recording beyond [`MAX_BYTES`] (naming `--episodes`); environment errors.
pub fn record(suite: &Suite, split: &str, episodes: Option<usize>, threads: usize, harness: Harness) -> Result<Demos> {
    let Some(s) = suite.splits.iter().find(|s| s.name == split) else {
        let names: Vec<&str> = suite.splits.iter().map(|s| s.name.as_str()).collect();
        return Err(DemosError::NoSplit { suite: suite.name.clone(), split: split.to_owned(), have: names.join(", ") });
    };
    if let Some(n) = episodes {
        crate::support::limits::EVAL_EPISODES.check_usize(n).map_err(DemosError::Bounds)?;
    }
    suite.check_pinned(Some(split), threads)?;
    // The layout: every row's environment shows the split's most block slots (`EnvConfig::slots`):
    // a task's blocks, absent rows, then the gripper's, table's and floor's rows, the layout
    // multi-task training and its policies read.
    let slots = s.rows.iter().map(|r| r.task.object_count()).max().unwrap_or(0);
    let padded = ObsSpec::new(ObsMode::Entities, slots);
    let rows = padded.rows();
    let (r_dim, f_dim) = (padded.robot_dim(), padded.object_dim());
    let names = padded.names();
    let feature = |n: &String| n.split_once('/').map_or(n.clone(), |(_, f)| f.to_owned());
    let layout = DemoLayout {
        robot: names[..r_dim].iter().map(feature).collect(),
        entity: names[r_dim..r_dim + f_dim].iter().map(feature).collect(),
        rows,
    };
    let per_obs = (r_dim + rows * (f_dim + 1)) as u64 * 4;
    let bytes: u64 = s
        .rows
        .iter()
        .map(|r| episodes.unwrap_or(r.episodes) as u64 * (r.task.spec.max_episode_steps as u64 + 1) * (per_obs + 28))
        .sum();
    if bytes > MAX_BYTES {
        return Err(DemosError::Bounds(format!(
            "{} episodes per row of split {split} would make a demos file of up to {:.1} GiB, beyond {} GiB: lower --episodes",
            episodes.map_or("the suite's".to_owned(), |n| n.to_string()),
            bytes as f64 / (1u64 << 30) as f64,
            MAX_BYTES >> 30
        )));
    }
    let mut played = Vec::new();
    // On a terminal only (indicatif draws nothing elsewhere).
    let bar =
        crate::support::progress::bar(s.rows.iter().map(|r| episodes.unwrap_or(r.episodes) as u64).sum(), "episode");
    for (i, row) in s.rows.iter().enumerate() {
        let n = episodes.unwrap_or(row.episodes);
        crate::support::limits::seed_range(row.seed, n as u64).map_err(DemosError::Bounds)?;
        let spec = EvalSpec {
            task: &row.task,
            challenge: false,
            distribution: row.distribution.as_deref(),
            level: row.level,
            episodes: n,
            seed: row.seed,
            threads,
        };
        let k = threads.clamp(1, n).min(crate::support::limits::THREADS.max as usize);
        let envs = (0..k).map(|_| make_env(&spec, ObsMode::Entities, slots)).collect::<Result<Vec<_>, _>>()?;
        let mut envs = VectorEnv::from_envs(envs, k)?;
        if envs.obs_spec() != padded {
            return Err(DemosError::Layout { task: row.task.id().to_owned(), shown: envs.obs_spec().rows(), rows });
        }
        let by_thread: Vec<Result<Vec<Numbered>>> = envs.each(|t, env| {
            let mut out = Vec::new();
            for e in (t..n).step_by(k) {
                let seed = row.seed + e as u64;
                let mut solver = ScriptedPolicy::solver(slots);
                let (rec, obs) = crate::episode::rollout::run_episode_observed(env, &mut solver, seed)
                    .map_err(|source| DemosError::Episode { task: row.task.id().to_owned(), seed, source })?;
                let spec = env.obs_spec();
                let episode = DemoEpisode {
                    task: row.task.id().to_owned(),
                    task_sha256: row.task.source.hash.clone(),
                    row: i,
                    seed,
                    steps: rec.steps.len(),
                    episode_return: rec.episode_return,
                    outcome: Outcome::of(&rec),
                    level: Some(env.level()),
                    distribution: env.distribution_name().map(str::to_owned),
                };
                let mut p = DemoTensors::default();
                for o in &obs {
                    p.robot.extend_from_slice(spec.robot(o));
                    spec.all_rows(o).for_each(|row| p.entities.extend_from_slice(row));
                    p.mask.extend_from_slice(spec.mask(o).expect("the entities observation has a mask"));
                }
                for st in &rec.steps {
                    p.actions.extend_from_slice(&st.action);
                    p.rewards.push(st.reward);
                    p.terminations.push(f32::from(u8::from(st.terminated)));
                    p.truncations.push(f32::from(u8::from(st.truncated)));
                }
                out.push((e, (episode, p)));
                bar.inc(1);
            }
            Ok(out)
        });
        let mut row_played = Vec::with_capacity(n);
        for t in by_thread {
            row_played.extend(t?);
        }
        row_played.sort_by_key(|(e, _)| *e);
        played.extend(row_played.into_iter().map(|(_, p)| p));
    }
    bar.finish_and_clear();
    let policy = PolicyId { name: crate::benchmark::provenance::SOLVER_POLICY.to_owned(), sha256: None };
    let mut d = Demos {
        layout,
        provenance: Provenance::new(harness, policy, Some(suite.id())),
        split: split.to_owned(),
        episodes: Vec::with_capacity(played.len()),
        tensors: DemoTensors::default(),
    };
    for (episode, tensors) in played {
        d.episodes.push(episode);
        d.tensors.append(tensors);
    }
    Ok(d)
}

/// [`record`] into the demos file `out`, which is checked before any episode is played (a folder,
/// a FIFO nobody reads, a read-only file are refused at once), then written by [`Demos::write`].
///
/// # Errors
/// What [`record`] and [`Demos::write`] report, or an output the writer refuses.
pub fn record_to(
    out: &Path,
    suite: &Suite,
    split: &str,
    episodes: Option<usize>,
    threads: usize,
    harness: Harness,
) -> Result<Demos> {
    crate::support::io::check_output(out)?;
    let d = record(suite, split, episodes, threads, harness)?;
    d.write(out)?;
    Ok(d)
}

impl Demos {
    /// Episodes that ended in success.
    pub fn successes(&self) -> usize {
        self.episodes.iter().filter(|e| e.outcome == Outcome::Success).count()
    }

    /// Observations (steps + episodes).
    pub fn observations(&self) -> usize {
        self.tensors.mask.len() / self.layout.rows.max(1)
    }

    /// Steps.
    pub fn steps(&self) -> usize {
        self.tensors.rewards.len()
    }

    /// The tensors by name with their shapes.
    fn tensors(&self) -> Vec<(&'static str, Vec<usize>, &[f32])> {
        let (o, t, l, d) = (self.observations(), self.steps(), &self.layout, &self.tensors);
        vec![
            ("robot", vec![o, l.robot.len()], &d.robot[..]),
            ("entities", vec![o, l.rows, l.entity.len()], &d.entities[..]),
            ("mask", vec![o, l.rows], &d.mask[..]),
            ("actions", vec![t, crate::env::ACTION_DIM], &d.actions[..]),
            ("rewards", vec![t], &d.rewards[..]),
            ("terminations", vec![t], &d.terminations[..]),
            ("truncations", vec![t], &d.truncations[..]),
        ]
    }

    /// Writes the safetensors file (through the one atomic writer).
    ///
    /// # Errors
    /// What the writer reports (a folder, a FIFO nobody reads, a read-only file, a full disk).
    pub fn write(&self, path: &Path) -> Result<()> {
        let bytes: Vec<(&str, Vec<usize>, Vec<u8>)> = self
            .tensors()
            .into_iter()
            .map(|(name, shape, v)| (name, shape, v.iter().flat_map(|x| x.to_le_bytes()).collect()))
            .collect();
        let views = bytes
            .iter()
            .map(|(name, shape, b)| Ok((*name, TensorView::new(Dtype::F32, shape.clone(), b)?)))
            .collect::<Result<Vec<_>, safetensors::SafeTensorError>>()?;
        // One metadata entry, so that the file's bytes do not depend on a map's order: the same
        // episodes give the same file.
        let header = serde_json::json!({
            "version": VERSION,
            "split": self.split,
            "provenance": self.provenance,
            "layout": self.layout,
            "episodes": self.episodes,
        });
        let meta = HashMap::from([(FORMAT.to_owned(), serde_json::to_string(&header)?)]);
        let data = safetensors::tensor::serialize(views, Some(meta))?;
        Ok(crate::support::io::write_file(path, &data)?)
    }

    /// Reads a demos file, checking its format, version and that the tensors agree with the episodes.
    ///
    /// # Errors
    /// Not a demos file (naming what is wrong), another version, tensors of the wrong shape.
    pub fn read(path: &Path) -> Result<Demos> {
        Ok(Self::read_hashed(path)?.0)
    }

    /// As [`Demos::read`], with the `sha256:` of the bytes read: one bounded read, so that a run
    /// records the hash of the very bytes it trained on.
    ///
    /// # Errors
    /// As [`Demos::read`].
    pub fn read_hashed(path: &Path) -> Result<(Demos, String)> {
        let bytes = crate::support::io::read_bytes(path, "demos file", MAX_BYTES)?;
        let bad = |why: String| DemosError::Unusable { path: path.to_owned(), why };
        let (_, header) =
            SafeTensors::read_metadata(&bytes).map_err(|e| bad(format!("not a safetensors file ({e})")))?;
        let meta = header.metadata().clone().unwrap_or_default();
        let Some(text) = meta.get(FORMAT) else {
            let other = meta.get("format").map_or(String::new(), |f| format!(" (it is a {f} file)"));
            return Err(bad(format!("its metadata has no {FORMAT:?} entry{other}")));
        };
        #[derive(Deserialize)]
        struct Header {
            version: u32,
            split: String,
            provenance: Provenance,
            layout: DemoLayout,
            episodes: Vec<DemoEpisode>,
        }
        let h: Header = serde_json::from_str(text).map_err(|e| bad(format!("its {FORMAT} entry: {e}")))?;
        if h.version != VERSION {
            return Err(bad(format!("version {} (this build reads version {VERSION})", h.version)));
        }
        let Header { split, provenance, layout, episodes, .. } = h;
        let st = SafeTensors::deserialize(&bytes).map_err(|e| bad(e.to_string()))?;
        let t: usize = episodes.iter().map(|e| e.steps).sum();
        let o = t + episodes.len();
        let tensor = |name: &str, shape: Vec<usize>| -> Result<Vec<f32>> {
            let v = st.tensor(name).map_err(|_| bad(format!("it has no tensor {name:?}")))?;
            if v.dtype() != Dtype::F32 || v.shape() != shape.as_slice() {
                return Err(bad(format!(
                    "tensor {name} is {:?} {:?}; its episodes call for F32 {shape:?}",
                    v.dtype(),
                    v.shape()
                )));
            }
            Ok(v.data().chunks_exact(4).map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]])).collect())
        };
        let (r, e, f) = (layout.robot.len(), layout.rows, layout.entity.len());
        let tensors = DemoTensors {
            robot: tensor("robot", vec![o, r])?,
            entities: tensor("entities", vec![o, e, f])?,
            mask: tensor("mask", vec![o, e])?,
            actions: tensor("actions", vec![t, crate::env::ACTION_DIM])?,
            rewards: tensor("rewards", vec![t])?,
            terminations: tensor("terminations", vec![t])?,
            truncations: tensor("truncations", vec![t])?,
        };
        check_values(&tensors, &episodes, &layout).map_err(bad)?;
        let sha256 = crate::benchmark::provenance::sha256(&bytes);
        Ok((Demos { tensors, layout, provenance, split, episodes }, sha256))
    }
}

/// The largest magnitude of an observation value a demos file may hold. Observations are metres,
/// metres per step and one-hot flags; a value beyond this is a damaged or edited file, and one such
/// value would swamp a learner's running normaliser.
pub const MAX_OBSERVATION_VALUE: f32 = 1e3;

/// A value for a message: exponent form when very large or very small, as a person reads it.
fn show(v: f32) -> String {
    if v != 0.0 && v.is_finite() && !(1e-4..1e6).contains(&v.abs()) {
        format!("{v:e}")
    } else {
        v.to_string()
    }
}

/// Where row `index` of tensors whose episodes start at `starts` falls: "episode i, `noun` k".
fn locate(index: usize, starts: &[usize], noun: &str) -> String {
    let i = starts.partition_point(|&s| s <= index).saturating_sub(1);
    format!("episode {i}, {noun} {} (row {index})", index - starts[i])
}

/// The values a recording can hold, checked as every reader (Python's `load_demos` too) checks them:
/// observations finite and within [`MAX_OBSERVATION_VALUE`], actions within [-1, 1] (the solver
/// clips them), masks and flags 0 or 1, each episode ended at its last step and at no other, each
/// reward what the environment gives (-1 for a step that does not end the episode; 0 or a negative
/// whole number for its last), and the rewards summing to the episode's recorded return.
fn check_values(t: &DemoTensors, episodes: &[DemoEpisode], layout: &DemoLayout) -> Result<(), String> {
    let (rows, robot) = (layout.rows, layout.robot.len());
    let row = rows * layout.entity.len();
    let mut step_starts = Vec::with_capacity(episodes.len());
    let mut at = 0;
    for e in episodes {
        step_starts.push(at);
        at += e.steps;
    }
    let obs_starts: Vec<usize> = step_starts.iter().enumerate().map(|(i, s)| s + i).collect();
    let observations = [("robot", &t.robot, robot), ("entities", &t.entities, row)];
    for (name, values, width) in observations {
        if let Some(k) = values.iter().position(|v| !v.is_finite() || v.abs() > MAX_OBSERVATION_VALUE) {
            return Err(format!(
                "tensor {name:?} holds {} at {}; an observation is finite and within ±{MAX_OBSERVATION_VALUE}",
                show(values[k]),
                locate(k / width.max(1), &obs_starts, "observation")
            ));
        }
    }
    if let Some(k) = t.actions.iter().position(|a| !(-1.0..=1.0).contains(a)) {
        return Err(format!(
            "tensor \"actions\" holds {} at {}; an action's components are within [-1, 1]",
            show(t.actions[k]),
            locate(k / crate::env::ACTION_DIM, &step_starts, "step")
        ));
    }
    for (name, values, width, starts, noun) in [
        ("mask", &t.mask, rows.max(1), &obs_starts, "observation"),
        ("terminations", &t.terminations, 1, &step_starts, "step"),
        ("truncations", &t.truncations, 1, &step_starts, "step"),
    ] {
        if let Some(k) = values.iter().position(|&v| v != 0.0 && v != 1.0) {
            return Err(format!(
                "tensor {name:?} holds {} at {}; its values are 0 or 1",
                show(values[k]),
                locate(k / width, starts, noun)
            ));
        }
    }
    for (i, (e, &start)) in episodes.iter().zip(&step_starts).enumerate() {
        for (field, value) in
            [("task", Some(&e.task)), ("task_sha256", Some(&e.task_sha256)), ("distribution", e.distribution.as_ref())]
        {
            if value.is_some_and(|v| v.is_empty()) {
                return Err(format!("field episodes[{i}].{field} is empty; a recording names it"));
            }
        }
        if e.steps == 0 {
            return Err(format!("episode {i} has no steps; a recorded episode has at least one"));
        }
        let last = start + e.steps - 1;
        for k in start..start + e.steps {
            let ends = t.terminations[k] == 1.0 || t.truncations[k] == 1.0;
            if ends != (k == last) {
                return Err(if ends {
                    format!(
                        "tensors \"terminations\"/\"truncations\" end an episode at {}, before its last step",
                        locate(k, &step_starts, "step")
                    )
                } else {
                    format!(
                        "episode {i} ({} steps) is not ended at its last step by terminations or truncations",
                        e.steps
                    )
                });
            }
            let r = t.rewards[k];
            let fits = if k == last { r <= 0.0 && r.fract() == 0.0 } else { r == -1.0 };
            if !fits {
                return Err(format!(
                    "tensor \"rewards\" holds {} at {}; the environment gives -1 for a step that does not end the \
                     episode, and 0 or a negative whole number for its last",
                    show(r),
                    locate(k, &step_starts, "step")
                ));
            }
        }
        let sum: f64 = t.rewards[start..start + e.steps].iter().map(|&r| f64::from(r)).sum();
        if (sum - f64::from(e.episode_return)).abs() > 1e-3 {
            return Err(format!(
                "episode {i}'s rewards sum to {sum}, its header's episode_return is {}",
                e.episode_return
            ));
        }
    }
    Ok(())
}
