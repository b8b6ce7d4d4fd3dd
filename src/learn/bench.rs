//! Training throughput (DDPG by default; `--algo` any registered
//! algorithm) as training sees it, in the two numbers people compare RL
//! libraries by: environment steps per second while collecting with the
//! exploring actor, and gradient updates per second.
//!
//! * Collection runs the training loop's own path: every worker steps its
//!   environment in its own thread with the plain-Rust actor plus
//!   exploration noise, then the transitions go into the replay buffer and
//!   the normaliser (timed).
//! * Updates are full updates of the algorithm (DDPG: critic and actor
//!   step; a gradient, then its optimiser step) on batches of `batch_size`
//!   drawn from those transitions, with libtorch using `torch_threads`
//!   threads, plus one end of cycle (target update) per 40 batches as in a
//!   training cycle.
//!
//! The networks are untrained (seeded), which does not change the cost of a
//! forward pass or an update.

use crate::env::registry;
use crate::learn::agents::algorithm::{Algorithm, Spec};
use crate::learn::agents::arch::{Arch, NetConfig};
use crate::learn::agents::registry::{Algo, AlgoConfigs};
use crate::learn::agents::replay::ReplayBuffer;
use crate::learn::agents::shared::{Precision, SharedConfig};
use crate::learn::train::{play_all, stream_seed, Behaviour, TrainError};
use crate::support::limits::Bound;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use serde::Serialize;
use std::time::Instant;

/// This module's results: a refused setting, an environment or a rollout that failed.
type Result<T, E = TrainError> = std::result::Result<T, E>;

/// Gradient updates of `bench --ddpg`.
pub const BENCH_UPDATES: Bound = Bound::new("--updates", 1, 1_000_000, "");

/// What to measure.
#[derive(Debug, Clone)]
pub struct TrainBenchConfig {
    /// Environment id or task file (.toml).
    pub env: String,
    /// Workers stepping environments in parallel during collection.
    pub workers: usize,
    /// Environment steps to collect (at least; whole episodes are played).
    pub steps: usize,
    /// Gradient updates to time.
    pub updates: usize,
    /// Transitions per update batch.
    pub batch_size: usize,
    /// Threads libtorch may use for the updates.
    pub torch_threads: usize,
    /// Seed of the networks, layouts and noise.
    pub seed: u64,
    /// Arithmetic of the updates' hidden-layer products.
    pub precision: Precision,
    /// The algorithm.
    pub algo: Algo,
    /// The networks (`train --net`).
    pub net: NetConfig,
    /// A set actor's critics are MLPs (`train --flat-critic`).
    pub flat_critic: bool,
}

/// Measured rates.
#[derive(Debug, Clone, Serialize)]
pub struct TrainBenchReport {
    /// Always "blockpuzzle".
    pub r#impl: &'static str,
    /// The algorithm.
    pub algo: Algo,
    /// The networks: "mlp", "set network", "set network + attention", "set network, flat critics", ….
    pub net: String,
    /// Environment id.
    pub env: String,
    /// Collection workers.
    pub workers: usize,
    /// libtorch threads during the updates.
    pub threads: usize,
    /// Transitions per update batch.
    pub batch_size: usize,
    /// Arithmetic of the updates' hidden-layer products.
    pub precision: Precision,
    /// Environment steps per second while collecting (actor forward, noise,
    /// environment step, replay insert, normaliser update), all workers.
    pub env_steps_per_s: f64,
    /// Share of the collection time spent in the actor and noise.
    pub forward_fraction: f64,
    /// Gradient updates per second.
    pub updates_per_s: f64,
    /// Environment steps timed.
    pub steps: usize,
    /// Seconds of the timed collection.
    pub collect_seconds: f64,
    /// Updates timed.
    pub updates: usize,
    /// Seconds of the timed updates.
    pub train_seconds: f64,
    /// Transitions in the replay buffer during the updates.
    pub buffer_transitions: usize,
    /// OpenBLAS' kernel family, when known.
    pub openblas_core: Option<String>,
}

/// Environment steps in the warm-up before the timed collection.
const WARMUP_STEPS: usize = 200;
/// Updates before the timed ones.
const WARMUP_UPDATES: usize = 20;

