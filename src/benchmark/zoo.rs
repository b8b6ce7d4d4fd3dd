//! The model zoo: trained policies shipped in the repository, so that every
//! row of `results/table-mujoco-*.md` can be checked in minutes without training.
//!
//! An entry is two files in `zoo/` (or `$BLOCKPUZZLE_ZOO`):
//!
//! * `NAME.safetensors`: the tensors, float32, in the `safetensors` format
//!   (readable with `safetensors.numpy.load_file` in Python):
//!   `actor.{i}.weight` (`out × in`), `actor.{i}.bias` (`out`) for each dense
//!   layer, input first; the same under `critic.` where the entry keeps
//!   DDPG's critic (AggreVaTeD's expert-advantage weights need it); and
//!   `obs_norm.mean`, `obs_norm.std` (the observation normaliser).
//!   Its `__metadata__` holds `format` and `name`.
//! * `NAME.json`: [`ZooMeta`], what the tensors are and where they came from:
//!   task (id, text, content hash), algorithm, epoch, environment steps,
//!   the normaliser's clip range, the network's layout, the command that
//!   trained it, its evaluations, and the SHA-256 of the tensors file.
//!
//! The policy acts as: `x = clip((obs − mean) / std, ±clip)`; hidden layers
//! `ReLU(W x + b)`; the last layer `tanh` (DDPG: the action) or linear
//! (PGGD: `[μ | σ pre-activation]`, the action `clip(μ, ±1)`).
//!
//! Every consumer of policies (`eval`, `rollout --policy`, `render
//! --policy`, `table`, AggreVaTeD's `--expert`) takes a zoo name as well as
//! a file or run directory: [`crate::benchmark::load::load_policy`].

use crate::benchmark::saved::{SavedPolicy, Trainer};
use crate::policy::actor::mlp::{Dense, PlainNet};
use crate::policy::actor::normalizer::Normalizer;
use crate::policy::actor::{AnyPolicy, DeterministicPolicy, PggdPolicy, PolicyKind};
use crate::task::TaskSource;
use safetensors::tensor::{Dtype, SafeTensors, TensorView};
use serde::{Deserialize, Serialize};

use std::collections::HashMap;
use std::io::Write;
use std::path::{Path, PathBuf};
use thiserror::Error;

/// The format tag this blockpuzzle writes in every entry's metadata.
pub const FORMAT: &str = "blockpuzzle-zoo/7";

/// The formats it reads: version 2 added the outcome counts of evaluations
/// (version 1 entries load with none); version 3 set networks (a network's
/// `set` layout and `layers` shapes; entries without them are MLPs as before);
/// version 4 each evaluation's provenance and task hash (one record per engine);
/// version 5 policies trained on several tasks ([`ZooMeta::multi_task`]); version 6 policies trained on
/// a stream of generated tasks ([`MultiTask::stream`]); version 7 records what the policy is
/// ([`ZooMeta::kind`], [`ZooMeta::obs_mode`]) and the algorithm that trained it ([`ZooMeta::algo`]).
pub const READS: [&str; 7] = [
    "blockpuzzle-zoo/1",
    "blockpuzzle-zoo/2",
    "blockpuzzle-zoo/3",
    "blockpuzzle-zoo/4",
    "blockpuzzle-zoo/5",
    "blockpuzzle-zoo/6",
    FORMAT,
];

/// What a format-7 entry upgraded from an older format names as its algorithm until `zoo upgrade
/// --algo` records it.
pub const UNRECORDED: &str = "unrecorded";

/// [`ZooMeta::algo`] as entries write it: the trainer's name, or [`UNRECORDED`] for none.
mod recorded_algo {
    use super::{Trainer, UNRECORDED};
    use serde::{de::Error as _, Deserialize, Deserializer, Serializer};

    pub(super) fn serialize<S: Serializer>(algo: &Option<Trainer>, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(algo.map_or(UNRECORDED, Trainer::name))
    }

    pub(super) fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Option<Trainer>, D::Error> {
        let name = String::deserialize(d)?;
        if name == UNRECORDED {
            return Ok(None);
        }
        Trainer::named(&name).map(Some).ok_or_else(|| {
            let names: Vec<&str> = Trainer::ALL.iter().map(|t| t.name()).collect();
            D::Error::custom(format!("algo {name:?} is none of {} or {UNRECORDED}", names.join(", ")))
        })
    }
}

/// Zoo errors: each names the file and what to do.
#[derive(Debug, Error)]
pub enum ZooError {
    /// Reading or writing failed.
    #[error("zoo entry {path}: {source}")]
    Io { path: PathBuf, source: std::io::Error },
    /// The files are damaged, do not belong together, or hold impossible values.
    #[error("zoo entry {path} is not usable: {reason}")]
    Corrupt { path: PathBuf, reason: String },
    /// Export would replace an entry.
    #[error("the zoo already has an entry {path}; pass --force to replace it, or choose another --name")]
    Exists { path: PathBuf },
    /// A name that cannot be an entry's.
    #[error("--name {name:?}: an entry's name is 1 to {MAX_NAME} letters, digits, '-' and '_' (it becomes NAME.safetensors and NAME.json in the zoo folder); for example \"BlocksTouch-v0-ddpg-mine\"")]
    BadName { name: String },
    /// An entry's metadata without its tensors.
    #[error("zoo entry {json}: its tensors, {tensors}, are missing; an entry is two files, NAME.json and NAME.safetensors: copy both, or export it again (zoo export)")]
    NoTensors { json: PathBuf, tensors: PathBuf },
    /// The zoo path is a file.
    #[error("the zoo {zoo} is not a folder; set $BLOCKPUZZLE_ZOO or --zoo to a folder of NAME.safetensors + NAME.json entries (zoo export creates it if missing)")]
    NotAFolder { zoo: PathBuf },
    /// The zoo folder does not exist.
    #[error("the zoo folder {zoo} does not exist (set $BLOCKPUZZLE_ZOO or --zoo to a folder of NAME.safetensors + NAME.json entries)")]
    NoZoo { zoo: PathBuf },
    /// A description that carries a result's figure.
    #[error("--description carries the figure {figure:?}: an entry's figures are its recorded evaluations (`zoo list` shows them, recomputed from their outcomes) and its results/ pages; say what the policy is and where its numbers are, without them")]
    FigureInDescription { figure: String },
    /// A name that is neither a file nor an entry of the zoo.
    #[error("no policy file or zoo entry named {name:?} (the zoo in {zoo} has: {known}); pass a policy file, a run directory or one of those names")]
    Unknown { name: String, zoo: PathBuf, known: String },
    /// A path given where an entry's name is wanted (`zoo check`, `upgrade`, `describe`).
    #[error("{name:?} is {what} here, not the name of a zoo entry: `zoo {command}` takes the names of the zoo in {zoo} (`zoo list` shows them; --zoo FOLDER picks another zoo)")]
    PathForName { name: String, what: &'static str, command: &'static str, zoo: PathBuf },
}

/// The network layout of one net: layer sizes (input first) and output.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct NetLayout {
    /// Sizes from input to output, e.g. `[31, 256, 256, 256, 4]`.
    pub sizes: Vec<usize>,
    /// Whether the output goes through tanh (DDPG's actor) or is linear.
    pub tanh_out: bool,
    /// A set network's layout (absent: an MLP); its first `encoder_layers`
    /// layers encode each object row, the next four (with `attention`) are the
    /// attention block, the rest the head (zoo/README.md).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub set: Option<crate::policy::actor::mlp::SetLayout>,
    /// A set network's layers as `[out, in]` (its inputs do not chain as an MLP's sizes do).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub layers: Vec<[usize; 2]>,
    /// Every hidden layer's output layer-normalised before its ReLU (a critic of `train --critic-norm`).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub hidden_norm: bool,
}

