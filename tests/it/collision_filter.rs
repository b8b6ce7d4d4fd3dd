//! The collision filter changes nothing: trajectories with and without the
//! excluded robot pairs are bit-identical.

use crate::common::trajectory;
use blockpuzzle::env::{registry, BlockEnv};
use blockpuzzle::policy::{Policy, RandomPolicy, ScriptedPolicy};
use blockpuzzle::sim::scene::EXCLUDED_BODY_PAIRS;

fn pair(id: &str) -> (BlockEnv, BlockEnv) {
    let mut off = registry::config(id).unwrap();
    off.collision_filter = false;
    let on = registry::config(id).unwrap();
    assert!(on.collision_filter);
    let (a, b) = (BlockEnv::new(on).unwrap(), BlockEnv::new(off).unwrap());
    assert_eq!(a.scene().model.nexclude(), b.scene().model.nexclude() + EXCLUDED_BODY_PAIRS.len());
    (a, b)
}

#[test]
fn filtered_and_unfiltered_trajectories_are_bit_identical() {
    for (id, level, challenge) in
        [("BlocksChoose-v0", 10, false), ("BlocksChoose-v0", 10, true), ("BlocksTouch-v0", 5, false)]
    {
        let (mut on, mut off) = pair(id);
        for e in [&mut on, &mut off] {
            e.set_level(level).unwrap();
            e.set_challenge(challenge).unwrap();
        }
        for seed in 0..12 {
            let mut p: Box<dyn Policy> = if seed % 3 == 0 {
                Box::new(ScriptedPolicy::for_env(on.config()))
            } else {
                Box::new(RandomPolicy::new(seed))
            };
            let a = trajectory(&mut on, p.as_mut(), seed).unwrap();
            let mut p: Box<dyn Policy> = if seed % 3 == 0 {
                Box::new(ScriptedPolicy::for_env(off.config()))
            } else {
                Box::new(RandomPolicy::new(seed))
            };
            let b = trajectory(&mut off, p.as_mut(), seed).unwrap();
            assert_eq!(a, b, "{id} seed {seed}");
        }
    }
}

#[test]
fn end_of_step_kinematics_match_a_full_forward() {
    // The default end-of-step pass recomputes only kinematics, velocities
    // and contacts; gymnasium-robotics runs a full mj_forward, which also
    // refreshes the constraint solver's warm start. That perturbs the last
    // bits of the next solve; over a contact-rich random episode the states
    // stay within 0.1 mm and the episodes end alike.
    let mut full_cfg = registry::config("BlocksChoose-v0").unwrap();
    full_cfg.full_forward = true;
    let mut full = BlockEnv::new(full_cfg).unwrap();
    let mut fast = registry::make("BlocksChoose-v0").unwrap();
    for seed in 0..4 {
        let a = trajectory(&mut full, &mut RandomPolicy::new(seed), seed).unwrap();
        let b = trajectory(&mut fast, &mut RandomPolicy::new(seed), seed).unwrap();
        assert_eq!(a.len(), b.len());
        for (x, y) in a.iter().zip(&b) {
            let dq = x.0.iter().zip(&y.0).map(|(p, q)| (p - q).abs()).fold(0.0, f64::max);
            assert!(dq < 1e-4, "seed {seed}: qpos differs by {dq}");
            assert_eq!((x.4, x.5), (y.4, y.5));
        }
    }
}
