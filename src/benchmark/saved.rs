//! A trained policy as a file: [`SavedPolicy`] (the actor, its normaliser,
//! the task it was trained on and, for DDPG, its critic), the JSON form runs
//! write (`policy.json`, `best_policy.json`, snapshots). The zoo's
//! safetensors form is `crate::benchmark::zoo`; a policy named on the command line
//! (file, run directory or zoo name) is resolved by `crate::benchmark::load`.

use crate::policy::actor::mlp::PlainNet;
use crate::policy::actor::{AnyPolicy, PolicyKind};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// A run directory's configuration file: its presence makes a folder a run directory.
pub const CONFIG_FILE: &str = "config.json";
/// A run's latest policy, in its run directory.
pub const POLICY_FILE: &str = "policy.json";
/// A run's policy of the best finals success, in its run directory.
pub const BEST_POLICY_FILE: &str = "best_policy.json";

/// Why a policy file cannot be used ([`read`]), naming the file.
#[derive(Debug, thiserror::Error)]
pub enum SavedError {
    /// The file cannot be read (missing, a folder, too large, not text).
    #[error("cannot read policy {} (train one with `blockpuzzle train`)", path.display())]
    Unreadable {
        /// The file.
        path: PathBuf,
        /// Why, in the OS's words or the reader's.
        #[source]
        source: std::io::Error,
    },
    /// An empty file (a write that never finished, or a file made by hand).
    #[error(
        "{} is empty: a policy file is the JSON `blockpuzzle train` writes (a run directory's policy.json or \
         snapshots/epoch-NNNN.json); give one of those, the run directory or a zoo name",
        path.display()
    )]
    Empty {
        /// The file.
        path: PathBuf,
    },
    /// The text is not a policy file's JSON.
    #[error("{} is not a blockpuzzle policy file", path.display())]
    Malformed {
        /// The file.
        path: PathBuf,
        /// Where the JSON is wrong.
        #[source]
        source: serde_json::Error,
    },
    /// The policy does not pass [`SavedPolicy::check`].
    #[error("policy {} is not usable: {reason}", path.display())]
    Unusable {
        /// The file.
        path: PathBuf,
        /// The first problem.
        reason: String,
    },
    /// Two policies that cannot be blended ([`SavedPolicy::blend`]): both named, and why.
    #[error("{0}")]
    Unblendable(String),
}

/// A saved policy: the actor, its normaliser and what it was trained on.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SavedPolicy {
    /// Environment id it was trained on.
    pub env_id: String,
    /// The task it was trained on, by content (absent in policies saved before tasks were files).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub task: Option<crate::task::TaskSource>,
    /// A policy trained on several tasks (`train --env A,B` or `--suite S`): its training tasks by
    /// content, in the run's order (`task` is then absent and `env_id` the run's label; empty for
    /// one task and in policies saved before it was recorded).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub tasks: Vec<crate::task::TaskSource>,
    /// A policy trained on a stream of generated tasks (`train --families F --generator-seeds A..B`): the
    /// stream's record, from which its tasks are drawn again ([`SavedPolicy::training_tasks`]); `tasks` is
    /// then empty (a thousand tasks by content would be megabytes).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stream: Option<crate::benchmark::stream::StreamRecord>,
    /// Epochs of training behind it.
    pub epoch: usize,
    /// Environment steps of training behind it (absent in policies saved before it was recorded).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub env_steps: Option<u64>,
    /// Its finals success when saved.
    pub finals_success: f64,
    /// The algorithm that trained it (absent in policies saved before it was recorded).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub algo: Option<Trainer>,
    /// The version of the solver whose actions it learned from ([`crate::policy::SOLVER_VERSION`] of
    /// the builds that labelled its run): BC, DAgger and runs with `--demos`. Absent for a policy that
    /// learned from rewards alone, and in files written before it was recorded.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub solver: Option<u32>,
    /// The observation it reads, as the run recorded it (absent in policies saved before it was
    /// recorded; checked against the network when the file is read).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub obs_mode: Option<crate::env::ObsMode>,
    /// The rule objects other than blocks whose rows follow the blocks' ([`crate::env::Fixture`]), in
    /// row order, as the run recorded them (absent in policies saved before it was recorded; checked
    /// against the mode's when the file is read).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fixtures: Option<Vec<crate::env::Fixture>>,
    /// The policy.
    pub policy: AnyPolicy,
    /// DDPG's critic Q(s, a) of the same epoch (input: the normalised
    /// observation, then the action), so that the policy can be an AggreVaTeD
    /// expert with `--pg-weight expert-advantage`. Absent for PGGD and in
    /// policies saved before the critic was kept.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub critic: Option<PlainNet>,
    /// A policy interpolated between two (`blockpuzzle blend`, [`SavedPolicy::blend`]): where its
    /// weights came from. Its other records are the tuned policy's.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub blend: Option<BlendRecord>,
    /// The policy a fine-tuning run started from (`train --init-from`), by name as given and hash:
    /// what [`SavedPolicy::blend`] requires of a base (absent for a run from scratch, and in
    /// policies saved before it was recorded).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub started_from: Option<crate::benchmark::provenance::PolicyId>,
}

