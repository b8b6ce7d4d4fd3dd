//! Evaluating a trained policy: success rate over seeded episodes with a
//! Wilson 95% interval, episodes spread over the threads of a
//! [`VectorEnv`] (each episode's seed fixes it, so the result does not
//! depend on the thread count).

use crate::benchmark::provenance::{Harness, PolicyId, Provenance};
use crate::benchmark::saved::SavedPolicy;
use crate::benchmark::suite::SuiteError;
use crate::env::vector::VectorEnv;
use crate::env::EnvError;
use crate::env::{BlockEnv, EnvConfig, ObsMode, ACTION_DIM};
use crate::episode::outcome::wilson95;
use crate::episode::outcome::{Outcome, Outcomes};
use crate::episode::rollout::run_episode;
use crate::episode::rollout::RolloutError;
use crate::policy::actor::{obs_dim_without_grey, without_grey, AnyPolicy};
use crate::policy::{ObsHashPolicy, Policy, ScriptedPolicy};
use crate::task::Task;
use crate::task::TaskError;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// The first seed of the test episodes (episode k uses seed + k): the default of
/// `eval`, `table` and `render --policy`, and the seed of zoo evaluations.
/// Validation (model selection) uses other seeds, e.g. 2,000,000 onwards.
pub const TEST_SEED: u64 = 1_000_000;

/// Why an evaluation could not be made.
#[derive(Debug, thiserror::Error)]
pub enum EvalError {
    /// The environment could not be made or set as asked (an unknown level, no challenge distribution).
    #[error(transparent)]
    Env(#[from] EnvError),
    /// The policy does not fit the environment's observation (what it reads, what the environment shows).
    #[error("{0}")]
    Misfit(String),
    /// The episodes or their seeds are beyond `eval`'s bounds.
    #[error("{0}")]
    Bounds(String),
    /// A recorded training task of the policy no longer compiles.
    #[error(transparent)]
    Task(#[from] TaskError),
    /// The suite's pinned rows are not what its file says.
    #[error(transparent)]
    Suite(#[from] SuiteError),
    /// An episode failed in the simulator.
    #[error("episode seed {seed}")]
    Episode {
        /// Its seed.
        seed: u64,
        /// What failed.
        #[source]
        source: RolloutError,
    },
    /// The caller's `on_row` stopped a suite's evaluation (its error, as it gave it).
    #[error(transparent)]
    Stopped(Stop),
}

/// The error with which a suite's `on_row` stops the evaluation ([`evaluate_suite`]), returned as
/// [`EvalError::Stopped`].
pub type Stop = Box<dyn std::error::Error + Send + Sync>;

/// What hears of each row of a suite as it is done ([`evaluate_suite`]): the split's name, the row,
/// rows done and rows in all; its error stops the evaluation there.
pub type OnRow<'a> = dyn FnMut(&str, &RowResult, usize, usize) -> Result<(), Stop> + 'a;

/// This module's results.
type Result<T, E = EvalError> = std::result::Result<T, E>;

/// A trained policy as a [`Policy`]. A policy trained without the grey
/// block (BlocksTouch) acting in an environment with one sees it removed
/// from its observation: the paper's "DDPG (2 blocks)" row.
#[derive(Debug, Clone)]
pub struct Trained {
    policy: AnyPolicy,
    grey_blind: bool,
}

impl Trained {
    /// Whether the policy sees the observation with grey blocks removed.
    pub fn grey_blind(&self) -> bool {
        self.grey_blind
    }
}

impl Policy for Trained {
    fn act(&mut self, obs: &[f32]) -> [f32; ACTION_DIM] {
        if self.grey_blind {
            Policy::act(&mut self.policy, &without_grey(obs))
        } else {
            Policy::act(&mut self.policy, obs)
        }
    }
}

/// A policy that needs no training, evaluated as a reference point.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
pub enum Baseline {
    /// The solver: the scripted controllers, choosing what to do from the `entities`
    /// observation alone ([`ScriptedPolicy::solver`]).
    Scripted,
    /// Pseudo-random actions from a hash of the observation ([`ObsHashPolicy`]), the same in Python.
    ObsHash,
}

impl Baseline {
    /// Every baseline.
    pub const ALL: [Baseline; 2] = [Baseline::Scripted, Baseline::ObsHash];

    /// The baseline called `name` (`scripted`, `obs-hash`), if any.
    pub fn named(name: &str) -> Option<Baseline> {
        Self::ALL.into_iter().find(|b| b.name() == name)
    }

    /// Its policy in `env` (the one suites evaluate).
    pub fn policy(self, env: &BlockEnv) -> Box<dyn Policy> {
        Box::new(Actor::baseline(self, env))
    }

    /// Its name in outputs: `scripted`, `obs-hash`.
    pub fn name(self) -> &'static str {
        match self {
            Baseline::Scripted => "scripted",
            Baseline::ObsHash => "obs-hash",
        }
    }
}

/// What is evaluated: a saved policy (with where it was loaded from), or a baseline.
#[derive(Debug, Clone, Copy)]
pub enum Subject<'a> {
    /// A trained policy.
    Saved(&'a Path, &'a SavedPolicy),
    /// A policy that needs no training.
    Baseline(Baseline),
}

impl Subject<'_> {
    /// How results name it: a saved policy by the name it was given and its
    /// content hash, a baseline as `baseline:NAME`.
    pub fn id(&self) -> PolicyId {
        match self {
            Subject::Saved(path, saved) => saved.policy_id(&path.display().to_string()),
            Subject::Baseline(b) => PolicyId { name: format!("baseline:{}", b.name()), sha256: None },
        }
    }

