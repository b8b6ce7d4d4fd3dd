//! The vector engine: environment i's trajectory is the same whatever the
//! number of environments and threads, next-step autoreset, per-environment
//! seeds and masks, and bad input refused before anything moves.

use crate::common::vector_actions as actions;
use blockpuzzle::env::vector::{ResetOptions, VectorEnv};
use blockpuzzle::env::{registry, EnvConfig, ACTION_DIM};

fn config(id: &str) -> EnvConfig {
    EnvConfig::new(registry::task(id).unwrap())
}

/// Environment `index`'s observations, rewards and flags over `steps` steps.
fn trajectory(n: usize, threads: usize, index: usize, steps: usize) -> Vec<f32> {
    crate::common::vector_trajectory(&config("GripperTouch-v0"), (n, threads), index, steps, 10)
}

#[test]
fn an_environment_is_the_same_whatever_the_count_and_threads() {
    // 120 steps cross at least one episode end (GripperTouch-v0: 50 steps), so autoresets are included.
    let a = trajectory(3, 1, 2, 120);
    assert_eq!(a, trajectory(3, 3, 2, 120));
    assert_eq!(a, trajectory(5, 2, 2, 120));
}

#[test]
fn the_step_after_an_episode_ends_resets_it() {
    let mut v = VectorEnv::new(&config("GripperTouch-v0"), 2, 2).unwrap();
    let d = v.obs_spec().dim();
    let mut obs = vec![0.0; 2 * d];
    v.reset(&[Some(1), Some(2)], None, &ResetOptions::default(), &mut obs).unwrap();
    assert!(v.reports().iter().all(|r| r.autoreset && r.info.is_some()));
    let mut ended_at = None;
    for t in 0..200 {
        let r = v.step(&actions(2, t), &mut obs).unwrap().to_vec();
        if let Some(e) = ended_at {
            assert!(r[0].autoreset && r[0].reward == 0.0 && !r[0].terminated && !r[0].truncated, "step {t}: {r:?}");
            assert_eq!(t, e + 1);
            return;
        }
        if r[0].terminated || r[0].truncated {
            ended_at = Some(t);
        }
    }
    panic!("environment 0 never ended");
}

#[test]
fn masks_seeds_and_options_reach_only_their_environments() {
    let mut v = VectorEnv::new(&config("BlocksChoose-v0"), 3, 2).unwrap();
    let d = v.obs_spec().dim();
    let mut obs = vec![0.0; 3 * d];
    v.reset(&[Some(0), Some(1), Some(2)], None, &ResetOptions { level: Some(4), ..Default::default() }, &mut obs)
        .unwrap();
    assert!(v.reports().iter().all(|r| r.info.as_ref().unwrap().level == 4));
    let before = obs.clone();
    let options = ResetOptions { challenge: Some(true), ..Default::default() };
    v.reset(&[Some(9), Some(9), Some(9)], Some(&[false, true, false]), &options, &mut obs).unwrap();
    assert_eq!(obs[..d], before[..d]);
    assert_eq!(obs[2 * d..], before[2 * d..]);
    assert_ne!(obs[d..2 * d], before[d..2 * d]);
    assert!(v.reports()[0].info.is_none() && v.reports()[1].info.as_ref().unwrap().challenge);
    assert!(v.envs()[1].challenge() && !v.envs()[0].challenge());
}

#[test]
fn bad_input_is_refused_before_any_environment_moves() {
    let mut v = VectorEnv::new(&config("GripperTouch-v0"), 3, 2).unwrap();
    let d = v.obs_spec().dim();
    let mut obs = vec![0.0; 3 * d];
    v.reset(&[Some(0); 3], None, &ResetOptions::default(), &mut obs).unwrap();
    let before = obs.clone();
    let mut bad = actions(3, 0);
    bad[ACTION_DIM + 2] = f32::NAN;
    let e = v.step(&bad, &mut obs).unwrap_err();
    assert_eq!(e.index, 1);
    assert!(e.to_string().contains("environment 1: invalid action"), "{e}");
    assert_eq!(obs, before);
    assert!(v.step(&actions(2, 0), &mut obs).unwrap_err().to_string().contains("3 × 4"));
    assert!(v.step(&actions(3, 0), &mut obs[..d]).unwrap_err().to_string().contains("observation buffer"));
    assert!(v
        .reset(&[None; 2], None, &ResetOptions::default(), &mut obs)
        .unwrap_err()
        .to_string()
        .contains("num_envs = 3"));
    let e = v.reset(&[None; 3], None, &ResetOptions { level: Some(99), ..Default::default() }, &mut obs).unwrap_err();
    assert!(e.to_string().contains("beyond the maximum level"), "{e}");
    // Still usable.
    v.step(&actions(3, 0), &mut obs).unwrap();
    let err = |n, k| VectorEnv::new(&config("GripperTouch-v0"), n, k).err().map(|e| e.to_string()).unwrap_or_default();
    assert!(err(0, 1).contains("1 to 4,096"), "{}", err(0, 1));
    assert!(err(2, 0).contains("threads"), "{}", err(2, 0));
}

#[test]
fn each_runs_every_environment_once_in_order() {
    let mut v = VectorEnv::new(&config("GripperTouch-v0"), 4, 2).unwrap();
    let seen = v.each(|i, env| {
        env.reset(Some(i as u64)).unwrap();
        (i, env.level())
    });
    assert_eq!(seen.iter().map(|s| s.0).collect::<Vec<_>>(), vec![0, 1, 2, 3]);
    assert_eq!(v.threads(), 2);
}
