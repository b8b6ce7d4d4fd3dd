//! Solver-imitation probe (issue 73): why does behaviour cloning of the solver plateau near half
//! the solver's success on the stream's families?
//!
//! Online BC mixes three questions: what the network can represent, how the optimiser fits it,
//! and what the data covers. This probe takes the environment loop out. It records the solver
//! (`ScriptedPolicy::solver`, which reads the `entities` observation alone) on a few tasks of
//! the stream's families once, holds out every fifth episode, then trains one or more students on
//! the same batches by regression onto the solver's actions, and plays each on the same tasks
//! from unseen episode seeds (the "fit" question: can it copy its teacher on its own tasks?).
//!
//! Each student is `--student NAME:key=value,...` (keys below; unset keys keep the recipe's
//! value: the entity set network, rows 64 wide, head 3 × 256, Adam 0.001, no decay):
//! `width`, `hidden`, `layers`, `encoder`, `lr`, `decay` (`none` or `cos`: cosine to 0 over the
//! steps), `pooling` (`mean-max`, `attention`, `colour`, `query`), `transformer` (blocks),
//! `tokens` (1: robot tokens), `typenorm` (1: statistics per row type).
//!
//! The data: per task, `--episodes` solver episodes from episode seed 0 on (seeds ≡ 0 mod 5 held
//! out), acted with Gaussian noise of `--noise` on the solver's action (DART) and labelled with
//! its clean action. Evaluation: `--eval-episodes` deterministic episodes per task from seed
//! 2,000,000 (no suite's seeds). Everything is fixed by the arguments: the same command prints
//! the same numbers.
//!
//! Usage: cargo run --release --example solver_probe -- --families push --tasks 16 \
//!   --student base: --student wide:width=256
//! (needs the stream cache or computes the pool: `--generator-seeds`, default 200..347)

use anyhow::{bail, Context, Result};
use blockpuzzle::benchmark::stream::{self, SeedRange};
use blockpuzzle::env::{EnvConfig, ObsMode, ObsSpec, ACTION_DIM};
use blockpuzzle::episode::outcome::{wilson95, Outcome, Outcomes};
use blockpuzzle::episode::rollout::{play_episode, run_episode, Event};
use blockpuzzle::learn::agents::arch::{Arch, NetConfig, NetKind, Pooling};
use blockpuzzle::learn::agents::nets::{append_grads, Adam, Net};
use blockpuzzle::policy::actor::normalizer::Normalizer;
use blockpuzzle::policy::actor::{AnyPolicy, DeterministicPolicy};
use blockpuzzle::policy::{Policy, ScriptedPolicy};
use blockpuzzle::task::Task;
use blockpuzzle::BlockEnv;
use clap::Parser;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};
use rayon::prelude::*;
use std::time::Instant;
use tch::{Kind, Tensor};

/// The first evaluation episode seed (no suite's: `evaluate::TEST_SEED` is the test set's).
const EVAL_SEED: u64 = 2_000_000;
/// Every fifth episode (seeds ≡ 0 mod 5) is held out for the validation error.
const VALIDATION_EVERY: u64 = 5;
/// Gradient steps between report lines.
const REPORT_EVERY: usize = 1000;
/// An action component off by more than this counts as a miss in the report.
const MISS: f64 = 0.25;

