//! Training end to end (DDPG, PGGD, AggreVaTeD, SAC): run directory, resume,
//! checkpoints, policies.
#![cfg(feature = "train")]

use blockpuzzle::benchmark::load::load_policy;
use blockpuzzle::learn::agents::arch::{NetConfig, NetKind, Pooling};
use blockpuzzle::learn::agents::ddpg::{Ddpg, DdpgConfig};
use blockpuzzle::learn::agents::registry::Algo;
use blockpuzzle::learn::agents::shared::SharedConfig;
use blockpuzzle::learn::train::{
    branch, checkpoint, policy_from_checkpoint, read_progress, train, AggrevatedConfig, EpochRow, PgWeight,
    ReplayLayout, TrainConfig,
};
use blockpuzzle::policy::actor::AnyPolicy;
use std::path::Path;

fn tiny(env: &str, epochs: usize) -> TrainConfig {
    TrainConfig {
        env: env.into(),
        suite: None,
        families: None,
        generator_seeds: None,
        active_tasks: blockpuzzle::learn::train::DEFAULT_ACTIVE_TASKS,
        family_weights: None,
        split: "train".into(),
        counts: None,
        workers: 2,
        epochs,
        cycles: 3,
        rollouts: 1,
        batches: 5,
        batch_size: 32,
        buffer_size: 10_000,
        replay: Some(ReplayLayout::PerWorker),
        test_episodes: 2,
        success_threshold: None,
        seed: 7,
        torch_threads: 1,
        snapshot_every: 1,
        level_replay: 0.0,
        challenge_share: 0.0,
        shared: SharedConfig { hidden: 32, layers: 2, ..SharedConfig::default() },
        algo: Algo::Ddpg,
        algos: Default::default(),
        aggrevated: Default::default(),
        finetune: Default::default(),
        hindsight_colours: 0,
        hindsight_strategy: Default::default(),
        net: Default::default(),
        task: None,
        tasks: Vec::new(),
        stream: None,
        branched_from: None,
    }
}

/// A small stream run of `algo` with the entity network: gripper and push tasks of generator seeds
/// 0-2, two of them with environments each epoch.
fn stream_run(algo: &str, epochs: usize) -> TrainConfig {
    TrainConfig {
        env: String::new(),
        families: Some("gripper,push".into()),
        generator_seeds: Some("0..3".parse().unwrap()),
        active_tasks: 2,
        algo: Algo::named(algo).unwrap(),
        net: NetConfig { net: NetKind::Entity, ..NetConfig::default() },
        ..tiny("", epochs)
    }
}

fn tiny_pggd(env: &str, epochs: usize, aggrevated: AggrevatedConfig) -> TrainConfig {
    TrainConfig { algo: Algo::Pggd, aggrevated, ..tiny(env, epochs) }
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
            reduce_seconds: 0.0,
            eval_seconds: 0.0,
            persist_seconds: 0.0,
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
    // --snapshot-every 1 keeps each epoch's policy; the last is the latest policy.
    let first = load_policy(&dir.path().join("snapshots/epoch-0001.json")).unwrap();
    let last = load_policy(&dir.path().join("snapshots/epoch-0002.json")).unwrap();
    assert_eq!((first.epoch, last.epoch), (1, 2));
    assert_eq!(last, load_policy(&dir.path().join("policy.json")).unwrap());
    assert_ne!(first.policy, last.policy);
    assert!(rows[1].env_steps > rows[0].env_steps && rows[1].env_steps <= 2 * 3 * 2 * 50, "{rows:?}");
    assert_eq!(rows[1].updates, 2 * 3 * 5);
    // The actor's time is a part of the collection time.
    assert!(rows.iter().all(|r| r.forward_seconds > 0.0 && r.forward_seconds < r.env_seconds), "{rows:?}");
    // Evaluation is a part of the episodes' time; the second epoch counts the first one's file writing.
    assert!(rows.iter().all(|r| r.eval_seconds > 0.0 && r.eval_seconds < r.env_seconds), "{rows:?}");
    assert!(rows[0].persist_seconds == 0.0 && rows[1].persist_seconds > 0.0, "{rows:?}");
    let header = std::fs::read_to_string(dir.path().join("progress.csv")).unwrap();
    assert!(header.starts_with("epoch,curriculum/level,train/success,test/success,finals/success"));
    let cfg: TrainConfig =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("config.json")).unwrap()).unwrap();
    assert_eq!(TrainConfig { task: None, ..cfg.clone() }, tiny("BlocksTouch-v0", 2));
    let task = cfg.task.expect("the run records its task");
    assert_eq!(task.id, "BlocksTouch-v0");
    assert_eq!(task.hash, blockpuzzle::env::registry::task("BlocksTouch-v0").unwrap().source.hash);
    // The builds and engines that ran its epochs (one here, from epoch 0).
    let spans = blockpuzzle::learn::train::RunDir { dir: dir.path().to_owned() }.read_provenance().unwrap();
    assert_eq!(spans.len(), 1);
    assert_eq!((spans[0].from_epoch, spans[0].build.mujoco.clone()), (0, blockpuzzle::sim::mj::version()));
    // A run carried with its checkpoint, config and progress only gives its policy file again, field for field.
    assert_eq!(policy_from_checkpoint(dir.path()).unwrap(), last);
    let carried = tempfile::tempdir().unwrap();
    for f in ["config.json", "progress.csv", "checkpoint.bin"] {
        std::fs::copy(dir.path().join(f), carried.path().join(f)).unwrap();
    }
    assert_eq!(policy_from_checkpoint(carried.path()).unwrap(), last);
    // DDPG learns from rewards alone: no solver version.
    assert_eq!(last.solver, None);
    // Through the CLI: `zoo export --from` the carried run.
    let zoo = tempfile::tempdir().unwrap();
    let out = std::process::Command::new(crate::common::CLI)
        .args(["zoo", "export", "--name", "carried", "--description", "d", "--trained-with", "t", "--zoo"])
        .arg(zoo.path())
        .arg("--from")
        .arg(carried.path())
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    // The same entry as the run's own policy file exports (the zoo keeps the normaliser's statistics in f32).
    let (_, exported) = blockpuzzle::benchmark::zoo::load(&zoo.path().join("carried.json")).unwrap();
    let info = blockpuzzle::benchmark::zoo::ExportInfo { name: "direct".into(), ..Default::default() };
    let direct = blockpuzzle::benchmark::zoo::export(zoo.path(), &last, &info).unwrap().with_extension("json");
    let (_, direct) = blockpuzzle::benchmark::zoo::load(&direct).unwrap();
    assert_eq!((exported.policy, exported.epoch), (direct.policy, 2));
    // Without its epoch's progress row, or with another run's config, it is refused by name.
    let config = std::fs::read_to_string(carried.path().join("config.json")).unwrap();
    std::fs::write(carried.path().join("config.json"), config.replace("\"seed\": 7", "\"seed\": 8")).unwrap();
    let e = policy_from_checkpoint(carried.path()).unwrap_err().to_string();
    assert!(e.contains("config.json") && e.contains("restore"), "{e}");
    std::fs::write(carried.path().join("config.json"), config).unwrap();
    let progress = std::fs::read_to_string(carried.path().join("progress.csv")).unwrap();
    let first_row: Vec<&str> = progress.lines().take(2).collect();
    std::fs::write(carried.path().join("progress.csv"), first_row.join("\n") + "\n").unwrap();
    let e = policy_from_checkpoint(carried.path()).unwrap_err().to_string();
    assert!(e.contains("no row for epoch 2"), "{e}");
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
    // A resume on the same build records no new span.
    assert_eq!(blockpuzzle::learn::train::RunDir { dir: split.path().to_owned() }.read_provenance().unwrap().len(), 1);
}

/// A branch continues its parent's state exactly (no change: the same run
/// as the parent continued), records where it came from, changes only what
/// a branch may change, and leaves the parent as it was.
#[test]
fn a_branch_continues_the_parent_exactly_and_leaves_it_alone() {
    let config = |epochs| TrainConfig { success_threshold: Some(0.0), ..tiny("BlocksChoose-v0", epochs) };
    let straight = tempfile::tempdir().unwrap();
    let a = train(&config(3), straight.path(), false, &mut quiet).unwrap();
    let parent = tempfile::tempdir().unwrap();
    train(&config(2), parent.path(), false, &mut quiet).unwrap();
    let before = std::fs::read(parent.path().join("checkpoint.bin")).unwrap();
    let root = tempfile::tempdir().unwrap();

    // Unchanged settings: exactly the parent's run continued.
    let same = root.path().join("same");
    let record = branch(parent.path(), &same, &config(3)).unwrap();
    assert_eq!((record.epoch, record.changed.len()), (2, 0));
    assert!(!same.join("snapshots").exists(), "snapshots stay with the parent");
    let b = train(&config(3), &same, true, &mut quiet).unwrap();
    assert_eq!(comparable(&a), comparable(&b));
    assert_eq!(
        load_policy(&straight.path().join("policy.json")).unwrap().policy,
        load_policy(&same.join("policy.json")).unwrap().policy
    );
    // The record survives resuming the branch.
    let saved: TrainConfig = serde_json::from_slice(&std::fs::read(same.join("config.json")).unwrap()).unwrap();
    assert_eq!(saved.branched_from.as_ref().map(|r| r.epoch), Some(2));
    assert_eq!(saved.options(), "5 batches per cycle, branched at epoch 2");
    let mut label = TrainConfig { batches: 60, ..config(1) };
    label.algos.ddpg = DdpgConfig { action_l2: 0.0, td3: true, ..DdpgConfig::default() };
    assert_eq!(label.options(), "TD3, no action penalty, 60 batches per cycle");

    // Changed draws: recorded, and the branch goes its own way from epoch 2 on.
    let more = TrainConfig { challenge_share: 1.0, level_replay: 0.5, ..config(4) };
    let changed = root.path().join("changed");
    let record = branch(parent.path(), &changed, &more).unwrap();
    assert_eq!(record.changed, ["--challenge-share", "--level-replay"]);
    assert_eq!(record.env_steps, read_progress(&parent.path().join("progress.csv")).unwrap()[1].env_steps);
    let c = train(&more, &changed, true, &mut quiet).unwrap();
    assert_eq!(c.len(), 4);
    assert_eq!(comparable(&c[..2]), comparable(&a[..2]), "the parent's history");
    assert_ne!(comparable(&c[2..3]), comparable(&a[2..3]), "lower levels replayed from epoch 2 on");
    // The parent is untouched.
    assert_eq!(std::fs::read(parent.path().join("checkpoint.bin")).unwrap(), before);
    assert_eq!(read_progress(&parent.path().join("progress.csv")).unwrap().len(), 2);
    assert!(checkpoint::load(&parent.path().join("checkpoint.bin"), "BlocksChoose-v0", 67, 4).is_ok());

    // The action penalties: the branch's agent uses its own from the first update,
    // and its checkpoints carry it (a branch resumed is the branch trained straight).
    let free = |epochs| {
        let mut c = config(epochs);
        c.algos.ddpg = DdpgConfig { action_l2: 0.0, preact_l2: 0.01, ..DdpgConfig::default() };
        c
    };
    let (split, whole) = (root.path().join("free-split"), root.path().join("free-whole"));
    assert_eq!(branch(parent.path(), &split, &free(3)).unwrap().changed, ["--action-l2", "--preact-l2"]);
    train(&free(3), &split, true, &mut quiet).unwrap();
    let d = train(&free(4), &split, true, &mut quiet).unwrap();
    branch(parent.path(), &whole, &free(4)).unwrap();
    let e = train(&free(4), &whole, true, &mut quiet).unwrap();
    assert_eq!(comparable(&d), comparable(&e));
    assert_ne!(d[2].actor_loss, a[2].actor_loss, "the penalty is part of the actor's loss");
    assert_eq!(comparable(&d[..2]), comparable(&a[..2]));

    // Refused: a setting the checkpoint fixes, an existing directory, a directory without a run.
    let other = TrainConfig { shared: SharedConfig { gamma: 0.9, ..config(3).shared }, ..config(3) };
    let err = branch(parent.path(), &root.path().join("gamma"), &other).unwrap_err().to_string();
    assert!(err.contains("--gamma") && err.contains("--challenge-share"), "{err}");
    assert!(!root.path().join("gamma").exists());
    let err = branch(parent.path(), &same, &config(3)).unwrap_err().to_string();
    assert!(err.contains("already exists"), "{err}");
    let err = branch(root.path(), &root.path().join("x"), &config(3)).unwrap_err().to_string();
    assert!(err.contains("not a run directory"), "{err}");
    let leftovers: Vec<_> = std::fs::read_dir(root.path()).unwrap().map(|e| e.unwrap().file_name()).collect();
    assert_eq!(leftovers.len(), 4, "no temporary folders left: {leftovers:?}");
}

