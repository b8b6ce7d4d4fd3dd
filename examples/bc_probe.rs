//! Behaviour-cloning probe: can a permutation-invariant set actor (`--net set`) imitate a good
//! flat policy on BlocksChoose-v0 as fast and as well as the flat MLP actor?
//!
//! With reinforcement learning the set actor learns about twice as slowly per environment step
//! as the MLP. This probe takes RL out of the picture: it rolls out a zoo expert (a flat MLP
//! policy), then trains both actors by regression on the expert's actions, on the same batches
//! with the same optimiser, and compares how fast the error falls and how well each student
//! then plays. A set actor that imitates as fast and as well points at RL (the critic, credit
//! assignment, exploration) rather than at what the network can represent or how it optimises.
//!
//! Data: the expert's episodes of seeds 0, 1, … at the maximum level, one in four (seeds ≡ 3
//! mod 4) from the challenge distribution, observed in the `objects` mode; the expert acts on
//! each observation's flat view. Episodes of seeds ≡ 0 mod 5 are held out for validation.
//! Evaluation: deterministic episodes from seed 2,000,000 on, normal and challenge.
//! `--seed` fixes the students' initial weights and their batches; the episodes are fixed by
//! their own seeds, so the same arguments print the same numbers.
//!
//! Usage: cargo run --release --example bc_probe -- [options]
//! (defaults: --episodes 200 --steps 3000 --eval-episodes 100 --seed 0 --torch-threads 1
//! --expert BlocksChoose-v0-ddpg-ours)

use anyhow::{bail, ensure, Context, Result};
use blockpuzzle::benchmark::evaluate::Trained;
use blockpuzzle::env::{ObsMode, ObsSpec, ACTION_DIM, BLOCK_OBS};
use blockpuzzle::episode::outcome::{wilson95, Outcome, Outcomes};
use blockpuzzle::episode::rollout::{play_episode, run_episode, Event};
use blockpuzzle::learn::agents::arch::{Arch, NetConfig, NetKind};
use blockpuzzle::learn::agents::nets::{append_grads, Adam, Net};
use blockpuzzle::learn::agents::shared::SharedConfig;
use blockpuzzle::policy::actor::{AnyPolicy, DeterministicPolicy};
use blockpuzzle::policy::Policy;
use blockpuzzle::BlockEnv;
use clap::Parser;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::path::{Path, PathBuf};
use std::time::Instant;
use tch::{Kind, Tensor};

/// The task the probe runs on.
const ENV_ID: &str = "BlocksChoose-v0";
/// The students' Adam learning rate (DDPG's actor's default).
const LR: f64 = 1e-3;
/// Rows per gradient step.
const BATCH: usize = 256;
/// Gradient steps between report lines.
const REPORT_EVERY: usize = 250;
/// The first evaluation seed (validation seeds: `evaluate::TEST_SEED` is the test set's).
const EVAL_SEED: u64 = 2_000_000;
/// Every fifth episode (seeds ≡ 0 mod 5) is held out for validation.
const VALIDATION_EVERY: u64 = 5;
/// Every fourth episode (seeds ≡ 3 mod 4) is a challenge one, where the task has that distribution.
const CHALLENGE_EVERY: u64 = 4;

#[derive(Parser, Debug)]
#[command(about = "Can a set actor imitate a flat expert on BlocksChoose-v0 as well as an MLP actor?")]
struct Args {
    /// Expert episodes to learn from (seeds 0, 1, …; those ≡ 0 mod 5 are the validation set).
    #[arg(long, default_value_t = 200)]
    episodes: u64,
    /// Gradient steps of each student.
    #[arg(long, default_value_t = 3000)]
    steps: usize,
    /// Evaluation episodes per distribution (normal, and challenge), from seed 2,000,000.
    #[arg(long, default_value_t = 100)]
    eval_episodes: u64,
    /// Seed of the students' initial weights and of the batches.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// libtorch threads (0: one per core).
    #[arg(long, default_value_t = 1)]
    torch_threads: usize,
    /// The expert: a zoo name, a policy file or a run directory (as `blockpuzzle eval --checkpoint`).
    #[arg(long, default_value = "BlocksChoose-v0-ddpg-ours")]
    expert: PathBuf,
}