    /// The observation it reads: a saved policy's; the solver's `entities` one (the scripted
    /// baseline), the flat one (`obs-hash`).
    pub fn obs_mode(&self) -> ObsMode {
        match self {
            Subject::Saved(_, saved) => saved.obs_mode(),
            Subject::Baseline(Baseline::Scripted) => ObsMode::Entities,
            Subject::Baseline(Baseline::ObsHash) => ObsMode::Flat,
        }
    }

    /// The block slots the environment shows: a multi-task flat policy's training layout
    /// ([`SavedPolicy::slots`]), else 0 (each task's own).
    ///
    /// # Errors
    /// A recorded training task that no longer compiles.
    pub fn slots(&self) -> Result<usize> {
        Ok(match self {
            Subject::Saved(_, saved) => saved.slots()?,
            Subject::Baseline(_) => 0,
        })
    }
}

/// What acts in the episodes of one evaluation (one per evaluation: its size does not matter).
#[derive(Debug, Clone)]
#[allow(clippy::large_enum_variant)]
enum Actor {
    Trained(Trained),
    Scripted(ScriptedPolicy),
    ObsHash,
}

impl Actor {
    /// `subject` acting in `env`: a trained policy fitted to its observation, or a baseline made for it.
    fn fit(subject: Subject, env: &BlockEnv) -> Result<Actor> {
        Ok(match subject {
            Subject::Saved(path, saved) => Actor::Trained(trained_policy(path, saved.clone(), env)?),
            Subject::Baseline(b) => Actor::baseline(b, env),
        })
    }

    /// The baseline `b` made for `env`.
    fn baseline(b: Baseline, env: &BlockEnv) -> Actor {
        match b {
            Baseline::Scripted => Actor::Scripted(ScriptedPolicy::solver(env.obs_spec().max_objects)),
            Baseline::ObsHash => Actor::ObsHash,
        }
    }

    fn grey_blind(&self) -> bool {
        matches!(self, Actor::Trained(t) if t.grey_blind())
    }
}

impl Policy for Actor {
    fn reset(&mut self) {
        match self {
            Actor::Trained(p) => p.reset(),
            Actor::Scripted(p) => p.reset(),
            Actor::ObsHash => {}
        }
    }
    fn act(&mut self, obs: &[f32]) -> [f32; ACTION_DIM] {
        match self {
            Actor::Trained(p) => p.act(obs),
            Actor::Scripted(p) => p.act(obs),
            Actor::ObsHash => ObsHashPolicy::action(obs),
        }
    }
    fn reads(&self) -> Option<ObsMode> {
        match self {
            Actor::Trained(p) => p.reads(),
            Actor::Scripted(p) => p.reads(),
            Actor::ObsHash => None,
        }
    }
}