/// The replay log: each checkpoint appends the epoch's transitions, segments
/// the buffer no longer holds are deleted, the buffer is rebuilt exactly
/// past a full ring, and a damaged segment is a clear error.
#[test]
fn replay_log_appends_prunes_and_rebuilds_the_buffer_exactly() {
    let small = |epochs| TrainConfig { buffer_size: 200, ..tiny("GripperTouch-v0", epochs) };
    let straight = tempfile::tempdir().unwrap();
    let a = train(&small(5), straight.path(), false, &mut quiet).unwrap();
    let split = tempfile::tempdir().unwrap();
    train(&small(3), split.path(), false, &mut quiet).unwrap();
    let b = train(&small(5), split.path(), true, &mut quiet).unwrap();
    assert_eq!(comparable(&a), comparable(&b));
    let ckpt = |d: &Path| checkpoint::load(&d.join("checkpoint.bin"), "GripperTouch-v0", 29, 4).unwrap();
    let (la, lb) = (ckpt(straight.path()), ckpt(split.path()));
    for (ra, rb) in la.replays.iter().zip(&lb.replays) {
        assert_eq!(ra.len(), 200, "the ring is full");
        assert!(ra.pushed() > 400, "and has wrapped");
        assert_eq!(ra.parts(), rb.parts());
    }
    // The checkpoint holds no transitions; the log only what the buffers still hold (plus at most an epoch).
    let log = straight.path().join("replay");
    let segments: Vec<_> = std::fs::read_dir(&log).unwrap().map(|e| e.unwrap().path()).collect();
    let logged: u64 = segments.iter().map(|p| std::fs::metadata(p).unwrap().len()).sum();
    let row = 4 * (2 * 29 + 4 + 4) as u64;
    assert!(logged <= 2 * (200 + 200) * row + 64 * segments.len() as u64, "{logged} bytes in {segments:?}");
    assert!(segments.iter().all(|p| p.file_name().unwrap().to_string_lossy().starts_with('w')));
    assert!(std::fs::metadata(straight.path().join("checkpoint.bin")).unwrap().len() < 200 * row * 2);

    // A damaged segment is named.
    let newest = segments.iter().max().unwrap();
    let mut bytes = std::fs::read(newest).unwrap();
    let n = bytes.len();
    bytes[n - 3] ^= 0xff;
    std::fs::write(newest, &bytes).unwrap();
    let err = checkpoint::load(&straight.path().join("checkpoint.bin"), "GripperTouch-v0", 29, 4).err().unwrap();
    let msg = err.to_string();
    assert!(msg.contains("corrupt") && msg.contains(&*newest.file_name().unwrap().to_string_lossy()), "{msg}");
}

/// This project's options: TD3, 3-step returns, the pre-tanh penalty, correlated noise, lower levels replayed.
fn tiny_ours(env: &str, epochs: usize) -> TrainConfig {
    let mut c = tiny(env, epochs);
    c.algos.ddpg.td3 = true;
    c.shared.n_step = 3;
    c.algos.ddpg.preact_l2 = 0.01;
    c.algos.ddpg.noise_correlation = 0.8;
    c.level_replay = 0.5;
    c.success_threshold = Some(0.0); // climb a level each epoch, so that lower levels exist
    c
}

#[test]
fn td3_n_step_and_level_replay_resume_exactly() {
    let straight = tempfile::tempdir().unwrap();
    let a = train(&tiny_ours("BlocksTouch-v0", 3), straight.path(), false, &mut quiet).unwrap();
    let split = tempfile::tempdir().unwrap();
    train(&tiny_ours("BlocksTouch-v0", 2), split.path(), false, &mut quiet).unwrap();
    let b = train(&tiny_ours("BlocksTouch-v0", 3), split.path(), true, &mut quiet).unwrap();
    assert_eq!(comparable(&a), comparable(&b));
    assert_eq!(a.iter().map(|r| r.level).collect::<Vec<_>>(), vec![0, 1, 2]);
    let ckpt = |d: &Path| checkpoint::load(&d.join("checkpoint.bin"), "BlocksTouch-v0", 48, 4).unwrap();
    let (la, lb) = (ckpt(straight.path()), ckpt(split.path()));
    let (x, y) = (la.agent.as_any().downcast_ref::<Ddpg>(), lb.agent.as_any().downcast_ref::<Ddpg>());
    let (Some(x), Some(y)) = (x, y) else { panic!("DDPG agents") };
    let (tx, ty) = (x.twin.as_ref().expect("TD3 twin critic"), y.twin.as_ref().unwrap());
    assert_eq!(tx.critic.to_vecs(), ty.critic.to_vecs(), "second critic resumed exactly");
    assert_eq!(tx.noise_seed, ty.noise_seed);
    assert_eq!(x.actor.to_vecs(), y.actor.to_vecs());
    assert_eq!(la.replays.len(), 2, "one buffer per worker");
    for (ra, rb) in la.replays.iter().zip(&lb.replays) {
        assert_eq!(ra.parts(), rb.parts());
    }
    // 3-step returns: some transitions bootstrap with γ² or γ³ (episode ends), most with γ³.
    let g = 0.98f32;
    let disc = &la.replays[0].parts().0.discount;
    assert!(disc.iter().all(|&d| d == g || d == g * g || d == g * g * g), "{:?}", &disc[..10]);
    assert!(disc.iter().filter(|&&d| d == g * g * g).count() > disc.len() / 2);
    // The actor is updated on every other update only.
    assert_eq!((x.actor_opt.t, x.critic_opt.t), (23, 45)); // updates 0, 2, ..., 44 of 45
}

#[test]
fn bad_settings_are_refused_before_anything_is_written() {
    let dir = tempfile::tempdir().unwrap();
    let run = dir.path().join("run");
    type Change = Box<dyn Fn(&mut TrainConfig)>;
    let bad: Vec<(&str, Change)> = vec![
        ("--lr-actor", Box::new(|c| c.shared.lr_actor = f64::NAN)),
        ("--lr-actor", Box::new(|c| c.shared.lr_actor = -1.0)),
        ("--lr-critic", Box::new(|c| c.shared.lr_critic = f64::INFINITY)),
        ("--polyak", Box::new(|c| c.shared.polyak = 1.5)),
        ("--random-eps", Box::new(|c| c.algos.ddpg.random_eps = f64::NAN)),
        ("--n-step", Box::new(|c| c.shared.n_step = 0)),
        ("--policy-delay", Box::new(|c| c.algos.ddpg.policy_delay = 0)),
        ("--level-replay", Box::new(|c| c.level_replay = 2.0)),
        ("--pg-lr", Box::new(|c| c.algos.pggd.lr = 0.0)),
        ("--t0", Box::new(|c| c.aggrevated.t0 = f64::NAN)),
        ("--challenge-share", Box::new(|c| c.challenge_share = 0.5)),
        ("--epochs", Box::new(|c| c.epochs = 0)),
        ("--torch-threads", Box::new(|c| c.torch_threads = 1 << 20)),
    ];
    for (flag, set) in bad {
        let mut c = tiny("BlocksTouch-v0", 1);
        set(&mut c);
        let err = format!("{:#}", anyhow::Error::from(train(&c, &run, false, &mut quiet).unwrap_err()));
        assert!(err.contains(flag) || (flag == "--challenge-share" && err.contains("no challenge")), "{flag}: {err}");
        assert!(!run.join("config.json").exists(), "{flag}: nothing written");
    }
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
    let err = anyhow::Error::from(train(&tiny("GripperTouch-v0", 2), dir.path(), true, &mut quiet).unwrap_err());
    assert!(format!("{err:#}").contains("not a blockpuzzle checkpoint"), "{err:#}");
}

#[test]
fn resume_with_other_settings_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    train(&tiny("GripperTouch-v0", 1), dir.path(), false, &mut quiet).unwrap();
    let mut other = tiny("GripperTouch-v0", 2);
    other.shared.gamma = 0.9;
    other.seed = 8;
    other.batch_size = 64;
    let err = train(&other, dir.path(), true, &mut quiet).unwrap_err().to_string();
    assert!(err.contains("differ from") && err.contains("--gamma"), "{err}");
    assert!(err.contains("--seed") && err.contains("--batch-size") && !err.contains("--epochs"), "{err}");
    let mut other = tiny("GripperTouch-v0", 2);
    other.algos.ddpg.td3 = true;
    let err = train(&other, dir.path(), true, &mut quiet).unwrap_err().to_string();
    assert!(err.contains("--td3"), "{err}");
    // --epochs and thread counts may change.
    let more = TrainConfig { torch_threads: 0, snapshot_every: 0, ..tiny("GripperTouch-v0", 2) };
    assert_eq!(train(&more, dir.path(), true, &mut quiet).unwrap().len(), 2);
    let err = train(&tiny("GripperTouch-v0", 2), Path::new("/nonexistent/run"), true, &mut quiet).unwrap_err();
    assert!(!err.to_string().is_empty());
}

#[test]
fn pggd_resume_restores_the_exact_state() {
    let straight = tempfile::tempdir().unwrap();
    let a = train(&tiny_pggd("GripperTouch-v0", 3, Default::default()), straight.path(), false, &mut quiet).unwrap();
    let split = tempfile::tempdir().unwrap();
    train(&tiny_pggd("GripperTouch-v0", 2, Default::default()), split.path(), false, &mut quiet).unwrap();
    let b = train(&tiny_pggd("GripperTouch-v0", 3, Default::default()), split.path(), true, &mut quiet).unwrap();
    assert_eq!(comparable(&a), comparable(&b));
    let pa = load_policy(&straight.path().join("policy.json")).unwrap();
    assert!(matches!(pa.policy, AnyPolicy::Pggd(_)), "policy.json holds the PGGD policy");
    assert_eq!(pa.policy, load_policy(&split.path().join("policy.json")).unwrap().policy);
    assert!(a.iter().all(|r| r.critic_loss == 0.0 && r.beta == 0.0 && r.expert_share == 0.0));
    // A DDPG resume of a PGGD run is refused.
    let err = train(&tiny("GripperTouch-v0", 4), split.path(), true, &mut quiet).unwrap_err();
    assert!(err.to_string().contains("--algo"), "{err}");
}

/// A tiny DDPG expert on BlocksTouch-v0 in `dir`.
fn expert(dir: &Path) {
    train(&tiny("BlocksTouch-v0", 1), dir, false, &mut quiet).unwrap();
}

#[test]
fn aggrevated_mixes_by_beta() {
    let exp = tempfile::tempdir().unwrap();
    expert(exp.path());
    let with = |beta0: f64, t0: f64, pg_weight: PgWeight| AggrevatedConfig {
        expert: Some(exp.path().to_owned()),
        beta0,
        t0,
        pg_weight,
    };
    // β = 1: the expert takes every exploration step.
    let dir = tempfile::tempdir().unwrap();
    let rows =
        train(&tiny_pggd("BlocksChoose-v0", 2, with(1.0, 50.0, PgWeight::Return)), dir.path(), false, &mut quiet)
            .unwrap();
    assert!(rows.iter().all(|r| r.beta == 1.0 && r.expert_share == 1.0), "{rows:?}");
    // The run keeps its own copy of the expert and resumes from it, even when
    // the expert's run directory is gone.
    let copy = load_policy(&dir.path().join("expert_policy.json")).unwrap();
    assert_eq!(copy.policy, load_policy(exp.path()).unwrap().policy);
    let moved = tempfile::tempdir().unwrap();
    std::fs::rename(exp.path(), moved.path().join("expert")).unwrap();
    train(&tiny_pggd("BlocksChoose-v0", 3, with(1.0, 50.0, PgWeight::Return)), dir.path(), true, &mut quiet).unwrap();
    std::fs::rename(moved.path().join("expert"), exp.path()).unwrap();
    // β = 0 (t0 = 0: β0 from the start): never.
    let dir = tempfile::tempdir().unwrap();
    let rows = train(&tiny_pggd("BlocksChoose-v0", 1, with(0.0, 0.0, PgWeight::Return)), dir.path(), false, &mut quiet)
        .unwrap();
    assert!(rows.iter().all(|r| r.beta == 0.0 && r.expert_share == 0.0), "{rows:?}");
    // The paper's schedule (β0 = 0, t0 = 50) with the expert critic's advantage.
    let dir = tempfile::tempdir().unwrap();
    let rows = train(
        &tiny_pggd("BlocksChoose-v0", 2, with(0.0, 50.0, PgWeight::ExpertAdvantage)),
        dir.path(),
        false,
        &mut quiet,
    )
    .unwrap();
    assert_eq!(rows[0].beta, 1.0);
    assert!((rows[1].beta - (-1.0f64 / 50.0).exp()).abs() < 1e-12, "{rows:?}");
    assert!(rows.iter().all(|r| r.actor_loss.is_finite()));
}