#[derive(Parser, Debug)]
#[command(about = "How well does an entity network imitate the solver on a few stream tasks, offline?")]
struct Args {
    /// Families of the stream (comma-separated names or files).
    #[arg(long, default_value = "push")]
    families: String,
    /// The stream's generator seeds.
    #[arg(long, default_value = "200..347")]
    generator_seeds: SeedRange,
    /// Tasks per family (the pool's first ones).
    #[arg(long, default_value_t = 8)]
    tasks: usize,
    /// Solver episodes per task (seeds 0, 1, …; those ≡ 0 mod 5 held out).
    #[arg(long, default_value_t = 50)]
    episodes: u64,
    /// Gaussian noise on the solver's acting action (its labels stay clean).
    #[arg(long, default_value_t = 0.0)]
    noise: f64,
    /// Gradient steps of each student.
    #[arg(long, default_value_t = 10_000)]
    steps: usize,
    /// Rows per gradient step.
    #[arg(long, default_value_t = 256)]
    batch: usize,
    /// Evaluation episodes per task.
    #[arg(long, default_value_t = 20)]
    eval_episodes: u64,
    /// Seed of the students' initial weights, the batches and the noise.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// libtorch threads.
    #[arg(long, default_value_t = 1)]
    torch_threads: usize,
    /// A student, `NAME:key=value,...` (see the file's header); repeat for more.
    #[arg(long, required = true)]
    student: Vec<String>,
}

fn main() -> Result<()> {
    blockpuzzle::learn::blas::ensure_fast_kernels();
    let args = Args::parse();
    tch::set_num_threads(blockpuzzle::learn::blas::torch_threads(args.torch_threads).map_err(anyhow::Error::msg)?);
    let started = Instant::now();
    let specs: Vec<StudentSpec> = args.student.iter().map(|s| StudentSpec::parse(s)).collect::<Result<_>>()?;

    let families = stream::families(&args.families)?;
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    let pool = stream::pool(&families, args.generator_seeds, threads, stream::cache_dir().as_deref(), false)?;
    let mut tasks: Vec<(String, Task)> = Vec::new();
    for (k, (name, _)) in families.iter().enumerate() {
        let of_family = pool.record.tasks.iter().zip(&pool.tasks).filter(|(r, _)| r.family == k);
        tasks.extend(of_family.take(args.tasks).map(|(_, t)| (name.clone(), t.clone())));
    }
    if tasks.is_empty() {
        bail!("no task in the pool of --families {} --generator-seeds {}", args.families, args.generator_seeds);
    }
    let slots = pool.record.max_blocks;
    println!(
        "{} tasks ({} per family of {}), {} block slots, {} episodes each, noise {}",
        tasks.len(),
        args.tasks,
        args.families,
        slots,
        args.episodes,
        args.noise
    );

    let parts: Vec<(Data, Data, usize, usize)> =
        tasks.par_iter().enumerate().map(|(i, (_, t))| collect(&args, i as u64, t, slots)).collect::<Result<_>>()?;
    let (mut train, mut val) = (Data::default(), Data::default());
    let (mut wins, mut episodes) = (0, 0);
    for (t, v, w, n) in parts {
        train.extend(t);
        val.extend(v);
        wins += w;
        episodes += n;
    }
    println!(
        "data: {} training rows, {} validation rows; the solver (noise {}) succeeded in {wins}/{episodes}; \
         validation MSE of the mean action {:.5}",
        train.len(),
        val.len(),
        args.noise,
        val.mse_to(&train.actions().mean_dim([0i64].as_slice(), true, Kind::Float))
    );

    let spec = ObsSpec::new(ObsMode::Entities, slots);
    let mut students: Vec<Student> =
        specs.iter().map(|s| Student::new(s, &spec, args.seed, &train)).collect::<Result<_>>()?;
    let (train_y, val_y) = (train.actions(), val.actions());
    let val_x: Vec<Tensor> = students.iter().map(|s| s.norm.tensor(&val.obs)).collect();
    let mut rng = ChaCha8Rng::seed_from_u64(args.seed);
    rng.set_stream(1);
    println!("\ntraining: {} steps of {} rows; per student: batch MSE, validation MSE, share of validation rows with a component off by > {MISS}, per-component validation MSE, update seconds", args.steps, args.batch);
    let mut recent = vec![0.0; students.len()];
    for step in 1..=args.steps {
        let rows: Vec<i64> = (0..args.batch).map(|_| rng.gen_range(0..train.len()) as i64).collect();
        let index = Tensor::of_slice(&rows);
        let y = train_y.index_select(0, &index);
        for (k, s) in students.iter_mut().enumerate() {
            s.set_lr(step, args.steps);
            recent[k] += s.update(&index, &y) / REPORT_EVERY as f64;
        }
        if step % REPORT_EVERY == 0 || step == args.steps {
            for (k, s) in students.iter().enumerate() {
                let (mse, miss, per) = s.validation(&val_x[k], &val_y);
                let per: Vec<String> = per.iter().map(|v| format!("{v:.4}")).collect();
                println!(
                    "step {step:>7} {:<12} {:.5} {mse:.5} {miss:.4} [{}] {:.0} s",
                    s.spec.name,
                    recent[k],
                    per.join(" "),
                    s.seconds
                );
                recent[k] = 0.0;
            }
        }
    }

    println!("\nevaluation: {} deterministic episodes per task from seed {EVAL_SEED}", args.eval_episodes);
    let mut header = vec!["solver".to_owned()];
    header.extend(students.iter().map(|s| s.spec.name.clone()));
    println!("| family | {} |", header.join(" | "));
    println!("|---|{}", "---:|".repeat(header.len()));
    let policies: Vec<DeterministicPolicy> = students.iter().map(Student::frozen).collect();
    let mut per_family: Vec<Vec<(Outcomes, Vec<usize>)>> = Vec::new();
    for (name, _) in &families {
        let of: Vec<&Task> = tasks.iter().filter(|(f, _)| f == name).map(|(_, t)| t).collect();
        let mut row = Vec::new();
        for player in 0..=policies.len() {
            let results: Vec<(Outcomes, Vec<usize>)> = of
                .par_iter()
                .map(|t| {
                    let mut p: Box<dyn Policy> = match player {
                        0 => Box::new(ScriptedPolicy::solver(slots)),
                        k => Box::new(AnyPolicy::Deterministic(policies[k - 1].clone())),
                    };
                    evaluate(t, slots, p.as_mut(), args.eval_episodes)
                })
                .collect::<Result<_>>()?;
            let mut tally = Outcomes::default();
            let mut steps = Vec::new();
            for (o, s) in results {
                tally = tally.merge(o);
                steps.extend(s);
            }
            row.push((tally, steps));
        }
        let cells: Vec<String> = row.iter().map(|(t, s)| describe(t, s)).collect();
        println!("| {name} | {} |", cells.join(" | "));
        per_family.push(row);
    }
    for (f, (name, _)) in families.iter().enumerate() {
        for (p, (tally, _)) in per_family[f].iter().enumerate() {
            println!("{name} {}: not successful: {}", header[p], tally.summary());
        }
    }
    println!("\nwall time {:.1} s", started.elapsed().as_secs_f64());
    Ok(())
}