/// The algorithm that trained a policy, as policy files and format-7 zoo entries record it (`ddpg`
/// with `--td3` is `td3`; the training registry's names are checked against these by its tests).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Trainer {
    /// Behaviour cloning of the solver.
    Bc,
    /// DAgger with the solver as expert.
    Dagger,
    /// DDPG.
    Ddpg,
    /// TD3 (`--algo ddpg --td3`).
    Td3,
    /// SAC.
    Sac,
    /// PGGD (AggreVaTeD with an expert).
    Pggd,
}

impl Trainer {
    /// Every trainer, in the order help texts list them.
    pub const ALL: [Trainer; 6] = [Self::Bc, Self::Dagger, Self::Ddpg, Self::Td3, Self::Sac, Self::Pggd];

    /// The recorded name (`bc`, `dagger`, `ddpg`, `td3`, `sac`, `pggd`).
    pub const fn name(self) -> &'static str {
        match self {
            Self::Bc => "bc",
            Self::Dagger => "dagger",
            Self::Ddpg => "ddpg",
            Self::Td3 => "td3",
            Self::Sac => "sac",
            Self::Pggd => "pggd",
        }
    }

    /// The trainer of that recorded name.
    pub fn named(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|t| t.name() == name)
    }

    /// The kind of policy it trains: PGGD a Gaussian one, every other algorithm a deterministic one.
    pub fn trains(self) -> PolicyKind {
        match self {
            Self::Pggd => PolicyKind::Gaussian,
            _ => PolicyKind::Deterministic,
        }
    }

    /// Whether it trains a policy of `kind`: the one check of a recorded algorithm against what acts,
    /// for policy files, zoo entries and `zoo upgrade --algo`.
    ///
    /// # Errors
    /// The mismatch, in words each caller completes with its fix.
    pub fn check_trains(self, kind: PolicyKind) -> Result<(), String> {
        if self.trains() == kind {
            return Ok(());
        }
        Err(format!(
            "{self} trains a {} policy, and this one is {kind} (PGGD trains gaussian policies, every other algorithm \
             deterministic ones)",
            self.trains()
        ))
    }
}

impl std::fmt::Display for Trainer {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// Where a blended policy's weights came from: (1 − `weight`)·`base` + `weight`·`tuned`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BlendRecord {
    /// The policy fine-tuned from (name as given, and hash).
    pub base: crate::benchmark::provenance::PolicyId,
    /// The fine-tuned policy.
    pub tuned: crate::benchmark::provenance::PolicyId,
    /// The tuned policy's share of each weight.
    pub weight: f64,
}

impl SavedPolicy {
    /// Whether the policy (and critic, if kept) can act: see
    /// [`AnyPolicy::check`]; the critic maps observation and action to one value.
    ///
    /// # Errors
    /// The first problem, named.
    pub fn check(&self) -> Result<(), String> {
        self.policy.check()?;
        let mode = match self.obs_mode {
            Some(m) if !self.policy.reads(m) => {
                let reads =
                    self.policy.legacy_obs_mode().map_or_else(|_| "another".to_owned(), |r| format!("the `{r}`"));
                return Err(format!(
                    "obs_mode records `{m}`, but its network reads {reads} observation (an edited file)"
                ));
            }
            Some(m) => m,
            None => self.policy.legacy_obs_mode()?,
        };
        check_fixtures(self.fixtures.as_deref(), mode)?;
        if let Some(a) = self.algo {
            a.check_trains(self.policy.kind())
                .map_err(|e| format!("algo: {e}; the file was edited, or record the algorithm that trained it"))?;
        }
        if let Some(v) = self.solver {
            check_solver(v).map_err(|e| format!("{e} (an edited file)"))?;
        }
        // Each recorded task is the task its hash names (a stream's are drawn again where they are used).
        for t in self.task.iter().chain(&self.tasks) {
            t.compile().map_err(|e| e.to_string())?;
        }
        if let Some(b) = &self.blend {
            if !(0.0..=1.0).contains(&b.weight) {
                return Err(format!("blend.weight {} is outside [0, 1] (an edited file)", b.weight));
            }
            if self.started_from.as_ref().is_some_and(|s| s.sha256 != b.base.sha256) {
                return Err(format!(
                    "blend.base records {}, and the policy was fine-tuned from {} (started_from): an edited \
                     file; blend it again with `blockpuzzle blend`",
                    b.base.sha256.as_deref().unwrap_or("no hash"),
                    self.started_from.as_ref().and_then(|s| s.sha256.as_deref()).unwrap_or("no hash")
                ));
            }
        }
        if let Some(c) = &self.critic {
            let n_in = self.policy.obs_dim() + crate::env::ACTION_DIM;
            c.check(n_in, 1, crate::policy::actor::MAX_ABS_WEIGHT).map_err(|e| format!("critic: {e}"))?;
        }
        Ok(())
    }
}