#[test]
fn bad_expert_settings_are_clear_errors() {
    let exp = tempfile::tempdir().unwrap();
    expert(exp.path());
    let dir = tempfile::tempdir().unwrap();
    let adv = AggrevatedConfig { pg_weight: PgWeight::ExpertAdvantage, ..Default::default() };
    let err = train(&tiny_pggd("BlocksChoose-v0", 1, adv), dir.path(), false, &mut quiet).unwrap_err();
    assert!(err.to_string().contains("--expert"), "{err}");
    let missing = AggrevatedConfig { expert: Some("/nonexistent/expert".into()), ..Default::default() };
    let err = anyhow::Error::from(
        train(&tiny_pggd("BlocksChoose-v0", 1, missing), dir.path(), false, &mut quiet).unwrap_err(),
    );
    assert!(format!("{err:#}").contains("/nonexistent/expert"), "{err:#}");
    // An expert whose observation does not fit even without grey blocks.
    let gt = tempfile::tempdir().unwrap();
    train(&tiny("GripperTouch-v0", 1), gt.path(), false, &mut quiet).unwrap();
    let wrong = AggrevatedConfig { expert: Some(gt.path().to_owned()), ..Default::default() };
    let err = train(&tiny_pggd("BlocksChoose-v0", 1, wrong), dir.path(), false, &mut quiet).unwrap_err();
    assert!(err.to_string().contains("without grey blocks"), "{err}");
    assert!(!dir.path().join("expert_policy.json").exists(), "a rejected expert is not copied into the run");
    // DDPG takes no expert.
    let ddpg = TrainConfig {
        aggrevated: AggrevatedConfig { expert: Some(exp.path().to_owned()), ..Default::default() },
        ..tiny("BlocksChoose-v0", 1)
    };
    let err = train(&ddpg, dir.path(), false, &mut quiet).unwrap_err();
    assert!(err.to_string().contains("--algo pggd"), "{err}");
    // Nor does SAC; and SAC has no --td3.
    let sac = TrainConfig { algo: Algo::named("sac").unwrap(), ..ddpg };
    let err = train(&sac, dir.path(), false, &mut quiet).unwrap_err();
    assert!(err.to_string().contains("SAC trains without an expert"), "{err}");
    let mut td3 = tiny_sac("BlocksChoose-v0", 1);
    td3.algos.ddpg.td3 = true;
    let err = train(&td3, dir.path(), false, &mut quiet).unwrap_err();
    assert!(err.to_string().contains("--td3 is only used with --algo ddpg"), "{err}");
}

fn tiny_sac(env: &str, epochs: usize) -> TrainConfig {
    TrainConfig {
        algo: Algo::named("sac").unwrap(),
        shared: SharedConfig { n_step: 2, ..tiny(env, epochs).shared },
        ..tiny(env, epochs)
    }
}

/// SAC trains through the same loop: it resumes bit for bit (its noise
/// streams, temperature and twin critics included), saves its mean action
/// as a deterministic actor, and its checkpoint names its algorithm.
#[test]
fn sac_resumes_exactly_and_saves_a_deterministic_policy() {
    let straight = tempfile::tempdir().unwrap();
    let a = train(&tiny_sac("GripperTouch-v0", 3), straight.path(), false, &mut quiet).unwrap();
    let split = tempfile::tempdir().unwrap();
    train(&tiny_sac("GripperTouch-v0", 2), split.path(), false, &mut quiet).unwrap();
    let b = train(&tiny_sac("GripperTouch-v0", 3), split.path(), true, &mut quiet).unwrap();
    assert_eq!(comparable(&a), comparable(&b));
    assert!(a.iter().all(|r| r.critic_loss > 0.0 && r.critic_loss.is_finite()), "{a:?}");
    let pa = load_policy(&straight.path().join("policy.json")).unwrap();
    assert!(matches!(pa.policy, AnyPolicy::Deterministic(_)), "the mean action, as a deterministic actor");
    assert!(pa.critic.is_some(), "Q1 saved beside it");
    assert_eq!(pa.policy, load_policy(&split.path().join("policy.json")).unwrap().policy);
    let loaded = checkpoint::load(&split.path().join("checkpoint.bin"), "GripperTouch-v0", 29, 4).unwrap();
    assert_eq!(loaded.agent.name(), "sac");
    assert_eq!(tiny_sac("GripperTouch-v0", 1).default_run_dir().display().to_string(), "runs/GripperTouch-v0-sac-s7");
    // A DDPG resume of a SAC run is refused, naming the flag that differs.
    let err = train(&tiny("GripperTouch-v0", 4), split.path(), true, &mut quiet).unwrap_err();
    assert!(err.to_string().contains("--algo"), "{err}");
}

#[test]
fn expert_advantage_uses_the_critic_of_the_experts_epoch() {
    use blockpuzzle::benchmark::saved::SavedPolicy;
    let exp = tempfile::tempdir().unwrap();
    expert(exp.path());
    let adv = |expert: &Path| AggrevatedConfig {
        expert: Some(expert.to_owned()),
        pg_weight: PgWeight::ExpertAdvantage,
        ..Default::default()
    };
    let read = |p: &Path| -> SavedPolicy { serde_json::from_str(&std::fs::read_to_string(p).unwrap()).unwrap() };
    // A policy saved by training carries its critic: no checkpoint needed.
    let saved = read(&exp.path().join("policy.json"));
    assert!(saved.critic.is_some());
    let alone = tempfile::tempdir().unwrap();
    std::fs::copy(exp.path().join("policy.json"), alone.path().join("expert.json")).unwrap();
    let dir = tempfile::tempdir().unwrap();
    train(&tiny_pggd("BlocksChoose-v0", 1, adv(&alone.path().join("expert.json"))), dir.path(), false, &mut quiet)
        .unwrap();
    // The run's copy keeps the critic, so the run resumes without the original.
    assert_eq!(read(&dir.path().join("expert_policy.json")).critic, saved.critic);
    drop(alone);
    let cfg: TrainConfig =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("config.json")).unwrap()).unwrap();
    train(&TrainConfig { epochs: 2, ..cfg }, dir.path(), true, &mut quiet).unwrap();

    // An older policy without a critic: the checkpoint beside it is used only
    // when it is of the same epoch.
    let old = SavedPolicy { critic: None, ..saved };
    std::fs::write(exp.path().join("policy.json"), serde_json::to_string(&old).unwrap()).unwrap();
    let dir = tempfile::tempdir().unwrap();
    train(&tiny_pggd("BlocksChoose-v0", 1, adv(&exp.path().join("policy.json"))), dir.path(), false, &mut quiet)
        .unwrap();
    assert!(read(&dir.path().join("expert_policy.json")).critic.is_some(), "the copy gets the checkpoint's critic");
    let stale = SavedPolicy { epoch: old.epoch + 5, ..old };
    std::fs::write(exp.path().join("policy.json"), serde_json::to_string(&stale).unwrap()).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let err =
        train(&tiny_pggd("BlocksChoose-v0", 1, adv(&exp.path().join("policy.json"))), dir.path(), false, &mut quiet)
            .unwrap_err();
    let err = anyhow::Error::from(err);
    assert!(format!("{err:#}").contains("another policy"), "{err:#}");
    std::fs::remove_file(exp.path().join("checkpoint.bin")).unwrap();
    let err =
        train(&tiny_pggd("BlocksChoose-v0", 1, adv(&exp.path().join("policy.json"))), dir.path(), false, &mut quiet)
            .unwrap_err();
    let err = anyhow::Error::from(err);
    assert!(format!("{err:#}").contains("no ") && format!("{err:#}").contains("checkpoint.bin"), "{err:#}");
}

#[test]
fn each_method_has_its_own_default_run_directory() {
    let with = |pg_weight| AggrevatedConfig { expert: Some("e".into()), pg_weight, ..Default::default() };
    let dirs: Vec<_> = [
        tiny("BlocksChoose-v0", 1),
        tiny_pggd("BlocksChoose-v0", 1, AggrevatedConfig::default()),
        tiny_pggd("BlocksChoose-v0", 1, with(PgWeight::Return)),
        tiny_pggd("BlocksChoose-v0", 1, with(PgWeight::ExpertAdvantage)),
    ]
    .iter()
    .map(|c| c.default_run_dir().display().to_string())
    .collect();
    assert_eq!(
        dirs,
        [
            "runs/BlocksChoose-v0-ddpg-s7",
            "runs/BlocksChoose-v0-pggd-s7",
            "runs/BlocksChoose-v0-pggd-aggrevated-s7",
            "runs/BlocksChoose-v0-pggd-aggrevated-adv-s7"
        ]
    );
}

#[test]
fn a_task_file_run_records_its_task_refuses_a_changed_file_and_survives_a_moved_one() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("reach.toml");
    let text = blockpuzzle::env::registry::REGISTRY.iter().find(|r| r.id == "GripperTouch-v0").unwrap().toml;
    std::fs::write(&file, text.replace("GripperTouch-v0", "MyReach-v0")).unwrap();
    let run = dir.path().join("run");
    let env = file.to_str().unwrap();
    train(&tiny(env, 1), &run, false, &mut quiet).unwrap();
    let saved = blockpuzzle::benchmark::load::load_policy(&run).unwrap();
    assert_eq!(saved.env_id, "MyReach-v0");
    assert_eq!(saved.task.as_ref().unwrap().id, "MyReach-v0");
    assert!(std::fs::read_to_string(run.join("config.json")).unwrap().contains("MyReach-v0"));

    // A comment changes nothing; a changed setting is refused, by name.
    std::fs::write(&file, format!("# edited\n{}", text.replace("GripperTouch-v0", "MyReach-v0"))).unwrap();
    train(&tiny(env, 2), &run, true, &mut quiet).unwrap();
    std::fs::write(
        &file,
        text.replace("GripperTouch-v0", "MyReach-v0").replace("max_episode_steps = 50", "max_episode_steps = 40"),
    )
    .unwrap();
    let err = format!("{:#}", anyhow::Error::from(train(&tiny(env, 3), &run, true, &mut quiet).unwrap_err()));
    assert!(err.contains("has changed since the run started") && err.contains("max_episode_steps"), "{err}");

    // Moved away: the run goes on with its recorded copy, and its policy still finds its task.
    std::fs::remove_file(&file).unwrap();
    let rows = train(&tiny(env, 3), &run, true, &mut quiet).unwrap();
    assert_eq!(rows.len(), 3);
    let saved = blockpuzzle::benchmark::load::load_policy(&run).unwrap();
    let task = blockpuzzle::env::registry::recorded(saved.task.as_ref().unwrap()).unwrap();
    assert_eq!((task.id(), task.spec.max_episode_steps), ("MyReach-v0", 50));
}

/// A checkpoint written before algorithms declared their state (Adam step
/// counts and TD3's seed as fixed header fields, no `counters`) and before
/// they had settings of their own (every shared setting in the `ddpg` group)
/// loads to the same agent; a `config.json` of that time reads as it did.
#[test]
fn checkpoints_with_the_old_counter_fields_still_load() {
    let dir = tempfile::tempdir().unwrap();
    let mut config = tiny("GripperTouch-v0", 1);
    config.algos.ddpg.td3 = true;
    train(&config, dir.path(), false, &mut quiet).unwrap();
    let path = dir.path().join("checkpoint.bin");
    let mut now = checkpoint::load(&path, "GripperTouch-v0", 29, 4).unwrap();
    let bytes = std::fs::read(&path).unwrap();
    let hlen = u64::from_le_bytes(bytes[8..16].try_into().unwrap()) as usize;
    let mut header: serde_json::Value = serde_json::from_slice(&bytes[16..16 + hlen]).unwrap();
    let counters = header["counters"].take();
    assert!(counters["critic2_adam.t"].as_u64().unwrap() > 0, "{counters}");
    header.as_object_mut().unwrap().remove("counters");
    header["actor_adam_t"] = counters["actor_adam.t"].clone();
    header["critic_adam_t"] = counters["critic_adam.t"].clone();
    header["twin"] = serde_json::json!([counters["critic2_adam.t"], counters["critic2.noise_seed"]]);
    old_settings(&mut header);
    assert!(header["ddpg"]["td3"] == true && header["ddpg"]["hidden"] == 32, "{}", header["ddpg"]);
    let json = serde_json::to_vec(&header).unwrap();
    let mut old = bytes[..8].to_vec();
    old.extend_from_slice(&(json.len() as u64).to_le_bytes());
    old.extend_from_slice(&json);
    old.extend_from_slice(&bytes[16 + hlen..]);
    std::fs::write(&path, old).unwrap();
    let mut then = checkpoint::load(&path, "GripperTouch-v0", 29, 4).unwrap();
    assert_eq!(then.agent.state(), now.agent.state());
    assert_eq!(then.agent.norm(), now.agent.norm());

    let run = blockpuzzle::learn::train::RunDir { dir: dir.path().to_owned() };
    let recorded = run.read_config().unwrap();
    let mut json: serde_json::Value = serde_json::from_slice(&std::fs::read(run.config()).unwrap()).unwrap();
    old_settings(&mut json);
    std::fs::write(run.config(), serde_json::to_vec(&json).unwrap()).unwrap();
    assert_eq!(run.read_config().unwrap(), recorded);
}

