//! `blockpuzzle bench` (env steps/s and mj_step/s; with `--train`, training's collection and
//! update rates) and `align` (the replay of gymnasium-robotics FetchPush-v4 episodes).

use anyhow::{bail, Result};
use std::path::Path;

#[derive(Debug, clap::Args)]
pub(super) struct BenchArgs {
    /// Environment id or task file (.toml).
    #[arg(long, default_value = "BlocksTouch-v0")]
    env: String,
    /// Steps per thread.
    #[arg(long, default_value_t = 20_000, value_parser = crate::support::limits::BENCH_STEPS.parser::<usize>())]
    steps: usize,
    /// Threads, each stepping its own environment.
    #[arg(long, default_value_t = 1, value_parser = crate::support::limits::THREADS.parser::<usize>())]
    threads: usize,
    /// Print one JSON line instead of text.
    #[arg(long)]
    json: bool,
    /// Turn the robot collision filter off (to measure what it saves).
    #[arg(long)]
    no_collision_filter: bool,
    /// Measure training instead (`--algo`, DDPG by default): env steps/s while
    /// collecting with the exploring actor (replay insert included) and
    /// gradient updates/s. `--ddpg` is another name for it.
    #[arg(long = "train", alias = "ddpg", conflicts_with_all = ["threads", "no_collision_filter"])]
    pub(super) train: bool,
    /// With --train: collection workers, each stepping its own environment.
    #[arg(long, default_value_t = 1, requires = "train", value_parser = crate::learn::train::WORKERS.parser::<usize>())]
    workers: usize,
    /// With --train: gradient updates to time.
    #[arg(long, default_value_t = 300, requires = "train", value_parser = crate::learn::bench::BENCH_UPDATES.parser::<usize>())]
    updates: usize,
    /// With --train: transitions per update batch.
    #[arg(long, default_value_t = 256, requires = "train", value_parser = crate::learn::train::BATCH_SIZE.parser::<usize>())]
    batch_size: usize,
    /// With --train: threads libtorch may use for the updates (at most the number of cores).
    #[arg(long, default_value_t = 1, requires = "train", value_parser = crate::support::limits::COUNT.parser::<usize>())]
    torch_threads: usize,
    /// With --train: seed of networks, layouts and noise.
    #[arg(long, default_value_t = 0, requires = "train", value_parser = crate::support::limits::SEED.parser::<u64>())]
    seed: u64,
    /// With --train: arithmetic of the updates' hidden-layer products.
    #[arg(long, value_enum, default_value = "f32", requires = "train")]
    precision: crate::learn::agents::shared::Precision,
    /// With --train: the algorithm whose collection and updates to time (any of `train --algo`).
    #[arg(long, default_value = "ddpg", requires = "train", value_parser = crate::learn::agents::registry::Algo::parser())]
    algo: crate::learn::agents::registry::Algo,
    /// With --train: the networks, `mlp` on the flat observation or `set` on the `objects` one (as `train --net`).
    #[arg(long, value_enum, default_value = "mlp", requires = "train")]
    net: crate::learn::agents::arch::NetKind,
    /// With --train --net set: `mean-max` or `attention` (as `train --set-pooling`).
    #[arg(long, value_enum, default_value = "mean-max", requires = "train")]
    set_pooling: crate::learn::agents::arch::Pooling,
    /// With --train --net set: layer-normalise the pooled features (as `train --set-norm`).
    #[arg(long, requires = "train")]
    set_norm: bool,
    /// With --train --net set: the encoder reads robot tokens (as `train --set-robot-tokens`).
    #[arg(long, requires = "train")]
    set_robot_tokens: bool,
    /// With --train --net entity: statistics per row type (as `train --set-type-norm`).
    #[arg(long, requires = "train")]
    set_type_norm: bool,
    /// With --train --net set: pre-LayerNorm transformer blocks (as `train --set-transformer`).
    #[arg(long, default_value_t = 0, requires = "train", value_parser = crate::learn::agents::arch::SET_TRANSFORMER.parser::<usize>())]
    set_transformer: usize,
    /// With --train --net set: the width of the per-row layers (as `train --set-width`).
    #[arg(long, default_value_t = 0, requires = "train", value_parser = crate::learn::agents::arch::SET_WIDTH.parser::<usize>())]
    set_width: usize,
    /// With --train --net set: the critics are MLPs (as `train --flat-critic`).
    #[arg(long, requires = "train")]
    flat_critic: bool,
}