/// Recorded steps: observations and the solver's clean actions, row by row.
#[derive(Default)]
struct Data {
    obs: Vec<f32>,
    act: Vec<f32>,
}

impl Data {
    fn len(&self) -> usize {
        self.act.len() / ACTION_DIM
    }
    fn extend(&mut self, other: Data) {
        self.obs.extend(other.obs);
        self.act.extend(other.act);
    }
    fn actions(&self) -> Tensor {
        Tensor::of_slice(&self.act).view([-1, ACTION_DIM as i64])
    }
    fn mse_to(&self, prediction: &Tensor) -> f64 {
        (self.actions() - prediction).square().mean(Kind::Float).double_value(&[])
    }
}

/// The environment of `task` at its top level, `entities` observations with `slots` block slots.
fn make_env(task: &Task, slots: usize) -> Result<BlockEnv> {
    let mut env = BlockEnv::new(EnvConfig { obs_mode: ObsMode::Entities, slots, ..EnvConfig::new(task.clone()) })?;
    env.set_level(env.max_level())?;
    Ok(env)
}

/// The solver acting with Gaussian noise of `sigma` (clipped to the action box).
struct Noisy {
    solver: ScriptedPolicy,
    noise: Option<Normal<f64>>,
    rng: ChaCha8Rng,
}