/// The settings groups as files held them before the algorithms had settings
/// of their own: the shared ones and DDPG's together in `ddpg`, no `shared`.
fn old_settings(file: &mut serde_json::Value) {
    let map = file.as_object_mut().unwrap();
    let mut ddpg = map.remove("shared").unwrap();
    for (k, v) in map["ddpg"].as_object().unwrap() {
        ddpg[k] = v.clone();
    }
    map.insert("ddpg".into(), ddpg);
    map.remove("sac");
}

/// The set network over the `objects` observation, with hindsight colours and TD3.
fn tiny_set(env: &str, epochs: usize, pooling: Pooling) -> TrainConfig {
    let mut c = tiny(env, epochs);
    c.net = NetConfig { net: NetKind::Set, set_pooling: pooling, ..NetConfig::default() };
    c.hindsight_colours = 2;
    c.algos.ddpg.td3 = true;
    c
}

#[test]
fn a_set_network_with_hindsight_colours_trains_resumes_exactly_and_plays_any_object_count() {
    let straight = tempfile::tempdir().unwrap();
    let a = train(&tiny_set("BlocksChooseN-v0", 3, Pooling::MeanMax), straight.path(), false, &mut quiet).unwrap();
    let split = tempfile::tempdir().unwrap();
    train(&tiny_set("BlocksChooseN-v0", 2, Pooling::MeanMax), split.path(), false, &mut quiet).unwrap();
    let b = train(&tiny_set("BlocksChooseN-v0", 3, Pooling::MeanMax), split.path(), true, &mut quiet).unwrap();
    assert_eq!(comparable(&a), comparable(&b));
    let (pa, pb) = (
        load_policy(&straight.path().join("policy.json")).unwrap(),
        load_policy(&split.path().join("policy.json")).unwrap(),
    );
    assert_eq!(pa.policy, pb.policy, "same weights and normaliser after resuming");
    assert_eq!(pa.obs_mode(), blockpuzzle::env::ObsMode::Objects);
    assert!(pa.policy.net().set.is_some_and(|s| s.slots == 6), "BlocksChooseN-v0 has six object slots");
    // Resuming with the other network is refused, naming the flag.
    let flat = TrainConfig { net: NetConfig::default(), ..tiny_set("BlocksChooseN-v0", 4, Pooling::MeanMax) };
    let err = train(&flat, split.path(), true, &mut quiet).unwrap_err().to_string();
    assert!(err.contains("--net"), "{err}");
    let pairs = TrainConfig {
        hindsight_strategy: blockpuzzle::env::hindsight::Strategy::Pairs,
        ..tiny_set("BlocksChooseN-v0", 4, Pooling::MeanMax)
    };
    let err = train(&pairs, split.path(), true, &mut quiet).unwrap_err().to_string();
    assert!(err.contains("--hindsight-strategy"), "{err}");
    // The policy plays BlocksChoose-v0 (three slots) and BlocksTouch-v0 (two) as well.
    for id in ["BlocksChoose-v0", "BlocksTouch-v0", "BlocksChooseN-v0"] {
        let task = blockpuzzle::env::registry::task(id).unwrap();
        let spec = blockpuzzle::benchmark::evaluate::EvalSpec {
            task: &task,
            challenge: false,
            distribution: None,
            level: Some(0),
            episodes: 4,
            seed: 11,
            threads: 2,
        };
        let path = straight.path().join("policy.json");
        let r = blockpuzzle::benchmark::evaluate::evaluate(&path, pa.clone(), &spec).unwrap();
        assert_eq!(r.episodes, 4, "{id}");
    }
    // Hindsight colours ran: the environments recorded contacts (progress has the columns).
    let text = std::fs::read_to_string(straight.path().join("progress.csv")).unwrap();
    assert!(text.lines().next().unwrap().contains("hindsight/relabelled"));
}

#[test]
fn attention_pooling_trains_and_its_policy_acts_as_saved() {
    let dir = tempfile::tempdir().unwrap();
    let c = TrainConfig {
        hindsight_strategy: blockpuzzle::env::hindsight::Strategy::Pairs,
        ..tiny_set("BlocksChoose-v0", 1, Pooling::Attention)
    };
    train(&c, dir.path(), false, &mut quiet).unwrap();
    let saved = load_policy(&dir.path().join("policy.json")).unwrap();
    assert!(saved.policy.net().set.is_some_and(|s| s.attention));
    let cfg: TrainConfig =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("config.json")).unwrap()).unwrap();
    assert_eq!(cfg.net.set_pooling, Pooling::Attention);
    assert!(cfg.title().contains("set network + attention") && cfg.title().contains("hindsight colours 2"));
    assert!(
        cfg.hindsight_strategy == blockpuzzle::env::hindsight::Strategy::Pairs
            && cfg.title().contains("hindsight pairs")
    );
}

#[test]
fn set_networks_refuse_what_they_cannot_do() {
    let dir = tempfile::tempdir().unwrap();
    let mut c = tiny_set("BlocksChoose-v0", 1, Pooling::MeanMax);
    c.algo = Algo::Pggd;
    c.algos.ddpg.td3 = false;
    c.aggrevated.expert = Some("zoo-name-that-does-not-matter".into());
    let err = train(&c, &dir.path().join("x"), false, &mut quiet).unwrap_err().to_string();
    assert!(err.contains("--expert") && err.contains("--net mlp"), "{err}");
    assert!(!dir.path().join("x").exists(), "nothing written");
    let mut c = tiny_set("BlocksChoose-v0", 1, Pooling::MeanMax);
    c.net.set_encoder_layers = 0;
    let err = train(&c, &dir.path().join("y"), false, &mut quiet).unwrap_err().to_string();
    assert!(err.contains("--set-encoder-layers"), "{err}");
    let mut c = tiny_set("BlocksChoose-v0", 1, Pooling::MeanMax);
    c.net = NetConfig { set_norm: true, ..NetConfig::default() };
    let err = train(&c, &dir.path().join("z"), false, &mut quiet).unwrap_err().to_string();
    assert!(err.contains("--set-norm") && err.contains("--net set"), "{err}");
    assert!(!dir.path().join("z").exists(), "nothing written");
}

/// `--net entity`: the set network over the `entities` observation (its gripper, table and floor
/// rows included) trains with hindsight colours, saves a policy that asks for that observation and
/// plays another task's rows; an `objects` environment is refused, naming the observation.
#[test]
fn an_entity_set_network_trains_and_its_policy_reads_the_entities() {
    use blockpuzzle::env::{EnvConfig, ObsMode, ObsSpec};
    let dir = tempfile::tempdir().unwrap();
    let mut c = tiny_set("ToppleTower-v0", 1, Pooling::MeanMax);
    c.net.net = NetKind::Entity;
    train(&c, dir.path(), false, &mut quiet).unwrap();
    let path = dir.path().join("policy.json");
    let saved = load_policy(&path).unwrap();
    assert_eq!(saved.obs_mode(), ObsMode::Entities);
    let blocks = blockpuzzle::env::registry::task("ToppleTower-v0").unwrap().object_count();
    assert!(saved.policy.net().set.is_some_and(|s| s.slots == blocks + 3 && s.object == 26));
    assert!(c.title().contains("entity set network") && c.default_run_dir().to_string_lossy().contains("-entity-s"));
    let env_of = |id: &str, mode| {
        let task = blockpuzzle::env::registry::task(id).unwrap();
        blockpuzzle::env::BlockEnv::new(EnvConfig { obs_mode: mode, ..EnvConfig::new(task) }).unwrap()
    };
    let mut avoid = env_of("BlocksAvoid-v0", ObsMode::Entities);
    let mut t = blockpuzzle::benchmark::evaluate::trained_policy(&path, saved.clone(), &avoid).unwrap();
    let (obs, _) = avoid.reset(Some(0)).unwrap();
    let a = blockpuzzle::policy::Policy::act(&mut t, &obs);
    assert!(a.iter().all(|x| x.abs() <= 1.0), "{a:?}");
    let e = blockpuzzle::benchmark::evaluate::trained_policy(&path, saved, &env_of("BlocksAvoid-v0", ObsMode::Objects));
    assert!(e.unwrap_err().to_string().contains("give the environment obs_mode entities"));
    let wrong =
        blockpuzzle::learn::agents::arch::Arch::of(&ObsSpec::new(ObsMode::Objects, 3), &c.net).unwrap_err().to_string();
    assert!(wrong.contains("--net entity reads the `entities` observation"), "{wrong}");
}

#[test]
fn a_layer_normalised_set_network_trains_saves_and_refuses_to_resume_without_it() {
    let dir = tempfile::tempdir().unwrap();
    let mut c = tiny_set("BlocksChoose-v0", 1, Pooling::MeanMax);
    c.net.set_norm = true;
    train(&c, dir.path(), false, &mut quiet).unwrap();
    let saved = load_policy(&dir.path().join("policy.json")).unwrap();
    assert!(saved.policy.net().set.is_some_and(|s| s.norm), "the saved layout says so");
    let cfg: TrainConfig =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("config.json")).unwrap()).unwrap();
    assert!(cfg.net.set_norm && cfg.title().contains("layer-normalised"), "{}", cfg.title());
    assert!(cfg.default_run_dir().to_string_lossy().contains("-set-norm-s"));
    let mut plain = tiny_set("BlocksChoose-v0", 2, Pooling::MeanMax);
    plain.net.set_norm = false;
    let err = train(&plain, dir.path(), true, &mut quiet).unwrap_err().to_string();
    assert!(err.contains("--set-norm"), "{err}");
}

#[test]
fn flat_critics_train_a_set_actor_resume_exactly_and_are_refused_where_they_mean_nothing() {
    // TD3 (two critics) and SAC (two Q networks), each split by a resume.
    for algo in ["ddpg", "sac"] {
        let flat = |epochs| {
            let mut c = tiny_set("BlocksChoose-v0", epochs, Pooling::MeanMax);
            c.algo = Algo::named(algo).unwrap();
            c.algos.ddpg.td3 = algo == "ddpg";
            c.shared.flat_critic = true;
            c
        };
        let (straight, split) = (tempfile::tempdir().unwrap(), tempfile::tempdir().unwrap());
        let a = train(&flat(2), straight.path(), false, &mut quiet).unwrap();
        train(&flat(1), split.path(), false, &mut quiet).unwrap();
        let b = train(&flat(2), split.path(), true, &mut quiet).unwrap();
        assert_eq!(comparable(&a), comparable(&b), "{algo}");
        let saved = load_policy(&straight.path().join("policy.json")).unwrap();
        assert!(saved.policy.net().set.is_some(), "{algo}: the policy is the set actor");
        let cfg: TrainConfig =
            serde_json::from_str(&std::fs::read_to_string(straight.path().join("config.json")).unwrap()).unwrap();
        assert!(cfg.title().contains("flat critics"), "{}", cfg.title());
        assert!(cfg.default_run_dir().to_string_lossy().contains("-set-flatcritic-s"));
        // Resuming with set critics is refused, naming the flag.
        let mut same = flat(3);
        same.shared.flat_critic = false;
        let err = train(&same, split.path(), true, &mut quiet).unwrap_err().to_string();
        assert!(err.contains("--flat-critic"), "{algo}: {err}");
    }
    let dir = tempfile::tempdir().unwrap();
    let mut c = tiny("BlocksChoose-v0", 1);
    c.shared.flat_critic = true;
    let err = train(&c, &dir.path().join("mlp"), false, &mut quiet).unwrap_err().to_string();
    assert!(err.contains("--flat-critic") && err.contains("--net set"), "{err}");
    let mut c = tiny_set("BlocksChoose-v0", 1, Pooling::MeanMax);
    (c.algo, c.algos.ddpg.td3, c.shared.flat_critic) = (Algo::Pggd, false, true);
    let err = train(&c, &dir.path().join("pggd"), false, &mut quiet).unwrap_err().to_string();
    assert!(err.contains("--flat-critic") && err.contains("PGGD"), "{err}");
    assert!(!dir.path().join("mlp").exists() && !dir.path().join("pggd").exists(), "nothing written");
}

