//! The training loop, one epoch as four steps: `collect` (exploration
//! episodes into replay), `learn` (gradient steps), `evaluate` (test and
//! finals), `persist` (files and checkpoint). What ranks exchange is in
//! these steps only, through [`Comm`]; rank 0 alone writes the run's shared
//! files, and every rank writes its own checkpoint.

use super::checkpoint::{self, RunState};
use super::comm::Comm;
use super::learner::{Expert, Learner};
use super::rollouts::{play_plan, stream_seed, Behaviour, Draw, Episode, Planned};
use super::rundir::{read_progress, write_progress, ReplayRebuilt, RunDir};
use super::tasks::{draw_task, run_tasks, test_task};
use super::{computation_differences, plot, Context, EpochRow, ReplayLayout, Result, TrainConfig, TrainError};
use crate::benchmark::saved::SavedPolicy;
use crate::env::vector::VectorEnv;
use crate::env::{registry, EnvConfig};
use crate::learn::agents::algorithm::Algorithm;
use crate::learn::agents::algorithm::{Spec, UpdateStats};
use crate::learn::agents::arch::Arch;
use crate::learn::agents::registry::Algo;
use crate::learn::agents::replay::{Batch, ReplayBuffer};
use crate::policy::actor::AnyPolicy;
use crate::policy::actor::DeterministicPolicy;
use crate::policy::SOLVER_VERSION;
use crate::support::io::write_json;
use crate::task::Task;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Per-epoch callback for progress reporting (called on rank 0 only).
pub type OnEpoch<'a> = &'a mut dyn FnMut(&EpochRow, &TrainConfig);

/// How a run begins.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Start {
    /// A new run in a new directory.
    New,
    /// The run in the directory, from its checkpoint and replay log.
    Resume,
    /// The run in the directory, from its checkpoint (weights, optimiser state, normaliser, counters)
    /// without its replay log, as a run carried to a new machine is (`--rebuild-replay`): the
    /// buffers are collected again from the run's seeds where every stored transition was the
    /// solver's, else refilled from empty ([`ReplayRebuilt`]).
    ResumeRebuildingReplay,
}

impl From<bool> for Start {
    /// `true`: resume; `false`: a new run.
    fn from(resume: bool) -> Self {
        if resume {
            Start::Resume
        } else {
            Start::New
        }
    }
}

/// Trains in this process; with `resume`, continues from the run directory's checkpoint.
///
/// # Errors
/// Bad configuration, environment errors, I/O and checkpoint errors.
pub fn train(
    config: &TrainConfig,
    run_dir: &Path,
    start: impl Into<Start>,
    on_epoch: OnEpoch,
) -> Result<Vec<EpochRow>> {
    train_ranks(&Comm::local(), config, run_dir, start, on_epoch)
}

/// Trains as one rank of `comm`'s job (every rank calls it with the same
/// arguments). Returns the progress rows on rank 0, none elsewhere.
///
/// # Errors
/// As [`train`]; under MPI the caller aborts the job on an error.
pub fn train_ranks(
    comm: &Comm,
    config: &TrainConfig,
    run_dir: &Path,
    start: impl Into<Start>,
    on_epoch: OnEpoch,
) -> Result<Vec<EpochRow>> {
    let mut trainer = Trainer::start(comm, config, run_dir, start.into())?;
    while trainer.state.epoch < trainer.config.epochs {
        let row = trainer.epoch()?;
        if comm.is_root() {
            on_epoch(&row, &trainer.config);
        }
    }
    Ok(trainer.rows)
}

/// A batch of `n` transitions: `ratio` of them (rounded) from the demonstrations where there are
/// any, the rest from the run's own buffer.
fn draw(own: &ReplayBuffer, demos: Option<&ReplayBuffer>, n: usize, ratio: f64, rng: &mut ChaCha8Rng) -> Batch {
    let from_demos = demos.map_or(0, |_| ((n as f64) * ratio).round() as usize).min(n);
    let mut batch = own.sample(n - from_demos, rng);
    if let Some(d) = demos {
        d.sample_into(from_demos, rng, &mut batch);
    }
    batch
}

/// The tasks with environments in `epoch` (indices into the run's `n` tasks): a stream run's active
/// set ([`crate::benchmark::stream::active_tasks`], its families weighted by `--family-weights`),
/// else every task.
fn active_set(config: &TrainConfig, epoch: usize, n: usize) -> Vec<usize> {
    match &config.stream {
        Some(stream) => {
            let copies = stream.copies(config.family_weights.as_ref());
            debug_assert_eq!(copies.len(), n, "the stream's record lists the run's tasks");
            crate::benchmark::stream::active_tasks(config.seed, epoch, &copies, config.active_tasks)
        }
        None => (0..n).collect(),
    }
}

/// One environment per worker and task of `active` (worker-major), built on the workers' threads,
/// stepped on one thread per worker.
fn build_envs(config: &TrainConfig, env_configs: &[EnvConfig], active: &[usize]) -> Result<VectorEnv> {
    use rayon::prelude::*;
    let wanted: Vec<&EnvConfig> = (0..config.workers).flat_map(|_| active.iter().map(|&t| &env_configs[t])).collect();
    let pool = crate::env::vector::model_threads(config.workers).map_err(TrainError::Refused)?;
    let built = pool.install(|| {
        wanted.par_iter().map(|c| crate::env::BlockEnv::new((*c).clone())).collect::<Result<Vec<_>, _>>()
    })?;
    let mut envs = VectorEnv::from_envs(built, config.workers)?;
    // Hindsight colours replay the rules over every substep's contacts: the environments record them.
    envs.envs_mut().iter_mut().for_each(|e| e.record_substeps(config.hindsight_colours > 0));
    Ok(envs)
}

/// Refuses a task the solver cannot play (an imitation learner would learn to
/// stand still): the solver's reason, read off a first reset's observation of
/// each task (worker 0's environments).
fn solver_plays(envs: &mut VectorEnv, tasks: &[Task], seed: u64) -> Result<()> {
    for (env, task) in envs.envs_mut().iter_mut().zip(tasks) {
        let (obs, _) = env.reset(Some(seed))?;
        crate::policy::Script::from_observation(&env.obs_spec(), &obs).map_err(|why| {
            TrainError::Refused(format!("the solver cannot play {} ({why}), so there is nothing to imitate", task.id()))
        })?;
    }
    Ok(())
}

/// The memory a run needs at most, in bytes: its replay buffers when full
/// (or when they hold every transition the run collects, if fewer), one
/// update's batches and activations, and the learner's networks and
/// optimiser state (as its registration counts them, for MLPs of the run's shape).
fn memory_needed(config: &TrainConfig, obs_dim: usize, act_dim: usize, max_episode_steps: usize) -> u64 {
    let (workers, shards) = match config.replay_layout() {
        ReplayLayout::PerWorker => (1, config.workers),
        ReplayLayout::Shared => (config.workers, 1),
    };
    let collected = (config.epochs as u64)
        .saturating_mul(config.cycles as u64)
        .saturating_mul(config.rollouts as u64)
        .saturating_mul(max_episode_steps as u64)
        .saturating_mul(workers as u64)
        .saturating_mul(1 + config.hindsight_colours as u64);
    let stored = collected.min(config.buffer_size as u64);
    // obs, next obs, action, reward, done, extra, discount: f32 each.
    let transition = 4 * (2 * obs_dim + act_dim + 4) as u64;
    let replay = stored.saturating_mul(transition).saturating_mul(shards as u64);
    let batch_rows = (config.batch_size as u64).saturating_mul(config.workers as u64);
    let activations = (config.shared.hidden as u64) * (config.shared.layers as u64) * 16;
    let spec = Spec { arch: Arch::mlp(obs_dim), act_dim, shared: &config.shared };
    replay
        .saturating_add(batch_rows.saturating_mul(transition + activations))
        .saturating_add(config.algo.memory(&spec, &config.algos))
}

