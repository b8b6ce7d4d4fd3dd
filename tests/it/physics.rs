//! Dynamics drawn per episode (issue 76): a task's `[physics]` table, drawn from the episode's
//! seed, applied before the reset's settle, reported in `info` and in dumps, and checked.

use blockpuzzle::env::vector::{ResetOptions, VectorEnv};
use blockpuzzle::env::{registry, BlockEnv, EnvConfig};
use blockpuzzle::policy::ScriptedPolicy;
use blockpuzzle::sim::mj::ObjType;
use blockpuzzle::task::physics::{PhysicsSpec, PARAMS};
use blockpuzzle::task::Task;

/// BlocksTouch-v0 with `table` as its `[physics]` table (and another id).
fn touch_with(table: &str) -> Task {
    let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/tasks/BlocksTouch-v0.toml")).unwrap();
    let text = text.replace("id = \"BlocksTouch-v0\"", "id = \"TouchPhysics-v0\"");
    Task::from_toml(&format!("{text}\n[physics]\n{table}\n"), None).unwrap()
}

/// The solver, as `blockpuzzle rollout --policy scripted` plays it (built from the environment's
/// configuration, cloned so the environment is free to step).
fn solver_for(config: &EnvConfig) -> ScriptedPolicy {
    ScriptedPolicy::for_env(config)
}

/// The solver's episode of `seed`, frame by frame.
fn play(env: &mut BlockEnv, seed: u64) -> Vec<crate::common::Frame> {
    let mut solver = solver_for(env.config());
    crate::common::trajectory(env, &mut solver, seed).unwrap()
}

fn env(task: Task) -> BlockEnv {
    BlockEnv::new(EnvConfig::new(task)).unwrap()
}

const WIDE: &str = "friction = [0.5, 2]\ntorsional_friction = [0.5, 2]\nmass = [0.5, 2]\ndamping = [0.5, 2]\n\
                    gain = [0.8, 1.25]\nsolref = [0.8, 1.25]\nsolimp = [0.95, 1.02]\naction_noise = [0, 0.1]\n\
                    latency = [0, 2]\nobs_noise = [0, 0.005]";

/// A table that varies nothing steps the very episodes of the task without one: the machinery
/// (the model's copy, the draws on their own stream, the action and observation paths) is
/// transparent, and the layout's draws are the same with and without physics.
#[test]
fn a_nominal_table_plays_the_same_episodes_as_none() {
    let nominal =
        PARAMS.iter().map(|p| format!("{} = [{}, {}]", p.name, p.nominal, p.nominal)).collect::<Vec<_>>().join("\n");
    let (mut with, mut without) = (env(touch_with(&nominal)), env(registry::task("BlocksTouch-v0").unwrap()));
    for seed in 0..3 {
        let a = play(&mut with, seed);
        let b = play(&mut without, seed);
        assert_eq!(a, b, "seed {seed}");
    }
    assert!(with.physics().is_some() && without.physics().is_none());
}