/// `align --bench-steps`: env steps/s of the FetchPush-like scene from the reference's first state.
pub(super) fn align_bench(reference: &Path, steps: usize, threads: usize) -> Result<()> {
    let r = crate::episode::align::Reference::load(reference)?;
    let Some(ep) = r.episodes.first() else { bail!("{} holds no episodes", reference.display()) };
    let start = |env: &mut crate::env::BlockEnv, _: Option<u64>| {
        let (q, v) = crate::episode::align::start_state(env, ep)
            .map_err(|e| crate::env::EnvError::BadState { reason: e.to_string() })?;
        env.set_state(&q, &v)
    };
    let report = crate::benchmark::throughput::run_with(
        "FetchPush-like",
        &crate::episode::align::fetchpush_like,
        &start,
        steps,
        threads,
    )?;
    println!("{}", serde_json::to_string(&report)?);
    Ok(())
}

/// `blockpuzzle align`: the replay's per-episode deviations, and their plot.
pub(super) fn align(reference: &Path, plot: Option<&Path>) -> Result<()> {
    let r = crate::episode::align::Reference::load(reference)?;
    let title = format!(
        "FetchPush-v4 (gymnasium-robotics {}, MuJoCo {}) against FetchPush-like on MuJoCo {}",
        r.gymnasium_robotics,
        r.mujoco,
        crate::sim::mj::version()
    );
    println!("{title}");
    println!("| episode | steps | gripper max (m) | block max (m) | worst step |\n|---|---|---|---|---|");
    let all = crate::episode::align::replay_all(&r)?;
    for d in &all {
        println!(
            "| {} {} | {} | {:.2e} | {:.2e} | {} |",
            d.kind, d.seed, d.steps, d.grip_max, d.object_max, d.worst_step
        );
    }
    if let Some(png) = plot {
        let episodes: Vec<(String, Vec<[f64; 2]>)> =
            all.iter().map(|d| (format!("{} {}", d.kind, d.seed), d.per_step.clone())).collect();
        crate::learn::train::plot::deviations(png, &title, &episodes, crate::episode::align::TOLERANCE)?;
        println!("wrote {}", png.display());
    }
    Ok(())
}

/// `bench --train`: collection env steps/s and update rate.
pub(super) fn train(a: BenchArgs) -> Result<()> {
    let r = crate::learn::bench::run(&crate::learn::bench::TrainBenchConfig {
        env: a.env,
        workers: a.workers,
        steps: a.steps,
        updates: a.updates,
        batch_size: a.batch_size,
        torch_threads: a.torch_threads,
        seed: a.seed,
        precision: a.precision,
        algo: a.algo,
        net: crate::learn::agents::arch::NetConfig {
            net: a.net,
            set_pooling: a.set_pooling,
            set_norm: a.set_norm,
            set_robot_tokens: a.set_robot_tokens,
            set_type_norm: a.set_type_norm,
            set_transformer: a.set_transformer,
            set_width: a.set_width,
            ..Default::default()
        },
        flat_critic: a.flat_critic,
    })?;
    if a.json {
        println!("{}", serde_json::to_string(&r)?);
    } else {
        println!(
            "{:?} ({}) on {}: {} worker(s), {} torch thread(s), batch {}, {:?}\n  env steps/s (collect) {:>8.0}  ({:.0}% in the actor)\n  updates/s             {:>8.1}",
            r.algo, r.net, r.env, r.workers, r.threads, r.batch_size, r.precision, r.env_steps_per_s, 100.0 * r.forward_fraction, r.updates_per_s
        );
    }
    Ok(())
}

/// `blockpuzzle bench`: env steps/s and mj_step/s.
pub(super) fn run(a: &BenchArgs) -> Result<()> {
    let r = crate::benchmark::throughput::run(&a.env, a.steps, a.threads, !a.no_collision_filter)?;
    if a.json {
        println!("{}", serde_json::to_string(&r)?);
    } else {
        println!(
            "{}{}: {} thread(s) x {} steps in {:.2} s\n  env steps/s   {:>10.0}\n  mj_step/s     {:>10.0}\n  env overhead  {:>9.2}% of a step",
            r.env,
            if r.collision_filter { "" } else { " (no collision filter)" },
            r.threads,
            r.steps, r.seconds, r.env_steps_per_s, r.mj_steps_per_s, 100.0 * r.overhead_fraction
        );
    }
    Ok(())
}