/// One evaluation of the entry (a cell of the table, or a `blockpuzzle eval`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ZooEvaluation {
    /// The task evaluated on.
    pub env: String,
    /// Which distribution: `normal` (the maximum level) or `challenge`.
    pub distribution: String,
    /// Whether grey blocks were removed from the policy's view.
    pub grey_blind: bool,
    /// Episodes and the seed of the first (episode k: seed + k).
    pub episodes: usize,
    /// Seed of the first episode.
    pub seed: u64,
    /// Success rate.
    pub success_rate: f64,
    /// Its Wilson 95% interval.
    pub ci95: (f64, f64),
    /// Episodes per outcome ([`crate::episode::outcome`]; absent in format 1 entries).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub outcomes: Option<crate::episode::outcome::Outcomes>,
    /// The task's content hash (absent in entries written before evaluations recorded it).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub task_sha256: Option<String>,
    /// What made it: the engine above all, since numbers of different engines differ
    /// (absent in entries written before evaluations recorded it).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub provenance: Option<crate::benchmark::provenance::Provenance>,
}

impl ZooEvaluation {
    /// The MuJoCo version that made it, where recorded.
    pub fn mujoco(&self) -> Option<&str> {
        self.provenance.as_ref().map(|p| p.build.mujoco.as_str())
    }

    /// The `sha256:` of the policy that made it, where its provenance names one.
    pub fn policy_sha256(&self) -> Option<&str> {
        self.provenance.as_ref().and_then(|p| p.policy.sha256.as_deref())
    }

    /// Whether its provenance names a policy other than `policy` (a record that names none does not).
    pub fn names_another_policy(&self, policy: Option<&str>) -> bool {
        self.policy_sha256().is_some_and(|h| Some(h) != policy)
    }

    /// Whether its numbers hold together and name what exists, as a suite result's are checked
    /// ([`crate::benchmark::evaluate::SuiteResult::verify`]): episodes within
    /// [`crate::support::limits::EVAL_EPISODES`], outcome counts that sum to them, the success rate
    /// and its interval recomputed from the successes, a task this entry can be played on (a
    /// built-in id, or its own task) with that task's hash, and an engine this project runs
    /// ([`crate::benchmark::provenance::ENGINES`]).
    ///
    /// # Errors
    /// What does not hold, with the recorded and the recomputed value.
    pub fn check(&self, meta: &ZooMeta) -> Result<(), String> {
        use crate::episode::outcome::same_number;
        let bound = crate::support::limits::EVAL_EPISODES;
        if bound.check(self.episodes as u64).is_err() {
            return Err(format!("episodes {} is outside what an evaluation plays, {bound}", self.episodes));
        }
        if !matches!(self.distribution.as_str(), "normal" | "challenge") {
            return Err(format!("distribution {:?} is neither normal nor challenge", self.distribution));
        }
        let n = self.episodes as f64;
        let successes = match &self.outcomes {
            Some(o) if o.total() != self.episodes => {
                return Err(format!("its outcomes count {} episodes, and it records {}", o.total(), self.episodes))
            }
            Some(o) => o.success,
            // Format 1 kept no outcome counts: the rate must still be a count of episodes.
            None if (0.0..=1.0).contains(&self.success_rate)
                && ((self.success_rate * n).round() - self.success_rate * n).abs() <= 1e-6 * n.max(1.0) =>
            {
                (self.success_rate * n).round() as usize
            }
            None => {
                return Err(format!(
                    "success_rate {} is not a count of {} episodes over their number",
                    self.success_rate, self.episodes
                ))
            }
        };
        let rate = successes as f64 / n;
        if !same_number(self.success_rate, rate) {
            return Err(format!(
                "success_rate {}, but its outcomes give {rate} ({successes} of {} episodes)",
                self.success_rate, self.episodes
            ));
        }
        let ci = crate::episode::outcome::wilson95(successes, self.episodes);
        if !same_number(self.ci95.0, ci.0) || !same_number(self.ci95.1, ci.1) {
            return Err(format!("ci95 {:?}, but {successes} of {} episodes give {ci:?}", self.ci95, self.episodes));
        }
        // The task: the entry's own (or one of a multi-task run's), or a built-in id.
        let own = std::iter::once(&meta.task).chain(meta.multi_task.iter().flat_map(|m| &m.tasks));
        let hash = match own.clone().find(|t| t.id == self.env) {
            Some(t) => t.hash.clone(),
            None if !crate::env::registry::is_path(&self.env) => match crate::env::registry::task(&self.env) {
                Ok(t) => t.source.hash,
                Err(_) => {
                    return Err(format!(
                        "env {:?} is neither a built-in task nor this entry's own ({})",
                        self.env, meta.task.id
                    ))
                }
            },
            None => {
                return Err(format!("env {:?} is a path; a record names a built-in task or the entry's own", self.env))
            }
        };
        if let Some(h) = self.task_sha256.as_ref().filter(|h| **h != hash) {
            return Err(format!("task_sha256 {h}, and task {}'s hash is {hash}", self.env));
        }
        if let Some(m) = self.mujoco().filter(|m| !crate::benchmark::provenance::ENGINES.contains(m)) {
            return Err(format!(
                "MuJoCo {m:?} is no engine this project runs ({})",
                crate::benchmark::provenance::ENGINES.join(", ")
            ));
        }
        Ok(())
    }

    /// Whether `other` measures the same thing (task, distribution, view, episodes, seeds) on the same engine.
    pub fn same_measurement(&self, other: &ZooEvaluation) -> bool {
        (&self.env, &self.distribution, self.grey_blind, self.episodes, self.seed, self.mujoco())
            == (&other.env, &other.distribution, other.grey_blind, other.episodes, other.seed, other.mujoco())
    }
}

/// `NAME.json`: everything about an entry but its tensors.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ZooMeta {
    /// [`FORMAT`].
    pub format: String,
    /// The entry's name (its file stem).
    pub name: String,
    /// One line on what it is (e.g. the table row it stands for).
    pub description: String,
    /// Format 7 on: the algorithm that trained it (None, written [`UNRECORDED`], for an entry
    /// upgraded from an older format without `zoo upgrade --algo`). Formats 1–6: what acts, `ddpg`
    /// (a tanh actor) or `pggd` ([`ZooMeta::kind`] reads both).
    #[serde(with = "recorded_algo")]
    pub algo: Option<Trainer>,
    /// Format 7 on, where recorded: the version of the solver whose actions it learned from (BC,
    /// DAgger, runs with `--demos`; [`SavedPolicy::solver`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub solver: Option<u32>,
    /// Format 7 on: what acts.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub kind: Option<PolicyKind>,
    /// Format 7 on: the observation the policy reads, as recorded (readers take it from here).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub obs_mode: Option<crate::env::ObsMode>,
    /// Format 7 on: where an object row's colour one-hot begins in that observation (a set network
    /// pooled by colour reads it; the Python reader takes it from here, [`crate::env::COLOUR_FEATURE`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub colour_feature: Option<usize>,
    /// Format 7 on, where recorded: the rule objects other than blocks whose rows follow the blocks'
    /// in that observation ([`crate::env::Fixture`], in row order); checked against this build's.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fixtures: Option<Vec<crate::env::Fixture>>,
    /// The task it was trained on, by content; for a policy trained on several tasks the first
    /// of them (its probes are that task's).
    pub task: TaskSource,
    /// A policy trained on several tasks (format 5): the run's label and every training task.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub multi_task: Option<MultiTask>,
    /// Epochs of training behind it.
    pub epoch: usize,
    /// Environment steps of training behind it, where known.
    pub env_steps: Option<u64>,
    /// Its finals success in training when saved.
    pub finals_success: f64,
    /// The observation normaliser's clip range (mean and std are tensors).
    pub norm_clip: f32,
    /// The normaliser's standard-deviation floor.
    pub norm_eps: f64,
    /// Observations the normaliser had seen.
    pub norm_count: u64,
    /// The actor's layout.
    pub actor: NetLayout,
    /// The critic's layout, where the entry keeps one (DDPG).
    pub critic: Option<NetLayout>,
    /// PGGD: σ's floor (the network outputs μ and σ's pre-activation).
    pub sigma_min: Option<f64>,
    /// The command that trained it.
    pub trained_with: String,
    /// The file it was exported from, for the record.
    pub exported_from: String,
    /// For a blended policy (`blockpuzzle blend`): the two policies its weights came from, by name
    /// and hash, and the weight; sealed with the rest.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub blend: Option<crate::benchmark::saved::BlendRecord>,
    /// For a fine-tuned policy: the policy its run started from (`train --init-from`), by name and
    /// hash; sealed with the rest.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub started_from: Option<crate::benchmark::provenance::PolicyId>,
    /// Its evaluations, best recorded with `zoo export --eval`.
    pub evaluations: Vec<ZooEvaluation>,
    /// The source policy's actions on a few observations (reset states of its
    /// task), recorded at export: the entry must act exactly so.
    pub probes: Vec<Probe>,
    /// `sha256:` of `NAME.safetensors`: the tensors belong to this metadata.
    pub tensors_sha256: String,
    /// `sha256:` of this metadata itself, evaluations and this field set aside ([`ZooMeta::seal`]):
    /// an entry is checked as a whole, so that an edited field (a dropped `multi_task`, a task list, a
    /// label, a layout) is refused. Written from format 6 on and required there.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub meta_sha256: Option<String>,
}