/// The draw comes from the episode's seed: the same seed, the same values and the same episode,
/// on any number of threads; the values are in `info` at reset and at every step, and in dumps.
#[test]
fn a_seed_gives_the_same_dynamics_and_episode_on_any_thread_count() {
    let task = touch_with(WIDE);
    let (mut a, mut b) = (env(task.clone()), env(task.clone()));
    let mut draws = Vec::new();
    for seed in [0, 1, 0] {
        let (_, info) = a.reset(Some(seed)).unwrap();
        let drawn = info.physics.expect("info reports the draw");
        assert_eq!(Some(drawn), a.physics());
        draws.push(drawn);
        let s = a.step(&[0.3, -0.2, 0.1, 0.0]).unwrap();
        assert_eq!(s.info.physics, Some(drawn));
        let ta = play(&mut a, seed);
        let tb = play(&mut b, seed);
        assert_eq!(ta, tb, "seed {seed}");
    }
    assert_eq!(draws[0], draws[2]);
    assert_ne!(draws[0], draws[1]);
    // The model the episode steps has the drawn values; the nominal ones come back, never compounded.
    let body = a.model_id(ObjType::Body, "block0").unwrap();
    let nominal = env(registry::task("BlocksTouch-v0").unwrap()).data().model().body_mass()[body];
    let mass = a.data().model().body_mass()[body];
    let drawn = a.physics().unwrap().scales.mass;
    assert!((mass - nominal * drawn).abs() < 1e-12, "{mass} against {nominal} × {drawn}");
    // Threads: environment 1 of three, on one thread and on three.
    let config = EnvConfig::new(task);
    let one = crate::common::vector_trajectory(&config, (3, 1), 1, 60, 5);
    let three = crate::common::vector_trajectory(&config, (3, 3), 1, 60, 5);
    assert_eq!(one, three);
    // A dump records the episode's values.
    let mut e = env(touch_with(WIDE));
    let mut solver = solver_for(e.config());
    let record = blockpuzzle::episode::rollout::run_episode(&mut e, &mut solver, 4).unwrap();
    assert_eq!(record.physics, e.physics());
    assert!(serde_json::to_string(&record).unwrap().contains("\"latency\""));
}

/// What each parameter changes: the model's values, and the action's path (gain, latency).
#[test]
fn each_parameter_acts_where_it_says() {
    let mut e = env(touch_with(WIDE));
    let pinned = |e: &mut BlockEnv, fixed: &[(&str, f64)]| {
        let fixed: Vec<(String, f64)> = fixed.iter().map(|(n, v)| ((*n).to_owned(), *v)).collect();
        e.pin_physics(&fixed).unwrap();
        e.reset(Some(0)).unwrap();
    };
    let nominal = env(registry::task("BlocksTouch-v0").unwrap());
    let m0 = nominal.data().model();
    pinned(&mut e, &[("friction", 2.0), ("torsional_friction", 0.5), ("damping", 0.5), ("solref", 1.25)]);
    let m = e.data().model();
    let g = e.model_id(ObjType::Geom, "block0").unwrap();
    assert_eq!(m.geom_friction()[g][0], m0.geom_friction()[g][0] * 2.0);
    assert_eq!(m.geom_friction()[g][1], m0.geom_friction()[g][1] * 0.5);
    assert_eq!(m.geom_solref()[g][0], m0.geom_solref()[g][0] * 1.25);
    let damped = (0..m.nv()).find(|&i| m0.dof_damping()[i] > 0.0).expect("the arm has damped joints");
    assert_eq!(m.dof_damping()[damped], m0.dof_damping()[damped] * 0.5);
    // Gain: the gripper goes further per unit action; latency: the first steps apply nothing.
    let moved = |e: &mut BlockEnv, fixed: &[(&str, f64)], steps: usize| {
        pinned(e, fixed);
        let start = e.gripper_position();
        for _ in 0..steps {
            e.step(&[1.0, 0.0, 0.0, 0.0]).unwrap();
        }
        e.gripper_position()[0] - start[0]
    };
    let base = [("action_noise", 0.0), ("latency", 0.0), ("obs_noise", 0.0)];
    let slow = moved(&mut e, &[&base[..], &[("gain", 0.8)]].concat(), 2);
    let fast = moved(&mut e, &[&base[..], &[("gain", 1.25)]].concat(), 2);
    assert!(fast > slow * 1.3, "gain 1.25 moved {fast} m, gain 0.8 {slow} m");
    let late = moved(&mut e, &[("gain", 1.0), ("action_noise", 0.0), ("latency", 2.0), ("obs_noise", 0.0)], 2);
    assert!(late.abs() < 0.1 * slow, "with two steps of latency the gripper moved {late} m in two steps");
    // Observation noise: the observed grip is off the true one; without it, on it.
    pinned(&mut e, &[("gain", 1.0), ("action_noise", 0.0), ("latency", 0.0), ("obs_noise", 0.005)]);
    let s = e.step(&[0.0; 4]).unwrap();
    let off = (0..3).map(|k| (f64::from(s.obs[k]) - e.gripper_position()[k]).abs()).fold(0.0, f64::max);
    assert!(off > 1e-4, "observed grip {off} m off");
    pinned(&mut e, &[("gain", 1.0), ("action_noise", 0.0), ("latency", 0.0), ("obs_noise", 0.0)]);
    let s = e.step(&[0.0; 4]).unwrap();
    let off = (0..3).map(|k| (f64::from(s.obs[k]) - e.gripper_position()[k]).abs()).fold(0.0, f64::max);
    assert!(off < 1e-5, "observed grip {off} m off without noise");
}