#[test]
fn sac_and_pggd_train_set_networks_too() {
    for algo in ["sac", "pggd"] {
        let dir = tempfile::tempdir().unwrap();
        let mut c = tiny_set("BlocksAvoid-v0", 1, Pooling::Colour);
        c.algo = Algo::named(algo).unwrap();
        c.algos.ddpg.td3 = false;
        train(&c, dir.path(), false, &mut quiet).unwrap();
        let saved = load_policy(&dir.path().join("policy.json")).unwrap();
        let set = saved.policy.net().set.expect("a set network");
        assert!(set.by_colour && set.slots == 5, "{algo}: {set:?}");
        assert_eq!(saved.obs_mode(), blockpuzzle::env::ObsMode::Objects, "{algo}");
    }
}

#[test]
fn counts_train_recorded_refuse_to_change_on_resume_and_bad_ones_write_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let mut c = tiny("BlocksAvoid-v0", 1);
    c.counts = Some("red=0".parse().unwrap());
    train(&c, dir.path(), false, &mut quiet).unwrap();
    let cfg: TrainConfig =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("config.json")).unwrap()).unwrap();
    assert_eq!(cfg.counts.as_ref().map(ToString::to_string).as_deref(), Some("red=0"));
    assert!(cfg.title().contains("counts red=0"), "{}", cfg.title());
    assert_eq!(cfg.default_run_dir().display().to_string(), "runs/BlocksAvoid-v0-ddpg-red0-s7");
    // The policy keeps the task as written (its three red slots).
    let saved = load_policy(&dir.path().join("policy.json")).unwrap();
    assert_eq!(saved.task.as_ref().map(|t| t.id.as_str()), Some("BlocksAvoid-v0"));
    let mut other = tiny("BlocksAvoid-v0", 2);
    other.counts = None;
    let err = train(&other, dir.path(), true, &mut quiet).unwrap_err().to_string();
    assert!(err.contains("--counts"), "{err}");
    // A range the scene cannot hold is refused before anything is written.
    let mut bad = tiny("BlocksChooseN-v0", 1);
    bad.counts = Some("grey=0-9".parse().unwrap());
    let err = train(&bad, &dir.path().join("x"), false, &mut quiet).unwrap_err().to_string();
    assert!(err.contains("holds 4 copies of grey") && err.contains("0-4"), "{err}");
    assert!(!dir.path().join("x").exists(), "nothing written");
}

/// The configurations of the runs recorded in results/ read as they were written: those of
/// earlier versions (the oldest before n-step returns and TD3) take the shared settings from their
/// `ddpg` group, each algorithm's own from its group or the defaults; those of today's layout (a
/// `shared` group) read back field for field.
#[test]
fn the_recorded_runs_configurations_still_read() {
    fn walk(dir: &std::path::Path, out: &mut Vec<std::path::PathBuf>) {
        for entry in std::fs::read_dir(dir).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                walk(&path, out);
            } else if path.to_string_lossy().ends_with("config.json") {
                out.push(path);
            }
        }
    }
    let mut files = Vec::new();
    walk(&std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("results"), &mut files);
    let (mut read, mut current) = (0, 0);
    for path in files {
        let text = std::fs::read_to_string(&path).unwrap();
        let file: serde_json::Value = serde_json::from_str(&text).unwrap();
        let c: TrainConfig = serde_json::from_str(&text).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        // Written again, it is today's layout and reads back the same.
        let written = serde_json::to_value(&c).unwrap();
        let again: TrainConfig = serde_json::from_value(written.clone()).unwrap();
        assert_eq!(again, c);
        if file.get("shared").is_some() {
            assert_eq!(file, written, "{}", path.display());
            current += 1;
            continue;
        }
        let old = &file["ddpg"];
        let shared = &c.shared;
        assert_eq!(
            (shared.layers, shared.hidden),
            (old["layers"].as_u64().unwrap() as usize, old["hidden"].as_u64().unwrap() as usize)
        );
        assert_eq!(
            (shared.gamma, shared.lr_critic),
            (old["gamma"].as_f64().unwrap(), old["lr_critic"].as_f64().unwrap())
        );
        assert_eq!(shared.n_step, old.get("n_step").map_or(1, |v| v.as_u64().unwrap() as usize));
        assert_eq!(c.algos.ddpg.td3, old.get("td3").is_some_and(|v| v.as_bool().unwrap()));
        assert_eq!(c.algos.ddpg.noise_eps, old["noise_eps"].as_f64().unwrap());
        if let Some(p) = file.get("pggd") {
            assert_eq!(c.algos.pggd.lr, p["lr"].as_f64().unwrap());
        }
        read += 1;
    }
    assert!(read >= 20, "{read} recorded configurations of earlier layouts");
    assert!(current >= 5, "{current} recorded configurations of today's layout");
}

#[test]
fn bc_and_dagger_learn_the_solvers_labels_resume_exactly_and_refuse_what_they_cannot_use() {
    let imitate = |algo: &str, epochs| {
        let mut c = tiny("BlocksTouch-v0", epochs);
        c.algo = Algo::named(algo).unwrap();
        c.net = NetConfig { net: NetKind::Entity, ..NetConfig::default() };
        if algo == "dagger" {
            // DAgger's runs also read robot tokens (the robot features beside every row), keep
            // statistics per row type and have rows narrower than the head (which a resume must
            // rebuild from the checkpoint).
            c.algos.dagger.t0 = 1.0;
            c.net.set_robot_tokens = true;
            c.net.set_type_norm = true;
            c.net.set_width = 8;
        }
        c
    };
    // BC: the solver plays every exploration step (with noise on its actions); no critic.
    let dir = tempfile::tempdir().unwrap();
    let mut bc = imitate("bc", 2);
    bc.algos.bc.noise = 0.1;
    assert!(bc.title().contains("noise 0.1"), "{}", bc.title());
    let rows = train(&bc, dir.path(), false, &mut quiet).unwrap();
    assert!(rows.iter().all(|r| r.beta == 1.0 && r.expert_share == 1.0), "{rows:?}");
    assert!(rows.iter().all(|r| r.critic_loss == 0.0 && r.mean_q == 0.0 && r.actor_loss > 0.0), "{rows:?}");
    assert!(rows[0].train_success >= 0.5, "the solver's own episodes at level 0: {rows:?}");
    let saved = load_policy(&dir.path().join("policy.json")).unwrap();
    assert_eq!(saved.obs_mode(), blockpuzzle::env::ObsMode::Entities);
    // DAgger: the solver's share decays (1, e^-1, e^-2) and a resumed run continues exactly.
    let (straight, split) = (tempfile::tempdir().unwrap(), tempfile::tempdir().unwrap());
    let a = train(&imitate("dagger", 3), straight.path(), false, &mut quiet).unwrap();
    train(&imitate("dagger", 2), split.path(), false, &mut quiet).unwrap();
    let b = train(&imitate("dagger", 3), split.path(), true, &mut quiet).unwrap();
    assert_eq!(comparable(&a), comparable(&b));
    assert_eq!(a[0].beta, 1.0);
    assert!((a[2].beta - (-2.0f64).exp()).abs() < 1e-12, "{}", a[2].beta);
    assert!(
        a[2].expert_share < 0.5 && a[2].expert_share > 0.0,
        "the learner acts on most steps: {}",
        a[2].expert_share
    );
    let tokens = load_policy(&straight.path().join("policy.json")).unwrap();
    assert!(tokens.policy.net().set.is_some_and(|s| s.robot_tokens && s.object == 26 && s.fixtures == 3));
    let net = tokens.policy.net();
    assert_eq!((net.set.unwrap().width, net.layers[0].b.len()), (8, 8), "rows 8 wide");
    assert_eq!(
        net.layers[net.set.unwrap().head_start()].b.len(),
        imitate("dagger", 1).shared.hidden,
        "the head's width"
    );
    assert!(!saved.policy.net().set.unwrap().robot_tokens);
    assert!(imitate("dagger", 1).title().contains("DAgger"), "{}", imitate("dagger", 1).title());
    // What they cannot use is refused before anything is written.
    let refused = |c: TrainConfig, words: &[&str]| {
        let dir = tempfile::tempdir().unwrap();
        let e =
            format!("{:#}", anyhow::Error::from(train(&c, &dir.path().join("run"), false, &mut quiet).unwrap_err()));
        assert!(words.iter().all(|w| e.contains(w)), "{e}");
        assert!(!dir.path().join("run").exists(), "{e}");
    };
    refused(TrainConfig { net: NetConfig::default(), ..imitate("bc", 1) }, &["--algo bc", "--net entity"]);
    let mlp =
        TrainConfig { net: NetConfig { set_robot_tokens: true, ..NetConfig::default() }, ..tiny("BlocksTouch-v0", 1) };
    refused(mlp, &["--set-robot-tokens is only used with --net set"]);
    let set = NetConfig { net: NetKind::Set, set_type_norm: true, ..NetConfig::default() };
    refused(
        TrainConfig { net: set, ..tiny("BlocksChoose-v0", 1) },
        &["--set-type-norm is only used with --net entity"],
    );
    refused(TrainConfig { hindsight_colours: 2, ..imitate("dagger", 1) }, &["--hindsight-colours", "--algo dagger"]);
    let blocks = |n, pooling| NetConfig { set_transformer: n, set_pooling: pooling, ..imitate("dagger", 1).net };
    refused(
        TrainConfig { net: NetConfig { set_transformer: 2, ..NetConfig::default() }, ..tiny("BlocksTouch-v0", 1) },
        &["--set-transformer is only used with --net set"],
    );
    refused(
        TrainConfig { net: blocks(2, Pooling::Attention), ..imitate("dagger", 1) },
        &["--set-transformer replaces"],
    );
    let mut odd = TrainConfig { net: NetConfig { set_width: 0, ..blocks(2, Pooling::Query) }, ..imitate("dagger", 1) };
    odd.shared.hidden = 30;
    refused(odd, &["--hidden 30", "4 heads"]);
    let narrow_odd =
        TrainConfig { net: NetConfig { set_width: 6, ..blocks(2, Pooling::Query) }, ..imitate("dagger", 1) };
    refused(narrow_odd, &["--set-width 6", "4 heads"]);
    refused(
        TrainConfig { net: NetConfig { set_width: 64, ..NetConfig::default() }, ..tiny("BlocksTouch-v0", 1) },
        &["--set-width is only used with --net set"],
    );
    let mut bad = imitate("dagger", 1);
    bad.algos.dagger.beta0 = 1.5;
    refused(bad, &["--dagger-beta0", "[0, 1]"]);
    let mut noisy = imitate("dagger", 1);
    noisy.algos.bc.noise = 0.2;
    refused(noisy, &["--bc-noise is only used with --algo bc"]);
    // A task the solver cannot play (a green gripper): nothing to imitate, and the solver's reason.
    let tasks = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("tasks/BlocksTouch-v0.toml"))
        .unwrap()
        .replace("id = \"BlocksTouch-v0\"", "id = \"GreenGripperTouch-v0\"")
        .replace("gripper = \"grey\"", "gripper = \"green\"");
    let file = tasks.path().join("green-gripper.toml");
    std::fs::write(&file, text).unwrap();
    let green = TrainConfig { env: file.display().to_string(), ..imitate("bc", 1) };
    refused(green, &["the solver cannot play GreenGripperTouch-v0", "a green gripper", "nothing to imitate"]);
}