impl ZooMeta {
    /// The format's version number (`blockpuzzle-zoo/7` -> 7).
    pub fn version(&self) -> u32 {
        self.format.rsplit('/').next().and_then(|v| v.parse().ok()).unwrap_or(0)
    }

    /// What acts, recorded (format 7) or read from `algo` (before).
    pub fn kind(&self) -> Option<PolicyKind> {
        if self.version() >= 7 {
            return self.kind;
        }
        match self.algo {
            Some(Trainer::Ddpg) => Some(PolicyKind::Deterministic),
            Some(Trainer::Pggd) => Some(PolicyKind::Gaussian),
            _ => None,
        }
    }

    /// The algorithm that trained it, where the entry records it (format 7, not `unrecorded`).
    pub fn trained_by(&self) -> Option<Trainer> {
        self.algo.filter(|_| self.version() >= 7)
    }

    /// `sha256:` of the metadata with its evaluations (which `zoo evaluate` adds to) and `meta_sha256`
    /// set aside: what [`ZooMeta::meta_sha256`] records.
    pub fn seal(&self) -> String {
        let bare = ZooMeta { evaluations: Vec::new(), meta_sha256: None, ..self.clone() };
        // Serialising a struct of these types cannot fail; the fallback seals nothing and never matches.
        crate::benchmark::provenance::sha256(&serde_json::to_vec(&bare).unwrap_or_default())
    }

    /// The first field it carries that a newer format than its own introduced ([`READS`]), with
    /// that format's version: an older format carries nothing a newer one added (and seals), so an
    /// entry relabelled as older cannot slip forged fields past the seal.
    pub fn newer_field(&self) -> Option<(&'static str, u32)> {
        let evals = |f: fn(&ZooEvaluation) -> bool| self.evaluations.iter().any(f);
        let nets = || std::iter::once(&self.actor).chain(self.critic.as_ref());
        let stream = self.multi_task.as_ref().is_some_and(|m| m.stream.is_some());
        let fields = [
            ("evaluations[].outcomes", 2, evals(|e| e.outcomes.is_some())),
            ("a set network layout (actor.set, layers)", 3, nets().any(|n| n.set.is_some() || !n.layers.is_empty())),
            ("evaluations[].provenance", 4, evals(|e| e.provenance.is_some())),
            ("evaluations[].task_sha256", 4, evals(|e| e.task_sha256.is_some())),
            ("multi_task", 5, self.multi_task.is_some()),
            ("multi_task.stream", 6, stream),
            ("meta_sha256", 6, self.meta_sha256.is_some()),
            ("kind", 7, self.kind.is_some()),
            ("obs_mode", 7, self.obs_mode.is_some()),
            ("colour_feature", 7, self.colour_feature.is_some()),
            ("fixtures", 7, self.fixtures.is_some()),
            ("blend", 7, self.blend.is_some()),
            ("started_from", 7, self.started_from.is_some()),
            ("solver", 7, self.solver.is_some()),
            ("hidden_norm", 7, nets().any(|n| n.hidden_norm)),
        ];
        fields.into_iter().find(|&(_, v, present)| present && v > self.version()).map(|(f, v, _)| (f, v))
    }

    /// What it was trained on, as listings name it: its task's id, or a multi-task run's label.
    pub fn trained_on(&self) -> &str {
        self.multi_task.as_ref().map_or(self.task.id.as_str(), |m| m.label.as_str())
    }
}

/// What a policy trained on several tasks was trained on.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MultiTask {
    /// The run's label: `SUITE-SPLIT` (`train --suite`) or the ids joined by `+` (`train --env A,B`).
    pub label: String,
    /// The training tasks by content, in the run's order (empty for a stream).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub tasks: Vec<TaskSource>,
    /// A policy trained on a stream of generated tasks (format 6): the stream's record (its families'
    /// texts, the seed range, each task by id, seed, candidate and hash), from which its tasks are drawn
    /// again and checked on loading.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stream: Option<crate::benchmark::stream::StreamRecord>,
}

/// An observation and the action the exported policy took on it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Probe {
    /// The observation (the policy's own view).
    pub obs: Vec<f32>,
    /// Its deterministic action.
    pub action: Vec<f32>,
}

/// Reset observations of seeds 0, 1, 2 of the policy's task at its maximum
/// level, and the policy's actions on them.
///
/// # Errors
/// A task that cannot be built.
pub fn probes(saved: &SavedPolicy) -> Result<Vec<Probe>, ZooError> {
    let fail = |reason: String| ZooError::Corrupt { path: PathBuf::from(&saved.env_id), reason };
    let first = saved.training_tasks().map_err(|e| fail(e.to_string()))?.into_iter().next();
    let task = match first {
        Some(source) => crate::env::registry::recorded(&source).map_err(|e| fail(e.to_string()))?,
        None => return Err(fail("the policy does not record its task".into())),
    };
    // In the policy's own layout: a multi-task policy's rows are those of its tasks' most blocks
    // (absent rows padded), so that its probes replay as saved.
    let slots = saved.slots().map_err(|e| fail(e.to_string()))?.max(saved.policy.block_slots(saved.obs_mode()));
    let obs_mode = saved.obs_mode();
    let config = crate::env::EnvConfig { obs_mode, slots, ..crate::env::EnvConfig::new(task) };
    let mut env = crate::env::BlockEnv::new(config).map_err(|e| fail(e.to_string()))?;
    let level = env.max_level();
    env.set_level(level).map_err(|e| fail(e.to_string()))?;
    (0..3)
        .map(|seed| {
            let (obs, _) = env.reset(Some(seed)).map_err(|e| fail(e.to_string()))?;
            let obs = obs.to_vec();
            Ok(Probe { action: saved.policy.act(&obs), obs })
        })
        .collect()
}

fn io(path: &Path) -> impl Fn(std::io::Error) -> ZooError + '_ {
    move |source| ZooError::Io { path: path.to_owned(), source }
}

/// The zoo folder: `$BLOCKPUZZLE_ZOO`, else `zoo/` of this repository.
pub fn dir() -> PathBuf {
    match std::env::var_os("BLOCKPUZZLE_ZOO") {
        Some(d) if !d.is_empty() => PathBuf::from(d),
        _ => Path::new(env!("CARGO_MANIFEST_DIR")).join("zoo"),
    }
}

/// The entries' names in `zoo`, sorted.
pub fn names(zoo: &Path) -> Vec<String> {
    let Ok(rd) = std::fs::read_dir(zoo) else { return Vec::new() };
    let mut v: Vec<String> = rd
        .filter_map(|e| e.ok())
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|x| x == "safetensors"))
        .filter_map(|p| p.file_stem().map(|s| s.to_string_lossy().into_owned()))
        .collect();
    v.sort();
    v
}

/// A policy argument that names a zoo entry rather than a file: no such
/// file, no path separator, no extension.
pub fn is_name(arg: &Path) -> bool {
    !arg.exists() && arg.components().count() == 1 && arg.extension().is_none()
}

/// `zoo` itself, if it is a folder.
///
/// # Errors
/// [`ZooError::NoZoo`].
pub fn existing(zoo: &Path) -> Result<&Path, ZooError> {
    if zoo.is_dir() {
        Ok(zoo)
    } else if zoo.exists() {
        Err(ZooError::NotAFolder { zoo: zoo.to_owned() })
    } else {
        Err(ZooError::NoZoo { zoo: zoo.to_owned() })
    }
}