/// Refuses a run whose replay buffers and batches would not fit in this
/// machine's memory, naming the settings that size them.
fn check_memory(config: &TrainConfig, obs_dim: usize, act_dim: usize, max_episode_steps: usize) -> Result<()> {
    let (Some(have), need) =
        (crate::support::limits::memory_bytes(), memory_needed(config, obs_dim, act_dim, max_episode_steps))
    else {
        return Ok(());
    };
    if need > have {
        refuse!(
            "this run would need {} of memory (--workers {} with --buffer-size {} and --batch-size {}: replay \
             buffers of {obs_dim}-dimensional observations, filled by {} epochs, the update batches, and networks \
             of --layers {} x --hidden {}), more than this machine's {}; lower --buffer-size, --batch-size, \
             --hidden or --workers, or spread the workers over MPI ranks on several machines",
            crate::support::limits::gigabytes(need),
            config.workers,
            config.buffer_size,
            config.batch_size,
            config.epochs,
            config.shared.layers,
            config.shared.hidden,
            crate::support::limits::gigabytes(have)
        );
    }
    Ok(())
}

/// Before anything is created on a resume: the run exists and was written by
/// a job of this job's size (rank 0's checkpoint says; every rank learns it), and an imitation
/// run (`imitates`) was labelled by this build's solver version (its `provenance.json` says).
fn check_resume(comm: &Comm, run: &RunDir, imitates: bool) -> Result<()> {
    comm.root_check(|| {
        // An imitation run's labels are its solver's: another solver version would label the rest
        // of the run otherwise, and its regenerated buffers would not be the ones it had.
        let last = run.read_provenance()?.pop();
        if let Some(made_by) = last.map(|s| s.build).filter(|b| imitates && b.solver_version() != SOLVER_VERSION) {
            let version = made_by.solver_version();
            refuse!(
                "--resume: {} imitates the solver, and its epochs so far were labelled by solver version {version}; \
                 this build's solver is version {SOLVER_VERSION}, whose labels differ; resume it with a build of \
                 solver version {version} ({}), or start a new run with another --run-dir",
                run.dir.display(),
                made_by.maker()
            );
        }
        let path = [run.checkpoint(), checkpoint::previous(&run.checkpoint())].into_iter().find(|p| p.exists());
        let Some(path) = path else {
            refuse!(
                "--resume: {} holds no run (no {}); start a new run without --resume",
                run.dir.display(),
                run.checkpoint().display()
            );
        };
        let ranks = checkpoint::peek_state(&path)?.ranks;
        if ranks != comm.size() {
            refuse!(
                "{} was written by a job of {ranks} rank(s), this one has {}; resume with mpirun -np {ranks} (or \
                 without mpirun for 1)",
                path.display(),
                comm.size()
            );
        }
        Ok(())
    })
}

/// Every rank's build, gathered and checked on rank 0 ([`super::rank_engines`]): the engine of each
/// rank where the job's ranks run more than one, for the run's `provenance.json`.
fn job_engines(comm: &Comm) -> Result<Vec<String>> {
    let mine = serde_json::to_vec(&super::RankBuild::current()).expect("a build serialises");
    let gathered = comm.gather_bytes(&mine);
    let mut engines = Vec::new();
    comm.root_check(|| {
        let builds = gathered
            .iter()
            .enumerate()
            .map(|(rank, bytes)| {
                serde_json::from_slice(bytes).map_err(|e| {
                    TrainError::Refused(format!(
                        "rank {rank} sent no build this one reads ({e}): run every rank with one blockpuzzle version"
                    ))
                })
            })
            .collect::<Result<Vec<_>>>()?;
        engines = super::rank_engines(&builds)?;
        Ok(())
    })?;
    Ok(engines)
}

/// The folder of rank `rank`'s own files: the run directory for rank 0,
/// `rank-R/` inside it for the others.
pub(crate) fn rank_dir(run: &RunDir, rank: usize) -> RunDir {
    if rank == 0 {
        RunDir { dir: run.dir.clone() }
    } else {
        RunDir { dir: run.dir.join(format!("rank-{rank}")) }
    }
}

/// The run's settings and tasks: the tasks resolved by rank 0 (checked against
/// the run's recorded copies on resume, `saved`) and built by every other rank
/// from them; the recorded tasks, branch and replay layout filled in.
fn run_config(
    comm: &Comm,
    config: &TrainConfig,
    run: &RunDir,
    saved: Option<&TrainConfig>,
) -> Result<(TrainConfig, Vec<Task>)> {
    let (mut tasks, stream) = shared_tasks(comm, config, run, saved)?;
    if let (Some(counts), [task]) = (&config.counts, &mut tasks[..]) {
        *task = task.with_counts(counts)?;
    }
    let mut config = config.clone();
    if stream.is_some() {
        // A stream's pool is recorded by hashes: its tasks are drawn again from the families.
        config.stream = stream;
    } else if super::tasks::is_multi(&config) {
        config.tasks = tasks.iter().map(|t| t.source.clone()).collect();
    } else {
        config.task = Some(tasks[0].source.clone());
    }
    if let Some(saved) = saved {
        config.branched_from = saved.branched_from.clone();
        config.finetune.init_policy = saved.finetune.init_policy.clone();
        config.finetune.demos_sha256 = saved.finetune.demos_sha256.clone();
    }
    // Replay: as given; else a resumed run's own; else per worker.
    let recorded = saved.map(TrainConfig::replay_layout);
    config.replay = Some(config.replay.or(recorded).unwrap_or(ReplayLayout::PerWorker));
    if comm.size() > 1 && config.replay_layout() == ReplayLayout::Shared {
        refuse!(
            "{} shares replay per process (it predates per-worker replay); it cannot continue under mpirun",
            run.dir.display()
        );
    }
    Ok((config, tasks))
}

/// Where a run begins: a fresh agent and empty buffers, or a checkpoint's.
struct StartingPoint {
    agent: Box<dyn Algorithm>,
    replays: Vec<ReplayBuffer>,
    replay_log: checkpoint::ReplayLog,
    /// How many transitions each buffer had received at the checkpoint (a fresh run's: none).
    pushed: Vec<u64>,
    state: RunState,
    /// progress.csv's rows so far (rank 0).
    rows: Vec<EpochRow>,
}

impl StartingPoint {
    /// The agent and buffers fit the run's settings.
    fn check(&self, config: &TrainConfig, mine: &RunDir) -> Result<()> {
        if self.agent.name() != config.algo.name() {
            let (file, held) = (mine.checkpoint(), Algo::named(self.agent.name()).map_err(TrainError::Refused)?);
            refuse!("{} holds a {held:?} agent, not {:?}; pass --algo {held}", file.display(), config.algo);
        }
        let layout = config.replay_layout();
        let expected = if layout == ReplayLayout::PerWorker { config.workers } else { 1 };
        if self.replays.len() != expected {
            refuse!(
                "{} holds {} replay buffer(s), this run needs {expected} (--workers {}, --replay {:?})",
                mine.checkpoint().display(),
                self.replays.len(),
                config.workers,
                layout
            );
        }
        Ok(())
    }
}

