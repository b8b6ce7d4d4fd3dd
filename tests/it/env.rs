//! Environment API against real MuJoCo: dimensions, Gymnasium semantics,
//! determinism, bad input, instability handling.

use crate::common::trajectory;
use blockpuzzle::env::registry::{ids, make};
use blockpuzzle::env::{registry, BlockEnv, EnvConfig, EnvError, ACTION_DIM};
use blockpuzzle::policy::{Policy, RandomPolicy, ScriptedPolicy};

#[test]
fn registry_lists_and_builds_every_id() {
    let expected = [
        ("BlocksTouch-v0", 48, 29, 5),
        ("BlocksChoose-v0", 67, 36, 10),
        ("GripperTouch-v0", 29, 22, 0),
        ("BlocksChooseShuffled-v0", 67, 36, 10),
        ("ReachAvoid-v0", 48, 29, 5),
        ("ToppleTower-v0", 67, 36, 3),
        ("BlocksStack-v0", 67, 36, 4),
        ("BlocksChooseN-v0", 124, 57, 10),
        ("BlocksAvoid-v0", 105, 50, 5),
        ("BlocksGather-v0", 86, 43, 4),
    ];
    assert_eq!(ids(), expected.iter().map(|e| e.0).collect::<Vec<_>>());
    for (id, dim, nq, max_level) in expected {
        let mut env = make(id).unwrap();
        let (obs, info) = env.reset(Some(0)).unwrap();
        assert_eq!(obs.len(), dim, "{id}");
        assert_eq!(env.observation_space().dim(), dim);
        assert_eq!(env.action_space().dim(), ACTION_DIM);
        assert_eq!(env.data().qpos().len(), nq, "{id}");
        assert_eq!(env.max_level(), max_level);
        assert_eq!(info.elapsed_steps, 0);
        assert!(obs.iter().all(|v| v.is_finite()));
    }
}

#[test]
fn unknown_id_names_the_known_ones() {
    let err = make("BlocksPush-v9").err().unwrap();
    let msg = err.to_string();
    assert!(matches!(err, EnvError::UnknownId { .. }));
    for id in ids() {
        assert!(msg.contains(id), "{msg}");
    }
}

#[test]
fn observation_layout_matches_the_state() {
    let mut env = make("BlocksChoose-v0").unwrap();
    let (obs, _) = env.reset(Some(3)).unwrap();
    let grip = env.gripper_position();
    let blocks = env.block_positions();
    for k in 0..3 {
        assert!((obs[k] as f64 - grip[k]).abs() < 1e-6);
    }
    let colours = [[0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0], [0.0, 0.0, 0.0, 1.0]]; // blue, green, grey (last)
    for (i, b) in blocks.iter().enumerate() {
        let o = &obs[10 + 19 * i..10 + 19 * (i + 1)];
        for k in 0..3 {
            assert!((o[k] as f64 - b[k]).abs() < 1e-6, "block {i} position");
            assert!((o[3 + k] as f64 - (b[k] - grip[k])).abs() < 1e-6, "block {i} relative position");
        }
        assert_eq!(&o[15..19], &colours[i], "block {i} colour");
        assert!((b[2] - 0.425).abs() < 0.002, "block rests on the table: z = {}", b[2]);
    }
    // the gripper starts 0.2 m higher than FetchPush's and at Fetch's x, y
    assert!(
        (grip[0] - 1.342).abs() < 0.01 && (grip[1] - 0.749).abs() < 0.01 && (grip[2] - 0.535).abs() < 0.01,
        "{grip:?}"
    );
}

#[test]
fn same_seed_same_episode_bit_for_bit() {
    let mut a = make("BlocksChoose-v0").unwrap();
    let mut b = make("BlocksChoose-v0").unwrap();
    for seed in [0, 1, 42] {
        let ta = trajectory(&mut a, &mut RandomPolicy::new(seed), seed).unwrap();
        // b has run other episodes before: history must not matter
        trajectory(&mut b, &mut RandomPolicy::new(99), 1234).unwrap();
        let tb = trajectory(&mut b, &mut RandomPolicy::new(seed), seed).unwrap();
        assert_eq!(ta, tb, "seed {seed}");
    }
    let t0 = trajectory(&mut a, &mut RandomPolicy::new(0), 0).unwrap();
    let t1 = trajectory(&mut a, &mut RandomPolicy::new(0), 1).unwrap();
    assert_ne!(t0[0].2, t1[0].2, "different seeds place blocks differently");
}