/// The longest entry name (with `.safetensors` it stays within file systems' 255-byte names).
pub const MAX_NAME: usize = 100;

/// The tensors file of the entry `name` in `zoo`, if it exists.
///
/// # Errors
/// [`ZooError::Unknown`] listing the entries there are; [`ZooError::NoTensors`] for an entry's
/// metadata alone.
pub fn find(zoo: &Path, name: &str) -> Result<PathBuf, ZooError> {
    let path = zoo.join(format!("{name}.safetensors"));
    if path.exists() {
        return Ok(path);
    }
    existing(zoo)?;
    let json = path.with_extension("json");
    if json.is_file() {
        return Err(ZooError::NoTensors { json, tensors: path });
    }
    let known = names(zoo);
    Err(ZooError::Unknown { name: name.to_owned(), zoo: zoo.to_owned(), known: some_names(&known) })
}

/// How many entry names a message lists before it says how many more there are.
const NAMES_LISTED: usize = 12;

/// `a, b, c` for a few names, the first [`NAMES_LISTED`] and a count for many.
fn some_names(known: &[String]) -> String {
    match known.len() {
        0 => "no entries".into(),
        n if n <= NAMES_LISTED => known.join(", "),
        n => format!("{}, and {} more (`zoo list`)", known[..NAMES_LISTED].join(", "), n - NAMES_LISTED),
    }
}

/// As [`find`] for an entry name given to `zoo COMMAND`, where a path is refused as such: a folder,
/// pipe or file of that name here is not mistaken for an entry the zoo lacks.
///
/// # Errors
/// [`ZooError::PathForName`] for a path; otherwise as [`find`].
pub fn find_named(zoo: &Path, name: &str, command: &'static str) -> Result<PathBuf, ZooError> {
    let given = Path::new(name);
    if let Ok(meta) = std::fs::metadata(given) {
        if !zoo.join(format!("{name}.safetensors")).exists() {
            let what = crate::support::io::kind(meta.file_type());
            return Err(ZooError::PathForName { name: name.to_owned(), what, command, zoo: zoo.to_owned() });
        }
    }
    find(zoo, name)
}

/// Whether `path` is a zoo file: `X.safetensors`, or the `X.json` beside one.
pub fn is_zoo_file(path: &Path) -> bool {
    match path.extension().and_then(|e| e.to_str()) {
        Some("safetensors") => true,
        Some("json") => path.with_extension("safetensors").exists(),
        _ => false,
    }
}

/// Whether `path` is a zoo entry's `X.json` without the `X.safetensors` beside it (its `format`
/// names the zoo's): a policy file it is not.
pub fn is_lone_metadata(path: &Path) -> bool {
    // A regular file only (opening a FIFO would wait for a writer).
    if path.extension().map_or(true, |e| e != "json") || !path.is_file() || path.with_extension("safetensors").exists()
    {
        return false;
    }
    // The start of the file is enough: an entry's `format` comes first.
    let Ok(mut f) = std::fs::File::open(path) else { return false };
    let mut head = vec![0u8; 256];
    let n = std::io::Read::read(&mut f, &mut head).unwrap_or(0);
    String::from_utf8_lossy(&head[..n]).contains("\"blockpuzzle-zoo/")
}

/// A network's layout, `n_in` its whole input (observation, and a critic's action).
fn layout(net: &PlainNet, n_in: usize) -> NetLayout {
    let mut sizes = vec![n_in];
    sizes.extend(net.layers.iter().map(|l| l.b.len()));
    let layers = match net.set {
        None => Vec::new(),
        Some(_) => net.layers.iter().map(|l| [l.b.len(), l.n_in]).collect(),
    };
    NetLayout { sizes, tanh_out: net.tanh_out, set: net.set, layers, hidden_norm: net.hidden_norm }
}

fn le_bytes(v: &[f32]) -> Vec<u8> {
    v.iter().flat_map(|x| x.to_le_bytes()).collect()
}

/// The first figure in `description` that reads as a result (a rate such as 0.978 or 0.79x, or a
/// percentage): descriptions are recorded once and never recomputed, so they carry none (None:
/// none there). A weight such as "0.3 x" (one decimal) or a count is no result.
pub fn figure_in(description: &str) -> Option<String> {
    let chars: Vec<char> = description.chars().collect();
    for (i, c) in chars.iter().enumerate() {
        let before_ok = i == 0 || !(chars[i - 1].is_ascii_digit() || chars[i - 1] == '.');
        let rate = matches!(c, '0' | '1')
            && before_ok
            && chars.get(i + 1) == Some(&'.')
            && chars.get(i + 2).is_some_and(char::is_ascii_digit)
            && chars.get(i + 3).is_some_and(char::is_ascii_digit);
        let percent = *c == '%' && i > 0 && chars[i - 1].is_ascii_digit();
        if rate || percent {
            let from = if percent { i - 1 } else { i };
            let start =
                (0..=from).rev().take_while(|&j| chars[j].is_ascii_digit() || chars[j] == '.').last().unwrap_or(from);
            let end = (i..chars.len()).take_while(|&j| chars[j].is_ascii_digit() || ".%x".contains(chars[j])).last();
            return Some(chars[start..=end.unwrap_or(i)].iter().collect());
        }
    }
    None
}

/// Replaces an entry's description (`zoo describe`), checked as [`export`] checks it; the entry is
/// resealed and must load as before.
///
/// # Errors
/// A figure in the description, an entry that does not load, I/O.
pub fn describe(path: &Path, description: &str) -> Result<(), ZooError> {
    if let Some(figure) = figure_in(description) {
        return Err(ZooError::FigureInDescription { figure });
    }
    rewrite(path, |meta, _| {
        meta.description = description.to_owned();
        Ok(())
    })
}

/// What [`export`] records besides the policy.
#[derive(Debug, Clone, Default)]
pub struct ExportInfo {
    /// The entry's name (file stem).
    pub name: String,
    /// One line on what it is.
    pub description: String,
    /// The command that trained it.
    pub trained_with: String,
    /// Where it came from.
    pub exported_from: String,
    /// Environment steps behind it, where known.
    pub env_steps: Option<u64>,
    /// Its evaluations.
    pub evaluations: Vec<ZooEvaluation>,
    /// Keep DDPG's critic (needed by AggreVaTeD's expert-advantage weights).
    pub keep_critic: bool,
    /// Replace an entry of the same name (else that is an error).
    pub overwrite: bool,
    /// The algorithm that trained it where the policy file does not record it (older runs).
    pub algo: Option<Trainer>,
}

/// Whether the entry `name` may be written in `zoo`: it does not exist yet, or `overwrite`.
///
/// # Errors
/// [`ZooError::Exists`].
pub fn entry_free(zoo: &Path, name: &str, overwrite: bool) -> Result<(), ZooError> {
    let path = zoo.join(format!("{name}.safetensors"));
    if path.exists() && !overwrite {
        return Err(ZooError::Exists { path });
    }
    Ok(())
}