impl Args {
    /// Refuses arguments the probe cannot run with, saying why.
    fn check(&self) -> Result<()> {
        ensure!(
            (2..=100_000).contains(&self.episodes),
            "--episodes {} is out of range: give 2 to 100000 (seed 0 is held out for validation, so at least \
             seed 1 is needed for training)",
            self.episodes
        );
        ensure!((1..=1_000_000).contains(&self.steps), "--steps {} is out of range: give 1 to 1000000", self.steps);
        ensure!(
            (1..=100_000).contains(&self.eval_episodes),
            "--eval-episodes {} is out of range: give 1 to 100000",
            self.eval_episodes
        );
        Ok(())
    }
}

fn main() -> Result<()> {
    blockpuzzle::learn::blas::ensure_fast_kernels();
    let args = Args::parse();
    args.check()?;
    tch::set_num_threads(blockpuzzle::learn::blas::torch_threads(args.torch_threads).map_err(anyhow::Error::msg)?);
    let started = Instant::now();

    // The same task twice: the `objects` observation the data and the students use, and the
    // flat one the expert was trained on (to fit the expert and to check the flat view).
    let mut objects_env = make_env(ObsMode::Objects)?;
    let mut flat_env = make_env(ObsMode::Flat)?;
    let challenge = objects_env.config().task.distribution("challenge").is_some();
    let expert = load_expert(&args.expert, &flat_env)?;
    println!(
        "{ENV_ID} at level {}, `objects` observation ({} values, {} object slots); expert {}",
        objects_env.max_level(),
        objects_env.obs_spec().dim(),
        objects_env.obs_spec().max_objects,
        args.expert.display()
    );
    if !challenge {
        println!("{ENV_ID} has no challenge distribution: every episode is a normal one");
    }

    let checked = check_flat_view(&expert, &mut objects_env, &mut flat_env, 0, false)?
        + if challenge { check_flat_view(&expert, &mut objects_env, &mut flat_env, 3, true)? } else { 0 };
    let episodes = if challenge { "seed 0 (normal) and seed 3 (challenge)" } else { "seed 0" };
    println!("flat view check: the flat views of {checked} observations of {episodes} equal the flat environment's");

    let (train, val) = collect(&expert, &mut objects_env, args.episodes, challenge)?;
    println!(
        "data: {} training rows, {} validation rows; validation MSE of the mean training action: {:.5}",
        train.len(),
        val.len(),
        val.mse_of_mean(&train)
    );

    let students = train_students(&args, &objects_env.obs_spec(), &train, &val)?;

    println!("\nevaluation: {} deterministic episodes per distribution from seed {EVAL_SEED}", args.eval_episodes);
    let spec = objects_env.obs_spec();
    let mut players: Vec<(&str, Box<dyn Policy>)> = vec![("expert", Box::new(Viewed::flat(expert, spec)))];
    players.extend(students.iter().map(|s| (s.name, s.policy(spec))));
    let distributions: &[bool] = if challenge { &[false, true] } else { &[false] };
    for &on in distributions {
        for (name, policy) in &mut players {
            let tally = evaluate(&mut objects_env, policy.as_mut(), args.eval_episodes, on)?;
            println!("{:<9} {:<6} {}", if on { "challenge" } else { "normal" }, name, describe(&tally));
        }
    }
    println!("\nwall time {:.1} s", started.elapsed().as_secs_f64());
    Ok(())
}

/// The task at its maximum level, observed as `mode`.
fn make_env(mode: ObsMode) -> Result<BlockEnv> {
    let mut env = blockpuzzle::make(ENV_ID).with_context(|| format!("cannot build {ENV_ID}"))?;
    env.set_obs_mode(mode);
    env.set_level(env.max_level())?;
    Ok(env)
}