/// Fits `saved` (loaded from `path`) to `env`'s observations, directly or
/// with grey blocks removed.
///
/// # Errors
/// The observation sizes fit neither way.
pub fn trained_policy(path: &Path, saved: SavedPolicy, env: &BlockEnv) -> Result<Trained> {
    let spec = env.obs_spec();
    if let Some(layout) = saved.policy.net().set {
        // A set network plays any number of objects with the same row features.
        if !spec.mode.is_set() || (spec.robot_dim(), spec.object_dim()) != (layout.robot, layout.object) {
            return Err(EvalError::Misfit(format!(
                "policy {} is a set network over `{}` observations ({} robot and {} row features); {} \
                 gives `{}` observations with {} and {} (give the environment obs_mode {})",
                path.display(),
                saved.obs_mode(),
                layout.robot,
                layout.object,
                env.id(),
                spec.mode,
                spec.robot_dim(),
                spec.object_dim(),
                saved.obs_mode()
            )));
        }
        return Ok(Trained { policy: saved.policy.with_slots(spec.rows()), grey_blind: false });
    }
    let dim = env.observation_space().dim();
    let wanted = saved.policy.obs_dim();
    if wanted == dim {
        return Ok(Trained { policy: saved.policy, grey_blind: false });
    }
    if saved.is_multi_task() {
        // It reads its training tasks' layout (the environment shows it: `SavedPolicy::slots`).
        let slots = saved.slots()?;
        return Err(EvalError::Misfit(format!(
            "policy {} was trained on several tasks and reads their layout, {slots} block slots \
             ({wanted}-dimensional `{}` observations); {} has {} blocks ({dim}): a flat network plays no task \
             with more blocks than its training tasks had (a set network, `--net set`, plays any number)",
            path.display(),
            saved.obs_mode(),
            env.id(),
            env.config().task.object_count()
        )));
    }
    let blind = obs_dim_without_grey(&env.config().blocks());
    // Without grey blocks the view keeps every other block, so its size is fixed only where
    // no object of another colour comes in a varying number.
    let task = &env.config().task;
    let fixed = task.count_groups().iter().all(|g| task.colours()[g.first] == crate::sim::rules::Colour::Grey);
    if wanted == blind && fixed {
        return Ok(Trained { policy: saved.policy, grey_blind: true });
    }
    Err(EvalError::Misfit(format!(
        "policy {} expects {wanted}-dimensional observations ({}), {} has {dim} ({blind} without grey blocks)",
        path.display(),
        saved.env_id,
        env.id()
    )))
}

/// An evaluation's outcome.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Evaluation {
    /// Environment id.
    pub env: String,
    /// The task's content hash (`sha256:`).
    pub task_sha256: String,
    /// Challenge distribution.
    pub challenge: bool,
    /// Curriculum level.
    pub level: usize,
    /// Episodes played.
    pub episodes: usize,
    /// Seed of the first episode (episode k: seed + k).
    pub seed: u64,
    /// Successful episodes.
    pub successes: usize,
    /// successes / episodes.
    pub success_rate: f64,
    /// Wilson 95% interval.
    pub ci95: (f64, f64),
    /// Whether the policy saw the observation without grey blocks.
    pub grey_blind: bool,
    /// Episodes per outcome: what the unsuccessful ones did ([`crate::episode::outcome`]).
    pub outcomes: Outcomes,
    /// Mean episode length of the successful episodes (None without one).
    pub mean_steps_to_success: Option<f64>,
}

/// What to evaluate on.
#[derive(Debug, Clone)]
pub struct EvalSpec<'a> {
    /// The task.
    pub task: &'a Task,
    /// Challenge distribution (BlocksChoose-v0).
    pub challenge: bool,
    /// A named distribution of the task (None: the curriculum's, or the challenge one with `challenge`).
    pub distribution: Option<&'a str>,
    /// Curriculum level (None: the maximum).
    pub level: Option<usize>,
    /// Episodes.
    pub episodes: usize,
    /// Seed of the first episode.
    pub seed: u64,
    /// Threads, each with its own environment.
    pub threads: usize,
}

/// The environment of `spec`, its observation presented as `obs_mode` (the policy's) with at least
/// `slots` block slots ([`EnvConfig::slots`]).
pub(crate) fn make_env(spec: &EvalSpec, obs_mode: ObsMode, slots: usize) -> Result<BlockEnv, EnvError> {
    let mut env = BlockEnv::new(EnvConfig { obs_mode, slots, ..EnvConfig::new(spec.task.clone()) })?;
    if spec.challenge {
        env.set_challenge(true)?;
    }
    if spec.distribution.is_some() {
        env.set_distribution(spec.distribution)?;
    }
    env.set_level(spec.level.unwrap_or(env.max_level()))?;
    Ok(env)
}