/// Writes `saved` as the entry `info.name` in `zoo` (both files atomically;
/// the tensors first, so the metadata never names tensors that are not there).
///
/// # Errors
/// A policy without a recorded task, bad values, I/O.
pub fn export(zoo: &Path, saved: &SavedPolicy, info: &ExportInfo) -> Result<PathBuf, ZooError> {
    let tensors_path = zoo.join(format!("{}.safetensors", info.name));
    let corrupt = |reason: String| ZooError::Corrupt { path: tensors_path.clone(), reason };
    // No dots: a bare name without an extension is what `load_policy` looks up in the zoo.
    if info.name.is_empty()
        || info.name.len() > MAX_NAME
        || !info.name.chars().all(|c| c.is_ascii_alphanumeric() || "-_".contains(c))
    {
        // A long name is shown by its start and length.
        let name = match info.name.char_indices().nth(40) {
            Some((at, _)) => format!("{}… ({} characters)", &info.name[..at], info.name.chars().count()),
            None => info.name.clone(),
        };
        return Err(ZooError::BadName { name });
    }
    if let Some(figure) = figure_in(&info.description) {
        return Err(ZooError::FigureInDescription { figure });
    }
    entry_free(zoo, &info.name, info.overwrite)?;
    saved.check().map_err(&corrupt)?;
    let task = saved
        .training_tasks()
        .map_err(|e| corrupt(e.to_string()))?
        .into_iter()
        .next()
        .ok_or_else(|| corrupt("the policy does not record its task (saved before tasks were files)".into()))?;
    let multi_task = if !saved.is_multi_task() {
        None
    } else if saved.policy.net().set.is_none() {
        // A flat network reads its tasks padded to one layout, which the zoo's readers do not rebuild.
        return Err(corrupt(format!(
            "{} is a flat network trained on several tasks: the zoo takes multi-task policies with set networks \
             (train --net set or entity), which read any number of objects",
            saved.env_id
        )));
    } else {
        Some(MultiTask { label: saved.env_id.clone(), tasks: saved.tasks.clone(), stream: saved.stream.clone() })
    };
    let (net, norm, sigma_min) = match &saved.policy {
        AnyPolicy::Deterministic(p) => (&p.net, &p.norm, None),
        AnyPolicy::Pggd(p) => (&p.net, &p.norm, Some(p.sigma_min)),
    };
    let critic = if info.keep_critic { saved.critic.as_ref() } else { None };
    let mut arrays: Vec<(String, Vec<usize>, Vec<u8>)> = Vec::new();
    let mut add_net = |prefix: &str, net: &PlainNet| {
        for (i, l) in net.layers.iter().enumerate() {
            arrays.push((format!("{prefix}.{i}.weight"), vec![l.b.len(), l.n_in], le_bytes(&l.w)));
            arrays.push((format!("{prefix}.{i}.bias"), vec![l.b.len()], le_bytes(&l.b)));
        }
    };
    add_net("actor", net);
    if let Some(c) = critic {
        add_net("critic", c);
    }
    arrays.push(("obs_norm.mean".into(), vec![norm.dim()], le_bytes(norm.mean())));
    arrays.push(("obs_norm.std".into(), vec![norm.dim()], le_bytes(norm.std())));
    let views: Vec<(String, TensorView)> = arrays
        .iter()
        .map(|(n, shape, bytes)| {
            TensorView::new(Dtype::F32, shape.clone(), bytes)
                .map(|v| (n.clone(), v))
                .map_err(|e| corrupt(e.to_string()))
        })
        .collect::<Result<_, _>>()?;
    let header: HashMap<String, String> =
        [("format".to_owned(), FORMAT.to_owned()), ("name".to_owned(), info.name.clone())].into_iter().collect();
    let bytes = safetensors::tensor::serialize(views, Some(header)).map_err(|e| corrupt(e.to_string()))?;
    if let Some(a) = saved.algo.or(info.algo) {
        a.check_trains(saved.policy.kind())
            .map_err(|e| corrupt(format!("{e}; record the algorithm that trained it")))?;
    }
    if let (Some(recorded), Some(given)) = (saved.algo, info.algo) {
        if recorded != given {
            return Err(corrupt(format!(
                "--algo {given}: the policy file records that {recorded} trained it; leave --algo out"
            )));
        }
    }
    let meta = ZooMeta {
        format: FORMAT.into(),
        name: info.name.clone(),
        description: info.description.clone(),
        algo: saved.algo.or(info.algo),
        solver: saved.solver,
        kind: Some(saved.policy.kind()),
        obs_mode: Some(saved.obs_mode()),
        colour_feature: Some(crate::env::COLOUR_FEATURE),
        fixtures: Some(saved.obs_mode().fixtures().to_vec()),
        task,
        multi_task,
        epoch: saved.epoch,
        env_steps: info.env_steps,
        finals_success: saved.finals_success,
        norm_clip: norm.clip(),
        norm_eps: norm.eps(),
        norm_count: norm.count(),
        actor: layout(net, norm.dim()),
        critic: critic.map(|c| layout(c, norm.dim() + crate::env::ACTION_DIM)),
        sigma_min,
        trained_with: info.trained_with.clone(),
        exported_from: info.exported_from.clone(),
        blend: saved.blend.clone(),
        started_from: saved.started_from.clone(),
        evaluations: info.evaluations.clone(),
        probes: probes(saved)?,
        tensors_sha256: crate::benchmark::provenance::sha256(&bytes),
        meta_sha256: None,
    };
    let policy_sha = saved.policy_id(&info.name).sha256;
    if let Some((k, e)) = meta.evaluations.iter().enumerate().find(|(_, e)| e.policy_sha256() != policy_sha.as_deref())
    {
        return Err(corrupt(format!(
            "evaluation {} ({} {}) was made by {}, not by this policy ({}): record only this policy's evaluations",
            k + 1,
            e.env,
            e.distribution,
            e.policy_sha256().map_or_else(|| "an unnamed policy (it records no provenance)".to_owned(), str::to_owned),
            policy_sha.as_deref().unwrap_or("unnamed")
        )));
    }
    let meta = ZooMeta { meta_sha256: Some(meta.seal()), ..meta };
    if zoo.exists() && !zoo.is_dir() {
        return Err(ZooError::NotAFolder { zoo: zoo.to_owned() });
    }
    let json = serde_json::to_vec_pretty(&meta).map_err(|e| corrupt(e.to_string()))?;
    let json_path = tensors_path.with_extension("json");
    // A folder made here goes again if the export fails (a full disk leaves nothing behind), and
    // both files are written in full before either is put in place.
    let created = crate::support::io::CreatedDir::create(zoo).map_err(io(zoo))?;
    let mut tensors_out = crate::support::io::Output::create(&tensors_path).map_err(io(&tensors_path))?;
    tensors_out.write_all(&bytes).and_then(|()| tensors_out.flush()).map_err(io(&tensors_path))?;
    let mut json_out = crate::support::io::Output::create(&json_path).map_err(io(&json_path))?;
    json_out.write_all(&json).and_then(|()| json_out.flush()).map_err(io(&json_path))?;
    tensors_out.finish().map_err(io(&tensors_path))?;
    json_out.finish().map_err(io(&json_path))?;
    created.keep();
    Ok(tensors_path)
}

/// What [`record_evaluations`] did with each evaluation.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Recorded {
    /// Added: the entry had no record of the measurement on this engine.
    Added,
    /// Replaced the record of the same measurement on the same engine.
    Replaced,
    /// Replaced a record that named no engine and had these numbers (the same success rate, and
    /// the same outcome counts where it has them), so it was this engine's.
    Confirmed,
    /// Added beside a record that names no engine and has other numbers (so it was another engine's,
    /// or another version's); that record is kept as it was.
    Disagrees,
}

/// Records `new` evaluations in the entry at `path`, in its metadata only (the
/// tensors and their checksum stay): see [`Recorded`] for each. The metadata
/// is rewritten atomically in this blockpuzzle's [`FORMAT`], sealed.
///
/// # Errors
/// The entry does not load ([`load`]) or cannot be written; an evaluation names another policy.
pub fn record_evaluations(path: &Path, new: Vec<ZooEvaluation>) -> Result<Vec<Recorded>, ZooError> {
    rewrite(path, |meta, _| {
        let mut done = Vec::new();
        for e in new {
            let unlabelled = |r: &ZooEvaluation| {
                r.provenance.is_none()
                    && (&r.env, &r.distribution, r.grey_blind, r.episodes, r.seed)
                        == (&e.env, &e.distribution, e.grey_blind, e.episodes, e.seed)
            };
            // The same numbers: the same success rate, and the same outcome counts where the record has
            // them (format 1 entries do not).
            let agrees = |r: &ZooEvaluation| {
                r.success_rate == e.success_rate && (r.outcomes.is_none() || r.outcomes == e.outcomes)
            };
            let before = meta.evaluations.len();
            meta.evaluations.retain(|r| !(unlabelled(r) && agrees(r)));
            let confirmed = meta.evaluations.len() < before;
            let what = if let Some(r) = meta.evaluations.iter_mut().find(|r| r.same_measurement(&e)) {
                *r = e;
                Recorded::Replaced
            } else {
                let disagrees = meta.evaluations.iter().any(unlabelled);
                meta.evaluations.push(e);
                match (confirmed, disagrees) {
                    (_, true) => Recorded::Disagrees,
                    (true, false) => Recorded::Confirmed,
                    (false, false) => Recorded::Added,
                }
            };
            done.push(what);
        }
        Ok(done)
    })
}