impl Policy for Noisy {
    fn act(&mut self, obs: &[f32]) -> [f32; ACTION_DIM] {
        let clean = self.solver.act(obs);
        match &self.noise {
            None => clean,
            Some(n) => clean.map(|a| (a as f64 + n.sample(&mut self.rng)).clamp(-1.0, 1.0) as f32),
        }
    }
    fn reads(&self) -> Option<ObsMode> {
        self.solver.reads()
    }
}

/// Task `index`'s solver episodes: training rows, validation rows, successes, episodes.
fn collect(args: &Args, index: u64, task: &Task, slots: usize) -> Result<(Data, Data, usize, usize)> {
    let mut env = make_env(task, slots)?;
    let noise = (args.noise > 0.0).then(|| Normal::new(0.0, args.noise)).transpose()?;
    let mut rng = ChaCha8Rng::seed_from_u64(args.seed);
    rng.set_stream(1000 + index);
    let mut actor = Noisy { solver: ScriptedPolicy::solver(slots), noise, rng };
    let labeller = ScriptedPolicy::solver(slots);
    let (mut train, mut val, mut wins) = (Data::default(), Data::default(), 0);
    for seed in 0..args.episodes {
        let data = if seed % VALIDATION_EVERY == 0 { &mut val } else { &mut train };
        let mut success = false;
        play_episode(&mut env, &mut actor, seed, |event| {
            if let Event::Step { obs, step, .. } = event {
                data.obs.extend_from_slice(obs);
                data.act.extend_from_slice(&labeller.decide(obs).0);
                success |= step.info.is_success;
            }
        })
        .with_context(|| format!("{} episode {seed}", task.id()))?;
        wins += usize::from(success);
    }
    Ok((train, val, wins, args.episodes as usize))
}

/// What a `--student` asks for.
#[derive(Debug, Clone)]
struct StudentSpec {
    name: String,
    net: NetConfig,
    hidden: usize,
    layers: usize,
    lr: f64,
    cosine: bool,
}

impl StudentSpec {
    fn parse(text: &str) -> Result<Self> {
        let Some((name, rest)) = text.split_once(':') else {
            bail!("--student {text:?}: give NAME:key=value,... (NAME: alone for the recipe's network)");
        };
        let mut s = StudentSpec {
            name: name.to_owned(),
            net: NetConfig { net: NetKind::Entity, set_width: 64, ..NetConfig::default() },
            hidden: 256,
            layers: 3,
            lr: 1e-3,
            cosine: false,
        };
        for item in rest.split(',').filter(|i| !i.is_empty()) {
            let Some((key, value)) = item.split_once('=') else {
                bail!("--student {text:?}: {item:?} is no key=value")
            };
            let bad = || anyhow::anyhow!("--student {text:?}: {key}={value:?} is not a valid value");
            match key {
                "width" => s.net.set_width = value.parse().map_err(|_| bad())?,
                "hidden" => s.hidden = value.parse().map_err(|_| bad())?,
                "layers" => s.layers = value.parse().map_err(|_| bad())?,
                "encoder" => s.net.set_encoder_layers = value.parse().map_err(|_| bad())?,
                "lr" => s.lr = value.parse().map_err(|_| bad())?,
                "decay" => s.cosine = matches!(value, "cos"),
                "transformer" => s.net.set_transformer = value.parse().map_err(|_| bad())?,
                "tokens" => s.net.set_robot_tokens = value == "1",
                "typenorm" => s.net.set_type_norm = value == "1",
                "pooling" => {
                    s.net.set_pooling = match value {
                        "mean-max" => Pooling::MeanMax,
                        "attention" => Pooling::Attention,
                        "colour" => Pooling::Colour,
                        "query" => Pooling::Query,
                        _ => return Err(bad()),
                    }
                }
                _ => bail!("--student {text:?}: unknown key {key:?}"),
            }
        }
        Ok(s)
    }
}