/// The bounds are where the simulation holds: at each end of every range, the solver's episodes
/// stay finite and stable, and MuJoCo raises no warning (no bad number, no full contact buffer,
/// no singular inertia).
#[test]
fn the_whole_range_stays_stable() {
    use blockpuzzle::sim::mj::Warning;
    let ends = |pick: fn([f64; 2]) -> f64| {
        PARAMS
            .iter()
            .map(|p| {
                let v = pick(p.bounds);
                format!("{} = [{v}, {v}]", p.name)
            })
            .collect::<Vec<_>>()
            .join("\n")
    };
    let warnings = [
        Warning::Inertia,
        Warning::ContactFull,
        Warning::ConstraintFull,
        Warning::BadQpos,
        Warning::BadQvel,
        Warning::BadQacc,
    ];
    for table in [ends(|b| b[0]), ends(|b| b[1])] {
        let mut e = env(touch_with(&table));
        for seed in 0..3 {
            let (mut obs, _) = e.reset(Some(seed)).unwrap();
            let mut solver = solver_for(e.config());
            loop {
                let s = e.step(&blockpuzzle::policy::Policy::act(&mut solver, &obs)).unwrap();
                assert!(!s.info.unstable && s.obs.iter().all(|v| v.is_finite()), "{table}, seed {seed}");
                obs = s.obs;
                if s.terminated || s.truncated {
                    break;
                }
            }
            for w in warnings {
                assert_eq!(e.data().warning_count(w), 0, "{w:?} at {table}, seed {seed}");
            }
        }
    }
}

/// Bad input: each refused with the field and the fix, before anything runs.
#[test]
fn bad_physics_is_refused_with_the_field_and_the_fix() {
    let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/tasks/BlocksTouch-v0.toml")).unwrap();
    for (table, wanted) in [
        ("mass = [2, 1]", "physics.mass = [2, 1]: low is above high"),
        ("friction = [0, 1]", "physics.friction = [0, 1]: a scale of sliding friction must be positive"),
        ("mass = [1, 1000]", "physics.mass = [1, 1000]: the scale of each block's mass must stay within [0.1, 10]"),
        ("damping = [1, nan]", "give two finite numbers"),
        ("wind = [0, 1]", "unknown field `wind`"),
        ("latency = [0, 0.5]", "latency counts whole steps"),
    ] {
        let e = Task::from_toml(&format!("{text}\n[physics]\n{table}\n"), None).unwrap_err().to_string();
        assert!(e.contains(wanted), "{table}: {e}");
    }
    // Options: a task with no table, an unknown name, a parameter not varied, a value out of range.
    let mut plain = env(registry::task("BlocksTouch-v0").unwrap());
    let e = plain.pin_physics(&[("mass".into(), 1.0)]).unwrap_err().to_string();
    assert!(e.contains("a task with no [physics] table"), "{e}");
    plain.pin_physics(&[]).unwrap();
    let mut e = env(touch_with("mass = [0.5, 2]"));
    for (name, v, wanted) in [
        ("wind", 1.0, "no such parameter"),
        ("friction", 1.0, "does not vary it"),
        ("mass", 3.0, "outside the task's range [0.5, 2]"),
    ] {
        let err = e.pin_physics(&[(name.into(), v)]).unwrap_err().to_string();
        assert!(err.contains(wanted), "{name}: {err}");
    }
    // The vector engine takes the same options, checked the same way.
    let mut v = VectorEnv::new(&EnvConfig::new(touch_with("mass = [0.5, 2]")), 2, 1).unwrap();
    let mut obs = vec![0.0; 2 * v.obs_spec().dim()];
    let options = ResetOptions { physics: Some(vec![("mass".into(), 2.0)]), ..ResetOptions::default() };
    v.reset(&[Some(0), Some(1)], None, &options, &mut obs).unwrap();
    let bad = ResetOptions { physics: Some(vec![("mass".into(), 9.0)]), ..ResetOptions::default() };
    assert!(v.reset(&[Some(0), Some(1)], None, &bad, &mut obs).unwrap_err().to_string().contains("outside"));
}