/// Loads the expert as `blockpuzzle eval --checkpoint NAME` does, fitted to the flat environment.
fn load_expert(name: &Path, flat_env: &BlockEnv) -> Result<Trained> {
    let saved = blockpuzzle::benchmark::load::load_policy(name)
        .with_context(|| format!("cannot load --expert {}", name.display()))?;
    if saved.obs_mode() != ObsMode::Flat {
        bail!("--expert {} is a set network; the probe imitates a flat (MLP) policy", name.display());
    }
    if saved.env_id != ENV_ID {
        eprintln!("note: --expert {} was trained on {}, not {ENV_ID}", name.display(), saved.env_id);
    }
    Ok(blockpuzzle::benchmark::evaluate::trained_policy(name, saved, flat_env)?)
}

/// The flat view of an `objects` observation laid out as `spec`: the robot features, then the
/// first [`BLOCK_OBS`] features of each object row in slot order (an `objects` row appends the
/// object's half extents to the flat row; an absent object's row is zero in both layouts).
/// `ObsSpec::keep_objects` keeps or drops whole rows, so it cannot cut the half extents off.
fn flat_view(spec: &ObsSpec, obs: &[f32]) -> Vec<f32> {
    let mut flat = spec.robot(obs).to_vec();
    for row in spec.objects(obs) {
        flat.extend_from_slice(&row[..BLOCK_OBS]);
    }
    flat
}

/// A policy playing in the `objects` environment: it reads the observation as it is, or
/// (`flat_of` its layout) the flat view of it.
struct Viewed<P> {
    policy: P,
    flat_of: Option<ObsSpec>,
}

impl<P> Viewed<P> {
    /// `policy`, which reads flat observations, fed the flat view of observations laid out as `spec`.
    fn flat(policy: P, spec: ObsSpec) -> Self {
        Self { policy, flat_of: Some(spec) }
    }
}

impl<P: Policy> Policy for Viewed<P> {
    fn reset(&mut self) {
        self.policy.reset();
    }
    fn act(&mut self, obs: &[f32]) -> [f32; ACTION_DIM] {
        match &self.flat_of {
            Some(spec) => self.policy.act(&flat_view(spec, obs)),
            None => self.policy.act(obs),
        }
    }
}

/// Checks [`flat_view`] against the flat environment: the expert plays the episode of `seed`
/// in both environments, and every observation it acts on in the flat one must equal, bit for
/// bit, the flat view of the `objects` one. Returns the number of observations compared.
fn check_flat_view(
    expert: &Trained,
    objects_env: &mut BlockEnv,
    flat_env: &mut BlockEnv,
    seed: u64,
    challenge: bool,
) -> Result<usize> {
    objects_env.set_challenge(challenge)?;
    flat_env.set_challenge(challenge)?;
    let mut direct = Vec::new();
    play_episode(flat_env, &mut expert.clone(), seed, |event| {
        if let Event::Step { obs, .. } = event {
            direct.push(obs.to_vec());
        }
    })?;
    let spec = objects_env.obs_spec();
    let mut viewed = Vec::new();
    play_episode(objects_env, &mut Viewed::flat(expert.clone(), spec), seed, |event| {
        if let Event::Step { obs, .. } = event {
            viewed.push(flat_view(&spec, obs));
        }
    })?;
    let names = flat_env.obs_spec().names();
    for (step, (want, got)) in direct.iter().zip(&viewed).enumerate() {
        if want.len() != got.len() {
            bail!(
                "flat view check failed (seed {seed}): the flat view has {} values, the flat observation {}",
                got.len(),
                want.len()
            );
        }
        if let Some(k) = (0..want.len()).find(|&k| want[k].to_bits() != got[k].to_bits()) {
            bail!(
                "flat view check failed (seed {seed}, step {step}): {} is {} in the flat observation, {} in the \
                 flat view of the `objects` one",
                names.get(k).map_or("?", String::as_str),
                want[k],
                got[k]
            );
        }
    }
    if direct.len() != viewed.len() {
        bail!(
            "flat view check failed (seed {seed}): the expert's episode lasted {} steps in the flat environment, \
             {} in the `objects` one",
            direct.len(),
            viewed.len()
        );
    }
    Ok(direct.len())
}

/// Recorded steps: each `objects` observation, its flat view and the expert's action, row by row.
#[derive(Default)]
struct Dataset {
    obs: Vec<f32>,
    flat: Vec<f32>,
    act: Vec<f32>,
}