/// One student: its network, normaliser (fitted once on the training rows) and optimiser.
struct Student {
    spec: StudentSpec,
    net: Net,
    norm: Normalizer,
    opt: Adam,
    train_x: Tensor,
    seconds: f64,
}

impl Student {
    fn new(spec: &StudentSpec, obs: &ObsSpec, seed: u64, train: &Data) -> Result<Self> {
        let arch = Arch::of(obs, &spec.net).map_err(anyhow::Error::msg)?;
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let net = arch.net((spec.hidden, spec.layers), 0, ACTION_DIM, true, &mut rng);
        let mut norm = arch.normalizer(0.01, 5.0);
        norm.update(&train.obs);
        let train_x = norm.tensor(&train.obs);
        let opt = Adam::new(&net.params, spec.lr);
        Ok(Self { spec: spec.clone(), net, norm, opt, train_x, seconds: 0.0 })
    }

    fn set_lr(&mut self, step: usize, steps: usize) {
        if self.spec.cosine {
            let progress = (step - 1) as f64 / steps as f64;
            self.opt.lr = self.spec.lr * 0.5 * (1.0 + (std::f64::consts::PI * progress).cos());
        }
    }

    /// One Adam step on the batch `index` (labels `y`); its MSE before the step.
    fn update(&mut self, index: &Tensor, y: &Tensor) -> f64 {
        let start = Instant::now();
        let x = self.train_x.index_select(0, index);
        let loss = (self.net.forward(&x) - y).square().mean(Kind::Float);
        self.net.zero_grad();
        loss.backward();
        let mut grads = Vec::new();
        append_grads(&self.net.params, &mut grads);
        self.opt.step(&mut self.net.params, &grads);
        self.seconds += start.elapsed().as_secs_f64();
        loss.double_value(&[])
    }

    /// Validation MSE, the share of rows with a component off by more than [`MISS`], per-component MSE.
    fn validation(&self, x: &Tensor, y: &Tensor) -> (f64, f64, Vec<f64>) {
        tch::no_grad(|| {
            let err = self.net.forward(x) - y;
            let sq = err.square();
            let mse = sq.mean(Kind::Float).double_value(&[]);
            let worst = err.abs().amax([1i64].as_slice(), false);
            let miss = worst.gt(MISS).to_kind(Kind::Float).mean(Kind::Float).double_value(&[]);
            let per = sq.mean_dim([0i64].as_slice(), false, Kind::Float);
            (mse, miss, (0..ACTION_DIM as i64).map(|k| per.double_value(&[k])).collect())
        })
    }

    fn frozen(&self) -> DeterministicPolicy {
        DeterministicPolicy { net: self.net.to_plain(), norm: self.norm.clone() }
    }
}

/// `episodes` deterministic episodes of `policy` on `task` from [`EVAL_SEED`]: outcomes, steps of the successes.
fn evaluate(task: &Task, slots: usize, policy: &mut dyn Policy, episodes: u64) -> Result<(Outcomes, Vec<usize>)> {
    let mut env = make_env(task, slots)?;
    let mut tally = Outcomes::default();
    let mut steps = Vec::new();
    for seed in EVAL_SEED..EVAL_SEED + episodes {
        let ep =
            run_episode(&mut env, policy, seed).with_context(|| format!("{} evaluation seed {seed}", task.id()))?;
        if ep.success {
            steps.push(ep.steps.len());
        }
        tally.add(Outcome::of(&ep));
    }
    Ok((tally, steps))
}

/// Success with its Wilson 95% interval and the median steps of the successes.
fn describe(tally: &Outcomes, steps: &[usize]) -> String {
    let n = tally.total();
    let (low, high) = wilson95(tally.success, n);
    let mut s = steps.to_vec();
    s.sort_unstable();
    let median = s.get(s.len() / 2).map_or("–".to_owned(), |m| m.to_string());
    format!("{:.3} [{low:.2}, {high:.2}] ({median} steps)", tally.success as f64 / n.max(1) as f64)
}