/// What `zoo upgrade` records in an entry that records none yet, beside bringing it to this format.
#[derive(Default)]
pub struct Upgrade<'a> {
    /// The algorithm that trained it (`--algo`), for entries of formats before 7.
    pub algo: Option<Trainer>,
    /// The version of the solver whose actions it learned from (`--solver`), for entries exported
    /// before policy files recorded it.
    pub solver: Option<u32>,
    /// The policy it was fine-tuned from and that policy's name and hash (`--started-from`), for
    /// entries exported before `train --init-from` recorded it.
    pub started_from: Option<(&'a SavedPolicy, crate::benchmark::provenance::PolicyId)>,
}

/// Brings the entry at `path` to this format, sealed, with `records` recorded, in one rewrite
/// ([`rewrite`]): all of them or, where one is refused, none. A record the entry already holds
/// alike is kept; one that would change what it records is refused. The start must read the entry's
/// observation through a network of the same layers (fine-tuning changes weights, not shapes).
///
/// # Errors
/// [`ZooError::Corrupt`] naming the entry and the record that does not fit (an algorithm that
/// cannot train its kind, a solver version no build had, another record), or [`rewrite`]'s.
pub fn upgrade(path: &Path, records: Upgrade<'_>) -> Result<(), ZooError> {
    let bad = |reason: String| ZooError::Corrupt { path: path.with_extension("json"), reason };
    if let Some(version) = records.solver {
        crate::benchmark::saved::check_solver(version).map_err(|e| bad(format!("--solver: {e}")))?;
    }
    rewrite(path, |meta, saved| {
        if let Some(algo) = records.algo {
            match meta.trained_by() {
                Some(a) if a != algo => {
                    return Err(bad(format!(
                        "it records {a} as the algorithm that trained it; --algo {algo} would change a record"
                    )))
                }
                _ => {
                    algo.check_trains(saved.policy.kind())
                        .map_err(|e| bad(format!("--algo {algo}: {e}; give the algorithm that trained it")))?;
                    meta.algo = Some(algo);
                }
            }
        }
        if let Some(version) = records.solver {
            match meta.solver {
                Some(v) if v != version => {
                    return Err(bad(format!(
                        "it records that it learned from solver version {v}; --solver {version} would change a record"
                    )))
                }
                _ => meta.solver = Some(version),
            }
        }
        if let Some((start, id)) = records.started_from {
            let shapes = |p: &SavedPolicy| -> Vec<(usize, usize)> {
                p.policy.net().layers.iter().map(|l| (l.n_in, l.b.len())).collect()
            };
            match &meta.started_from {
                Some(s) if s.sha256 == id.sha256 => {}
                Some(s) => {
                    return Err(bad(format!(
                        "it records that it was fine-tuned from {} ({}); --started-from {} ({}) would change a record",
                        s.name,
                        s.sha256.as_deref().unwrap_or("no hash"),
                        id.name,
                        id.sha256.as_deref().unwrap_or("no hash")
                    )))
                }
                None if start.obs_mode() != saved.obs_mode() || shapes(start) != shapes(saved) => {
                    return Err(bad(format!(
                        "--started-from {}: it reads `{}` observations through layers {:?}, and this entry `{}` \
                         through {:?}; a policy is fine-tuned from one of its own network, give that one",
                        id.name,
                        start.obs_mode(),
                        shapes(start),
                        saved.obs_mode(),
                        shapes(saved)
                    )))
                }
                None => meta.started_from = Some(id),
            }
        }
        Ok(())
    })
}

/// The one rewrite of an entry's metadata: it loads first (an edited entry is neither rewritten
/// nor sealed), an older format is brought to this one (its kind and observation recorded, its
/// algorithm [`UNRECORDED`]), `edit` changes it, and it is written atomically in [`FORMAT`],
/// sealed, once every evaluation names this policy as this build names it.
fn rewrite<T>(
    path: &Path,
    edit: impl FnOnce(&mut ZooMeta, &SavedPolicy) -> Result<T, ZooError>,
) -> Result<T, ZooError> {
    let json_path = path.with_extension("json");
    let (mut meta, saved) = load(&json_path)?;
    if meta.version() < 7 {
        // What an older entry says of itself, recorded: its kind, its observation; who trained it
        // is unknown here (`zoo upgrade --algo` records it).
        meta.kind = Some(saved.policy.kind());
        meta.obs_mode = Some(saved.obs_mode());
        meta.algo = None;
    }
    meta.colour_feature = Some(crate::env::COLOUR_FEATURE);
    meta.fixtures = Some(saved.obs_mode().fixtures().to_vec());
    let out = edit(&mut meta, &saved)?;
    // A sealed entry requires every evaluation to name this policy.
    let policy_sha = saved.policy_id(&meta.name).sha256;
    if let Some(e) = meta.evaluations.iter().find(|e| e.names_another_policy(policy_sha.as_deref())) {
        return Err(ZooError::Corrupt {
            path: json_path.clone(),
            reason: format!(
                "its evaluation of {} {} names the policy {}, which this build names {}: it cannot be sealed so; \
                 remove that evaluation, or play it again with `zoo evaluate` on its engine",
                e.env,
                e.distribution,
                e.policy_sha256().unwrap_or_default(),
                policy_sha.as_deref().unwrap_or("unnamed")
            ),
        });
    }
    meta.format = FORMAT.into();
    meta.meta_sha256 = Some(meta.seal());
    let text = serde_json::to_string_pretty(&meta)
        .map_err(|e| ZooError::Corrupt { path: json_path.clone(), reason: e.to_string() })?;
    // What is written must load as every reader loads it: checked on the bytes before they are
    // written, so that the entry on disk is the old one or the new one, never one that does not load.
    parse_meta(json_path.clone(), &text).and_then(|m| check_entry(&json_path, &m)).map_err(|e| ZooError::Corrupt {
        path: json_path.clone(),
        reason: format!("the rewritten entry would not load ({e}); it is left as it was"),
    })?;
    crate::support::io::write_file(&json_path, text.as_bytes())
        .map_err(|e| ZooError::Corrupt { path: json_path.clone(), reason: crate::support::error::chain(&e) })?;
    Ok(out)
}

/// Reads an entry's metadata (`X.json`, or the one beside `X.safetensors`).
///
/// # Errors
/// A missing or malformed file.
pub fn read_meta(path: &Path) -> Result<ZooMeta, ZooError> {
    let json_path = path.with_extension("json");
    let text = crate::support::io::read_text(&json_path, "zoo entry", crate::support::limits::RESULT_FILE_BYTES)
        .map_err(io(&json_path))?;
    parse_meta(json_path, &text)
}

/// An entry's metadata from the text of its JSON file `json_path`, as [`read_meta`] reads it.
fn parse_meta(json_path: PathBuf, text: &str) -> Result<ZooMeta, ZooError> {
    let meta: ZooMeta = serde_json::from_str(text)
        .map_err(|e| ZooError::Corrupt { path: json_path.clone(), reason: format!("bad metadata: {e}") })?;
    if !READS.contains(&meta.format.as_str()) {
        return Err(ZooError::Corrupt {
            path: json_path,
            reason: format!(
                "format {:?}, this blockpuzzle reads {} (a newer blockpuzzle wrote it? update this one)",
                meta.format,
                READS.join(", ")
            ),
        });
    }
    if let Some((field, introduced)) = meta.newer_field() {
        return Err(ZooError::Corrupt {
            path: json_path,
            reason: format!(
                "it says format {:?}, and carries {field}, which blockpuzzle-zoo/{introduced} introduced: an entry \
                 relabelled as an older format, whose unsealed fields cannot be trusted; restore the entry, or export \
                 the policy again",
                meta.format
            ),
        });
    }
    Ok(meta)
}