/// Plays `spec.episodes` deterministic episodes of the policy in `saved`.
///
/// # Errors
/// Unknown environment, bad level or challenge flag, a policy that does not
/// fit the environment, environment failures.
pub fn evaluate(path: &Path, saved: SavedPolicy, spec: &EvalSpec) -> Result<Evaluation> {
    evaluate_subject(Subject::Saved(path, &saved), spec)
}

/// Plays `spec.episodes` deterministic episodes of `subject`: a saved policy or a baseline.
///
/// # Errors
/// As [`evaluate`].
pub fn evaluate_subject(subject: Subject, spec: &EvalSpec) -> Result<Evaluation> {
    let env = make_env(spec, subject.obs_mode(), subject.slots()?)?;
    let policy = Actor::fit(subject, &env)?;
    play(spec, env, policy)
}

/// Plays `spec.episodes` episodes of `policy`, which fits `env` (made by
/// [`make_env`] from `spec`; it becomes the first of the threads' environments).
fn play(spec: &EvalSpec, env: BlockEnv, policy: Actor) -> Result<Evaluation> {
    crate::support::limits::EVAL_EPISODES.check_usize(spec.episodes).map_err(EvalError::Bounds)?;
    crate::support::limits::seed_range(spec.seed, spec.episodes as u64).map_err(EvalError::Bounds)?;
    // One environment per thread; environment t plays episodes t, t + threads, …. (A machine's
    // core count, the CLI's default, may pass the vector engine's thread bound: use the bound.)
    let threads = spec.threads.clamp(1, spec.episodes).min(crate::support::limits::THREADS.max as usize);
    let (mode, slots) = (env.obs_spec().mode, env.config().slots);
    let more = (1..threads).map(|_| make_env(spec, mode, slots));
    let mut envs = VectorEnv::from_envs(std::iter::once(Ok(env)).chain(more).collect::<Result<_, _>>()?, threads)?;
    // On a terminal only (indicatif draws nothing elsewhere).
    let bar = crate::support::progress::bar(spec.episodes as u64, "episode");
    // Each thread's outcome counts and the summed length of its successful episodes.
    let tallies: Vec<Result<(Outcomes, usize)>> = envs.each(|t, env| {
        let mut policy = policy.clone();
        let (mut tally, mut success_steps) = (Outcomes::default(), 0);
        for k in (t..spec.episodes).step_by(threads) {
            let seed = spec.seed + k as u64;
            let ep = run_episode(env, &mut policy, seed).map_err(|source| EvalError::Episode { seed, source })?;
            let outcome = Outcome::of(&ep);
            if outcome == Outcome::Success {
                success_steps += ep.steps.len();
            }
            tally.add(outcome);
            bar.inc(1);
        }
        Ok((tally, success_steps))
    });
    bar.finish_and_clear();
    let (outcomes, success_steps) = tallies
        .into_iter()
        .try_fold((Outcomes::default(), 0), |(all, steps), t| t.map(|(t, s)| (all.merge(t), steps + s)))?;
    let successes = outcomes.success;
    Ok(Evaluation {
        env: spec.task.id().to_owned(),
        task_sha256: spec.task.source.hash.clone(),
        challenge: spec.challenge,
        level: envs.envs()[0].level(),
        episodes: spec.episodes,
        seed: spec.seed,
        successes,
        success_rate: successes as f64 / spec.episodes as f64,
        ci95: wilson95(successes, spec.episodes),
        grey_blind: policy.grey_blind(),
        outcomes,
        mean_steps_to_success: (successes > 0).then(|| success_steps as f64 / successes as f64),
    })
}

/// One row of a suite evaluated, or why it was skipped.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct RowResult {
    /// Task id.
    pub task: String,
    /// The compiled task's content hash (`sha256:`; [`crate::task::TaskSource::hash`]):
    /// an edited task file changes it even where the suite's text stays the same.
    pub task_sha256: String,
    /// "normal" or the distribution's name.
    pub distribution: String,
    /// First seed.
    pub seed: u64,
    /// Episodes.
    pub episodes: usize,
    /// The evaluation (None: skipped).
    pub evaluation: Option<Evaluation>,
    /// Share of episodes that failed by red touching blue.
    pub failure_rate: Option<f64>,
    /// Why the row was skipped (e.g. the policy's observation does not fit the task).
    pub skipped: Option<String>,
}