#[test]
fn unseeded_resets_continue_the_seeded_stream() {
    let mut a = make("BlocksTouch-v0").unwrap();
    let mut b = make("BlocksTouch-v0").unwrap();
    a.reset(Some(5)).unwrap();
    b.reset(Some(5)).unwrap();
    assert_eq!(a.reset(None).unwrap().0, b.reset(None).unwrap().0);
}

#[test]
fn time_limit_truncates_with_minus_one_rewards() {
    let mut env = make("BlocksTouch-v0").unwrap();
    env.reset(Some(0)).unwrap();
    let mut total = 0.0;
    for t in 1..=50 {
        let s = env.step(&[0.0, 0.0, 1.0, 0.0]).unwrap(); // straight up: never touches anything
        total += s.reward;
        assert_eq!(s.reward, -1.0);
        assert!(!s.terminated);
        assert_eq!(s.truncated, t == 50, "step {t}");
        assert_eq!(s.info.elapsed_steps, t);
    }
    assert_eq!(total, -50.0);
    assert!(matches!(env.step(&[0.0; 4]), Err(EnvError::EpisodeOver)));
}

#[test]
fn bad_actions_are_errors_not_panics() {
    let mut env = make("BlocksTouch-v0").unwrap();
    assert!(matches!(env.step(&[0.0; 4]), Err(EnvError::NotReset)));
    env.reset(Some(0)).unwrap();
    for bad in [vec![0.0; 3], vec![0.0; 5], vec![f32::NAN, 0.0, 0.0, 0.0], vec![0.0, f32::INFINITY, 0.0, 0.0]] {
        let err = env.step(&bad).unwrap_err();
        assert!(matches!(err, EnvError::BadAction { .. }), "{bad:?}: {err}");
    }
    // out-of-range values are clipped, like Gymnasium's Fetch
    let big = env.step(&[100.0, 0.0, 0.0, 0.0]).unwrap();
    let mut env2 = make("BlocksTouch-v0").unwrap();
    env2.reset(Some(0)).unwrap();
    assert_eq!(env2.step(&[1.0, 0.0, 0.0, -7.0]).unwrap().obs, big.obs);
}

#[test]
fn levels_and_challenge_are_checked() {
    let mut env = make("BlocksTouch-v0").unwrap();
    assert!(env.set_level(5).is_ok());
    let err = env.set_level(6).unwrap_err();
    assert!(err.to_string().contains("maximum level 5"), "{err}");
    assert!(matches!(env.set_challenge(true), Err(EnvError::NoChallenge { .. })));
    let mut choose = make("BlocksChoose-v0").unwrap();
    choose.set_challenge(true).unwrap();
    let (_, info) = choose.reset(Some(0)).unwrap();
    assert!(info.challenge);
}

#[test]
fn instability_truncates_and_never_leaks_nan() {
    let mut env = make("BlocksTouch-v0").unwrap();
    let (obs0, _) = env.reset(Some(0)).unwrap();
    let s = env.step(&[0.1, 0.0, 0.0, 0.0]).unwrap();
    let dof = env.scene().blocks[0].dof;
    env.data_mut().qvel_mut()[dof] = f64::NAN;
    let bad = env.step(&[0.1, 0.0, 0.0, 0.0]).unwrap();
    assert!(bad.truncated && !bad.terminated && bad.info.unstable);
    assert!(bad.obs.iter().all(|v| v.is_finite()));
    assert_eq!(bad.obs, s.obs, "the last finite observation is repeated");
    let (obs, _) = env.reset(Some(0)).unwrap();
    assert_eq!(obs, obs0, "the next reset starts clean");
    let s2 = env.step(&[0.1, 0.0, 0.0, 0.0]).unwrap();
    assert_eq!(s2.obs, s.obs);
    assert!(!s2.info.unstable);
}