/// A new run: weights drawn from the run seed (the same on every rank), empty buffers.
#[allow(clippy::too_many_arguments)]
fn fresh(
    comm: &Comm,
    config: &TrainConfig,
    run_id: &str,
    max_levels: &[usize],
    run: &RunDir,
    mine: &RunDir,
    dims: (Arch, usize),
    init: Option<&DeterministicPolicy>,
) -> Result<StartingPoint> {
    let tasks = max_levels.len();
    let (arch, act_dim) = dims;
    let obs_dim = arch.obs_dim;
    if mine.checkpoint().exists() || run.checkpoint().exists() {
        refuse!("{} already holds a run; pass --resume to continue it or choose another --run-dir", run.dir.display());
    }
    let mut rng = ChaCha8Rng::seed_from_u64(stream_seed(config.seed, &[0]));
    let spec = Spec { arch, act_dim, shared: &config.shared };
    let mut agent = config.algo.build(&spec, &config.algos, &mut rng);
    if let (Some(policy), Some(path)) = (init, &config.finetune.init_from) {
        agent.init_from(policy).map_err(|e| TrainError::Refused(format!("--init-from {}: {e}", path.display())))?;
        keep_policy(&mut *agent, config, policy)?;
    }
    // The curriculum's start: level 0, or each task's top with --start-at-top.
    let levels: Vec<usize> = max_levels.iter().map(|&m| if config.finetune.start_at_top { m } else { 0 }).collect();
    let state = RunState {
        env_id: run_id.to_owned(),
        obs_dim,
        act_dim,
        epoch: 0,
        level: levels.iter().sum(),
        levels,
        tallies: vec![[0, 0]; tasks],
        env_steps: 0,
        updates: 0,
        episodes_per_worker: 0,
        wall_seconds: 0.0,
        best_finals: -1.0,
        ranks: comm.size(),
        rank: comm.rank(),
        config_seal: None,
    };
    let shards = match config.replay_layout() {
        ReplayLayout::PerWorker => config.workers,
        ReplayLayout::Shared => 1,
    };
    let replays = (0..shards).map(|_| ReplayBuffer::new(obs_dim, act_dim, config.buffer_size)).collect();
    let pushed = vec![0; shards];
    Ok(StartingPoint { agent, replays, replay_log: checkpoint::ReplayLog::default(), pushed, state, rows: Vec::new() })
}

/// What the learner keeps of the policy the run started from: the anchor of `--anchor-alpha`, the
/// proposer of `--ibrl` (not checkpointed).
fn keep_policy(agent: &mut dyn Algorithm, config: &TrainConfig, policy: &DeterministicPolicy) -> Result<()> {
    let uses = config.finetune.start_uses();
    if uses.any() {
        agent.keep_start(policy, uses).map_err(|e| TrainError::Refused(e.to_string()))?;
    }
    Ok(())
}

/// A resumed run: this rank's checkpoint of the last epoch every rank
/// completed, after rank 0 checked that the settings are the run's.
#[allow(clippy::too_many_arguments)]
fn resumed(
    comm: &Comm,
    config: &TrainConfig,
    run_id: &str,
    tasks: usize,
    run: &RunDir,
    mine: &RunDir,
    saved_config: Option<TrainConfig>,
    dims: (Arch, usize),
    with_replay: bool,
) -> Result<StartingPoint> {
    let path = resume_checkpoint(comm, &mine.checkpoint(), run)?;
    if comm.is_root() {
        let mut saved = match saved_config {
            Some(c) => c,
            None => run.read_config()?,
        };
        // The run's config.json is the one its checkpoint was written with (or, at a branch's first
        // resume, the checkpoint is the parent's, written with the parent's). Checked before the
        // checkpoint's replay is read: another run's checkpoint is named as such.
        super::check_config_seal(run, &saved, &path, &checkpoint::peek_state(&path)?, "--resume")?;
        saved.replay = Some(saved.replay_layout());
        let changed = computation_differences(&saved, config);
        if !changed.is_empty() || (saved.task.is_none() && saved.env != config.env) {
            refuse!(
                "--resume with settings that differ from {} ({}); resume with the run's settings or start a new run with another --run-dir",
                run.config().display(),
                if changed.is_empty() { "--env".to_owned() } else { changed.join(", ") }
            );
        }
    }
    let mut loaded = match with_replay {
        true => checkpoint::load(&path, run_id, dims.0.obs_dim, dims.1)?,
        false => checkpoint::load_without_replay(&path, run_id, dims.0.obs_dim, dims.1)?,
    };
    // One-task checkpoints written before per-task levels hold the level alone.
    if loaded.state.levels.is_empty() && tasks == 1 {
        loaded.state.levels = vec![loaded.state.level];
    }
    if loaded.state.levels.len() != tasks {
        refuse!(
            "--resume: {} holds the levels of {} task(s), this run has {tasks}",
            path.display(),
            loaded.state.levels.len()
        );
    }
    loaded.state.tallies.resize(tasks, [0, 0]);
    if loaded.agent.norm().set_layout() != dims.0.set {
        refuse!("--resume: {} was saved with other networks than --net asks for", path.display());
    }
    // A resume has the checkpoint's settings; a branch's first epoch, its own.
    config.algo.take_branch_settings(&mut *loaded.agent, &config.algos).map_err(TrainError::Refused)?;
    let epoch = loaded.state.epoch;
    let rows = if comm.is_root() {
        read_progress(&run.progress())?.into_iter().filter(|r| r.epoch < epoch).collect()
    } else {
        Vec::new()
    };
    Ok(StartingPoint {
        agent: loaded.agent,
        replays: loaded.replays,
        replay_log: loaded.log,
        pushed: loaded.pushed,
        state: loaded.state,
        rows,
    })
}

/// Records the demonstrations' hash in the run's config; a resume refuses a file other than the one
/// the run started with.
fn record_demos(config: &mut TrainConfig, file: &super::finetune::DemoFile, resume: bool) -> Result<()> {
    match (&config.finetune.demos_sha256, resume) {
        (Some(recorded), true) if *recorded != file.sha256 => refuse!(
            "--resume: --demos {} is not the file this run started with ({recorded}); restore that file",
            config.finetune.demos.as_deref().unwrap_or(Path::new("")).display()
        ),
        _ => config.finetune.demos_sha256 = Some(file.sha256.clone()),
    }
    Ok(())
}

/// Options that would do nothing on these tasks, refused before any environment is built: a
/// challenge share without a challenge distribution, level replay without a second level.
fn refuse_idle_options(config: &TrainConfig, tasks: &[Task]) -> Result<()> {
    if config.challenge_share > 0.0 && tasks.iter().all(|t| t.distribution("challenge").is_none()) {
        match tasks {
            [task] => refuse!("--challenge-share: the task {} has no challenge distribution", task.id()),
            _ => refuse!("--challenge-share: none of the run's tasks has a challenge distribution"),
        }
    }
    if config.level_replay > 0.0 && tasks.iter().all(|t| t.max_level() == 0) {
        let which = match tasks {
            [task] => format!("the task {} has", task.id()),
            _ => "every one of the run's tasks has".to_owned(),
        };
        refuse!(
            "--level-replay {}: {which} one curriculum level, so there is no earlier level to replay; leave \
             --level-replay out (or 0)",
            config.level_replay
        );
    }
    Ok(())
}

/// The demonstrations (`--demos`) in a buffer of their own, their observations counted by a new
/// run's normaliser unless it starts from a policy's; None without demonstrations.
fn demo_buffer(
    demos: Option<&super::finetune::DemoFile>,
    config: &TrainConfig,
    envs: &VectorEnv,
    tasks: &[Task],
    agent: &mut dyn Algorithm,
    resume: bool,
) -> Result<Option<ReplayBuffer>> {
    let (Some(file), Some(path)) = (demos, &config.finetune.demos) else { return Ok(None) };
    let spec = envs.obs_spec();
    let episodes = super::finetune::demo_episodes(file, path, &spec, tasks)?;
    let steps = episodes.iter().map(|e| e.len()).sum::<usize>();
    let act_dim = envs.envs()[0].action_space().dim();
    let mut replay = ReplayBuffer::new(spec.dim(), act_dim, steps);
    for e in &episodes {
        e.store_transitions(&mut replay, config.shared.gamma, config.shared.n_step);
    }
    if !resume && config.finetune.init_from.is_none() {
        agent.norm_mut().update(&episodes.iter().flat_map(|e| e.obs.concat()).collect::<Vec<_>>());
    }
    Ok(Some(replay))
}