#[test]
fn a_multi_task_run_draws_its_tasks_keeps_a_level_each_and_resumes_exactly() {
    // Two tasks of different block counts in one layout (the entities of the most blocks), one
    // drawn per exploration episode, the solver labelling both; threshold 0: each task moves up a
    // level whenever it has had `test_episodes` test episodes (2 workers × 2 over 2 tasks: every epoch).
    let multi = |epochs| {
        let mut c = tiny("BlocksTouch-v0,BlocksChoose-v0", epochs);
        c.algo = Algo::named("dagger").unwrap();
        c.net = NetConfig { net: NetKind::Entity, ..NetConfig::default() };
        c.success_threshold = Some(0.0);
        c
    };
    assert_eq!(multi(1).task_id(), "BlocksTouch-v0+BlocksChoose-v0");
    assert!(multi(1)
        .default_run_dir()
        .to_string_lossy()
        .starts_with("runs/BlocksTouch-v0+BlocksChoose-v0-dagger-entity"));
    let (straight, split) = (tempfile::tempdir().unwrap(), tempfile::tempdir().unwrap());
    let a = train(&multi(3), straight.path(), false, &mut quiet).unwrap();
    train(&multi(2), split.path(), false, &mut quiet).unwrap();
    // A branch of it continues it exactly, with the parent's tasks by content; a branch that asks for
    // other tasks is refused.
    let root = tempfile::tempdir().unwrap();
    let child = root.path().join("branch");
    assert_eq!(branch(split.path(), &child, &multi(3)).unwrap().epoch, 2);
    let elsewhere = TrainConfig { env: "BlocksTouch-v0,BlocksStack-v0".into(), ..multi(3) };
    let other = branch(split.path(), &root.path().join("other"), &elsewhere);
    let e = format!("{:#}", anyhow::Error::from(other.unwrap_err()));
    assert!(e.contains("BlocksTouch-v0+BlocksChoose-v0") && e.contains("--env"), "{e}");
    let branched = train(&multi(3), &child, true, &mut quiet).unwrap();
    let b = train(&multi(3), split.path(), true, &mut quiet).unwrap();
    assert_eq!(comparable(&a), comparable(&b));
    assert_eq!(comparable(&a), comparable(&branched));
    let recorded =
        |dir: &std::path::Path| blockpuzzle::learn::train::RunDir { dir: dir.to_owned() }.read_config().unwrap();
    assert_eq!(recorded(&child).tasks, recorded(split.path()).tasks);
    assert_eq!(a.iter().map(|r| r.level).collect::<Vec<_>>(), [0, 2, 4], "both tasks move up every epoch");
    let state = checkpoint::peek_state(&straight.path().join("checkpoint.bin")).unwrap();
    assert_eq!((state.levels.clone(), state.level), (vec![3, 3], 6));
    let config: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(straight.path().join("config.json")).unwrap()).unwrap();
    let ids: Vec<&str> = config["tasks"].as_array().unwrap().iter().map(|t| t["id"].as_str().unwrap()).collect();
    assert_eq!(ids, ["BlocksTouch-v0", "BlocksChoose-v0"]);
    assert!(config.get("task").is_none(), "{config}");
    // The policy reads the widest layout and names the run's tasks, not one of them.
    let saved = load_policy(&straight.path().join("policy.json")).unwrap();
    assert_eq!(saved.env_id, "BlocksTouch-v0+BlocksChoose-v0");
    assert!(saved.task.is_none());
    let choose = blockpuzzle::env::registry::task("BlocksChoose-v0").unwrap().object_count();
    let touch = blockpuzzle::env::registry::task("BlocksTouch-v0").unwrap().object_count();
    assert!(choose > touch);
    let spec = blockpuzzle::env::ObsSpec::new(blockpuzzle::env::ObsMode::Entities, choose);
    assert_eq!(state.obs_dim, spec.dim());
    // Played where it is told: any task's env, not a task of its own.
    let eval = |extra: &[&str]| {
        let policy = straight.path().join("policy.json");
        let args = [&["eval", "--checkpoint", policy.to_str().unwrap(), "--episodes", "1"][..], extra].concat();
        std::process::Command::new(crate::common::CLI).args(args).current_dir(straight.path()).output().unwrap()
    };
    let alone = eval(&[]);
    let e = String::from_utf8_lossy(&alone.stderr);
    assert!(!alone.status.success() && e.contains("trained on several tasks") && e.contains("--env"), "{e}");
    assert!(eval(&["--env", "BlocksTouch-v0"]).status.success());
    // It records its tasks by content, and goes into the zoo as it is: its label, its tasks, probes of
    // its first task in its own layout; loaded back, it names no one task either.
    let ids: Vec<&str> = saved.tasks.iter().map(|t| t.id.as_str()).collect();
    assert_eq!(ids, ["BlocksTouch-v0", "BlocksChoose-v0"]);
    let zoo = tempfile::tempdir().unwrap();
    let info = blockpuzzle::benchmark::zoo::ExportInfo {
        name: "two-tasks".into(),
        description: "a multi-task test entry".into(),
        trained_with: "tests/it/train.rs".into(),
        exported_from: "policy.json".into(),
        env_steps: saved.env_steps,
        evaluations: Vec::new(),
        keep_critic: false,
        overwrite: false,
        algo: None,
    };
    let entry = blockpuzzle::benchmark::zoo::export(zoo.path(), &saved, &info).unwrap();
    let (meta, back) = blockpuzzle::benchmark::zoo::load(&entry).unwrap();
    assert_eq!(meta.format, blockpuzzle::benchmark::zoo::FORMAT);
    assert_eq!((meta.trained_on(), meta.task.id.as_str()), ("BlocksTouch-v0+BlocksChoose-v0", "BlocksTouch-v0"));
    assert_eq!(meta.probes[0].obs.len(), state.obs_dim, "the probes are in the policy's layout");
    assert_eq!((back.env_id.as_str(), back.task.is_none(), &back.tasks), (saved.env_id.as_str(), true, &saved.tasks));
    assert_eq!(back.policy_id("x").sha256, saved.policy_id("x").sha256);
    let one = blockpuzzle::benchmark::saved::SavedPolicy { tasks: vec![saved.tasks[0].clone()], ..saved.clone() };
    assert_ne!(one.policy_id("x").sha256, saved.policy_id("x").sha256, "the tasks are part of what made it");
    // `zoo export --evaluate` of it needs the tasks to evaluate on, and says so before writing anything.
    let o = std::process::Command::new(crate::common::CLI)
        .args(["zoo", "export", "--from", straight.path().join("policy.json").to_str().unwrap(), "--name", "two"])
        .args(["--description", "d", "--trained-with", "t", "--evaluate", "2", "--zoo", zoo.path().to_str().unwrap()])
        .output()
        .unwrap();
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && e.contains("several tasks") && e.contains("--evaluate-env"), "{e}");
    assert!(!zoo.path().join("two.json").exists());
    // A flat network trained on several tasks reads them padded to one layout: the zoo refuses it.
    let flat_dir = tempfile::tempdir().unwrap();
    let mut flat = tiny("BlocksTouch-v0,BlocksChoose-v0", 1);
    flat.algo = Algo::named("ddpg").unwrap();
    train(&flat, flat_dir.path(), false, &mut quiet).unwrap();
    let flat_saved = load_policy(&flat_dir.path().join("policy.json")).unwrap();
    let e = blockpuzzle::benchmark::zoo::export(
        zoo.path(),
        &flat_saved,
        &blockpuzzle::benchmark::zoo::ExportInfo { name: "flat".into(), ..info.clone() },
    )
    .unwrap_err();
    assert!(e.to_string().contains("flat network trained on several tasks"), "{e}");
    // A suite's split names the tasks too (a file here; `--suite procgen` in the experiments).
    let dir = tempfile::tempdir().unwrap();
    let suite = dir.path().join("two.toml");
    let row = |task: &str, split: &str| {
        let seed = if split == "train" { 0 } else { 100 };
        format!("[[splits.{split}]]\ntask = \"{task}\"\nseed = {seed}\nepisodes = 2\n\n")
    };
    let text = format!(
        "version = 1\nname = \"two\"\nsummary = \"two tasks\"\n\n{}{}{}",
        row("BlocksTouch-v0", "train"),
        row("BlocksChoose-v0", "train"),
        row("BlocksStack-v0", "test")
    );
    std::fs::write(&suite, text).unwrap();
    let from_suite = TrainConfig { env: String::new(), suite: Some(suite.display().to_string()), ..multi(3) };
    assert_eq!(from_suite.task_id(), "two-train");
    let c = train(&from_suite, &dir.path().join("run"), false, &mut quiet).unwrap();
    assert_eq!(comparable(&a), comparable(&c), "the same tasks in the same order: the same run");

    // Refused before anything is written: one-task settings, a split the suite lacks, and a
    // resume whose tasks are not the run's.
    let refused = |c: TrainConfig, dir: &Path, resume: bool, words: &[&str]| {
        let e = format!("{:#}", anyhow::Error::from(train(&c, dir, resume, &mut quiet).unwrap_err()));
        assert!(words.iter().all(|w| e.contains(w)), "{e}");
    };
    let nowhere = dir.path().join("nowhere");
    refused(
        TrainConfig { counts: Some("grey=1".parse().unwrap()), ..multi(1) },
        &nowhere,
        false,
        &["--counts applies to one task"],
    );
    refused(
        TrainConfig { split: "check".into(), ..from_suite.clone() },
        &nowhere,
        false,
        &["--split check", "train, test"],
    );
    refused(
        TrainConfig { split: "test".into(), ..multi(1) },
        &nowhere,
        false,
        &["--split test is only used with --suite"],
    );
    refused(TrainConfig { env: " ".into(), ..multi(1) }, &nowhere, false, &["no task", "--env ID"]);
    assert!(!nowhere.exists());
    let other = TrainConfig { env: "BlocksTouch-v0,BlocksStack-v0".into(), ..multi(4) };
    refused(other, straight.path(), true, &["differ from those recorded", "BlocksChoose-v0", "BlocksStack-v0"]);
}

/// A stream run: the families' tasks of a seed range as its pool, a few of them with environments
/// each epoch (a new set every epoch here), the pool recorded by hash; it resumes exactly, refuses
/// another stream on resume, and its policy names the pool's tasks.
#[test]
fn a_stream_run_trains_on_generated_tasks_records_its_pool_and_resumes_exactly() {
    let stream = |epochs| stream_run("dagger", epochs);
    assert_eq!(stream(1).task_id(), "gripper+push-0-3");
    assert!(stream(1).default_run_dir().to_string_lossy().starts_with("runs/gripper+push-0-3-dagger-entity"));
    let (straight, split) = (tempfile::tempdir().unwrap(), tempfile::tempdir().unwrap());
    let a = train(&stream(3), straight.path(), false, &mut quiet).unwrap();
    train(&stream(2), split.path(), false, &mut quiet).unwrap();
    // Another stream on resume is refused, naming both; nothing of the run changes.
    let other = TrainConfig { generator_seeds: Some("0..4".parse().unwrap()), ..stream(3) };
    let e = format!("{:#}", anyhow::Error::from(train(&other, split.path(), true, &mut quiet).unwrap_err()));
    assert!(e.contains("--generator-seeds 0..3") && e.contains("--generator-seeds 0..4"), "{e}");
    let b = train(&stream(3), split.path(), true, &mut quiet).unwrap();
    assert_eq!(comparable(&a), comparable(&b));
    assert!(a.iter().all(|r| r.level == 0) && a[2].env_steps > a[0].env_steps);
    // `report` and `plot --run-dir` read a stream run (its tasks have no curriculum).
    let dir = straight.path().to_str().unwrap();
    for args in [vec!["report", dir], vec!["plot", "--run-dir", dir]] {
        let out = std::process::Command::new(crate::common::CLI).args(&args).output().unwrap();
        let text = String::from_utf8_lossy(&out.stdout);
        assert!(out.status.success(), "{args:?}: {}", String::from_utf8_lossy(&out.stderr));
        assert!(args[0] != "report" || text.contains("gripper+push-0-3") && text.contains("level 0 of 0"), "{text}");
    }
    let config = blockpuzzle::learn::train::RunDir { dir: straight.path().to_owned() }.read_config().unwrap();
    let record = config.stream.clone().unwrap();
    assert!(config.tasks.is_empty() && config.task.is_none());
    assert_eq!(record.generator_seeds, [0, 3]);
    assert_eq!(record.families.iter().map(|f| f.family.as_str()).collect::<Vec<_>>(), ["gripper", "push"]);
    let pool = record.tasks.len();
    assert!(pool >= 4, "{record:?}");
    // The policy records the stream (not its tasks by content) and draws every task of the pool again from
    // it, in the layout of the most blocks.
    let saved = load_policy(&straight.path().join("policy.json")).unwrap();
    assert_eq!(policy_from_checkpoint(straight.path()).unwrap(), saved);
    // DAgger learns from the solver: the policy names the version that labelled it, and so does its
    // zoo entry.
    assert_eq!(saved.solver, Some(blockpuzzle::policy::SOLVER_VERSION));
    let shelf = tempfile::tempdir().unwrap();
    let info = blockpuzzle::benchmark::zoo::ExportInfo { name: "d".into(), ..Default::default() };
    let entry = blockpuzzle::benchmark::zoo::export(shelf.path(), &saved, &info).unwrap().with_extension("json");
    let (meta, loaded) = blockpuzzle::benchmark::zoo::load(&entry).unwrap();
    assert_eq!((meta.solver, loaded.solver), (saved.solver, saved.solver));
    assert_eq!(saved.env_id, "gripper+push-0-3");
    assert!(saved.tasks.is_empty() && saved.task.is_none() && saved.is_multi_task());
    assert_eq!(saved.stream.as_ref(), Some(&record));
    assert!(record.families.iter().all(|f| f.text.contains(&format!("family = \"{}\"", f.family))), "{record:?}");
    let tasks = saved.training_tasks().unwrap();
    let hashes: Vec<&str> = tasks.iter().map(|t| t.hash.as_str()).collect();
    assert_eq!(hashes, record.tasks.iter().map(|t| t.hash.as_str()).collect::<Vec<_>>());
    // Named as the same tasks listed would be.
    let listed = blockpuzzle::benchmark::saved::SavedPolicy { tasks: tasks.clone(), stream: None, ..saved.clone() };
    assert_eq!(listed.policy_id("p"), saved.policy_id("p"));
    // An edited record is refused by what it draws, naming the task or the family.
    let mut edited = record.clone();
    edited.tasks[1].candidate += 1;
    let e = edited.draw().unwrap_err().to_string();
    assert!(e.contains(&edited.tasks[1].id) && e.contains("edited"), "{e}");
    let mut edited = record.clone();
    edited.families[0].text = edited.families[0].text.replace("max_candidates = 20", "max_candidates = 19");
    let e = edited.draw().unwrap_err().to_string();
    assert!(e.contains("gripper") && e.contains("edited"), "{e}");
    let mut edited = record.clone();
    edited.families[1].text.clear();
    let e = edited.draw().unwrap_err().to_string();
    assert!(e.contains("push") && e.contains("by hash alone"), "{e}");
    // The zoo keeps the record too (format 6), and loading draws the tasks again and refuses an edited one.
    let zoo = tempfile::tempdir().unwrap();
    let info = blockpuzzle::benchmark::zoo::ExportInfo { name: "streamed".into(), ..Default::default() };
    let json = blockpuzzle::benchmark::zoo::export(zoo.path(), &saved, &info).unwrap().with_extension("json");
    let (meta, loaded) = blockpuzzle::benchmark::zoo::load(&json).unwrap();
    assert_eq!(meta.format, blockpuzzle::benchmark::zoo::FORMAT);
    let multi = meta.multi_task.as_ref().unwrap();
    assert!(multi.tasks.is_empty() && multi.stream.as_ref() == Some(&record) && meta.task.hash == hashes[0]);
    assert_eq!(loaded.policy_id("p"), saved.policy_id("p"));
    let text = std::fs::read_to_string(&json).unwrap();
    let candidate = format!("\"candidate\": {}", record.tasks[1].candidate);
    let at = text.find(&format!("\"id\": \"{}\"", record.tasks[1].id)).unwrap();
    let edit = at + text[at..].find(&candidate).unwrap();
    let edited = format!("{}\"candidate\": 7{}", &text[..edit], &text[edit + candidate.len()..]);
    std::fs::write(&json, edited).unwrap();
    let e = blockpuzzle::benchmark::zoo::load(&json).unwrap_err().to_string();
    assert!(e.contains(&record.tasks[1].id) && e.contains("edited"), "{e}");
    // The layout has a slot for every block the families can draw (push: 1 + 1 + 1 + 2 + 2), whichever
    // seeds the pool holds, so that pools of the same families train policies of one layout.
    assert_eq!(record.max_blocks, 7);
    let most = tasks.iter().map(|t| blockpuzzle::env::registry::recorded(t).unwrap().object_count()).max();
    assert!(most.unwrap() <= 7);
    let spec = blockpuzzle::env::ObsSpec::new(blockpuzzle::env::ObsMode::Entities, 7);
    assert_eq!(checkpoint::peek_state(&straight.path().join("checkpoint.bin")).unwrap().obs_dim, spec.dim());
    // `--active-tasks` belongs to streams.
    let e = format!(
        "{:#}",
        anyhow::Error::from(
            train(
                &TrainConfig { active_tasks: 3, ..tiny("BlocksTouch-v0", 1) },
                &straight.path().join("x"),
                false,
                &mut quiet
            )
            .unwrap_err()
        )
    );
    assert!(e.contains("--active-tasks") && e.contains("--families"), "{e}");
    assert!(!straight.path().join("x").exists());
    // Weighted families (`--family-weights`, issue 73) are recorded, and a resume with others is refused.
    let weighted = |w: &str, epochs| TrainConfig { family_weights: Some(w.parse().unwrap()), ..stream(epochs) };
    let heavy = tempfile::tempdir().unwrap();
    train(&weighted("push=3", 1), heavy.path(), false, &mut quiet).unwrap();
    let config = blockpuzzle::learn::train::RunDir { dir: heavy.path().to_owned() }.read_config().unwrap();
    assert_eq!(config.family_weights.map(|w| w.to_string()).as_deref(), Some("push=3"));
    let e = format!(
        "{:#}",
        anyhow::Error::from(train(&weighted("push=2", 2), heavy.path(), true, &mut quiet).unwrap_err())
    );
    assert!(e.contains("--family-weights") && e.contains("differ"), "{e}");
    train(&weighted("push=3", 2), heavy.path(), true, &mut quiet).unwrap();
}