impl Dataset {
    /// Rows held.
    fn len(&self) -> usize {
        self.act.len() / ACTION_DIM
    }

    /// The inputs of a student: the flat views (`flat`) or the `objects` observations, row by row.
    fn inputs(&self, flat: bool) -> &[f32] {
        if flat {
            &self.flat
        } else {
            &self.obs
        }
    }

    /// The actions as a `[rows, ACTION_DIM]` tensor.
    fn actions(&self) -> Tensor {
        Tensor::of_slice(&self.act).view([-1, ACTION_DIM as i64])
    }

    /// The mean squared error of always answering `train`'s mean action on these rows: what a
    /// student that ignores the observation would score.
    fn mse_of_mean(&self, train: &Dataset) -> f64 {
        let mean = train.actions().mean_dim([0i64].as_slice(), true, Kind::Float);
        (self.actions() - mean).square().mean(Kind::Float).double_value(&[])
    }
}

/// Rolls the expert out for seeds `0..episodes` in `env` (`objects` observations, the expert
/// reading their flat views), seeds ≡ 3 mod 4 from the challenge distribution where `challenge`;
/// returns the training and the validation rows (seeds ≡ 0 mod 5).
fn collect(expert: &Trained, env: &mut BlockEnv, episodes: u64, challenge: bool) -> Result<(Dataset, Dataset)> {
    let spec = env.obs_spec();
    let mut policy = Viewed::flat(expert.clone(), spec);
    let (mut train, mut val) = (Dataset::default(), Dataset::default());
    // Expert successes and episodes, normal and challenge.
    let mut tally = [(0, 0); 2];
    for seed in 0..episodes {
        let hard = challenge && seed % CHALLENGE_EVERY == CHALLENGE_EVERY - 1;
        env.set_challenge(hard)?;
        let data = if seed % VALIDATION_EVERY == 0 { &mut val } else { &mut train };
        let mut success = false;
        play_episode(env, &mut policy, seed, |event| {
            if let Event::Step { obs, action, step, .. } = event {
                data.obs.extend_from_slice(obs);
                data.flat.extend(flat_view(&spec, obs));
                data.act.extend_from_slice(action);
                success |= step.info.is_success;
            }
        })
        .with_context(|| format!("expert episode seed {seed}"))?;
        let t = &mut tally[usize::from(hard)];
        *t = (t.0 + usize::from(success), t.1 + 1);
    }
    println!(
        "expert episodes: {episodes} (successes: normal {}/{}, challenge {}/{})",
        tally[0].0, tally[0].1, tally[1].0, tally[1].1
    );
    Ok((train, val))
}

/// One student: its network, normaliser and optimiser, and the data in the form it reads.
struct Student {
    name: &'static str,
    net: Net,
    norm: blockpuzzle::policy::actor::normalizer::Normalizer,
    opt: Adam,
    /// It reads the flat view (else the `objects` observation as it is).
    flat: bool,
    /// Normalised inputs, `[rows, input]`.
    train_x: Tensor,
    val_x: Tensor,
    /// Wall seconds spent in its updates.
    seconds: f64,
}

impl Student {
    /// A fresh network of `arch` (DDPG's default hidden layers, initialised from `seed`), its
    /// normaliser fitted once on the training rows, and Adam as DDPG's actor has it.
    fn new(name: &'static str, arch: Arch, flat: bool, seed: u64, train: &Dataset, val: &Dataset) -> Self {
        let config = SharedConfig::default();
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let net = arch.net((config.hidden, config.layers), 0, ACTION_DIM, true, &mut rng);
        let mut norm = arch.normalizer(config.norm_eps, config.norm_clip);
        norm.update(train.inputs(flat));
        let (train_x, val_x) = (norm.tensor(train.inputs(flat)), norm.tensor(val.inputs(flat)));
        let opt = Adam::new(&net.params, LR);
        Self { name, net, norm, opt, flat, train_x, val_x, seconds: 0.0 }
    }