#[test]
fn scripted_controller_solves_level_zero() {
    for id in ["BlocksTouch-v0", "BlocksChoose-v0", "GripperTouch-v0"] {
        let mut env = make(id).unwrap();
        let mut policy = ScriptedPolicy::for_env(env.config());
        let mut wins = 0;
        for seed in 0..10 {
            let t = trajectory(&mut env, &mut policy, seed).unwrap();
            let last = t.last().unwrap();
            if last.4 && last.3 == 0.0 {
                wins += 1;
            }
        }
        assert!(wins >= 9, "{id}: scripted success {wins}/10 at level 0");
    }
}

#[test]
fn random_policy_rarely_succeeds_at_full_difficulty() {
    // sanity check that success is not trivial: random actions at the
    // hardest BlocksTouch level should mostly time out
    let mut env = make("BlocksTouch-v0").unwrap();
    env.set_level(env.max_level()).unwrap();
    let mut wins = 0;
    for seed in 0..10 {
        let t = trajectory(&mut env, &mut RandomPolicy::new(seed), seed).unwrap();
        wins += t.last().unwrap().4 as usize;
    }
    assert!(wins <= 5, "random policy won {wins}/10");
}

#[test]
fn custom_configs_are_validated() {
    let mut cfg = registry::config("BlocksTouch-v0").unwrap();
    cfg.n_substeps = 0;
    assert!(matches!(BlockEnv::new(cfg), Err(EnvError::Config(_))));
    let mut spec = registry::task("BlocksTouch-v0").unwrap().spec;
    spec.max_episode_steps = 0;
    assert!(matches!(EnvConfig::from_spec(spec), Err(EnvError::Task(_))));
    let mut spec = registry::task("BlocksTouch-v0").unwrap().spec;
    spec.objects[0].get_mut().colour = blockpuzzle::Colour::Grey;
    let err = EnvConfig::from_spec(spec).err().unwrap();
    assert!(err.to_string().contains("blue"), "{err}");
    let _ = RandomPolicy::new(0).act(&[]);
}

/// `set_state` starts an episode from any state: the same state and actions
/// give the same trajectory bit for bit (cold solver start, whatever ran
/// before), the observation is that of the state, and bad states are errors.
#[test]
fn set_state_starts_reproducible_episodes_from_a_state() {
    let mut env = make("BlocksTouch-v0").unwrap();
    assert!(matches!(env.set_state(&[0.0; 3], &[0.0; 3]), Err(EnvError::BadState { .. })));
    env.reset(Some(4)).unwrap();
    env.step(&[0.3, -0.2, 0.0, 0.0]).unwrap();
    let (mut q, v) = (env.data().qpos().to_vec(), env.data().qvel().to_vec());
    let run = |env: &mut BlockEnv, q: &[f64], v: &[f64]| {
        let obs = env.set_state(q, v).unwrap();
        let grip = env.gripper_position();
        assert!((0..3).all(|k| (obs[k] as f64 - grip[k]).abs() < 1e-6), "{:?} vs {grip:?}", &obs[..3]);
        assert_eq!(env.data().qpos(), q);
        let mut out = vec![obs];
        for k in 0..10 {
            let a = [0.5, (k as f32 * 0.3).sin(), -0.4, 0.0];
            out.push(env.step(&a).unwrap().obs);
        }
        (out, env.data().qpos().to_vec())
    };
    let first = run(&mut env, &q, &v);
    // Something else in between (another episode, other solver warm starts).
    env.reset(Some(9)).unwrap();
    for _ in 0..5 {
        env.step(&[-1.0, 1.0, 0.2, 0.0]).unwrap();
    }
    assert_eq!(run(&mut env, &q, &v), first);
    q[0] = f64::NAN;
    let e = env.set_state(&q, &v).unwrap_err();
    assert!(matches!(e, EnvError::BadState { .. }) && e.to_string().contains("qpos[0] is NaN"), "{e}");
    let e = env.set_state(&q[..5], &v).unwrap_err();
    assert!(e.to_string().contains("qpos has 5 values"), "{e}");
}