/// A stream's bad input is refused before anything is written, each error naming the problem and the fix.
#[test]
fn bad_streams_are_refused_before_anything_is_written() {
    let dir = tempfile::tempdir().unwrap();
    let run = dir.path().join("run");
    let cache = dir.path().join("cache");
    let refused = |args: &[&str], wanted: &[&str]| {
        let base =
            ["train", "--algo", "dagger", "--net", "entity", "--epochs", "1", "--run-dir", run.to_str().unwrap()];
        let out = std::process::Command::new(crate::common::CLI)
            .args(base.iter().chain(args))
            .env("BLOCKPUZZLE_CACHE_DIR", &cache)
            .output()
            .unwrap();
        let e = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{args:?} was accepted");
        for w in wanted {
            assert!(e.contains(w), "{args:?}: {e}");
        }
        assert!(!run.exists(), "{args:?} left {}", run.display());
    };
    refused(&["--families", "push,nope", "--generator-seeds", "0..4"], &["nope", "no such family", "push, gripper"]);
    refused(&["--families", "push", "--generator-seeds", "4..4"], &["4..4 is empty", "FIRST..END"]);
    refused(&["--families", "push", "--generator-seeds", "4"], &["FIRST..END"]);
    refused(
        &["--families", "gripper,push", "--generator-seeds", "990..1010"],
        &["suite procgen", "1000..1008", "990..1000"],
    );
    refused(&["--families", "push"], &["--generator-seeds"]);
    refused(&["--families", "push,,gather", "--generator-seeds", "0..4"], &["item 2 of the list is empty"]);
    refused(&["--families", "push,", "--generator-seeds", "0..4"], &["item 2 of the list is empty"]);
    // Nor does any run train on a suite's test split (issue 60).
    refused(&["--suite", "procgen", "--split", "test"], &["--split test", "score", "--split train"]);
    let validation = concat!(env!("CARGO_MANIFEST_DIR"), "/experiments/generalist/suites/validation.toml");
    refused(&["--suite", validation, "--split", "validation"], &["--split validation", "--split train"]);
    // An --env list means what it says: no empty item, no task twice by id or by content (issue 60).
    refused(&["--env", "BlocksTouch-v0,,BlocksChoose-v0"], &["item 2 of the list is empty"]);
    refused(&["--env", "BlocksTouch-v0,BlocksChoose-v0,BlocksTouch-v0"], &["one task twice", "list each task once"]);
    let copy = dir.path().join("touch.toml");
    std::fs::copy(format!("{}/tasks/BlocksTouch-v0.toml", env!("CARGO_MANIFEST_DIR")), &copy).unwrap();
    refused(&["--env", &format!("BlocksTouch-v0,{}", copy.display())], &["same content", "BlocksTouch-v0"]);
    refused(&["--env", "BlocksTouch-v0", "--generator-seeds", "0..4"], &["--families"]);
    // Family weights: for a stream's own families, each a whole number from 1 to 16 (issue 73).
    let stream = ["--families", "push,gripper", "--generator-seeds", "0..4"];
    refused(
        &[&stream[..], &["--family-weights", "avoid=3"]].concat(),
        &["avoid", "not a family of this stream", "push, gripper"],
    );
    refused(&[&stream[..], &["--family-weights", "push=0"]].concat(), &["push=0", "from 1 to 16"]);
    refused(&[&stream[..], &["--family-weights", "push"]].concat(), &["FAMILY=WEIGHT"]);
    refused(&["--env", "BlocksTouch-v0", "--family-weights", "push=2"], &["--families"]);
    // Options that would do nothing: level replay on a task of one level (issue 74).
    let one_level = dir.path().join("one-level.toml");
    let text = std::fs::read_to_string(format!("{}/tasks/BlocksTouch-v0.toml", env!("CARGO_MANIFEST_DIR"))).unwrap();
    std::fs::write(&one_level, text.replace("max_level = 5", "max_level = 0").replace("BlocksTouch-v0", "OneLevel-v0"))
        .unwrap();
    refused(
        &["--env", one_level.to_str().unwrap(), "--level-replay", "0.3"],
        &["--level-replay 0.3", "OneLevel-v0 has one curriculum level", "leave --level-replay out"],
    );
    let family = dir.path().join("no-green.toml");
    let text = std::fs::read_to_string(format!("{}/families/gripper.toml", env!("CARGO_MANIFEST_DIR"))).unwrap();
    let text =
        text.replace("max_candidates = 20", "max_candidates = 1").replace("colour = \"green\"", "colour = \"grey\"");
    std::fs::write(&family, text).unwrap();
    refused(
        &["--families", family.to_str().unwrap(), "--generator-seeds", "0..2"],
        &["no task in the stream", "green"],
    );
}

/// A flat multi-task policy reads its training tasks' layout (the most blocks of any, the others'
/// rows absent): evaluation, suites and rollouts show it that layout, so it plays every one of its
/// own tasks, and a task with more blocks than it was trained with is refused, saying why (issue 60).
#[test]
fn a_flat_multi_task_policy_plays_each_of_its_tasks() {
    let run = tempfile::tempdir().unwrap();
    train(&tiny("GripperTouch-v0,BlocksChoose-v0", 1), run.path(), false, &mut quiet).unwrap();
    let policy = run.path().join("policy.json");
    let saved = load_policy(&policy).unwrap();
    let choose = blockpuzzle::env::registry::task("BlocksChoose-v0").unwrap().object_count();
    assert_eq!(saved.slots().unwrap(), choose);
    // The policy file records who trained it and what it reads (issue 61); an edited record is refused.
    assert_eq!(
        (saved.algo, saved.obs_mode),
        (Some(blockpuzzle::benchmark::saved::Trainer::Ddpg), Some(blockpuzzle::env::ObsMode::Flat))
    );
    let mut edited: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&policy).unwrap()).unwrap();
    edited["obs_mode"] = "entities".into();
    let file = run.path().join("edited.json");
    std::fs::write(&file, edited.to_string()).unwrap();
    let e = format!("{:#}", load_policy(&file).unwrap_err());
    assert!(e.contains("obs_mode records `entities`") && e.contains("edited.json"), "{e}");
    // The fixtures after the blocks' rows are recorded too (none in the flat observation), and a file
    // recording other ones is refused.
    assert_eq!(saved.fixtures.as_deref(), Some(&[][..]));
    edited["obs_mode"] = "flat".into();
    edited["fixtures"] = serde_json::json!(["gripper"]);
    std::fs::write(&file, edited.to_string()).unwrap();
    let e = format!("{:#}", load_policy(&file).unwrap_err());
    assert!(e.contains("fixtures records [gripper]") && e.contains("export it again"), "{e}");
    // A file written before the record is read as before (the one mode its network reads); `zoo
    // export` records it (zoo::an_entry_records_its_mode_kind_and_algorithm).
    let legacy = edited.as_object_mut().unwrap();
    legacy.remove("obs_mode");
    legacy.remove("fixtures");
    std::fs::write(&file, edited.to_string()).unwrap();
    let old = load_policy(&file).unwrap();
    assert_eq!((old.obs_mode, old.fixtures.as_deref()), (Some(blockpuzzle::env::ObsMode::Flat), Some(&[][..])));
    std::fs::remove_file(&file).unwrap();
    let cli = |args: &[&str]| {
        let o = std::process::Command::new(crate::common::CLI).args(args).current_dir(run.path()).output().unwrap();
        (o.status.success(), format!("{}{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr)))
    };
    let p = policy.to_str().unwrap();
    for env in ["GripperTouch-v0", "BlocksChoose-v0"] {
        let (ok, text) = cli(&["eval", "--checkpoint", p, "--env", env, "--episodes", "1"]);
        assert!(ok, "{env}: {text}");
        let (ok, text) = cli(&["rollout", "--policy", p, "--env", env, "--episodes", "1", "--out", "r.jsonl"]);
        assert!(ok, "{env}: {text}");
    }
    // A suite of its tasks: no row skipped.
    let suite = run.path().join("own.toml");
    std::fs::write(
        &suite,
        "version = 1\nname = \"own\"\nsummary = \"s\"\n[[splits.train]]\ntask = \"GripperTouch-v0\"\nseed = 0\n\
         episodes = 1\n[[splits.test]]\ntask = \"BlocksChoose-v0\"\nseed = 10\nepisodes = 1\n",
    )
    .unwrap();
    let (ok, text) = cli(&["eval", "--checkpoint", p, "--suite", suite.to_str().unwrap(), "--out", "own.json"]);
    assert!(ok, "{text}");
    let result: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(run.path().join("own.json")).unwrap()).unwrap();
    for split in result["splits"].as_array().unwrap() {
        for row in split["rows"].as_array().unwrap() {
            assert!(row["skipped"].is_null() && row["evaluation"].is_object(), "{row}");
        }
    }
    // More blocks than its layout holds: refused, with the reason and the way out.
    let (ok, text) = cli(&["eval", "--checkpoint", p, "--env", "BlocksChooseN-v0", "--episodes", "1"]);
    assert!(!ok, "{text}");
    for want in ["trained on several tasks", &format!("{choose} block slots"), "more blocks", "--net set"] {
        assert!(text.contains(want), "{want:?} missing from: {text}");
    }
}

