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
//! `tokens` (1: robot tokens), `typenorm` (1: statistics per row type), `heads` (K ≥ 2: K action
//! heads and K logits trained by multiple-choice learning: the squared error of the nearest head,
//! a little of every head's, and cross-entropy on which head was nearest; acting takes the most
//! likely head, so a label that is "left or right of red" is not averaged into "straight on"),
//! `balance` (1: each row of a batch from a family drawn uniformly, then a row of it, instead of a
//! row drawn uniformly from all: every family gets the same share of the updates whatever the
//! length of its episodes), `family` (1: one action head per family of `--families`, each trained
//! on its family's rows alone and acting on its family's tasks: the trunk is shared, the last layer
//! is not; the family is given, so this measures whether the families compete for one function).
//!
//! The data: per task, `--episodes` solver episodes from episode seed 0 on (seeds ≡ 0 mod 5 held
//! out), acted with Gaussian noise of `--noise` on the solver's action (DART) and labelled with
//! its clean action. Evaluation: `--eval-episodes` deterministic episodes per task from seed
//! 2,000,000 (no suite's seeds). Everything is fixed by the arguments: the same command prints
//! the same numbers. `--trace N` prints, for the solver and each student, one line per failed
//! evaluation episode (the first N a family): a character a step for the phase the state is in
//! (travelling, over a blue block, at it, holding it, over green; fingers open or not) and a digit
//! where the count of blue blocks on green changes, which shows where a pick-and-place stalls.
//! Each DAgger round prints its rows by that phase (the student's mean action beside the solver's
//! mean label), and the last steps of the first failed episode of the first two tasks, what the
//! student played beside what the solver labels there.
//!
//! Usage: cargo run --release --example solver_probe -- --families push --tasks 16 \
//!   --student base: --student wide:width=256
//! (needs the stream cache or computes the pool: `--generator-seeds`, default 200..347)

