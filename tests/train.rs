//! DDPG training end to end: run directory, resume, checkpoints, policies.

use blockpuzzle::agents::ddpg::DdpgConfig;
use blockpuzzle::train::{checkpoint, load_policy, read_progress, train, EpochRow, TrainConfig};
use std::path::Path;

fn tiny(env: &str, epochs: usize) -> TrainConfig {
    TrainConfig {
        env: env.into(),
        workers: 2,
        epochs,
        cycles: 3,
        rollouts: 1,
        batches: 5,
        batch_size: 32,
        buffer_size: 10_000,
        test_episodes: 2,
        success_threshold: 0.7,
        seed: 7,
        torch_threads: 1,
        ddpg: DdpgConfig { hidden: 32, layers: 2, ..DdpgConfig::default() },
    }
}

fn quiet(_: &EpochRow, _: &TrainConfig) {}

/// Rows without the wall-clock columns.
fn comparable(rows: &[EpochRow]) -> Vec<EpochRow> {
    rows.iter()
        .map(|r| EpochRow {
            wall_seconds: 0.0,
            env_seconds: 0.0,
            forward_seconds: 0.0,
            update_seconds: 0.0,
            cpu_utilisation: 0.0,
            ..r.clone()
        })
        .collect()
}

#[test]
fn short_run_writes_every_run_directory_file() {
    let dir = tempfile::tempdir().unwrap();
    let rows = train(&tiny("BlocksTouch-v0", 2), dir.path(), false, &mut quiet).unwrap();
    assert_eq!(rows.len(), 2);
    for f in ["config.json", "progress.csv", "checkpoint.bin", "policy.json", "best_policy.json", "success.png"] {
        assert!(dir.path().join(f).exists(), "{f} missing");
    }
    let progress = read_progress(&dir.path().join("progress.csv")).unwrap();
    assert_eq!(comparable(&progress), comparable(&rows));
    assert!(rows[1].env_steps > rows[0].env_steps && rows[1].env_steps <= 2 * 3 * 2 * 50, "{rows:?}");
    assert_eq!(rows[1].updates, 2 * 3 * 5);
    // The actor's time is a part of the collection time.
    assert!(rows.iter().all(|r| r.forward_seconds > 0.0 && r.forward_seconds < r.env_seconds), "{rows:?}");
    let header = std::fs::read_to_string(dir.path().join("progress.csv")).unwrap();
    assert!(header.starts_with("epoch,curriculum/level,train/success,test/success,finals/success"));
    let cfg: TrainConfig =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("config.json")).unwrap()).unwrap();
    assert_eq!(cfg, tiny("BlocksTouch-v0", 2));
    // a second fresh run into the same directory is refused
    let err = train(&tiny("BlocksTouch-v0", 2), dir.path(), false, &mut quiet).unwrap_err();
    assert!(err.to_string().contains("--resume"), "{err}");
}

#[test]
fn resume_restores_the_exact_state() {
    let straight = tempfile::tempdir().unwrap();
    let a = train(&tiny("GripperTouch-v0", 3), straight.path(), false, &mut quiet).unwrap();
    let split = tempfile::tempdir().unwrap();
    train(&tiny("GripperTouch-v0", 2), split.path(), false, &mut quiet).unwrap();
    let b = train(&tiny("GripperTouch-v0", 3), split.path(), true, &mut quiet).unwrap();
    assert_eq!(comparable(&a), comparable(&b));
    let (pa, pb) = (
        load_policy(&straight.path().join("policy.json")).unwrap(),
        load_policy(&split.path().join("policy.json")).unwrap(),
    );
    assert_eq!(pa.policy, pb.policy, "same weights and normaliser after resuming");
}

#[test]
fn saved_policy_acts_like_the_trained_one() {
    let dir = tempfile::tempdir().unwrap();
    train(&tiny("GripperTouch-v0", 1), dir.path(), false, &mut quiet).unwrap();
    let loaded = checkpoint::load(&dir.path().join("checkpoint.bin"), "GripperTouch-v0", 29, 4).unwrap();
    let from_json = load_policy(dir.path()).unwrap();
    let obs: Vec<f32> = (0..29).map(|i| (i as f32 * 0.37).sin()).collect();
    assert_eq!(loaded.agent.policy().act(&obs), from_json.policy.act(&obs));
}

#[test]
fn corrupt_and_mismatched_checkpoints_are_clear_errors() {
    let dir = tempfile::tempdir().unwrap();
    train(&tiny("GripperTouch-v0", 1), dir.path(), false, &mut quiet).unwrap();
    let ckpt = dir.path().join("checkpoint.bin");
    let err = checkpoint::load(&ckpt, "BlocksTouch-v0", 48, 4).err().unwrap();
    assert!(err.to_string().contains("trained on GripperTouch-v0"), "{err}");
    let err = checkpoint::load(&ckpt, "GripperTouch-v0", 30, 4).err().unwrap();
    assert!(err.to_string().contains("sizes"), "{err}");

    let mut bytes = std::fs::read(&ckpt).unwrap();
    let n = bytes.len();
    bytes[n - 10] ^= 0xff;
    std::fs::write(&ckpt, &bytes).unwrap();
    let err = checkpoint::load(&ckpt, "GripperTouch-v0", 29, 4).err().unwrap();
    assert!(err.to_string().contains("corrupt") && err.to_string().contains("checksum"), "{err}");
    std::fs::write(&ckpt, &bytes[..n / 2]).unwrap();
    let err = checkpoint::load(&ckpt, "GripperTouch-v0", 29, 4).err().unwrap();
    assert!(err.to_string().contains("corrupt"), "{err}");
    std::fs::write(&ckpt, b"hello").unwrap();
    let err = train(&tiny("GripperTouch-v0", 2), dir.path(), true, &mut quiet).unwrap_err();
    assert!(format!("{err:#}").contains("not a blockpuzzle checkpoint"), "{err:#}");
}

#[test]
fn resume_with_other_settings_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    train(&tiny("GripperTouch-v0", 1), dir.path(), false, &mut quiet).unwrap();
    let mut other = tiny("GripperTouch-v0", 2);
    other.ddpg.gamma = 0.9;
    let err = train(&other, dir.path(), true, &mut quiet).unwrap_err();
    assert!(err.to_string().contains("different settings"), "{err}");
    let err = train(&tiny("GripperTouch-v0", 2), Path::new("/nonexistent/run"), true, &mut quiet).unwrap_err();
    assert!(!err.to_string().is_empty());
}