/// A split's rows and their mean success.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct SplitResult {
    /// `train`, `test`, or another name.
    pub name: String,
    /// Its rows.
    pub rows: Vec<RowResult>,
    /// Mean success rate over the rows evaluated (None: all skipped).
    pub mean_success: Option<f64>,
}

/// A policy on a suite (docs/suites.md defines the scores).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct SuiteResult {
    /// What made it.
    pub provenance: Provenance,
    /// The suite's name and the SHA-256 of its text.
    pub suite: crate::benchmark::suite::SuiteId,
    /// What it measures.
    pub summary: String,
    /// The policy as given (a baseline: `baseline:NAME`).
    pub policy: String,
    /// Its epoch of training (none for a baseline).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub policy_epoch: Option<usize>,
    /// The task it was trained on (none for a baseline).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub policy_task: Option<String>,
    /// The env steps its training had taken when it was saved, as its file records them (none for
    /// a baseline, a policy file that does not record them, and results written before this field):
    /// the x of `plot --curve`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub policy_env_steps: Option<u64>,
    /// Per split.
    pub splits: Vec<SplitResult>,
    /// The suite's score: the test split's mean success (a validation suite's: the validation split's).
    pub score: Option<f64>,
    /// The generalisation gap: train's mean success − test's (validation's).
    pub gap: Option<f64>,
}

/// Evaluates the policy in `saved` (loaded from `path`) on every row of
/// `suite`; a row whose observation the policy cannot take (directly or
/// with grey blocks removed) is skipped with the reason. `on_row` hears of
/// each row as it is done (split name, the row, rows done, rows in all): a
/// progress display; its error stops the evaluation there.
///
/// # Errors
/// Environment failures (a row whose environment cannot be made is one), or
/// `on_row`'s error.
pub fn evaluate_suite(
    subject: Subject,
    suite: &crate::benchmark::suite::Suite,
    threads: usize,
    harness: Harness,
    on_row: &mut OnRow,
) -> Result<SuiteResult> {
    suite.check_pinned(None, threads)?;
    let total: usize = suite.splits.iter().map(|s| s.rows.len()).sum();
    let mut done = 0;
    let mut splits = Vec::new();
    for split in &suite.splits {
        let mut rows = Vec::new();
        for row in &split.rows {
            let spec = EvalSpec {
                task: &row.task,
                challenge: false,
                distribution: row.distribution.as_deref(),
                level: row.level,
                episodes: row.episodes,
                seed: row.seed,
                threads,
            };
            // An environment error fails the suite; only a policy that does not fit skips the row.
            let env = make_env(&spec, subject.obs_mode(), subject.slots()?)?;
            let (evaluation, skipped) = match Actor::fit(subject, &env) {
                Err(e) => (None, Some(crate::support::error::chain(&e))),
                Ok(policy) => (Some(play(&spec, env, policy)?), None),
            };
            rows.push(RowResult {
                task: row.task.id().to_owned(),
                task_sha256: row.task.source.hash.clone(),
                distribution: row.distribution_label().to_owned(),
                seed: row.seed,
                episodes: row.episodes,
                failure_rate: evaluation.as_ref().map(|e| e.outcomes.failure as f64 / e.episodes as f64),
                evaluation,
                skipped,
            });
            done += 1;
            on_row(&split.name, rows.last().expect("a row was just pushed"), done, total)
                .map_err(EvalError::Stopped)?;
        }
        let mean_success = SplitResult::mean_of(&rows);
        splits.push(SplitResult { name: split.name.clone(), rows, mean_success });
    }
    let (score, gap) = SuiteResult::score_and_gap(&splits);
    Ok(SuiteResult {
        provenance: Provenance::new(harness, subject.id(), Some(suite.id())),
        suite: suite.id(),
        summary: suite.summary.clone(),
        policy: match subject {
            Subject::Saved(path, _) => path.display().to_string(),
            Subject::Baseline(b) => format!("baseline:{}", b.name()),
        },
        policy_epoch: match subject {
            Subject::Saved(_, saved) => Some(saved.epoch),
            Subject::Baseline(_) => None,
        },
        policy_task: match subject {
            Subject::Saved(_, saved) => Some(saved.env_id.clone()),
            Subject::Baseline(_) => None,
        },
        policy_env_steps: match subject {
            Subject::Saved(_, saved) => saved.env_steps,
            Subject::Baseline(_) => None,
        },
        splits,
        score,
        gap,
    })
}