/// What each update exchanges under `mpirun`: gradients of `gradient_len` numbers from every rank's
/// `workers` workers.
fn announce_ranks(comm: &Comm, workers: usize, gradient_len: usize) {
    let (p, w, bytes) = (comm.size(), workers, 4 * gradient_len);
    eprintln!(
        "mpirun: {p} ranks × {w} workers; each update averages {} gradients of {} KiB: every rank sends and \
         receives about {} KiB",
        p * w,
        bytes / 1024,
        2 * (p - 1) * w * bytes / p / 1024
    );
}

/// The policy file a run writes after an epoch (`policy.json`, snapshots, `best_policy.json`), from
/// its config, its state after the epoch, the epoch's finals success and the agent's policy and
/// critic. A multi-task policy names its run's tasks (`config.json` records them) and holds no one
/// task; a stream run's, its stream's record. A run that learns from the solver records `solver`, the
/// version that labelled it, where known. [`super::export::policy_from_checkpoint`] writes the same file from a
/// checkpoint alone.
pub(crate) fn saved_policy(
    config: &TrainConfig,
    state: &RunState,
    finals_success: f64,
    policy: AnyPolicy,
    critic: Option<crate::policy::actor::mlp::PlainNet>,
    solver: Option<u32>,
) -> SavedPolicy {
    let (task, tasks, stream) = match (&config.stream, &config.tasks[..]) {
        (Some(stream), _) => (None, Vec::new(), Some(stream.clone())),
        (None, []) => (config.task.clone(), Vec::new(), None),
        // A list or suite split of one task saves it as the one task, as a one-task run does.
        (None, [task]) => (Some(task.clone()), Vec::new(), None),
        (None, all) => (None, all.to_vec(), None),
    };
    SavedPolicy {
        env_id: state.env_id.clone(),
        task,
        tasks,
        stream,
        epoch: state.epoch,
        env_steps: Some(state.env_steps),
        finals_success,
        algo: Some(config.trainer()),
        solver: solver.filter(|_| config.learns_from_solver()),
        obs_mode: Some(config.net.obs_mode()),
        fixtures: Some(config.net.obs_mode().fixtures().to_vec()),
        policy,
        critic,
        blend: None,
        started_from: config.finetune.init_policy.clone(),
    }
}