/// Whether `version` is a solver version some build of this project has had (1 to this build's).
///
/// # Errors
/// Another number, with the range.
pub fn check_solver(version: u32) -> Result<(), String> {
    let newest = crate::policy::SOLVER_VERSION;
    if (1..=newest).contains(&version) {
        return Ok(());
    }
    Err(format!("solver {version} is no solver version this build knows (1 to {newest})"))
}

/// Whether a recorded fixtures list is the one `mode` has in this build.
///
/// # Errors
/// A list that differs, both named.
pub fn check_fixtures(recorded: Option<&[crate::env::Fixture]>, mode: crate::env::ObsMode) -> Result<(), String> {
    match recorded {
        Some(f) if f != mode.fixtures() => {
            let names = |f: &[crate::env::Fixture]| f.iter().map(|x| x.name()).collect::<Vec<_>>().join(", ");
            Err(format!(
                "fixtures records [{}], but this build's `{mode}` observation has [{}] after the blocks' rows; \
                 the file was written for another layout (or edited): export it again from its run",
                names(f),
                names(mode.fixtures())
            ))
        }
        _ => Ok(()),
    }
}

impl SavedPolicy {
    /// The observation it reads: the recorded mode ([`SavedPolicy::obs_mode`] field), or for a file
    /// written before it was recorded the one its network reads ([`AnyPolicy::legacy_obs_mode`]).
    pub fn obs_mode(&self) -> crate::env::ObsMode {
        self.obs_mode.or_else(|| self.policy.legacy_obs_mode().ok()).unwrap_or_default()
    }

    /// Its record completed: the mode and fixtures of a file written before they were recorded,
    /// as [`SavedPolicy::obs_mode`] reads them, so that writing it again (`zoo export`) records them.
    pub fn with_record(mut self) -> Self {
        let mode = self.obs_mode();
        self.obs_mode = Some(mode);
        self.fixtures = Some(mode.fixtures().to_vec());
        self
    }

    /// The tasks it was trained on, by content, in the run's order: its one task, a multi-task run's
    /// tasks, or a stream's drawn again from its record (empty for policies saved before tasks were files).
    ///
    /// # Errors
    /// A stream record whose tasks do not draw as recorded ([`crate::benchmark::stream::StreamRecord::draw`]).
    pub fn training_tasks(&self) -> Result<Vec<crate::task::TaskSource>, crate::benchmark::stream::RecordError> {
        Ok(match (&self.task, &self.stream) {
            (Some(t), _) => vec![t.clone()],
            (None, Some(stream)) => stream.draw()?.into_iter().map(|t| t.source).collect(),
            (None, None) => self.tasks.clone(),
        })
    }

    /// The block slots of the observation it reads: a multi-task run shows every task in the layout
    /// of its most blocks (a stream: of the most its families can draw), so a flat or `objects`
    /// policy of several tasks reads that layout on any task; 0 for a one-task policy and a set
    /// network (each reads a task's own layout).
    ///
    /// # Errors
    /// A recorded task that no longer compiles to its hash.
    pub fn slots(&self) -> Result<usize, crate::task::TaskError> {
        if self.policy.net().set.is_some() || !self.is_multi_task() {
            return Ok(0);
        }
        let most = self.stream.as_ref().map_or(0, |s| s.max_blocks);
        let tasks = self.tasks.iter().map(|t| t.compile().map(|t| t.object_count())).collect::<Result<Vec<_>, _>>()?;
        Ok(tasks.into_iter().max().unwrap_or(0).max(most))
    }

    /// Whether it was trained on more than one task (a list, a suite split or a stream).
    pub fn is_multi_task(&self) -> bool {
        !self.tasks.is_empty() || self.stream.is_some()
    }