use anyhow::{bail, Context, Result};
use blockpuzzle::benchmark::stream::{self, SeedRange};
use blockpuzzle::env::{EnvConfig, Fixture, ObsMode, ObsSpec, ACTION_DIM, OBJECT_FEATURES, ROBOT_OBS};
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
    /// DAgger rounds after the first training: each student plays `--dagger-episodes` episodes per
    /// task, the solver labels every step, the rows join that student's, and it trains
    /// `--dagger-steps` more steps.
    #[arg(long, default_value_t = 0)]
    dagger: usize,
    /// Episodes per task in each DAgger round.
    #[arg(long, default_value_t = 50)]
    dagger_episodes: u64,
    /// Gradient steps after each DAgger round.
    #[arg(long, default_value_t = 3000)]
    dagger_steps: usize,
    /// Label every row with the mean of the solver's actions at the gripper moved by 0 and by ±SMOOTH
    /// metres along each axis (seven observations; the object rows' relative positions follow): a
    /// teacher smoothed over a few millimetres around each state. 0: the solver's own action.
    #[arg(long, default_value_t = 0.0)]
    smooth: f64,
    /// Add to the training rows each one's mirror image across the vertical plane along the
    /// table's long axis (y reflected about the table's centre: positions, velocities, the
    /// fingers swapped, rotations conjugated), labelled by the solver on the mirrored observation
    /// (it is a function of the observation, so any state can be labelled): twice the rows for
    /// the same episodes. The validation rows stay the recorded ones. Prints how often the
    /// solver's label of a mirror image is the mirror image of its label (its equivariance).
    #[arg(long)]
    mirror: bool,
    /// libtorch threads.
    #[arg(long, default_value_t = 1)]
    torch_threads: usize,
    /// Print the coarse phase trace (one character a step, [`phase_char`]) of the first N failed
    /// evaluation episodes per family of the solver and of each student: where an episode stalls.
    #[arg(long, default_value_t = 0)]
    trace: usize,
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

    let family_of = |name: &str| families.iter().position(|(f, _)| f == name).unwrap_or(0);
    let parts: Vec<(Data, Data, usize, usize)> = tasks
        .par_iter()
        .enumerate()
        .map(|(i, (f, t))| collect(&args, i as u64, family_of(f), t, slots))
        .collect::<Result<_>>()?;
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
        specs.iter().map(|s| Student::new(s, &spec, args.seed, &train, families.len())).collect::<Result<_>>()?;
    let (val_y, val_f) = (val.actions(), val.families());
    let val_x: Vec<Tensor> = students.iter().map(|s| s.norm.tensor(&val.obs)).collect();
    let mut rng = ChaCha8Rng::seed_from_u64(args.seed);
    rng.set_stream(1);
    println!("\ntraining: {} steps of {} rows; per student: batch MSE, validation MSE, share of validation rows with a component off by > {MISS}, per-component validation MSE, update seconds", args.steps, args.batch);
    fit(&mut students, args.steps, args.batch, &mut rng, &val_x, &val_y, &val_f);
    for round in 1..=args.dagger {
        println!(
            "\nDAgger round {round}: {} episodes per task played by each student, labelled by the solver",
            args.dagger_episodes
        );
        for s in students.iter_mut() {
            let player = s.frozen();
            let parts: Vec<(Data, usize)> = tasks
                .par_iter()
                .enumerate()
                .map(|(i, (f, t))| {
                    let show = (i < 2).then_some(i);
                    let labeller = Labeller::new(slots, args.smooth);
                    dagger_episodes(
                        args.dagger_episodes,
                        round,
                        (family_of(f), t),
                        &labeller,
                        player(family_of(f)),
                        show,
                    )
                })
                .collect::<Result<_>>()?;
            let mut data = Data::default();
            let mut wins = 0;
            for (d, w) in parts {
                data.extend(d);
                wins += w;
            }
            let episodes = args.dagger_episodes as usize * tasks.len();
            println!(
                "{:<12} succeeded in {wins}/{episodes} of its own episodes; {} rows added",
                s.spec.name,
                data.len()
            );
            phase_labels(&spec, &data);
            s.add(&data);
        }
        fit(&mut students, args.dagger_steps, args.batch, &mut rng, &val_x, &val_y, &val_f);
    }

    println!("\nevaluation: {} deterministic episodes per task from seed {EVAL_SEED}", args.eval_episodes);
    let mut header = vec!["solver".to_owned()];
    header.extend(students.iter().map(|s| s.spec.name.clone()));
    println!("| family | {} |", header.join(" | "));
    println!("|---|{}", "---:|".repeat(header.len()));
    type Frozen = Box<dyn Fn(usize) -> Box<dyn Policy> + Sync>;
    let policies: Vec<Frozen> = students.iter().map(Student::frozen).collect();
    // Player 0 is the solver, player k the k-th student, each as it acts on a task of family `name`.
    let player_of = |player: usize, name: &str| -> Box<dyn Policy> {
        match player {
            0 => Box::new(ScriptedPolicy::solver(slots)),
            k => policies[k - 1](family_of(name)),
        }
    };
    let mut per_family: Vec<Vec<(Outcomes, Vec<usize>)>> = Vec::new();
    for (name, _) in &families {
        let of: Vec<&Task> = tasks.iter().filter(|(f, _)| f == name).map(|(_, t)| t).collect();
        let mut row = Vec::new();
        for player in 0..=policies.len() {
            let results: Vec<(Outcomes, Vec<usize>)> = of
                .par_iter()
                .map(|t| {
                    let mut p = player_of(player, name);
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
    if args.trace > 0 {
        println!("\nphase traces of failed episodes (. travel, D over a blue not on green, C at a blue not holding, H holding a blue, G over green not holding; `,` and `g`: `.` and `G` with the fingers not open; a digit: blues on green changed to it; the last: the outcome)");
        for (name, _) in &families {
            let of: Vec<&Task> = tasks.iter().filter(|(f, _)| f == name).map(|(_, t)| t).collect();
            for (player, who) in header.iter().enumerate() {
                let mut shown = 0;
                'tasks: for t in &of {
                    let mut env = make_env(t, slots)?;
                    let mut p = player_of(player, name);
                    for seed in EVAL_SEED..EVAL_SEED + args.eval_episodes {
                        let (success, trace) = trace_episode(&mut env, p.as_mut(), seed, slots)?;
                        if !success {
                            println!("{name} {who} {} seed {seed}: {trace}", t.id());
                            shown += 1;
                            if shown >= args.trace {
                                break 'tasks;
                            }
                        }
                    }
                }
            }
        }
    }
    println!("\nwall time {:.1} s", started.elapsed().as_secs_f64());
    Ok(())
}

/// `steps` Adam steps of every student, each on `batch` of its own rows (the same uniform draws
/// for all, mapped to rows by [`Student::row`]), with a report every [`REPORT_EVERY`] steps.
fn fit(
    students: &mut [Student],
    steps: usize,
    batch: usize,
    rng: &mut ChaCha8Rng,
    val_x: &[Tensor],
    val_y: &Tensor,
    val_f: &Tensor,
) {
    let mut recent = vec![0.0; students.len()];
    let balance = students.iter().any(|s| s.spec.balance);
    for step in 1..=steps {
        // A family draw only where a student balances, so that the others' batches do not depend on it.
        let draws: Vec<(f64, f64)> =
            (0..batch).map(|_| (if balance { rng.gen::<f64>() } else { 0.0 }, rng.gen::<f64>())).collect();
        for (k, s) in students.iter_mut().enumerate() {
            s.set_lr(step, steps);
            let rows: Vec<i64> = draws.iter().map(|&d| s.row(d)).collect();
            recent[k] += s.update(&Tensor::of_slice(&rows)) / REPORT_EVERY as f64;
        }
        if step % REPORT_EVERY == 0 || step == steps {
            for (k, s) in students.iter().enumerate() {
                let (mse, miss, per) = s.validation(&val_x[k], val_y, val_f);
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
}

/// The first episode seed of DAgger's rounds (apart from the recorded 0.. and the evaluation's).
const DAGGER_SEED: u64 = 1_000_000;

/// `episodes` episodes of `task` played by `policy` (DAgger round `round`'s seeds), every step
/// labelled with the solver's action; the rows and the policy's successes.
fn dagger_episodes(
    episodes: u64,
    round: usize,
    (family, task): (usize, &Task),
    labeller: &Labeller,
    mut policy: Box<dyn Policy>,
    show: Option<usize>,
) -> Result<(Data, usize)> {
    let slots = labeller.slots;
    let mut env = make_env(task, slots)?;
    let (mut data, mut wins, mut shown) = (Data::default(), 0, false);
    let first = DAGGER_SEED + round as u64 * episodes;
    for seed in first..first + episodes {
        let start = data.len();
        let success = record(&mut env, policy.as_mut(), seed, (labeller, family), &mut data)
            .with_context(|| format!("{} DAgger episode {seed}", task.id()))?;
        wins += usize::from(success);
        if let (Some(i), false, false) = (show, success, shown) {
            shown = true;
            // The first failed episode of the first tasks, its last steps: what the student played
            // and what the solver labels there.
            let spec = ObsSpec::new(ObsMode::Entities, slots);
            let dim = spec.dim();
            let mut text = format!("  task {i}, {} DAgger episode {seed} (failed), its last 16 steps: phase, grip z, aperture, finger speed; played; label\n", task.id());
            for r in data.len().saturating_sub(16).max(start)..data.len() {
                let obs = &data.obs[r * dim..(r + 1) * dim];
                let row = |v: &[f32]| {
                    v[r * ACTION_DIM..(r + 1) * ACTION_DIM]
                        .iter()
                        .map(|x| format!("{x:+.2}"))
                        .collect::<Vec<_>>()
                        .join(" ")
                };
                text += &format!(
                    "    {} {:.3} {:.4} {:.4}   {}   {}\n",
                    phase_char(&spec, obs).0,
                    obs[2],
                    obs[3] + obs[4],
                    obs[8].abs() + obs[9].abs(),
                    row(&data.played),
                    row(&data.act)
                );
            }
            print!("{text}");
        }
    }
    Ok((data, wins))
}

/// Recorded steps: observations and the solver's clean actions, row by row.
#[derive(Default)]
struct Data {
    obs: Vec<f32>,
    act: Vec<f32>,
    /// Each row's family (its index in `--families`).
    family: Vec<usize>,
    /// The action played in each row (the labeller's own under no noise; a student's in DAgger).
    played: Vec<f32>,
}

impl Data {
    fn len(&self) -> usize {
        self.act.len() / ACTION_DIM
    }
    fn extend(&mut self, other: Data) {
        self.obs.extend(other.obs);
        self.act.extend(other.act);
        self.family.extend(other.family);
        self.played.extend(other.played);
    }
    fn actions(&self) -> Tensor {
        Tensor::of_slice(&self.act).view([-1, ACTION_DIM as i64])
    }
    /// Each row's family, `[rows]` i64.
    fn families(&self) -> Tensor {
        Tensor::of_slice(&self.family.iter().map(|&f| f as i64).collect::<Vec<i64>>())
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
fn collect(args: &Args, index: u64, family: usize, task: &Task, slots: usize) -> Result<(Data, Data, usize, usize)> {
    let mut env = make_env(task, slots)?;
    let noise = (args.noise > 0.0).then(|| Normal::new(0.0, args.noise)).transpose()?;
    let mut rng = ChaCha8Rng::seed_from_u64(args.seed);
    rng.set_stream(1000 + index);
    let mut actor = Noisy { solver: ScriptedPolicy::solver(slots), noise, rng };
    let labeller = Labeller::new(slots, args.smooth);
    let (mut train, mut val, mut wins) = (Data::default(), Data::default(), 0);
    for seed in 0..args.episodes {
        let data = if seed % VALIDATION_EVERY == 0 { &mut val } else { &mut train };
        let success = record(&mut env, &mut actor, seed, (&labeller, family), data)
            .with_context(|| format!("{} episode {seed}", task.id()))?;
        wins += usize::from(success);
    }
    if args.mirror {
        let spec = ObsSpec::new(ObsMode::Entities, slots);
        let (dim, rows) = (spec.dim(), train.len());
        let mut images = Data::default();
        for r in 0..rows {
            let image = mirror_y(&spec, &train.obs[r * dim..(r + 1) * dim]);
            let label = labeller.label(&image);
            let a = &train.act[r * ACTION_DIM..(r + 1) * ACTION_DIM];
            let mirrored = [a[0], -a[1], a[2], a[3]];
            if label.iter().zip(mirrored).all(|(x, y)| (x - y).abs() <= 1e-3) {
                images.played.push(1.0);
            } else {
                images.played.push(0.0);
            }
            images.obs.extend_from_slice(&image);
            images.act.extend_from_slice(&label);
            images.family.push(family);
        }
        // `played` is not read for training rows; here it holds whether each label was equivariant.
        let equivariant = images.played.iter().sum::<f32>() as usize;
        println!("{}: {equivariant} of {rows} mirrored labels are the mirror image of the row's label", task.id());
        images.played = vec![0.0; rows * ACTION_DIM];
        train.extend(images);
    }
    Ok((train, val, wins, args.episodes as usize))
}

/// `obs` (the `entities` layout of `spec`) mirrored across the vertical plane y = the table's
/// centre: every present row's y position reflected, its y offset and y velocity negated, its
/// rotation conjugated by the reflection (Euler x and z negated, as are the angular velocity's x
/// and z: a pseudovector), and the two fingers swapped. The action mirrors as (x, -y, z, grip).
fn mirror_y(spec: &ObsSpec, obs: &[f32]) -> Vec<f32> {
    let at = |name: &str| OBJECT_FEATURES.iter().position(|f| *f == name).expect("a feature of OBJECT_FEATURES");
    let dim = spec.object_dim();
    let table = spec.fixture_row(Fixture::Table).expect("the entities layout has a table row");
    let centre = obs[ROBOT_OBS + table * dim + at("pos.y")];
    let mask: Vec<f32> = spec.mask(obs).expect("the entities layout has a mask").to_vec();
    let mut out = obs.to_vec();
    out[1] = 2.0 * centre - obs[1];
    out[6] = -obs[6];
    out.swap(3, 4);
    out.swap(8, 9);
    for (r, present) in mask.iter().enumerate() {
        if *present == 0.0 {
            continue;
        }
        let row = &mut out[ROBOT_OBS + r * dim..ROBOT_OBS + (r + 1) * dim];
        row[at("pos.y")] = 2.0 * centre - row[at("pos.y")];
        for name in ["rel_pos.y", "rel_velp.y", "euler.x", "euler.z", "velr.x", "velr.z"] {
            row[at(name)] = -row[at(name)];
        }
    }
    out
}

/// The solver as the rows' labeller, its action smoothed over `smooth` metres of the gripper's place
/// (`--smooth`).
struct Labeller {
    solver: ScriptedPolicy,
    spec: ObsSpec,
    slots: usize,
    smooth: f64,
}

impl Labeller {
    fn new(slots: usize, smooth: f64) -> Self {
        Labeller { solver: ScriptedPolicy::solver(slots), spec: ObsSpec::new(ObsMode::Entities, slots), slots, smooth }
    }

    fn label(&self, obs: &[f32]) -> [f32; ACTION_DIM] {
        if self.smooth == 0.0 {
            return self.solver.decide(obs).0;
        }
        let rel = blockpuzzle::env::OBJECT_FEATURES.iter().position(|f| *f == "rel_pos.x").unwrap_or(3);
        let (dim, rows) = (self.spec.object_dim(), self.spec.rows());
        let mut sum = [0.0f64; ACTION_DIM];
        let mut moved = obs.to_vec();
        let offsets = std::iter::once((0, 0.0)).chain((0..3).flat_map(|k| [(k, self.smooth), (k, -self.smooth)]));
        let mut n = 0;
        for (axis, by) in offsets {
            moved.copy_from_slice(obs);
            moved[axis] += by as f32;
            for r in 0..rows {
                moved[ROBOT_OBS + r * dim + rel + axis] -= by as f32;
            }
            let a = self.solver.decide(&moved).0;
            for k in 0..ACTION_DIM {
                sum[k] += f64::from(a[k]);
            }
            n += 1;
        }
        sum.map(|v| (v / n as f64) as f32)
    }
}

/// Episode `seed` played by `policy`, every step's observation with `labeller`'s action (rows of
/// `family`) added to `data`; whether it succeeded.
fn record(
    env: &mut BlockEnv,
    policy: &mut dyn Policy,
    seed: u64,
    (labeller, family): (&Labeller, usize),
    data: &mut Data,
) -> Result<bool> {
    let mut success = false;
    play_episode(env, policy, seed, |event| {
        if let Event::Step { obs, step, action, .. } = event {
            data.obs.extend_from_slice(obs);
            data.act.extend_from_slice(&labeller.label(obs));
            data.played.extend_from_slice(action);
            data.family.push(family);
            success |= step.info.is_success;
        }
    })?;
    Ok(success)
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
    /// Action heads (1: plain regression).
    heads: usize,
    /// Draw a batch's rows family by family (uniform over families, then over its rows).
    balance: bool,
    /// One action head per family, chosen by the row's (the task's) family.
    per_family: bool,
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
            heads: 1,
            balance: false,
            per_family: false,
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
                "balance" => s.balance = value == "1",
                "family" => s.per_family = value == "1",
                "heads" => {
                    s.heads = value.parse().map_err(|_| bad())?;
                    if s.heads == 0 {
                        return Err(bad());
                    }
                }
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
    train_y: Tensor,
    /// Its training rows (the recorded ones and those its DAgger rounds added).
    rows: usize,
    /// Each family that has rows (its index in `--families`) with its rows, in the order first seen.
    groups: Vec<(usize, Vec<i64>)>,
    /// Each training row's family.
    train_f: Tensor,
    /// The families (the heads of a `family=1` student).
    families: usize,
    seconds: f64,
}

impl Student {
    fn new(spec: &StudentSpec, obs: &ObsSpec, seed: u64, train: &Data, families: usize) -> Result<Self> {
        let arch = Arch::of(obs, &spec.net)?;
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        if spec.per_family && spec.heads > 1 {
            bail!("--student {}: family=1 and heads=K are two ways to have several heads; take one", spec.name);
        }
        let net = match spec.heads {
            _ if spec.per_family => arch.net((spec.hidden, spec.layers), 0, families * ACTION_DIM, false, &mut rng),
            1 => arch.net((spec.hidden, spec.layers), 0, ACTION_DIM, true, &mut rng),
            k => arch.net((spec.hidden, spec.layers), 0, k * (ACTION_DIM + 1), false, &mut rng),
        };
        let mut norm = arch.normalizer(0.01, 5.0);
        norm.update(&train.obs);
        let train_x = norm.tensor(&train.obs);
        let opt = Adam::new(&net.params, spec.lr);
        let (train_y, rows) = (train.actions(), train.len());
        let train_f = train.families();
        let mut s = Self {
            spec: spec.clone(),
            net,
            norm,
            opt,
            train_x,
            train_y,
            rows: 0,
            groups: Vec::new(),
            train_f,
            families,
            seconds: 0.0,
        };
        s.group(&train.family);
        s.rows = rows;
        Ok(s)
    }

    /// Files rows `self.rows..` (of families `family`) into their families' groups.
    fn group(&mut self, family: &[usize]) {
        for (k, &f) in family.iter().enumerate() {
            let at = match self.groups.iter().position(|(g, _)| *g == f) {
                Some(at) => at,
                None => {
                    self.groups.push((f, Vec::new()));
                    self.groups.len() - 1
                }
            };
            self.groups[at].1.push((self.rows + k) as i64);
        }
    }

    /// The row of a batch that the uniform draws `(u, v)` pick.
    fn row(&self, (u, v): (f64, f64)) -> i64 {
        let pick = |n: usize, x: f64| ((x * n as f64) as usize).min(n - 1);
        if self.spec.balance {
            let (_, g) = &self.groups[pick(self.groups.len(), u)];
            g[pick(g.len(), v)]
        } else {
            pick(self.rows, v) as i64
        }
    }

    /// More training rows (normalised with the statistics fitted on the recorded ones).
    fn add(&mut self, data: &Data) {
        self.train_x = Tensor::cat(&[&self.train_x, &self.norm.tensor(&data.obs)], 0);
        self.train_y = Tensor::cat(&[&self.train_y, &data.actions()], 0);
        self.train_f = Tensor::cat(&[&self.train_f, &data.families()], 0);
        self.group(&data.family);
        self.rows += data.len();
    }

    fn set_lr(&mut self, step: usize, steps: usize) {
        if self.spec.cosine {
            let progress = (step - 1) as f64 / steps as f64;
            self.opt.lr = self.spec.lr * 0.5 * (1.0 + (std::f64::consts::PI * progress).cos());
        }
    }

    /// One Adam step on its training rows `index`; the batch's loss before the step (its MSE with one head).
    fn update(&mut self, index: &Tensor) -> f64 {
        let start = Instant::now();
        let x = self.train_x.index_select(0, index);
        let y = &self.train_y.index_select(0, index);
        let loss = match self.spec.heads {
            _ if self.spec.per_family => {
                let f = self.train_f.index_select(0, index);
                (family_head(&self.net.forward(&x), &f, self.families) - y).square().mean(Kind::Float)
            }
            1 => (self.net.forward(&x) - y).square().mean(Kind::Float),
            k => choice_loss(&self.net.forward(&x), y, k),
        };
        self.net.zero_grad();
        loss.backward();
        let mut grads = Vec::new();
        append_grads(&self.net.params, &mut grads);
        self.opt.step(&mut self.net.params, &grads);
        self.seconds += start.elapsed().as_secs_f64();
        loss.double_value(&[])
    }

    /// Validation MSE, the share of rows with a component off by more than [`MISS`], per-component MSE.
    fn validation(&self, x: &Tensor, y: &Tensor, f: &Tensor) -> (f64, f64, Vec<f64>) {
        tch::no_grad(|| {
            let err = self.predict(x, f) - y;
            let sq = err.square();
            let mse = sq.mean(Kind::Float).double_value(&[]);
            let worst = err.abs().amax([1i64].as_slice(), false);
            let miss = worst.gt(MISS).to_kind(Kind::Float).mean(Kind::Float).double_value(&[]);
            let per = sq.mean_dim([0i64].as_slice(), false, Kind::Float);
            (mse, miss, (0..ACTION_DIM as i64).map(|k| per.double_value(&[k])).collect())
        })
    }

    /// The action: the network's (one head), its family's head's (rows of families `f`) or its most
    /// likely head's.
    fn predict(&self, x: &Tensor, f: &Tensor) -> Tensor {
        match self.spec.heads {
            _ if self.spec.per_family => family_head(&self.net.forward(x), f, self.families),
            1 => self.net.forward(x),
            k => chosen(&self.net.forward(x), k),
        }
    }

    /// A maker of the student's policy for a task of family `f`.
    fn frozen(&self) -> Box<dyn Fn(usize) -> Box<dyn Policy> + Sync> {
        let plain = DeterministicPolicy { net: self.net.to_plain(), norm: self.norm.clone() };
        let (heads, per_family) = (self.spec.heads, self.spec.per_family);
        Box::new(move |f| match heads {
            _ if per_family => Box::new(FamilyHead { policy: plain.clone(), family: f }),
            1 => Box::new(AnyPolicy::Deterministic(plain.clone())),
            k => Box::new(Chooser { policy: plain.clone(), heads: k }),
        })
    }
}

/// The action of each row's family's head (through tanh), `[B, A]`, from an output of `families`
/// heads and the rows' families `f` (`[B]`, i64).
fn family_head(out: &Tensor, f: &Tensor, families: usize) -> Tensor {
    let heads = out.view([-1, families as i64, ACTION_DIM as i64]);
    let pick = f.view([-1, 1, 1]).expand([-1, 1, ACTION_DIM as i64].as_slice(), false);
    heads.gather(1, &pick, false).squeeze_dim(1).tanh()
}

/// A `family=1` network as the policy of one family's tasks: that family's head.
struct FamilyHead {
    policy: DeterministicPolicy,
    family: usize,
}

impl Policy for FamilyHead {
    fn act(&mut self, obs: &[f32]) -> [f32; ACTION_DIM] {
        let out = self.policy.act(obs);
        std::array::from_fn(|c| out[self.family * ACTION_DIM + c].tanh())
    }
}

/// Heads' actions `[B, K, A]` (through tanh) and logits `[B, K]` from a `k`-head output.
fn split_heads(out: &Tensor, k: usize) -> (Tensor, Tensor) {
    let a = (k * ACTION_DIM) as i64;
    let mu = out.narrow(1, 0, a).tanh().view([-1, k as i64, ACTION_DIM as i64]);
    let logits = out.narrow(1, a, k as i64);
    (mu, logits)
}

/// The most likely head's action, `[B, A]`.
fn chosen(out: &Tensor, k: usize) -> Tensor {
    let (mu, logits) = split_heads(out, k);
    let best = logits.argmax(1, true).unsqueeze(2).expand([-1, 1, ACTION_DIM as i64].as_slice(), false);
    mu.gather(1, &best, false).squeeze_dim(1)
}

/// Share of the loss every head gets beside the nearest one's (so that no head is left untrained).
const OTHER_HEADS: f64 = 0.05;

/// Multiple-choice learning (Guzman-Rivera et al. 2012; relaxed as Rupprecht et al. 2017): the
/// per-component squared error of the head nearest each label, plus [`OTHER_HEADS`] of every
/// head's, plus cross-entropy of the logits on the nearest head.
fn choice_loss(out: &Tensor, y: &Tensor, k: usize) -> Tensor {
    let (mu, logits) = split_heads(out, k);
    let err = (mu - y.unsqueeze(1)).square().mean_dim([2i64].as_slice(), false, Kind::Float);
    let nearest = err.argmin(1, false);
    let fit = err.min_dim(1, false).0.mean(Kind::Float) * (1.0 - OTHER_HEADS) + err.mean(Kind::Float) * OTHER_HEADS;
    fit + logits.cross_entropy_for_logits(&nearest)
}

/// A `heads`-head network as a policy: the most likely head's action.
struct Chooser {
    policy: DeterministicPolicy,
    heads: usize,
}

impl Policy for Chooser {
    fn act(&mut self, obs: &[f32]) -> [f32; ACTION_DIM] {
        let out = self.policy.act(obs);
        let logits = &out[self.heads * ACTION_DIM..];
        let best = (0..self.heads).fold(0, |b, h| if logits[h] > logits[b] { h } else { b });
        std::array::from_fn(|c| out[best * ACTION_DIM + c].tanh())
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

/// One episode of `policy`: whether it succeeded, and its coarse phase trace ([`phase_char`]).
fn trace_episode(env: &mut BlockEnv, policy: &mut dyn Policy, seed: u64, slots: usize) -> Result<(bool, String)> {
    let spec = ObsSpec::new(ObsMode::Entities, slots);
    let (mut trace, mut success, mut failure, mut placed) = (String::new(), false, false, 0);
    play_episode(env, policy, seed, |event| {
        if let Event::Step { obs, step, .. } = event {
            let (c, on) = phase_char(&spec, obs);
            if on != placed {
                trace.push_str(&on.to_string());
                placed = on;
            }
            trace.push(c);
            success |= step.info.is_success;
            failure |= step.info.is_failure;
        }
    })?;
    let end = if success {
        "success"
    } else if failure {
        "red touched blue"
    } else {
        "no verdict"
    };
    Ok((success, format!("{trace} {end}")))
}

/// A coarse phase of a pick-and-place state, read off `obs` as the solver reads it: `H` holding a
/// blue block (the grip within 2 cm of it, fingers closed on something), `C` at a blue block not
/// holding it, `D` within 1.5 cm above a blue block not on green, `G` over the green block, `.`
/// elsewhere; and how many blue blocks sit on green. A diagnostic only (not the solver's phases).
fn phase_char(spec: &ObsSpec, obs: &[f32]) -> (char, usize) {
    let size_at = blockpuzzle::env::OBJECT_FEATURES.len();
    let present = |k: usize| spec.mask(obs).map_or(true, |m| m.get(k).is_some_and(|&v| v > 0.5));
    let rows: Vec<(usize, [f64; 3], [f64; 3])> = spec
        .objects(obs)
        .enumerate()
        .filter(|&(k, r)| present(k) && ObsSpec::colour(r).iter().any(|&v| v > 0.5))
        .map(|(_, r)| {
            let hot = ObsSpec::colour(r);
            let c = (0..hot.len()).max_by(|&i, &j| hot[i].total_cmp(&hot[j])).unwrap_or(3);
            (c, std::array::from_fn(|k| r[k] as f64), std::array::from_fn(|k| r[size_at + k] as f64))
        })
        .collect();
    let grip = [obs[0] as f64, obs[1] as f64, obs[2] as f64];
    let aperture = (obs[3] + obs[4]) as f64;
    let xy = |a: [f64; 3], b: [f64; 3]| (a[0] - b[0]).hypot(a[1] - b[1]);
    let green = rows.iter().find(|r| r.0 == 2);
    let on_green = |p: [f64; 3], s: [f64; 3]| {
        green.is_some_and(|&(_, g, gs)| {
            (p[0] - g[0]).abs() < gs[0] && (p[1] - g[1]).abs() < gs[1] && (p[2] - g[2] - gs[2] - s[2]).abs() < 0.006
        })
    };
    let blues: Vec<&(usize, [f64; 3], [f64; 3])> = rows.iter().filter(|r| r.0 == 1).collect();
    let placed = blues.iter().filter(|b| on_green(b.1, b.2)).count();
    let at = |b: &&(usize, [f64; 3], [f64; 3])| xy(grip, b.1) < 0.02 && (grip[2] - b.1[2]).abs() < 0.02;
    let c = if blues.iter().any(|b| at(b) && (0.02..0.07).contains(&aperture)) {
        'H'
    } else if blues.iter().any(at) {
        'C'
    } else if blues.iter().any(|b| !on_green(b.1, b.2) && xy(grip, b.1) < 0.015 && grip[2] > b.1[2]) {
        'D'
    } else if green
        .is_some_and(|&(_, g, gs)| (grip[0] - g[0]).abs() < gs[0] + 0.03 && (grip[1] - g[1]).abs() < gs[1] + 0.03)
    {
        if aperture < 0.07 {
            'g'
        } else {
            'G'
        }
    } else if aperture < 0.07 {
        ','
    } else {
        '.'
    };
    (c, placed)
}

/// DAgger's rows by [`phase_char`]: how many, the mean action the student played and the mean label
/// the solver gave (x, y, z, gripper), and the share of rows whose gripper command has the other sign.
fn phase_labels(spec: &ObsSpec, data: &Data) {
    let dim = spec.dim();
    let mut by: std::collections::BTreeMap<char, (usize, [f64; ACTION_DIM], [f64; ACTION_DIM], usize)> =
        Default::default();
    // The holding rows by the label's height command: what the fingers show in each.
    let mut buckets = [(0usize, 0.0f64, 0.0f64, 0.0f64, 0.0f64); 3];
    for r in 0..data.len() {
        let obs = &data.obs[r * dim..(r + 1) * dim];
        let (played, label) = (&data.played[r * ACTION_DIM..][..ACTION_DIM], &data.act[r * ACTION_DIM..][..ACTION_DIM]);
        let (c, _) = phase_char(spec, obs);
        let e = by.entry(c).or_default();
        e.0 += 1;
        for k in 0..ACTION_DIM {
            e.1[k] += f64::from(played[k]);
            e.2[k] += f64::from(label[k]);
        }
        e.3 += usize::from((played[3] > 0.0) != (label[3] > 0.0));
        if c == 'H' {
            let b = &mut buckets[if label[2] < -0.1 {
                0
            } else if label[2] <= 0.1 {
                1
            } else {
                2
            }];
            b.0 += 1;
            b.1 += f64::from(obs[8].abs() + obs[9].abs());
            b.2 += f64::from(obs[8] + obs[9]);
            b.3 += f64::from(obs[3] + obs[4]);
            b.4 += f64::from(label[3]);
        }
    }
    println!("  phase   rows   played (x y z grip)            label (x y z grip)             grip sign differs");
    for (c, (n, played, label, flips)) in by {
        let mean = |v: [f64; ACTION_DIM]| v.map(|x| format!("{:+.2}", x / n as f64)).join(" ");
        println!("  {c}     {n:>6}   {}   {}   {:.2}", mean(played), mean(label), flips as f64 / n as f64);
    }
    println!(
        "  H rows by the label's z: rows, mean finger speed |v1|+|v2|, mean v1+v2, mean aperture, mean label grip"
    );
    for (name, (n, speed, vel, aperture, g)) in ["z < -0.1", "|z| <= 0.1", "z > 0.1"].iter().zip(buckets) {
        let m = |v: f64| v / n.max(1) as f64;
        println!("  {name:<11} {n:>6}   {:.4}   {:+.4}   {:.4}   {:+.2}", m(speed), m(vel), m(aperture), m(g));
    }
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