/// Declares [`RowSums`]: its fields, in the order ranks send them.
macro_rules! row_sums {
    ($($(#[$doc:meta])* $field:ident),* $(,)?) => {
        /// What an epoch's row sums over ranks before dividing: counts, and each mean's sum with the
        /// count it divides by. Ranks exchange them as one vector in field order (then each task's
        /// test successes and episodes).
        #[derive(Debug, Clone, Copy, Default)]
        struct RowSums {
            $($(#[$doc])* $field: f64,)*
        }

        impl RowSums {
            /// How many numbers it sends.
            const LEN: usize = [$(stringify!($field)),*].len();

            /// Its numbers in field order.
            fn to_vec(self) -> Vec<f64> {
                vec![$(self.$field),*]
            }

            /// The sums whose field number `i` (in field order) is `value(i)`.
            fn from_fn(value: impl Fn(usize) -> f64) -> Self {
                let mut i = 0;
                let mut next = || {
                    i += 1;
                    value(i - 1)
                };
                Self { $($field: next()),* }
            }
        }
    };
}

row_sums! {
    /// Exploration episodes.
    episodes,
    /// Exploration episodes that succeeded.
    wins,
    /// Exploration steps.
    steps,
    /// Exploration steps the expert played (AggreVaTeD, DAgger).
    expert_steps,
    /// Test episodes that succeeded.
    test_wins,
    /// Test episodes.
    tests,
    /// Finals episodes that succeeded.
    finals_wins,
    /// Finals episodes.
    finals,
    /// Sum of the updates' mean Q.
    q,
    /// Updates with a mean Q.
    q_n,
    /// Sum of the updates' critic losses.
    critic_loss,
    /// Updates with a critic loss.
    critic_loss_n,
    /// Sum of the updates' actor losses.
    actor_loss,
    /// Updates with an actor loss.
    actor_loss_n,
    /// Relabelled episodes (hindsight colours).
    relabelled,
    /// Relabelled episodes that succeed.
    relabelled_wins,
}

/// Everything a run holds between epochs.
struct Trainer<'a> {
    comm: &'a Comm,
    config: TrainConfig,
    /// The run directory (rank 0 writes its shared files).
    run: RunDir,
    /// This rank's own files (checkpoint, expert copy).
    mine: RunDir,
    /// The tasks (one, or a multi-task run's, in its recorded order).
    tasks: Vec<Task>,
    /// Every task's environment configuration (one observation layout for all).
    env_configs: Vec<EnvConfig>,
    /// The tasks with environments this epoch (indices into `tasks`): all of them, or a stream's
    /// active set ([`active_set`]).
    active: Vec<usize>,
    /// One environment per worker of this rank and active task (worker-major: `worker × active + k`
    /// holds task `active[k]`).
    envs: VectorEnv,
    learner: Learner,
    /// One buffer per worker (`per-worker`) or one (`shared`).
    replays: Vec<ReplayBuffer>,
    /// The demonstrations' transitions (`--demos`), which every batch draws its share from.
    demo_replay: Option<ReplayBuffer>,
    /// The replay buffers' log on disk (appended by every checkpoint).
    replay_log: checkpoint::ReplayLog,
    state: RunState,
    /// progress.csv's rows (rank 0).
    rows: Vec<EpochRow>,
    /// Each task's test success that moves its curriculum up a level.
    thresholds: Vec<f64>,
    /// Each task's maximum level.
    max_levels: Vec<usize>,
    obs_dim: usize,
    /// Seconds spent persisting the previous epoch (reported in the next row).
    persist_seconds: f64,
    /// The folders this run created, removed if it stops before its first
    /// checkpoint (kept from then on).
    created: Vec<crate::support::io::CreatedDir>,
}

/// What one epoch's collection and learning measured on this rank.
#[derive(Default)]
struct EpochTally {
    env_seconds: f64,
    update_seconds: f64,
    forward_seconds: f64,
    episodes: usize,
    wins: usize,
    steps: usize,
    expert_steps: usize,
    /// Hindsight colours: relabelled episodes stored, and those that succeed under their colours.
    relabelled: usize,
    relabelled_wins: usize,
    stats: Vec<UpdateStats>,
}

impl<'a> Trainer<'a> {
    /// Validates, resolves the task, builds environments and the agent
    /// (fresh, or from this rank's checkpoint).
    fn start(comm: &'a Comm, config: &TrainConfig, run_dir: &Path, start: Start) -> Result<Self> {
        config.validate(comm.size())?;
        let rank_engines = job_engines(comm)?;
        let resume = start != Start::New;
        // The policy a new run starts from, checked before anything is written (a resumed run's
        // actor is in its checkpoint).
        let init = match resume {
            // A resumed run's actor is in its checkpoint; its anchor (`--anchor-alpha`) is not.
            true if !config.finetune.keeps_policy() => None,
            _ => config.finetune.load(config)?,
        };
        let demos = config.finetune.read_demos()?;
        let run = RunDir { dir: run_dir.to_owned() };
        let mine = rank_dir(&run, comm.rank());
        if resume {
            check_resume(comm, &run, config.algo.info().imitates)?;
        }
        if std::fs::metadata(&run.dir).is_ok_and(|m| !m.is_dir()) {
            refuse!(
                "--run-dir {} is a file, not a folder; give the path of a new folder (or of a run to --resume)",
                run.dir.display()
            );
        }
        let created = [&run.dir, &mine.dir]
            .into_iter()
            .map(|d| {
                crate::support::io::CreatedDir::create(d)
                    .with_context(|| format!("cannot create run directory {}", d.display()))
            })
            .collect::<Result<Vec<_>>>()?;
        tch::set_num_threads(crate::learn::blas::torch_threads(config.torch_threads).map_err(TrainError::Refused)?);

        let saved_config =
            if comm.is_root() && resume && run.config().exists() { Some(run.read_config()?) } else { None };
        let (mut config, tasks) = run_config(comm, config, &run, saved_config.as_ref())?;
        if let (false, Some((id, _))) = (resume, &init) {
            config.finetune.init_policy = Some(id.clone());
        }
        if let Some(file) = &demos {
            record_demos(&mut config, file, resume)?;
        }
        refuse_idle_options(&config, &tasks)?;
        let thresholds: Vec<f64> =
            tasks.iter().map(|t| config.success_threshold.unwrap_or(t.spec.curriculum.success_threshold)).collect();
        // One layout for every task: the most block slots of any (a stream: of any its families can draw).
        let most = config.stream.as_ref().map_or(0, |s| s.max_blocks);
        let slots = tasks.iter().map(Task::object_count).max().unwrap_or(0).max(most);
        let env_configs: Vec<EnvConfig> = tasks
            .iter()
            .map(|t| EnvConfig { obs_mode: config.net.obs_mode(), slots, ..EnvConfig::new(t.clone()) })
            .collect();
        let max_steps = tasks.iter().map(|t| t.spec.max_episode_steps).max().unwrap_or(0);
        // Sized from the configuration before any environment is built (256 of them take a minute).
        check_memory(&config, env_configs[0].obs_spec().dim(), crate::env::ACTION_DIM, max_steps)?;
        let active = active_set(&config, 0, tasks.len());
        crate::support::limits::NUM_ENVS.check_usize(config.workers * active.len()).map_err(|e| {
            TrainError::Refused(format!(
                "{e}: {} workers × {} tasks; use fewer workers or tasks",
                config.workers,
                active.len()
            ))
        })?;
        let mut envs = build_envs(&config, &env_configs, &active)?;
        // A stream's tasks passed the solver's check when they were generated.
        if config.algo.info().imitates && config.stream.is_none() {
            solver_plays(&mut envs, &tasks, config.seed)?;
        }
        let first = &envs.envs()[0];
        let (obs_dim, act_dim) = (envs.obs_spec().dim(), first.action_space().dim());
        let arch = Arch::of(&envs.obs_spec(), &config.net).map_err(|e| TrainError::Refused(e.to_string()))?;
        let max_levels: Vec<usize> = tasks.iter().map(Task::max_level).collect();
        let dims = (arch, act_dim);
        let run_id = config.task_id();
        let begun = if resume {
            let with_replay = start != Start::ResumeRebuildingReplay;
            resumed(comm, &config, &run_id, tasks.len(), &run, &mine, saved_config, dims, with_replay)?
        } else {
            let policy = init.as_ref().map(|(_, p)| p);
            fresh(comm, &config, &run_id, &max_levels, &run, &mine, dims, policy)?
        };
        let mut begun = begun;
        if let (true, Some((id, policy))) = (resume, &init) {
            // The policy the run started from, as recorded: its anchor again.
            if let Some(recorded) = config.finetune.init_policy.as_ref().filter(|r| r.sha256 != id.sha256) {
                refuse!(
                    "--resume: {} is not the policy this run started from ({}); restore that policy to resume the run",
                    id.name,
                    recorded.sha256.as_deref().unwrap_or("unrecorded")
                );
            }
            keep_policy(&mut *begun.agent, &config, policy)?;
        }
        begun.check(&config, &mine)?;
        let demo_replay = demo_buffer(demos.as_ref(), &config, &envs, &tasks, &mut *begun.agent, resume)?;
        let seen = crate::policy::actor::obs_dim_without_grey(&envs.envs()[0].config().blocks());
        let expert = Expert::load(&config.aggrevated, seen, &mine.expert_policy(), resume)?;
        if comm.is_root() && comm.size() > 1 {
            announce_ranks(comm, config.workers, begun.agent.gradient_len());
        }
        let pushed = begun.pushed;
        let mut trainer = Self {
            comm,
            config,
            run,
            mine,
            tasks,
            env_configs,
            active,
            envs,
            learner: Learner { agent: begun.agent, expert, reduce_seconds: 0.0 },
            replays: begun.replays,
            demo_replay,
            replay_log: begun.replay_log,
            state: begun.state,
            rows: begun.rows,
            thresholds,
            max_levels,
            obs_dim,
            persist_seconds: 0.0,
            created,
        };
        // Exact where the solver collected every stored transition at level 0 in this run itself.
        let rebuilt = (start == Start::ResumeRebuildingReplay).then(|| {
            let epochs = trainer.state.epoch;
            let solver_only = (0..epochs).all(|e| trainer.solver_collects(e));
            let level_zero = trainer.state.levels.iter().all(|&l| l == 0);
            match solver_only && level_zero && trainer.config.branched_from.is_none() {
                true => ReplayRebuilt::Regenerated,
                false => ReplayRebuilt::Refilled,
            }
        });
        // The buffers are whole before the run's files say so.
        if rebuilt == Some(ReplayRebuilt::Regenerated) {
            trainer.regenerate_replay(&pushed)?;
        }
        // Every checkpoint from here on is sealed to the config.json written now.
        trainer.state.config_seal = Some(super::config_seal(&trainer.config));
        if comm.is_root() {
            let (run, epoch) = (&trainer.run, trainer.state.epoch);
            write_json(&run.config(), &trainer.config)?;
            run.record_provenance(epoch, rebuilt, rank_engines)?;
            if let Some(r) = rebuilt {
                eprintln!("{}: resumed at epoch {epoch} without its replay log; {}", run.dir.display(), r.describe());
            }
        }
        Ok(trainer)
    }

    /// Collects every exploration episode of the epochs done again, from the run's seeds, into the
    /// (empty) buffers: the transitions the run had, where the solver played every one of them at
    /// level 0 ([`ReplayRebuilt::Regenerated`]). The normaliser is the checkpoint's, which already
    /// counted them. Checked against the history lengths the checkpoint recorded.
    fn regenerate_replay(&mut self, pushed: &[u64]) -> Result<()> {
        let (epochs, rollouts) = (self.state.epoch, self.config.rollouts as u64);
        let mut tally = EpochTally::default();
        let mut base = 0;
        for epoch in 0..epochs {
            self.activate(epoch)?;
            self.set_levels(false)?;
            for _ in 0..self.config.cycles {
                self.play_into_replay(epoch, base, &mut tally)?;
                base += rollouts;
            }
        }
        let now: Vec<u64> = self.replays.iter().map(ReplayBuffer::pushed).collect();
        if base != self.state.episodes_per_worker || now != pushed {
            refuse!(
                "--rebuild-replay: collecting the run's {epochs} epochs again gave {base} episodes per worker and {now:?} \
                 transitions per buffer, where the checkpoint records {} and {pushed:?} (were --cycles or --rollouts \
                 changed during the run?); resume with its replay log, or start a new run",
                self.state.episodes_per_worker
            );
        }
        Ok(())
    }

    /// The global index of this rank's worker `w` (it keys the worker's random streams).
    fn shard(&self, w: usize) -> usize {
        self.comm.rank() * self.config.workers + w
    }

    /// One epoch: cycles of collect + learn, then evaluate, then persist.
    fn epoch(&mut self) -> Result<EpochRow> {
        let epoch = self.state.epoch;
        let started = Instant::now();
        let cpu_started = cpu_seconds();
        self.activate(epoch)?;
        self.set_levels(false)?;
        let mut tally = EpochTally::default();
        self.learner.reduce_seconds = 0.0;
        if self.solver_collects(epoch) && self.config.cycles > 1 {
            self.overlapped_cycles(epoch, &mut tally)?;
        } else {
            for cycle in 0..self.config.cycles {
                self.collect(epoch, &mut tally)?;
                self.learn(epoch, cycle, &mut tally);
            }
        }
        let eval_started = Instant::now();
        let (policy, test, test_tasks, finals) = self.evaluate(epoch)?;
        let eval_seconds = eval_started.elapsed().as_secs_f64();
        tally.env_seconds += eval_seconds;
        tally.forward_seconds +=
            test.iter().chain(&finals).map(|e| e.forward_seconds).sum::<f64>() / self.config.workers as f64;
        let (row, tested) = self.row(epoch, &tally, (&test, &test_tasks), &finals, eval_seconds, started, cpu_started);
        self.advance_curricula(&tested);
        self.state.epoch += 1;
        self.persist(&row, policy)?;
        Ok(row)
    }

    /// Builds the environments of `epoch`'s active set where it differs from the current one (a
    /// stream run's; a run of listed tasks keeps its environments).
    fn activate(&mut self, epoch: usize) -> Result<()> {
        let active = active_set(&self.config, epoch, self.tasks.len());
        if active != self.active {
            self.envs = build_envs(&self.config, &self.env_configs, &active)?;
            self.active = active;
        }
        Ok(())
    }

    /// Sets every environment to its task's level, or (`top`) to its task's maximum level.
    fn set_levels(&mut self, top: bool) -> Result<()> {
        let n = self.active.len();
        for (i, env) in self.envs.envs_mut().iter_mut().enumerate() {
            let t = self.active[i % n];
            let level = if top { self.max_levels[t] } else { self.state.levels[t].min(self.max_levels[t]) };
            env.set_level(level)?;
        }
        Ok(())
    }

    /// Adds the epoch's test episodes of each task (summed over ranks) to its tally; a task whose
    /// tally holds `test_episodes` episodes moves up a level if their success reaches its threshold,
    /// and its tally starts again. One task is tested `workers × ranks × test_episodes` times an
    /// epoch: the paper's rule, a decision every epoch on that epoch's test success.
    fn advance_curricula(&mut self, tested: &[[u64; 2]]) {
        let state = &mut self.state;
        for (t, got) in tested.iter().enumerate() {
            let tally = &mut state.tallies[t];
            (tally[0], tally[1]) = (tally[0] + got[0], tally[1] + got[1]);
            if tally[1] >= self.config.test_episodes as u64 {
                let success = if tally[1] == 0 { 0.0 } else { tally[0] as f64 / tally[1] as f64 };
                if success >= self.thresholds[t] && state.levels[t] < self.max_levels[t] {
                    state.levels[t] += 1;
                }
                *tally = [0, 0];
            }
        }
        state.level = state.levels.iter().sum();
    }

    /// Every worker plays `rollouts` exploration episodes; their transitions
    /// go to the worker's buffer, and every rank's observations (in global
    /// shard order) to the normaliser.
    fn collect(&mut self, epoch: usize, tally: &mut EpochTally) -> Result<()> {
        let rows = self.play_into_replay(epoch, self.state.episodes_per_worker, tally)?;
        self.count_collected(&rows);
        Ok(())
    }

    /// The end of a cycle's collection: the episode counter moves on, and every rank's
    /// observations (in global shard order) go to the normaliser.
    fn count_collected(&mut self, rows: &[f32]) {
        self.state.episodes_per_worker += self.config.rollouts as u64;
        let all = self.comm.gather_f32(rows);
        self.learner.agent.norm_mut().update(&all);
    }

    /// Whether the solver plays every step of `epoch`'s exploration episodes (behaviour cloning):
    /// they then depend on the run's seeds alone, not on the learner.
    fn solver_collects(&self, epoch: usize) -> bool {
        self.learner.expert.is_none() && self.learner.agent.solver_share(epoch) == Some(1.0)
    }

    /// Every worker plays `rollouts` exploration episodes of `epoch`, the first of them its
    /// `base`-th; their transitions go to the worker's buffer. Returns their observations.
    fn play_into_replay(&mut self, epoch: usize, base: u64, tally: &mut EpochTally) -> Result<Vec<f32>> {
        let t = Instant::now();
        let plan = self.plan_cycle(base);
        let explorer = self.learner.agent.explorer();
        let mixture = self.learner.mixture(&*explorer, epoch, &self.config);
        let behaviour = match &mixture {
            Some(m) => Behaviour::Mixture(m),
            None => Behaviour::exploring(&*self.learner.agent, &*explorer, epoch),
        };
        let eps = play_plan(&mut self.envs, &self.active, &behaviour, &plan)?;
        tally.env_seconds += t.elapsed().as_secs_f64();
        Ok(self.store_episodes(&eps, &plan, tally))
    }

    /// What every worker plays in a cycle of exploration episodes whose first is its `base`-th.
    fn plan_cycle(&self, base: u64) -> Vec<Planned> {
        let config = &self.config;
        let draws = (config.level_replay > 0.0 || config.challenge_share > 0.0).then(|| {
            self.tasks
                .iter()
                .enumerate()
                .map(|(t, task)| Draw {
                    level: self.state.levels[t].min(self.max_levels[t]),
                    max_level: self.max_levels[t],
                    level_replay: config.level_replay,
                    // A multi-task run's tasks without a challenge distribution play their own.
                    challenge_share: if task.distribution("challenge").is_some() {
                        config.challenge_share
                    } else {
                        0.0
                    },
                })
                .collect::<Vec<_>>()
        });
        let active = &self.active;
        (0..config.workers)
            .flat_map(|w| (0..config.rollouts).map(move |k| (w, k)))
            .map(|(w, k)| {
                let seed = stream_seed(config.seed, &[1, self.shard(w) as u64, base + k as u64]);
                let task = active[draw_task(seed, active.len())];
                Planned { worker: w, task, seed, draw: draws.as_ref().map(|d| d[task]) }
            })
            .collect()
    }

    /// Stores a cycle's episodes (and their hindsight relabellings) in the workers' buffers and
    /// counts them; returns their observations.
    fn store_episodes(&mut self, eps: &[Episode], plan: &[Planned], tally: &mut EpochTally) -> Vec<f32> {
        let config = &self.config;
        let mut rows = Vec::new();
        for (ep, planned) in eps.iter().zip(plan) {
            let max_steps = self.tasks[planned.task].spec.max_episode_steps;
            tally.episodes += 1;
            tally.wins += ep.success as usize;
            tally.steps += ep.len();
            tally.expert_steps += ep.expert_steps;
            tally.forward_seconds += ep.forward_seconds / config.workers as f64;
            let replay = match config.replay_layout() {
                ReplayLayout::PerWorker => &mut self.replays[planned.worker],
                ReplayLayout::Shared => &mut self.replays[0],
            };
            ep.store_transitions(replay, config.shared.gamma, config.shared.n_step);
            rows.extend(ep.obs.iter().flatten());
            // Hindsight colours: the same episode under other colourings, beside the original.
            for other in
                ep.relabelled(&self.envs.obs_spec(), config.hindsight_colours, config.hindsight_strategy, max_steps)
            {
                tally.relabelled += 1;
                tally.relabelled_wins += other.success as usize;
                other.store_transitions(replay, config.shared.gamma, config.shared.n_step);
                rows.extend(other.obs.iter().flatten());
            }
        }
        rows
    }

    /// An epoch's cycles where the solver plays every exploration episode: each cycle's updates
    /// run while the environments play the next cycle's episodes on their own threads, which the
    /// updates do not wait for. The next cycle's episodes do not depend on the learner, and they
    /// reach the buffers and the normaliser after the updates, as they would one after the other:
    /// the run is the same, transition for transition and weight for weight (tested). Its
    /// `time/env_seconds` then overlap its `time/update_seconds`.
    fn overlapped_cycles(&mut self, epoch: usize, tally: &mut EpochTally) -> Result<()> {
        self.collect(epoch, tally)?;
        for cycle in 0..self.config.cycles {
            if cycle + 1 == self.config.cycles {
                self.learn(epoch, cycle, tally);
                break;
            }
            let plan = self.plan_cycle(self.state.episodes_per_worker);
            let explorer = self.learner.agent.explorer();
            let behaviour = Behaviour::exploring(&*self.learner.agent, &*explorer, epoch);
            let (envs, active, learning) = self.split();
            let (played, env_seconds) = std::thread::scope(|scope| {
                let plan = &plan;
                let collecting = scope.spawn(move || {
                    let t = Instant::now();
                    (play_plan(envs, active, &behaviour, plan), t.elapsed().as_secs_f64())
                });
                learning.cycle(epoch, cycle, tally);
                collecting.join().unwrap_or_else(|panic| std::panic::resume_unwind(panic))
            });
            tally.env_seconds += env_seconds;
            let rows = self.store_episodes(&played?, &plan, tally);
            self.count_collected(&rows);
        }
        Ok(())
    }

    /// `batches` gradient steps, then the end of the cycle (DDPG's targets follow).
    fn learn(&mut self, epoch: usize, cycle: usize, tally: &mut EpochTally) {
        self.split().2.cycle(epoch, cycle, tally);
    }

    /// The environments (and the active tasks they hold) apart from what the updates use, so that
    /// the two can run side by side.
    fn split(&mut self) -> (&mut VectorEnv, &[usize], Learning<'_, 'a>) {
        let learning = Learning {
            config: &self.config,
            comm: self.comm,
            learner: &mut self.learner,
            replays: &self.replays,
            demos: self.demo_replay.as_ref(),
            updates: &mut self.state.updates,
            obs_dim: self.obs_dim,
        };
        (&mut self.envs, &self.active, learning)
    }

    /// The deterministic policy's test episodes at the current level and
    /// finals at the maximum level (a multi-task run's tasks in turn, each at its
    /// own levels), and the task of each test episode.
    #[allow(clippy::type_complexity)]
    fn evaluate(&mut self, epoch: usize) -> Result<(AnyPolicy, Vec<Episode>, Vec<usize>, Vec<Episode>)> {
        let (seed, n, tasks) = (self.config.seed, self.config.test_episodes, self.active.len());
        let shards = self.comm.size() * self.config.workers;
        let plan = |stream: u64| -> Vec<Planned> {
            (0..self.config.workers)
                .flat_map(|w| (0..n).map(move |k| (w, k)))
                .map(|(w, k)| {
                    let shard = self.shard(w);
                    let task = self.active[test_task(epoch, shards, n, shard, k, tasks)];
                    let seed = stream_seed(seed, &[stream, epoch as u64, shard as u64, k as u64]);
                    Planned { worker: w, task, seed, draw: None }
                })
                .collect()
        };
        let (test_plan, finals_plan) = (plan(3), plan(4));
        let policy = self.learner.agent.policy();
        let greedy = Behaviour::Greedy(&policy);
        self.set_levels(false)?;
        for env in self.envs.envs_mut() {
            env.set_distribution(None)?;
        }
        let test = play_plan(&mut self.envs, &self.active, &greedy, &test_plan)?;
        self.set_levels(true)?;
        let finals = play_plan(&mut self.envs, &self.active, &greedy, &finals_plan)?;
        Ok((policy, test, test_plan.iter().map(|p| p.task).collect(), finals))
    }

    /// The epoch's row: counts and success summed over ranks (one exchange),
    /// times measured on this rank.
    #[allow(clippy::too_many_arguments)]
    fn row(
        &mut self,
        epoch: usize,
        tally: &EpochTally,
        (test, test_tasks): (&[Episode], &[usize]),
        finals: &[Episode],
        eval_seconds: f64,
        started: Instant,
        cpu_started: f64,
    ) -> (EpochRow, Vec<[u64; 2]>) {
        let wins = |eps: &[Episode]| eps.iter().filter(|e| e.success).count() as f64;
        let sum_of = |f: fn(&UpdateStats) -> f64| {
            let v: Vec<f64> = tally.stats.iter().map(f).filter(|x| !x.is_nan()).collect();
            (v.iter().sum::<f64>(), v.len() as f64)
        };
        let (q, cl, al) = (sum_of(|s| s.mean_q), sum_of(|s| s.critic_loss), sum_of(|s| s.actor_loss));
        let local = RowSums {
            episodes: tally.episodes as f64,
            wins: tally.wins as f64,
            steps: tally.steps as f64,
            expert_steps: tally.expert_steps as f64,
            test_wins: wins(test),
            tests: test.len() as f64,
            finals_wins: wins(finals),
            finals: finals.len() as f64,
            q: q.0,
            q_n: q.1,
            critic_loss: cl.0,
            critic_loss_n: cl.1,
            actor_loss: al.0,
            actor_loss_n: al.1,
            relabelled: tally.relabelled as f64,
            relabelled_wins: tally.relabelled_wins as f64,
        };
        // Then each task's test (successes, episodes).
        let mut sent = local.to_vec();
        for t in 0..self.tasks.len() {
            let of_t = || test.iter().zip(test_tasks).filter(move |(_, &k)| k == t).map(|(e, _)| e);
            sent.extend([of_t().filter(|e| e.success).count() as f64, of_t().count() as f64]);
        }
        let per_rank = self.comm.gather_f64(&sent);
        // Summed over ranks in rank order.
        let total = |i: usize| -> f64 { per_rank.iter().map(|r| r[i]).fold(0.0, |a, x| a + x) };
        let all = RowSums::from_fn(total);
        let ratio = |a: f64, b: f64| if b == 0.0 { 0.0 } else { a / b };
        self.state.env_steps += all.steps as u64;
        let epoch_wall = started.elapsed().as_secs_f64();
        self.state.wall_seconds += epoch_wall;
        let cores = std::thread::available_parallelism().map_or(1, |n| n.get()) as f64;
        let at = RowSums::LEN;
        let tested = (0..self.tasks.len()).map(|t| [total(at + 2 * t) as u64, total(at + 2 * t + 1) as u64]);
        let row = EpochRow {
            epoch,
            level: self.state.level,
            train_success: ratio(all.wins, all.episodes),
            test_success: ratio(all.test_wins, all.tests),
            finals_success: ratio(all.finals_wins, all.finals),
            mean_q: ratio(all.q, all.q_n),
            critic_loss: ratio(all.critic_loss, all.critic_loss_n),
            actor_loss: ratio(all.actor_loss, all.actor_loss_n),
            env_steps: self.state.env_steps,
            updates: self.state.updates,
            wall_seconds: self.state.wall_seconds,
            env_seconds: tally.env_seconds,
            forward_seconds: tally.forward_seconds,
            update_seconds: tally.update_seconds,
            reduce_seconds: self.learner.reduce_seconds,
            eval_seconds,
            persist_seconds: self.persist_seconds,
            beta: self.learner.beta(epoch, &self.config).unwrap_or(0.0),
            expert_share: ratio(all.expert_steps, all.steps),
            relabelled: all.relabelled / all.episodes.max(1.0),
            relabelled_success: ratio(all.relabelled_wins, all.relabelled),
            cpu_utilisation: (cpu_seconds() - cpu_started) / (epoch_wall * cores).max(1e-9),
        };
        (row, tested.collect())
    }

    /// Rank 0 writes progress, plot and policies; then every rank its
    /// checkpoint (last, so that a crash before it repeats at most this epoch).
    fn persist(&mut self, row: &EpochRow, policy: AnyPolicy) -> Result<()> {
        let started = Instant::now();
        if self.comm.is_root() {
            let (run, state) = (&self.run, &self.state);
            self.rows.push(row.clone());
            write_progress(&run.progress(), &self.rows)?;
            // A multi-task run's level is the sum of its tasks' levels.
            let max_level = self.max_levels.iter().sum();
            plot::success_curves(&run.plot(), &self.config.title(), &self.rows, max_level)?;
            let saved = saved_policy(
                &self.config,
                state,
                row.finals_success,
                policy,
                self.learner.agent.critic(),
                Some(SOLVER_VERSION),
            );
            write_json(&run.policy(), &saved)?;
            if self.config.snapshot_every > 0 && state.epoch % self.config.snapshot_every == 0 {
                std::fs::create_dir_all(run.snapshots())
                    .with_context(|| format!("cannot create {}", run.snapshots().display()))?;
                write_json(&run.snapshot(state.epoch), &saved)?;
            }
            // Ties go to the newer policy: same finals score, more training.
            if row.finals_success >= state.best_finals {
                write_json(&run.best_policy(), &saved)?;
            }
        }
        self.state.best_finals = self.state.best_finals.max(row.finals_success);
        let (agent, settings) = (&mut *self.learner.agent, (&self.config.shared, &self.config.algos));
        checkpoint::save(&self.mine.checkpoint(), &self.state, agent, settings, &self.replays, &mut self.replay_log)?;
        self.created.drain(..).for_each(crate::support::io::CreatedDir::keep);
        // Counted from the next epoch's wall time on (the checkpoint already holds this epoch's).
        self.persist_seconds = started.elapsed().as_secs_f64();
        self.state.wall_seconds += self.persist_seconds;
        Ok(())
    }
}

/// What a cycle's updates use: the learner, the buffers and the update count, apart from the
/// environments (which may be playing the next cycle meanwhile, [`Trainer::overlapped_cycles`]).
struct Learning<'t, 'c> {
    config: &'t TrainConfig,
    comm: &'c Comm,
    learner: &'t mut Learner,
    replays: &'t [ReplayBuffer],
    demos: Option<&'t ReplayBuffer>,
    updates: &'t mut u64,
    obs_dim: usize,
}

impl Learning<'_, '_> {
    /// `batches` gradient steps, then the end of the cycle (DDPG's targets follow).
    fn cycle(self, epoch: usize, cycle: usize, tally: &mut EpochTally) {
        let t = Instant::now();
        let config = self.config;
        let (e, c) = (epoch as u64, cycle as u64);
        let first = self.comm.rank() * config.workers;
        match config.replay_layout() {
            // One batch of batch_size × workers from the process's buffer.
            ReplayLayout::Shared => {
                let mut rng = ChaCha8Rng::seed_from_u64(stream_seed(config.seed, &[2, e, c]));
                for _ in 0..config.batches {
                    self.learner.agent.hold_actor(*self.updates < config.finetune.critic_warmup);
                    let n = config.batch_size * config.workers;
                    let batch = draw(&self.replays[0], self.demos, n, config.finetune.demos_ratio, &mut rng);
                    tally.stats.extend(self.learner.update(&[batch], first, self.comm, self.obs_dim));
                    *self.updates += 1;
                }
            }
            // One batch per worker, each from its own buffer and stream.
            ReplayLayout::PerWorker => {
                let mut rngs: Vec<ChaCha8Rng> = (0..config.workers)
                    .map(|w| ChaCha8Rng::seed_from_u64(stream_seed(config.seed, &[5, e, c, (first + w) as u64])))
                    .collect();
                for _ in 0..config.batches {
                    self.learner.agent.hold_actor(*self.updates < config.finetune.critic_warmup);
                    let (demos, ratio) = (self.demos, config.finetune.demos_ratio);
                    let batches: Vec<Batch> = self
                        .replays
                        .iter()
                        .zip(&mut rngs)
                        .map(|(r, rng)| draw(r, demos, config.batch_size, ratio, rng))
                        .collect();
                    tally.stats.extend(self.learner.update(&batches, first, self.comm, self.obs_dim));
                    *self.updates += 1;
                }
            }
        }
        self.learner.end_cycle();
        tally.update_seconds += t.elapsed().as_secs_f64();
    }
}

/// The run's tasks on every rank: rank 0 resolves them (see [`run_tasks`]) and
/// sends their recorded form to the others, so all ranks build the same tasks
/// even when their hosts' task files differ.
fn shared_tasks(
    comm: &Comm,
    config: &TrainConfig,
    run: &RunDir,
    saved: Option<&TrainConfig>,
) -> Result<(Vec<Task>, Option<crate::benchmark::stream::StreamRecord>)> {
    if comm.size() == 1 {
        return run_tasks(config, run, saved);
    }
    let mut bytes = Vec::new();
    let tasks = if comm.is_root() {
        let (tasks, stream) = run_tasks(config, run, saved)?;
        let sources: Vec<&crate::task::TaskSource> = tasks.iter().map(|t| &t.source).collect();
        bytes = serde_json::to_vec(&(sources, &stream))?;
        Some((tasks, stream))
    } else {
        None
    };
    comm.broadcast_bytes(&mut bytes);
    match tasks {
        Some(t) => Ok(t),
        None => {
            let (sources, stream): (Vec<crate::task::TaskSource>, Option<crate::benchmark::stream::StreamRecord>) =
                serde_json::from_slice(&bytes).with_context(|| "the tasks sent by rank 0".to_owned())?;
            Ok((sources.iter().map(registry::recorded).collect::<Result<_, _>>()?, stream))
        }
    }
}

/// The checkpoint this rank resumes from: its latest, or under MPI the
/// previous one when another rank stopped before writing the latest epoch
/// (every rank resumes from the last epoch all of them completed). Both
/// files are considered, so a rank stopped between setting its latest
/// checkpoint aside and writing the next one resumes from the one set aside.
fn resume_checkpoint(comm: &Comm, path: &Path, run: &RunDir) -> Result<PathBuf> {
    let candidates: Vec<(u64, PathBuf)> = [path.to_owned(), checkpoint::previous(path)]
        .into_iter()
        .filter(|p| p.exists())
        .map(|p| Ok((checkpoint::peek_state(&p)?.epoch as u64, p)))
        .collect::<Result<_, checkpoint::CheckpointError>>()?;
    let Some(latest) = candidates.iter().map(|c| c.0).max() else {
        refuse!(
            "--resume: no checkpoint for rank {} in {} ({}); start a new run without --resume",
            comm.rank(),
            run.dir.display(),
            path.display()
        );
    };
    let epoch = comm.gather_u64(latest).into_iter().min().unwrap_or(latest);
    match candidates.into_iter().find(|c| c.0 == epoch) {
        Some((_, p)) => Ok(p),
        None => refuse!(
            "--resume: rank {} has no checkpoint of epoch {epoch}, the last epoch every rank completed (its latest \
             is of epoch {latest}, in {}); the run cannot continue exactly",
            comm.rank(),
            path.display()
        ),
    }
}

/// User + system CPU seconds of this process so far.
fn cpu_seconds() -> f64 {
    // SAFETY: getrusage writes one rusage struct into the zeroed value we
    // pass; RUSAGE_SELF is always valid.
    let usage = unsafe {
        let mut u: libc::rusage = std::mem::zeroed();
        if libc::getrusage(libc::RUSAGE_SELF, &mut u) != 0 {
            return 0.0;
        }
        u
    };
    let secs = |t: libc::timeval| t.tv_sec as f64 + t.tv_usec as f64 * 1e-6;
    secs(usage.ru_utime) + secs(usage.ru_stime)
}