impl SplitResult {
    /// The mean success rate over the rows evaluated (None: all skipped).
    pub fn mean_of(rows: &[RowResult]) -> Option<f64> {
        let rates: Vec<f64> = rows.iter().filter_map(|r| r.evaluation.as_ref().map(|e| e.success_rate)).collect();
        (!rates.is_empty()).then(|| rates.iter().sum::<f64>() / rates.len() as f64)
    }
}

/// A suite result whose numbers do not hold together ([`SuiteResult::verify`]): the field and what is
/// wrong with it.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{field}: {problem}")]
pub struct BadResult {
    /// Where, e.g. `splits[test].rows[2] (ReachAvoid-v0 normal).evaluation.success_rate`.
    pub field: String,
    /// What is wrong.
    pub problem: String,
}

use crate::episode::outcome::same_number;

/// The split a result of these splits is scored on (the suite's kind, from the splits it has).
fn scored_split_of(splits: &[SplitResult]) -> &'static str {
    crate::benchmark::suite::SuiteKind::of(|n| splits.iter().any(|s| s.name == n)).scored_split()
}

impl SuiteResult {
    /// The score and the gap of `splits` (docs/suites.md): the test split's mean success (a validation
    /// suite's: the validation split's), and the train split's mean minus that.
    pub fn score_and_gap(splits: &[SplitResult]) -> (Option<f64>, Option<f64>) {
        let mean = |name: &str| splits.iter().find(|s| s.name == name).and_then(|s| s.mean_success);
        let (train, test) = (mean("train"), mean(scored_split_of(splits)));
        (test, train.zip(test).map(|(a, b)| a - b))
    }