    /// `tuned` (named `tuned_name`) with its actor's weights interpolated towards `base`'s
    /// ([`crate::policy::actor::DeterministicPolicy::blend`]), recorded in [`SavedPolicy::blend`]: the
    /// tuned policy's task, epoch, algorithm, observation and normaliser, no critic.
    ///
    /// # Errors
    /// Either policy not deterministic (a PGGD policy), another observation, another network, a weight
    /// outside [0, 1]: the message names both sides.
    pub fn blend(
        base: (&str, &SavedPolicy),
        tuned: (&str, &SavedPolicy),
        weight: f64,
    ) -> Result<SavedPolicy, SavedError> {
        let ((base_name, b), (tuned_name, t)) = (base, tuned);
        let (AnyPolicy::Deterministic(bp), AnyPolicy::Deterministic(tp)) = (&b.policy, &t.policy) else {
            return Err(SavedError::Unblendable(format!(
                "{base_name} is a {} policy and {tuned_name} a {} one: only deterministic actors (DDPG, TD3, SAC, BC, \
                 DAgger) are blended",
                b.policy.kind(),
                t.policy.kind()
            )));
        };
        if b.obs_mode() != t.obs_mode() {
            return Err(SavedError::Unblendable(format!(
                "{base_name} reads `{}` observations and {tuned_name} `{}`: blend a policy with the one it was \
                 fine-tuned from",
                b.obs_mode(),
                t.obs_mode()
            )));
        }
        // Only a policy and the one it was fine-tuned from: unrelated policies of one network have
        // weights that mean different things, and a point between them is no trade between the two.
        let base_id = b.policy_id(base_name);
        match &t.started_from {
            Some(s) if s.sha256 == base_id.sha256 => {}
            Some(s) => {
                return Err(SavedError::Unblendable(format!(
                    "{tuned_name} was fine-tuned from {} ({}), not from {base_name} ({}): blend a policy with the one \
                     it was fine-tuned from (--base {})",
                    s.name,
                    s.sha256.as_deref().unwrap_or("no hash"),
                    base_id.sha256.as_deref().unwrap_or("no hash"),
                    s.name
                )))
            }
            None => {
                return Err(SavedError::Unblendable(format!(
                    "{tuned_name} records no policy it was fine-tuned from (a run from scratch, or a file saved before \
                     it was recorded): blend a policy of `train --init-from POLICY` with POLICY"
                )))
            }
        }
        let policy =
            tp.blend(bp, weight).map_err(|e| SavedError::Unblendable(format!("{base_name} and {tuned_name}: {e}")))?;
        Ok(SavedPolicy {
            policy: AnyPolicy::Deterministic(policy),
            critic: None,
            blend: Some(BlendRecord { base: base_id, tuned: t.policy_id(tuned_name), weight }),
            ..t.clone()
        })
    }

    /// The policy as results name it: `name` as the user gave it and the
    /// `sha256:` of what acts ([`AnyPolicy::canonical`]) with the task it was
    /// trained on (its content hash; a multi-task policy's tasks' hashes joined by `+`;
    /// the environment id for policies saved before tasks were files).
    pub fn policy_id(&self, name: &str) -> crate::benchmark::provenance::PolicyId {
        let task = match (&self.task, &self.tasks[..], &self.stream) {
            (Some(t), _, _) => t.hash.clone(),
            // A stream's tasks are named as a list of the same tasks would be.
            (None, _, Some(s)) => s.tasks.iter().map(|t| t.hash.as_str()).collect::<Vec<_>>().join("+"),
            (None, [], None) => self.env_id.clone(),
            (None, all, None) => all.iter().map(|t| t.hash.as_str()).collect::<Vec<_>>().join("+"),
        };
        let text = format!("{}\ntask {task}", self.policy.canonical());
        crate::benchmark::provenance::PolicyId {
            name: name.to_owned(),
            sha256: Some(crate::benchmark::provenance::sha256(text.as_bytes())),
        }
    }
}

/// Reads a policy file written by a run (JSON), checked ([`SavedPolicy::check`]).
///
/// # Errors
/// A missing, malformed or damaged file, named.
pub fn read(file: &Path) -> Result<SavedPolicy, SavedError> {
    let path = || file.to_owned();
    let text = crate::support::io::read_text(file, "policy file", crate::support::limits::POLICY_FILE_BYTES)
        .map_err(|source| SavedError::Unreadable { path: path(), source })?;
    if text.trim().is_empty() {
        return Err(SavedError::Empty { path: path() });
    }
    let saved: SavedPolicy =
        serde_json::from_str(&text).map_err(|source| SavedError::Malformed { path: path(), source })?;
    saved.check().map_err(|reason| SavedError::Unusable { path: path(), reason })?;
    Ok(saved.with_record())
}