/// Runs the benchmark.
///
/// # Errors
/// Unknown environment id, zero counts, environment failures.
pub fn run(c: &TrainBenchConfig) -> Result<TrainBenchReport> {
    use crate::learn::bench::BENCH_UPDATES;
    use crate::learn::train::{BATCH_SIZE, WORKERS};
    use crate::support::limits::BENCH_STEPS;
    for (bound, v) in
        [(WORKERS, c.workers), (BENCH_STEPS, c.steps), (BENCH_UPDATES, c.updates), (BATCH_SIZE, c.batch_size)]
    {
        bound.check_usize(v).map_err(TrainError::Refused)?;
    }
    if c.torch_threads == 0 {
        return Err(TrainError::Refused("--torch-threads must be at least 1".into()));
    }
    let shared = SharedConfig { precision: c.precision, flat_critic: c.flat_critic, ..SharedConfig::default() };
    let algos = AlgoConfigs::default();
    // The options table `train` goes by: a bench setting the timed run would not use is refused.
    crate::learn::train::options::check(&crate::learn::train::options::Options {
        algo: c.algo,
        net: &c.net,
        shared: &shared,
        algos: &algos,
        aggrevated: &Default::default(),
        hindsight_colours: 0,
        hindsight_strategy_given: false,
    })
    .map_err(TrainError::Refused)?;
    tch::set_num_threads(crate::learn::blas::torch_threads(c.torch_threads).map_err(TrainError::Refused)?);
    let task = registry::task(&c.env)?;
    let env_config = crate::env::EnvConfig { obs_mode: c.net.obs_mode(), ..crate::env::EnvConfig::new(task) };
    let mut envs = crate::env::vector::VectorEnv::new(&env_config, c.workers, c.workers)?;
    let (obs_dim, act_dim) = (envs.obs_spec().dim(), crate::env::ACTION_DIM);
    let arch = Arch::of(&envs.obs_spec(), &c.net).map_err(|e| TrainError::Refused(e.to_string()))?;
    c.precision.check().map_err(TrainError::Refused)?;
    let gamma = shared.gamma;
    let spec = Spec { arch, act_dim, shared: &shared };
    let mut agent = c.algo.build(&spec, &algos, &mut ChaCha8Rng::seed_from_u64(c.seed));
    let mut replay = ReplayBuffer::new(obs_dim, act_dim, 1_000_000);

    // Collect: one episode per worker per round, as in a training cycle.
    let mut round = 0u64;
    let mut collect =
        |target: usize, replay: &mut ReplayBuffer, agent: &mut dyn Algorithm| -> Result<(usize, f64, f64)> {
            let (mut steps, mut forward) = (0usize, 0.0);
            let t = Instant::now();
            while steps < target {
                let explorer = agent.explorer();
                let behaviour = Behaviour::exploring(agent, &*explorer, 0);
                let eps = play_all(&mut envs, &behaviour, 1, |w, _| stream_seed(c.seed, &[9, w as u64, round]))?;
                round += 1;
                for ep in &eps {
                    steps += ep.len();
                    forward += ep.forward_seconds;
                    ep.store(replay, agent.norm_mut(), gamma, 1);
                }
            }
            Ok((steps, t.elapsed().as_secs_f64(), forward / c.workers as f64))
        };
    collect(WARMUP_STEPS, &mut replay, &mut *agent)?;
    let (steps, collect_seconds, forward_seconds) = collect(c.steps, &mut replay, &mut *agent)?;

    // Update.
    let mut rng = ChaCha8Rng::seed_from_u64(stream_seed(c.seed, &[10]));
    let mut update = |agent: &mut dyn Algorithm| {
        let (gradient, _) = agent.gradient(&replay.sample(c.batch_size, &mut rng), 0, None);
        agent.apply_gradient(&gradient);
    };
    for _ in 0..WARMUP_UPDATES {
        update(&mut *agent);
    }
    let t = Instant::now();
    for k in 0..c.updates {
        update(&mut *agent);
        if (k + 1) % 40 == 0 {
            agent.end_cycle();
        }
    }
    let train_seconds = t.elapsed().as_secs_f64();

    Ok(TrainBenchReport {
        r#impl: "blockpuzzle",
        algo: c.algo,
        net: match (c.net.describe(), c.flat_critic) {
            (d, _) if d.is_empty() => "mlp".into(),
            (d, true) => format!("{d}, flat critics"),
            (d, false) => d,
        },
        env: c.env.clone(),
        workers: c.workers,
        threads: c.torch_threads,
        batch_size: c.batch_size,
        precision: c.precision,
        env_steps_per_s: steps as f64 / collect_seconds,
        forward_fraction: forward_seconds / collect_seconds,
        updates_per_s: c.updates as f64 / train_seconds,
        steps,
        collect_seconds,
        updates: c.updates,
        train_seconds,
        buffer_transitions: replay.len(),
        openblas_core: crate::learn::blas::openblas_core(),
    })
}