    /// The split the score is read from: `test`, or a validation suite's `validation`.
    pub fn scored_split(&self) -> &'static str {
        scored_split_of(&self.splits)
    }

    /// The train split's mean success (None when none of its rows was evaluated).
    pub fn train_mean(&self) -> Option<f64> {
        self.splits.iter().find(|s| s.name == "train").and_then(|s| s.mean_success)
    }

    /// Rows evaluated and rows in all.
    pub fn coverage(&self) -> (usize, usize) {
        self.splits
            .iter()
            .flat_map(|s| &s.rows)
            .fold((0, 0), |(d, a), row| (d + usize::from(row.evaluation.is_some()), a + 1))
    }

    /// Recomputes every derived number from the rows' outcome counts and compares it with the stored one:
    /// each row's successes, rate, interval and red–blue failure share, each split's mean, the score and
    /// the gap; the episode counts must agree with the row and lie within `eval`'s bounds, the suite must
    /// have its train and test splits, and a skipped row must say why. Nothing a reader shows is taken on
    /// trust (`results leaderboard`, `results compare`).
    ///
    /// # Errors
    /// The first field whose stored value is not the one its counts give, or that no evaluation could
    /// have written.
    pub fn verify(&self) -> Result<(), BadResult> {
        let bad = |field: String, problem: String| Err(BadResult { field, problem });
        let differs = |field: String, stored: String, derived: String| {
            bad(field, format!("stored {stored}, but its outcome counts give {derived}"))
        };
        let scored = self.scored_split();
        for required in ["train", scored] {
            if !self.splits.iter().any(|s| s.name == required && !s.rows.is_empty()) {
                return bad(
                    "splits".into(),
                    format!(
                        "no {required} split with rows; every suite has one (a validation suite: train and validation)"
                    ),
                );
            }
        }
        for (k, split) in self.splits.iter().enumerate() {
            if self.splits[..k].iter().any(|s| s.name == split.name) {
                return bad(format!("splits[{}]", split.name), "a split named twice".into());
            }
            for (i, row) in split.rows.iter().enumerate() {
                let at = |field: &str| {
                    format!("splits[{}].rows[{i}] ({} {}){field}", split.name, row.task, row.distribution)
                };
                let most = crate::support::limits::EVAL_EPISODES.max as usize;
                if row.episodes == 0 || row.episodes > most {
                    return bad(at(".episodes"), format!("{} is not an evaluation's (1 to {most})", row.episodes));
                }
                let Some(e) = &row.evaluation else {
                    if row.skipped.as_deref().map_or(true, |r| r.trim().is_empty()) {
                        return bad(at(".skipped"), "a row without an evaluation must say why it was skipped".into());
                    }
                    if row.failure_rate.is_some() {
                        return bad(at(".failure_rate"), "a skipped row has no failure rate".into());
                    }
                    continue;
                };
                if row.skipped.is_some() {
                    return bad(at(".skipped"), "a row with an evaluation was not skipped".into());
                }
                for (field, stored, wanted) in [
                    (".evaluation.episodes", e.episodes.to_string(), row.episodes.to_string()),
                    (".evaluation.seed", e.seed.to_string(), row.seed.to_string()),
                    (".evaluation.env", e.env.clone(), row.task.clone()),
                    (".evaluation.task_sha256", e.task_sha256.clone(), row.task_sha256.clone()),
                    (".evaluation.outcomes (their sum)", e.outcomes.total().to_string(), row.episodes.to_string()),
                    (".evaluation.successes", e.successes.to_string(), e.outcomes.success.to_string()),
                ] {
                    if stored != wanted {
                        return bad(at(field), format!("{stored}, but the row says {wanted}"));
                    }
                }
                let n = e.episodes as f64;
                let rate = e.successes as f64 / n;
                if !same_number(e.success_rate, rate) {
                    return differs(at(".evaluation.success_rate"), e.success_rate.to_string(), rate.to_string());
                }
                let ci = crate::episode::outcome::wilson95(e.successes, e.episodes);
                if !same_number(e.ci95.0, ci.0) || !same_number(e.ci95.1, ci.1) {
                    return differs(at(".evaluation.ci95"), format!("{:?}", e.ci95), format!("{ci:?}"));
                }
                let failure = e.outcomes.failure as f64 / n;
                if !row.failure_rate.is_some_and(|f| same_number(f, failure)) {
                    return differs(at(".failure_rate"), format!("{:?}", row.failure_rate), failure.to_string());
                }
                match e.mean_steps_to_success {
                    None if e.successes > 0 => {
                        return bad(at(".evaluation.mean_steps_to_success"), "missing beside successes".into())
                    }
                    Some(v) if e.successes == 0 || !(v.is_finite() && v >= 1.0) => {
                        return bad(
                            at(".evaluation.mean_steps_to_success"),
                            format!("{v} is not a mean episode length of {} successes", e.successes),
                        )
                    }
                    _ => {}
                }
            }
            let mean = SplitResult::mean_of(&split.rows);
            if mean.is_some() != split.mean_success.is_some()
                || mean.zip(split.mean_success).is_some_and(|(m, s)| !same_number(s, m))
            {
                let show = |v: Option<f64>| v.map_or_else(|| "none".to_owned(), |v| v.to_string());
                return differs(format!("splits[{}].mean_success", split.name), show(split.mean_success), show(mean));
            }
        }
        let (score, gap) = Self::score_and_gap(&self.splits);
        for (field, stored, derived) in [("score", self.score, score), ("gap", self.gap, gap)] {
            let agree = match (stored, derived) {
                (Some(s), Some(d)) => same_number(s, d),
                (None, None) => true,
                _ => false,
            };
            if !agree {
                let show = |v: Option<f64>| v.map_or_else(|| "none".to_owned(), |v| v.to_string());
                return differs(field.into(), show(stored), show(derived));
            }
        }
        Ok(())
    }

    /// Whether the rows are the suite's own, split for split and in order (task, distribution, seed and
    /// episodes), where the suite is at hand with the same text: no row dropped, added or reseeded.
    ///
    /// # Errors
    /// The first row or split that differs.
    pub fn verify_rows(&self, suite: &crate::benchmark::suite::Suite) -> Result<(), BadResult> {
        let bad = |field: String, problem: String| Err(BadResult { field, problem });
        let names = |v: Vec<&str>| v.join(", ");
        let (ours, theirs): (Vec<&str>, Vec<&str>) = (
            self.splits.iter().map(|s| s.name.as_str()).collect(),
            suite.splits.iter().map(|s| s.name.as_str()).collect(),
        );
        if ours != theirs {
            return bad(
                "splits".into(),
                format!("{}, but the suite {} has {}", names(ours), suite.name, names(theirs)),
            );
        }
        for (split, wanted) in self.splits.iter().zip(&suite.splits) {
            if split.rows.len() != wanted.rows.len() {
                return bad(
                    format!("splits[{}].rows", split.name),
                    format!(
                        "{} rows, but the suite {}'s split has {}",
                        split.rows.len(),
                        suite.name,
                        wanted.rows.len()
                    ),
                );
            }
            for (i, (row, w)) in split.rows.iter().zip(&wanted.rows).enumerate() {
                let (a, b) = (
                    (row.task.as_str(), row.distribution.as_str(), row.seed, row.episodes),
                    (w.task.id(), w.distribution_label(), w.seed, w.episodes),
                );
                if a != b {
                    return bad(
                        format!("splits[{}].rows[{i}]", split.name),
                        format!(
                            "{} {} ({} episodes from seed {}), but the suite's row is {} {} ({} episodes from seed {})",
                            a.0, a.1, a.3, a.2, b.0, b.1, b.3, b.2
                        ),
                    );
                }
            }
        }
        Ok(())
    }
    /// The result as a Markdown section: a table per split, the score and the gap.
    pub fn to_markdown(&self) -> String {
        let pct = |v: Option<f64>| v.map_or_else(|| "–".to_owned(), |v| format!("{v:.3}"));
        let trained = match (&self.policy_task, self.policy_epoch) {
            (Some(task), Some(epoch)) => format!("Policy trained on {task} (epoch {epoch}); suite"),
            _ => "A baseline (no training); suite".to_owned(),
        };
        let mut md = format!(
            "### {} on suite `{}` (MuJoCo {})\n\n{}\n\n{trained} sha256 `{}`.\n\n",
            self.policy, self.suite.name, self.provenance.build.mujoco, self.summary, self.suite.sha256
        );
        for split in &self.splits {
            md += &format!("**{}** (mean success {})\n\n", split.name, pct(split.mean_success));
            md += "| task | distribution | episodes | success [95% CI] | red–blue failure | steps to success | not successful |\n";
            md += "|---|---|---:|---|---:|---:|---|\n";
            for r in &split.rows {
                match (&r.evaluation, &r.skipped) {
                    (Some(e), _) => {
                        md += &format!(
                            "| {} | {} | {} | {:.3} [{:.3}, {:.3}] | {} | {} | {} |\n",
                            r.task,
                            r.distribution,
                            r.episodes,
                            e.success_rate,
                            e.ci95.0,
                            e.ci95.1,
                            pct(r.failure_rate),
                            e.mean_steps_to_success.map_or_else(|| "–".to_owned(), |s| format!("{s:.1}")),
                            e.outcomes.summary()
                        )
                    }
                    (None, reason) => {
                        md += &format!(
                            "| {} | {} | {} | skipped: {} | | | |\n",
                            r.task,
                            r.distribution,
                            r.episodes,
                            reason.as_deref().unwrap_or("").replace('|', "/")
                        )
                    }
                }
            }
            md += "\n";
        }
        let scored = self.scored_split();
        md += &format!(
            "Score ({scored} mean success): {}; generalisation gap (train − {scored}): {}.\n\n",
            pct(self.score),
            pct(self.gap)
        );
        md += &self.provenance.markdown();
        md += " Tasks by content:";
        let mut seen = std::collections::BTreeSet::new();
        for r in self.splits.iter().flat_map(|s| &s.rows) {
            if seen.insert((&r.task, &r.task_sha256)) {
                md += &format!(" {} {};", r.task, r.task_sha256);
            }
        }
        md.pop();
        md += ".\n";
        md
    }
}

impl crate::benchmark::zoo::ZooEvaluation {
    /// `e` as a zoo entry records it, with what made it.
    pub fn new(e: Evaluation, provenance: Provenance) -> Self {
        Self {
            provenance: Some(provenance),
            task_sha256: Some(e.task_sha256),
            env: e.env,
            distribution: if e.challenge { "challenge" } else { "normal" }.into(),
            grey_blind: e.grey_blind,
            episodes: e.episodes,
            seed: e.seed,
            success_rate: e.success_rate,
            ci95: e.ci95,
            outcomes: Some(e.outcomes),
        }
    }
}