/// Loads a zoo entry (`X.safetensors` or `X.json`) as a [`SavedPolicy`]: the
/// tensors must match the metadata's checksum and layout, and every value
/// must be finite and of a sane size ([`SavedPolicy::check`]).
///
/// # Errors
/// [`ZooError::Corrupt`] naming what does not fit.
pub fn load(path: &Path) -> Result<(ZooMeta, SavedPolicy), ZooError> {
    let meta = read_meta(path)?;
    let saved = check_entry(path, &meta)?;
    Ok((meta, saved))
}

/// Every check [`load`] makes of an entry whose metadata is `meta` (its JSON file beside `path`'s
/// tensor file), in order: its records (tasks, stream), its networks against the tensors, what
/// format 7 records of them, the policy as a whole and its probes, the seal, the evaluations. The
/// policy it loads is returned.
///
/// # Errors
/// [`ZooError::Corrupt`] naming what does not fit.
fn check_entry(path: &Path, meta: &ZooMeta) -> Result<SavedPolicy, ZooError> {
    check_records(path, meta)?;
    let (policy, critic) = read_networks(path, meta)?;
    if meta.version() >= 7 {
        check_recorded_kind(path, meta, &policy)?;
    }
    let saved = saved_of(meta, policy, critic);
    let corrupt = |reason: String| ZooError::Corrupt { path: path.with_extension("safetensors"), reason };
    saved.check().map_err(corrupt)?;
    check_probes(path, meta, &saved)?;
    check_seal(path, meta)?;
    check_evaluations(path, meta, &saved)?;
    Ok(saved.with_record())
}

/// A multi-task entry's label and records, and every task it records, compile; a stream draws as
/// recorded, its first task the entry's.
fn check_records(path: &Path, meta: &ZooMeta) -> Result<(), ZooError> {
    let bad_meta = |reason: String| ZooError::Corrupt { path: path.with_extension("json"), reason };
    if let Some(m) = &meta.multi_task {
        let plain = |c: char| c.is_ascii_alphanumeric() || "-_+.".contains(c);
        if m.label.is_empty() || m.label.len() > 4096 || !m.label.chars().all(plain) || m.label.starts_with('.') {
            return Err(bad_meta(format!(
                "multi_task.label {:?}: a run's label is task ids and names joined by '+' (letters, digits, '-', '_', \
                 '+', '.'); restore the entry",
                crate::support::limits::cut_long_lines(&m.label)
            )));
        }
        if m.tasks.is_empty() == m.stream.is_none() {
            return Err(bad_meta(
                "multi_task holds either its tasks or its stream, and this one holds neither or both; restore the entry"
                    .into(),
            ));
        }
    }
    for task in std::iter::once(&meta.task).chain(meta.multi_task.iter().flat_map(|m| &m.tasks)) {
        task.compile().map_err(|e| bad_meta(e.to_string()))?;
    }
    if let Some(stream) = meta.multi_task.as_ref().and_then(|m| m.stream.as_ref()) {
        // Its tasks draw as recorded, and its first is the entry's task (whose probes these are).
        let first = stream.draw().map_err(|e| bad_meta(e.to_string()))?.into_iter().next();
        if first.map(|t| t.source.hash) != Some(meta.task.hash.clone()) {
            return Err(bad_meta(format!(
                "task {} is not the first task of its stream; restore the entry",
                meta.task.id
            )));
        }
    }
    Ok(())
}

/// The actor (and critic, where kept) from the tensor file beside `path`, checked against the
/// metadata's layout and checksum.
fn read_networks(path: &Path, meta: &ZooMeta) -> Result<(AnyPolicy, Option<PlainNet>), ZooError> {
    let bad_meta = |reason: String| ZooError::Corrupt { path: path.with_extension("json"), reason };
    let tensors_path = path.with_extension("safetensors");
    let bytes =
        crate::support::io::read_bytes(&tensors_path, "zoo tensor file", crate::support::limits::POLICY_FILE_BYTES)
            .map_err(io(&tensors_path))?;
    let corrupt = |reason: String| ZooError::Corrupt { path: tensors_path.clone(), reason };
    // What the metadata says wrongly is reported against it, by field.
    let json_path = tensors_path.with_extension("json");
    let metadata = |field: &str, reason: String| ZooError::Corrupt {
        path: json_path.clone(),
        reason: format!("{field}: {reason} (the metadata was edited; restore both files of the entry together)"),
    };
    for (field, v, ok) in [
        ("norm_clip", meta.norm_clip as f64, meta.norm_clip.is_finite() && meta.norm_clip > 0.0),
        ("norm_eps", meta.norm_eps, meta.norm_eps.is_finite() && meta.norm_eps >= 0.0),
        ("sigma_min", meta.sigma_min.unwrap_or(0.0), meta.sigma_min.map_or(true, |s| s.is_finite() && s >= 0.0)),
    ] {
        if !ok {
            return Err(metadata(field, format!("{v} is not a usable value")));
        }
    }
    let outputs = if meta.sigma_min.is_some() { 2 * crate::env::ACTION_DIM } else { crate::env::ACTION_DIM };
    if meta.actor.sizes.last() != Some(&outputs) {
        return Err(metadata(
            "actor.sizes",
            format!("{:?} does not end in the actor's {outputs} outputs", meta.actor.sizes),
        ));
    }
    if crate::benchmark::provenance::sha256(&bytes) != meta.tensors_sha256 {
        return Err(corrupt(format!(
            "its checksum does not match {} (damaged, or the tensors of another entry); restore both files of the entry together",
            tensors_path.with_extension("json").display()
        )));
    }
    let st = SafeTensors::deserialize(&bytes).map_err(|e| corrupt(format!("not a safetensors file: {e}")))?;
    // `field`: the metadata that gives the shape.
    let read = |name: &str, shape: &[usize], field: &str| -> Result<Vec<f32>, ZooError> {
        let t = st.tensor(name).map_err(|e| corrupt(format!("tensor {name}: {e}")))?;
        if t.dtype() != Dtype::F32 || t.shape() != shape {
            return Err(metadata(
                field,
                format!(
                    "it gives tensor {name} the shape F32 {shape:?}, the tensor is {:?} {:?}",
                    t.dtype(),
                    t.shape()
                ),
            ));
        }
        Ok(t.data().chunks_exact(4).map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]])).collect())
    };
    let read_net = |prefix: &str, l: &NetLayout| -> Result<PlainNet, ZooError> {
        if l.sizes.len() < 2 {
            return Err(corrupt(format!("{prefix} has {} layer sizes, at least 2 needed", l.sizes.len())));
        }
        // [out, in] of each layer: an MLP's from its chained sizes, a set network's as written.
        let shapes: Vec<[usize; 2]> = match l.set {
            None => l.sizes.windows(2).map(|s| [s[1], s[0]]).collect(),
            Some(_) if l.layers.len() + 1 == l.sizes.len() => l.layers.clone(),
            Some(_) => return Err(corrupt(format!("{prefix} is a set network without the shapes of its layers"))),
        };
        let layers = shapes
            .iter()
            .enumerate()
            .map(|(i, &[out, n_in])| {
                let field = if l.set.is_some() { format!("{prefix}.layers[{i}]") } else { format!("{prefix}.sizes") };
                Ok(Dense {
                    w: read(&format!("{prefix}.{i}.weight"), &[out, n_in], &field)?,
                    b: read(&format!("{prefix}.{i}.bias"), &[out], &field)?,
                    n_in,
                })
            })
            .collect::<Result<_, ZooError>>()?;
        Ok(PlainNet { layers, tanh_out: l.tanh_out, set: l.set, hidden_norm: l.hidden_norm })
    };
    let net = read_net("actor", &meta.actor)?;
    let critic = meta.critic.as_ref().map(|l| read_net("critic", l)).transpose()?;
    let dim = meta.actor.sizes[0];
    let norm = Normalizer::from_stats(
        read("obs_norm.mean", &[dim], "actor.sizes[0]")?,
        read("obs_norm.std", &[dim], "actor.sizes[0]")?,
        meta.norm_count,
        meta.norm_eps,
        meta.norm_clip,
    );
    let out = *meta.actor.sizes.last().unwrap_or(&0);
    let policy = match (meta.kind(), meta.sigma_min) {
        (Some(PolicyKind::Deterministic), None) => AnyPolicy::Deterministic(DeterministicPolicy { net, norm }),
        (Some(PolicyKind::Gaussian), Some(sigma_min)) => {
            AnyPolicy::Pggd(PggdPolicy { net, norm, act_dim: out / 2, sigma_min })
        }
        (kind, s) => {
            let (field, value) = match kind {
                Some(k) => ("kind", k.name()),
                None if meta.version() >= 7 => ("kind", "none"),
                None => ("algo", meta.algo.map_or(UNRECORDED, Trainer::name)),
            };
            return Err(bad_meta(format!(
                "{field} {value:?} with sigma_min {s:?} is not a known policy kind (deterministic without sigma_min, \
                 gaussian with it); restore the entry"
            )));
        }
    };
    Ok((policy, critic))
}