/// A run carried to another machine with its checkpoint but not its replay log
/// (`--resume --rebuild-replay`): behaviour cloning, whose every stored transition the solver
/// played, collects its buffers again from the run's seeds and continues exactly as if never
/// stopped; DAgger, whose transitions came from learners the run no longer has, refills them from
/// empty. Both say so in provenance.json; without the flag, the missing log is refused naming it.
/// A run whose labels came from another solver version is refused either way.
#[test]
fn a_resume_without_the_replay_log_regenerates_bc_exactly_and_refills_dagger() {
    use blockpuzzle::learn::train::{ReplayRebuilt, RunDir, Start};
    let bc = |epochs| {
        let mut c = stream_run("bc", epochs);
        c.algos.bc.noise = 0.1;
        c
    };
    let spans = |d: &Path| RunDir { dir: d.to_owned() }.read_provenance().unwrap();
    let (straight, carried) = (tempfile::tempdir().unwrap(), tempfile::tempdir().unwrap());
    let a = train(&bc(3), straight.path(), Start::New, &mut quiet).unwrap();
    train(&bc(2), carried.path(), Start::New, &mut quiet).unwrap();
    std::fs::remove_dir_all(carried.path().join("replay")).unwrap();
    let e = format!("{:#}", anyhow::Error::from(train(&bc(3), carried.path(), Start::Resume, &mut quiet).unwrap_err()));
    assert!(e.contains("is missing") && e.contains("--rebuild-replay"), "{e}");
    let b = train(&bc(3), carried.path(), Start::ResumeRebuildingReplay, &mut quiet).unwrap();
    assert_eq!(comparable(&a), comparable(&b));
    let (pa, pb) = (
        load_policy(&straight.path().join("policy.json")).unwrap(),
        load_policy(&carried.path().join("policy.json")).unwrap(),
    );
    assert_eq!(pa.policy, pb.policy, "the same weights and normaliser as the run never stopped");
    let recorded: Vec<_> = spans(carried.path()).iter().map(|s| (s.from_epoch, s.replay)).collect();
    assert_eq!(recorded, [(0, None), (2, Some(ReplayRebuilt::Regenerated))]);
    // Its buffers were logged again: a plain resume from here reads them back.
    train(&bc(4), carried.path(), Start::Resume, &mut quiet).unwrap();
    // Labelled by another solver version: refused, naming both versions, and nothing written.
    let provenance = carried.path().join("provenance.json");
    let mut spans_json: serde_json::Value = serde_json::from_slice(&std::fs::read(&provenance).unwrap()).unwrap();
    let older = blockpuzzle::policy::SOLVER_VERSION - 1;
    spans_json.as_array_mut().unwrap().last_mut().unwrap()["solver"] = older.into();
    std::fs::write(&provenance, serde_json::to_vec_pretty(&spans_json).unwrap()).unwrap();
    let before = std::fs::read(carried.path().join("checkpoint.bin")).unwrap();
    for start in [Start::Resume, Start::ResumeRebuildingReplay] {
        let e = format!("{:#}", anyhow::Error::from(train(&bc(5), carried.path(), start, &mut quiet).unwrap_err()));
        assert!(e.contains(&format!("labelled by solver version {older}")) && e.contains("another --run-dir"), "{e}");
    }
    assert_eq!(std::fs::read(carried.path().join("checkpoint.bin")).unwrap(), before);
    assert_eq!(serde_json::from_slice::<serde_json::Value>(&std::fs::read(&provenance).unwrap()).unwrap(), spans_json);

    // DAgger: refilled, and the run goes on from its checkpoint.
    let mut dagger = tiny("BlocksTouch-v0", 2);
    dagger.algo = Algo::named("dagger").unwrap();
    dagger.net = NetConfig { net: NetKind::Entity, ..NetConfig::default() };
    let run = tempfile::tempdir().unwrap();
    train(&dagger, run.path(), Start::New, &mut quiet).unwrap();
    std::fs::remove_dir_all(run.path().join("replay")).unwrap();
    let rows =
        train(&TrainConfig { epochs: 3, ..dagger.clone() }, run.path(), Start::ResumeRebuildingReplay, &mut quiet)
            .unwrap();
    assert_eq!(rows.iter().map(|r| r.epoch).collect::<Vec<_>>(), [0, 1, 2]);
    assert_eq!(rows[2].updates, 3 * 3 * 5, "the updates of the epoch after the resume ran on refilled buffers");
    let recorded: Vec<_> = spans(run.path()).iter().map(|s| (s.from_epoch, s.replay)).collect();
    assert_eq!(recorded, [(0, None), (2, Some(ReplayRebuilt::Refilled))]);
}

/// The run state committed for runs that outlive a machine (`experiments/*/state/RUN/`: checkpoint,
/// config, progress and provenance, no replay log) is whole: the checkpoint loads without its replay
/// log as the config's run, at the epoch progress.csv has reached, and every epoch it ran was made
/// by a recorded clean build.
#[test]
fn the_committed_run_states_load_as_their_runs() {
    use blockpuzzle::learn::train::RunDir;
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("experiments");
    let mut found = 0;
    for experiment in std::fs::read_dir(&root).unwrap().flatten() {
        let Ok(runs) = std::fs::read_dir(experiment.path().join("state")) else { continue };
        for run in runs.flatten().filter(|r| r.path().is_dir()) {
            let dir = RunDir { dir: run.path() };
            let config = dir.read_config().unwrap();
            let ckpt = dir.dir.join("checkpoint.bin");
            let state = checkpoint::peek_state(&ckpt).unwrap();
            let loaded = checkpoint::load_without_replay(&ckpt, &config.task_id(), state.obs_dim, state.act_dim)
                .unwrap_or_else(|e| panic!("{}: {e}", ckpt.display()));
            assert_eq!(loaded.agent.name(), config.algo.name(), "{}", ckpt.display());
            assert!(!dir.dir.join("replay").exists(), "{}: no replay log in the repository", dir.dir.display());
            let rows = read_progress(&dir.dir.join("progress.csv")).unwrap();
            assert_eq!(rows.len(), state.epoch, "{}: progress.csv and the checkpoint", dir.dir.display());
            let spans = dir.read_provenance().unwrap();
            assert!(
                !spans.is_empty()
                    && spans.iter().all(|s| s.build.commit.as_ref().is_some_and(|c| !c.ends_with("-dirty"))),
                "{spans:?}"
            );
            found += 1;
        }
    }
    assert!(found >= 1, "no committed run state under {}", root.display());
}

/// The committed stream runs made by this build's solver on this build's engine keep their pools: each
/// pool drawn again (from the family texts its config.json records) is the one recorded, task by task.
/// What changes the generator's checks ([`GENERATOR_VERSION`]) must pass it. Ignored in the suite: on a
/// machine without the stream cache it checks every candidate of thousands of seeds (half an hour on
/// two cores per pool); run `cargo test --release --test it -- --ignored train::the_committed_stream`.
///
/// [`GENERATOR_VERSION`]: blockpuzzle::episode::generate::GENERATOR_VERSION
#[test]
#[ignore]
fn the_committed_stream_runs_keep_their_pools() {
    use blockpuzzle::benchmark::stream;
    use blockpuzzle::learn::train::RunDir;
    use blockpuzzle::task::family::Family;
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("experiments");
    let engine = blockpuzzle::sim::mj::version();
    let mut checked = std::collections::BTreeSet::new();
    for experiment in std::fs::read_dir(&root).unwrap().flatten() {
        let Ok(runs) = std::fs::read_dir(experiment.path().join("state")) else { continue };
        for run in runs.flatten().filter(|r| r.path().is_dir()) {
            let dir = RunDir { dir: run.path() };
            let Some(recorded) = dir.read_config().unwrap().stream else { continue };
            let spans = dir.read_provenance().unwrap();
            let start = &spans[0].build;
            if start.solver != Some(blockpuzzle::policy::SOLVER_VERSION) || start.mujoco != engine {
                continue;
            }
            let key: Vec<String> = recorded.families.iter().map(|f| f.hash.clone()).collect();
            if !checked.insert((key, recorded.generator_seeds)) {
                continue;
            }
            let families: Vec<(String, Family)> = recorded
                .families
                .iter()
                .map(|f| (f.name.clone(), Family::from_toml(&f.text, &f.name).unwrap()))
                .collect();
            let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
            let range = stream::SeedRange(recorded.generator_seeds);
            let pool = stream::pool(&families, range, threads, stream::cache_dir().as_deref(), true).unwrap();
            let changed = recorded.differences(&pool.record);
            assert!(changed.is_empty(), "{}: {changed:?}", dir.dir.display());
            eprintln!("{}: {} tasks, the recorded pool", dir.dir.display(), pool.tasks.len());
        }
    }
    assert!(!checked.is_empty(), "no committed stream run of solver {}", blockpuzzle::policy::SOLVER_VERSION);
}

/// Relative paths are recorded resolved (issue 74): a run started with `--families` and `--init-from`
/// relative to its folder resumes from any other folder, reading the same files. Off a terminal,
/// the pool and the epochs report their progress in plain lines.
#[test]
fn relative_paths_are_recorded_resolved_and_a_run_resumes_from_another_folder() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::create_dir(dir.path().join("fam")).unwrap();
    std::fs::copy(
        format!("{}/families/gripper.toml", env!("CARGO_MANIFEST_DIR")),
        dir.path().join("fam/my-gripper.toml"),
    )
    .unwrap();
    let bp = |cwd: &Path, args: &str| {
        let out = std::process::Command::new(crate::common::CLI)
            .args(args.split_whitespace())
            .current_dir(cwd)
            .env("BLOCKPUZZLE_CACHE_DIR", dir.path().join("cache"))
            .env("BLOCKPUZZLE_PROGRESS_SECONDS", "0")
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr).into_owned();
        assert!(out.status.success(), "{args}: {err}");
        err
    };
    let tiny = "train --algo dagger --net entity --set-width 16 --epochs 1 --cycles 1 --batches 2 --batch-size 16 \
                --test-episodes 1 --torch-threads 1";
    let err =
        bp(dir.path(), &format!("{tiny} --families fam/my-gripper.toml,push --generator-seeds 0..2 --run-dir first"));
    // Off a terminal (a pipe here) long work says how far it has come in plain lines (issue 74).
    for line in ["stream pool: generator seeds: 4 of 4 (100%)", "epoch 1/1 level 0"] {
        assert!(err.contains(line), "{line:?} missing from: {err}");
    }
    bp(dir.path(), &format!("{tiny} --families push --generator-seeds 0..2 --init-from first --run-dir second"));
    let config = |run: &str| -> serde_json::Value {
        serde_json::from_slice(&std::fs::read(dir.path().join(run).join("config.json")).unwrap()).unwrap()
    };
    let family = dir.path().join("fam/my-gripper.toml").display().to_string();
    assert_eq!(config("first")["families"], format!("{family},push"));
    assert_eq!(config("second")["finetune"]["init_from"], dir.path().join("first").display().to_string());
    // A bare resume from another folder reads the recorded (absolute) files.
    let elsewhere = tempfile::tempdir().unwrap();
    for run in ["first", "second"] {
        bp(elsewhere.path(), &format!("train --resume --run-dir {} --epochs 2", dir.path().join(run).display()));
    }
    // A family file no longer where the run recorded it (a checkout moved): the run's recorded copy
    // is drawn from, and said; an edited file there is refused by the pool's comparison.
    std::fs::rename(dir.path().join("fam"), dir.path().join("moved")).unwrap();
    let first = dir.path().join("first").display().to_string();
    let err = bp(elsewhere.path(), &format!("train --resume --run-dir {first} --epochs 3"));
    assert!(err.contains(&format!("note: the family file {family} is not there")), "{err}");
    std::fs::create_dir(dir.path().join("fam")).unwrap();
    let edited = std::fs::read_to_string(dir.path().join("moved/my-gripper.toml")).unwrap();
    std::fs::write(
        dir.path().join("fam/my-gripper.toml"),
        edited.replace("min_solver_success = 0.5", "min_solver_success = 0.6"),
    )
    .unwrap();
    let out = std::process::Command::new(crate::common::CLI)
        .args(["train", "--resume", "--run-dir", &first, "--epochs", "4"])
        .env("BLOCKPUZZLE_CACHE_DIR", dir.path().join("cache"))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && err.contains("the stream's pool differs"), "{err}");
}
