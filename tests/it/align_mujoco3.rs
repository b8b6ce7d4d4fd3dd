//! Alignment with gymnasium-robotics on the same engine: FetchPush-v4
//! episodes recorded on MuJoCo 3.11.0 (`bench/align_fetchpush.py`, path in
//! `BLOCKPUZZLE_ALIGN_REFERENCE`; `make test-mujoco3` records them first)
//! replayed in the FetchPush-like environment on MuJoCo 3.11.0 stay within
//! 1e-4 m, gripper and block, at every step of every episode.
#![cfg(feature = "mujoco3")]

use blockpuzzle::episode::align::{replay_all, Reference, TOLERANCE};
use std::path::PathBuf;

#[test]
fn fetchpush_like_follows_fetchpush_v4_on_mujoco_3() {
    let Some(path) = std::env::var_os("BLOCKPUZZLE_ALIGN_REFERENCE").map(PathBuf::from) else {
        panic!("set BLOCKPUZZLE_ALIGN_REFERENCE to a file of bench/align_fetchpush.py (make test-mujoco3 does)");
    };
    let reference = Reference::load(&path).unwrap();
    assert_eq!(reference.mujoco, blockpuzzle::sim::mj::version(), "the reference ran on another MuJoCo");
    assert!(
        reference.episodes.iter().any(|e| e.kind == "random")
            && reference.episodes.iter().any(|e| e.kind == "scripted")
    );
    for d in replay_all(&reference).unwrap() {
        println!(
            "{} seed {}: {} steps, gripper {:.2e} m, block {:.2e} m (worst at step {})",
            d.kind, d.seed, d.steps, d.grip_max, d.object_max, d.worst_step
        );
        assert!(d.steps > 40, "{d:?}: too short to say anything");
        assert!(d.grip_max < TOLERANCE && d.object_max < TOLERANCE, "{d:?}");
    }
}