/// Format 7's records of the policy: the algorithm that trained it, its kind, the colour feature,
/// the observation its network reads and its fixtures.
fn check_recorded_kind(path: &Path, meta: &ZooMeta, policy: &AnyPolicy) -> Result<(), ZooError> {
    let bad_meta = |reason: String| ZooError::Corrupt { path: path.with_extension("json"), reason };
    if let Some(v) = meta.solver {
        crate::benchmark::saved::check_solver(v).map_err(|e| bad_meta(format!("{e}; restore the entry")))?;
    }
    if let Some(a) = meta.trained_by() {
        a.check_trains(policy.kind()).map_err(|e| {
            bad_meta(format!("algo {:?} with kind {:?}: {e}; restore the entry", a.name(), policy.kind().name()))
        })?;
    }
    if meta.colour_feature != Some(crate::env::COLOUR_FEATURE) {
        return Err(bad_meta(format!(
            "colour_feature records {:?}, but this build's observation rows have their colour at feature {}; \
             restore the entry",
            meta.colour_feature,
            crate::env::COLOUR_FEATURE
        )));
    }
    // The recorded observation is one its network reads, with this build's fixtures.
    match meta.obs_mode {
        Some(m) if policy.reads(m) => {
            crate::benchmark::saved::check_fixtures(meta.fixtures.as_deref(), m).map_err(bad_meta)?;
        }
        recorded => {
            let reads = policy.legacy_obs_mode().map_or_else(|_| "another".to_owned(), |r| format!("the `{r}`"));
            return Err(bad_meta(format!(
                "obs_mode records {}, but its network reads {reads} observation; restore the entry",
                recorded.map_or_else(|| "nothing".to_owned(), |m| format!("`{m}`"))
            )));
        }
    }
    Ok(())
}

/// The policy an entry holds, as its run saved it: a multi-task policy with no one task, its label
/// and its tasks.
fn saved_of(meta: &ZooMeta, policy: AnyPolicy, critic: Option<PlainNet>) -> SavedPolicy {
    // A multi-task policy loads as its run saved it: no one task, its label and its tasks.
    let (env_id, task, tasks) = match &meta.multi_task {
        None => (meta.task.id.clone(), Some(meta.task.clone()), Vec::new()),
        Some(m) => (m.label.clone(), None, m.tasks.clone()),
    };
    SavedPolicy {
        env_id,
        task,
        tasks,
        stream: meta.multi_task.as_ref().and_then(|m| m.stream.clone()),
        epoch: meta.epoch,
        env_steps: meta.env_steps,
        finals_success: meta.finals_success,
        algo: meta.trained_by(),
        solver: meta.solver,
        obs_mode: meta.obs_mode,
        fixtures: meta.fixtures.clone(),
        policy,
        critic,
        blend: meta.blend.clone(),
        started_from: meta.started_from.clone(),
    }
}

/// The policy acts as the exported one did on every probe.
fn check_probes(path: &Path, meta: &ZooMeta, saved: &SavedPolicy) -> Result<(), ZooError> {
    let corrupt = |reason: String| ZooError::Corrupt { path: path.with_extension("safetensors"), reason };
    for (k, p) in meta.probes.iter().enumerate() {
        if p.obs.len() != saved.policy.obs_dim() || saved.policy.act(&p.obs) != p.action {
            return Err(corrupt(format!(
                "it does not act as the exported policy did on probe {k}: the tensors or the metadata's network \
                 (actor.tanh_out, actor.set, norm_*) were edited; restore both files of the entry together"
            )));
        }
    }
    Ok(())
}

/// The metadata as a whole is what was exported (format 6 on; older formats were written before it
/// was sealed): an edit that the other checks cannot name (a dropped multi_task, a description, an
/// epoch) is refused here.
fn check_seal(path: &Path, meta: &ZooMeta) -> Result<(), ZooError> {
    let bad_meta = |reason: String| ZooError::Corrupt { path: path.with_extension("json"), reason };
    let sealed = meta.version() >= 6;
    match &meta.meta_sha256 {
        Some(h) if !crate::support::limits::is_sha256(h) => {
            return Err(bad_meta(format!(
                "its meta_sha256 {:?} is not a content hash (sha256: and 64 hex digits): the file was damaged or \
                 written by hand; restore both files of the entry together, or export the policy again",
                crate::support::limits::cut_long_lines(h)
            )))
        }
        Some(h) if *h != meta.seal() => {
            return Err(bad_meta(
                "its metadata is not what was exported (meta_sha256 does not match: a field was edited); restore \
                 both files of the entry together, or export the policy again"
                    .into(),
            ))
        }
        None if sealed => {
            return Err(bad_meta(format!(
                "format {} records meta_sha256, and this entry has none (it was edited); restore both files of the \
                 entry together",
                meta.format
            )))
        }
        _ => {}
    }
    Ok(())
}

/// Every evaluation that names its policy names this one (in sealed entries: older ones were
/// written by builds whose policy ids this one need not reproduce), and each holds together.
fn check_evaluations(path: &Path, meta: &ZooMeta, saved: &SavedPolicy) -> Result<(), ZooError> {
    let bad_meta = |reason: String| ZooError::Corrupt { path: path.with_extension("json"), reason };
    let sealed = meta.version() >= 6;
    // Checked after the seal: an edited field changes the policy's id too, and the seal names that edit
    // for what it is.
    let policy_sha = saved.policy_id(&meta.name).sha256;
    let foreign = meta.evaluations.iter().enumerate().filter(|_| sealed);
    if let Some((k, e)) = foreign.into_iter().find(|(_, e)| e.names_another_policy(policy_sha.as_deref())) {
        return Err(bad_meta(format!(
            "evaluations[{k}] ({} {}) was made by the policy {}, not this one ({}); restore the entry, or play it \
             again with `zoo evaluate`",
            e.env,
            e.distribution,
            e.policy_sha256().unwrap_or_default(),
            policy_sha.as_deref().unwrap_or("unnamed")
        )));
    }
    for (k, e) in meta.evaluations.iter().enumerate() {
        e.check(meta).map_err(|why| {
            bad_meta(format!(
                "evaluations[{k}] ({} {}): {why}; restore the entry, or play its evaluations again with `zoo \
                 evaluate`",
                e.env, e.distribution
            ))
        })?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A rewrite whose result would not load leaves the entry's file as it was, byte for byte: it is
    /// checked before anything is written.
    #[test]
    fn a_rewrite_that_would_not_load_writes_nothing() {
        let dir = tempfile::tempdir().unwrap();
        for ext in ["json", "safetensors"] {
            std::fs::copy(super::dir().join(format!("BlocksTouch-v0-ddpg.{ext}")), dir.path().join(format!("e.{ext}")))
                .unwrap();
        }
        let json = dir.path().join("e.json");
        let before = std::fs::read(&json).unwrap();
        let e = rewrite(&json, |meta, _| {
            meta.norm_clip = -1.0;
            Ok(())
        })
        .unwrap_err()
        .to_string();
        assert!(e.contains("would not load") && e.contains("norm_clip"), "{e}");
        assert_eq!(std::fs::read(&json).unwrap(), before);
        // A rewrite that loads is written.
        rewrite(&json, |meta, _| {
            meta.description = "rewritten".into();
            Ok(())
        })
        .unwrap();
        assert_eq!(load(&json).unwrap().0.description, "rewritten");
    }
}