/// The table is task content: two tasks that differ only in it have different hashes, a family's
/// table goes into every task it generates, and a task without one keeps its hash.
#[test]
fn the_table_is_part_of_the_task_and_its_family() {
    let a = touch_with("mass = [0.5, 2]");
    let b = touch_with("mass = [0.5, 3]");
    assert_ne!(a.source.hash, b.source.hash);
    assert_eq!(a.spec.physics, Some(PhysicsSpec { mass: Some([0.5, 2.0]), ..PhysicsSpec::default() }));
    let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/families/push.toml")).unwrap();
    let family =
        blockpuzzle::task::family::Family::from_toml(&format!("{text}\n[physics]\nfriction = [0.5, 2]\n"), "push")
            .unwrap();
    let plain = blockpuzzle::task::family::Family::from_toml(&text, "push").unwrap();
    let (t, p) = (family.draw(3, 0).unwrap().task, plain.draw(3, 0).unwrap().task);
    assert_eq!(t.spec.physics.as_ref().and_then(|p| p.friction), Some([0.5, 2.0]));
    assert!(p.spec.physics.is_none() && t.source.hash != p.source.hash);
    let e = blockpuzzle::task::family::Family::from_toml(&format!("{text}\n[physics]\nfriction = [2, 1]\n"), "push")
        .unwrap_err()
        .to_string();
    assert!(e.contains("physics.friction = [2, 1]: low is above high"), "{e}");
}

/// A suite's rows give their tasks one of its named `[physics.NAME]` tables: the shipped `physics`
/// suite's test rows and nominal rows play the same tasks and seeds, with and without dynamics.
#[test]
fn a_suite_row_gives_its_tasks_a_named_table() {
    use blockpuzzle::benchmark::suite;
    let physics = suite::load("physics").unwrap();
    let split = |name: &str| physics.splits.iter().find(|s| s.name == name).unwrap();
    let (test, nominal) = (split("test"), split("nominal"));
    assert_eq!(test.rows.len(), nominal.rows.len());
    for (t, n) in test.rows.iter().zip(&nominal.rows) {
        assert_eq!((t.task.id(), t.seed, t.episodes), (n.task.id(), n.seed, n.episodes));
        assert!(t.task.spec.physics.is_some() && n.task.spec.physics.is_none());
        assert_ne!(t.task.source.hash, n.task.source.hash);
    }
    let rows = |physics: &str| {
        format!(
            "version = 1\nname = \"x\"\nsummary = \"s\"\n{physics}\n[[splits.train]]\ntask = \"BlocksTouch-v0\"\n\
             physics = \"wide\"\nseed = 0\nepisodes = 1\n[[splits.test]]\ntask = \"BlocksTouch-v0\"\nseed = 10\n\
             episodes = 1\n"
        )
    };
    let e = suite::parse(&rows(""), "x", None).unwrap_err().to_string();
    assert!(e.contains("physics = \"wide\" names no [physics.wide] table of the suite (it has: none)"), "{e}");
    let e = suite::parse(&rows("[physics.wide]\nmass = [2, 1]"), "x", None).unwrap_err().to_string();
    assert!(e.contains("[physics.wide]: physics.mass = [2, 1]: low is above high"), "{e}");
    let ok = suite::parse(&rows("[physics.wide]\nmass = [1, 2]"), "x", None).unwrap();
    assert_eq!(ok.splits[0].rows[0].task.spec.physics.as_ref().and_then(|p| p.mass), Some([1.0, 2.0]));
}