    /// One Adam step on the mean squared error over the training rows `batch` (their expert
    /// actions `target`); returns that error before the step.
    fn update(&mut self, batch: &Tensor, target: &Tensor) -> f64 {
        let start = Instant::now();
        let x = self.train_x.index_select(0, batch);
        let loss = (self.net.forward(&x) - target).square().mean(Kind::Float);
        self.net.zero_grad();
        loss.backward();
        let mut grads = Vec::new();
        append_grads(&self.net.params, &mut grads);
        self.opt.step(&mut self.net.params, &grads);
        let mse = loss.double_value(&[]);
        self.seconds += start.elapsed().as_secs_f64();
        mse
    }

    /// The mean squared error on every validation row (expert actions `target`).
    fn val_mse(&self, target: &Tensor) -> f64 {
        tch::no_grad(|| (self.net.forward(&self.val_x) - target).square().mean(Kind::Float).double_value(&[]))
    }

    /// The student as a policy in the `objects` environment of layout `spec`.
    fn policy(&self, spec: ObsSpec) -> Box<dyn Policy> {
        let frozen =
            AnyPolicy::Deterministic(DeterministicPolicy { net: self.net.to_plain(), norm: self.norm.clone() });
        Box::new(Viewed { policy: frozen, flat_of: self.flat.then_some(spec) })
    }
}

/// Trains the MLP on the flat view and the set network on the `objects` observation (laid out
/// as `spec`) on the same batches, reporting every [`REPORT_EVERY`] steps.
fn train_students(args: &Args, spec: &ObsSpec, train: &Dataset, val: &Dataset) -> Result<Vec<Student>> {
    let flat_dim = ObsSpec::flat(spec.max_objects).dim();
    let set = NetConfig { net: NetKind::Set, ..NetConfig::default() };
    let set_arch = Arch::of(&ObsSpec::new(ObsMode::Objects, spec.max_objects), &set)?;
    let mut students = [
        Student::new("mlp", Arch::mlp(flat_dim), true, args.seed, train, val),
        Student::new("set", set_arch, false, args.seed, train, val),
    ];
    let (train_act, val_act) = (train.actions(), val.actions());
    // The batches: drawn once per step and shared by both students.
    let mut rng = ChaCha8Rng::seed_from_u64(args.seed);
    rng.set_stream(1);
    println!(
        "\ntraining: {} steps of batch {BATCH}, Adam lr {LR}; columns: step, then per student train MSE \
         (batch), validation MSE, seconds in updates",
        args.steps
    );
    for step in 1..=args.steps {
        let rows: Vec<i64> = (0..BATCH).map(|_| rng.gen_range(0..train.len()) as i64).collect();
        let batch = Tensor::of_slice(&rows);
        let target = train_act.index_select(0, &batch);
        let losses = students.each_mut().map(|s| s.update(&batch, &target));
        if step % REPORT_EVERY == 0 || step == args.steps {
            let line: Vec<String> = students
                .iter()
                .zip(losses)
                .map(|(s, loss)| format!("{} {loss:.5} {:.5} {:6.1} s", s.name, s.val_mse(&val_act), s.seconds))
                .collect();
            println!("step {step:>6}  {}", line.join("   "));
        }
    }
    Ok(students.into())
}

/// Plays `episodes` deterministic episodes of `policy` in `env` from [`EVAL_SEED`] on, from the
/// challenge distribution if `challenge`, through the crate's episode loop; the outcome tally.
fn evaluate(env: &mut BlockEnv, policy: &mut dyn Policy, episodes: u64, challenge: bool) -> Result<Outcomes> {
    env.set_challenge(challenge)?;
    let mut tally = Outcomes::default();
    for seed in EVAL_SEED..EVAL_SEED + episodes {
        let episode = run_episode(env, policy, seed).with_context(|| format!("evaluation episode seed {seed}"))?;
        tally.add(Outcome::of(&episode));
    }
    Ok(tally)
}

/// Success rate with its Wilson 95% interval, then the unsuccessful outcomes' shares as `eval` prints them.
fn describe(tally: &Outcomes) -> String {
    let n = tally.total();
    let (low, high) = wilson95(tally.success, n);
    let rate = tally.success as f64 / n.max(1) as f64;
    format!("success {rate:.3} [{low:.3}, {high:.3}] ({}/{n}); not successful: {}", tally.success, tally.summary())
}
