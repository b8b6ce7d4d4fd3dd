//! Demonstrations: the solver's episodes on a suite split, the same whatever the thread count, with
//! the outcomes the suite evaluator counts, padded to the split's largest row count, written and
//! read back intact; files that are not demos are named.

use blockpuzzle::benchmark::demos::{self, Demos};
use blockpuzzle::benchmark::evaluate::{evaluate_suite, Baseline, Subject};
use blockpuzzle::benchmark::provenance::Harness;
use blockpuzzle::env::{BlockEnv, EnvConfig};
use blockpuzzle::episode::outcome::Outcome;

/// BlocksTouch-v0 (two blocks) and BlocksAvoid-v0 (five block slots, a red floor): rows of different
/// entity counts.
const SUITE: &str = r#"
version = 1
name = "demo-test"
summary = "two tasks of different sizes"
[[splits.train]]
task = "BlocksTouch-v0"
seed = 7
episodes = 3
[[splits.train]]
task = "BlocksAvoid-v0"
seed = 11
episodes = 3
[[splits.test]]
task = "BlocksTouch-v0"
seed = 1000
episodes = 1
"#;

#[test]
fn demos_are_the_solvers_episodes_padded_and_round_trip() {
    let suite = blockpuzzle::benchmark::suite::parse(SUITE, "demo-test.toml", None).unwrap();
    let one = demos::record(&suite, "train", None, 1, Harness::Cli).unwrap();
    let two = demos::record(&suite, "train", None, 2, Harness::Cli).unwrap();
    assert_eq!(one.tensors.robot, two.tensors.robot, "the same episodes whatever the thread count");
    assert_eq!(
        (one.tensors.entities == two.tensors.entities, one.tensors.actions == two.tensors.actions, &one.episodes),
        (true, true, &two.episodes)
    );
    assert_eq!(one.episodes.len(), 6);
    assert_eq!(
        one.episodes.iter().map(|e| (e.row, e.seed)).collect::<Vec<_>>(),
        [(0, 7), (0, 8), (0, 9), (1, 11), (1, 12), (1, 13)]
    );
    // Shapes: one observation more than steps per episode; rows padded to BlocksAvoid-v0's 5 + 3.
    let (t, o) = (one.steps(), one.observations());
    assert_eq!(t, one.episodes.iter().map(|e| e.steps).sum::<usize>());
    assert_eq!(o, t + one.episodes.len());
    let (rows, f) = (one.layout.rows, one.layout.entity.len());
    assert_eq!((rows, f, one.layout.robot.len()), (8, 26, 10));
    assert_eq!(
        (one.tensors.entities.len(), one.tensors.mask.len(), one.tensors.actions.len()),
        (o * rows * f, o * rows, t * 4)
    );
    let touch = blockpuzzle::env::registry::task("BlocksTouch-v0").unwrap().object_count();
    let first_obs_mask = &one.tensors.mask[..rows];
    // BlocksTouch-v0: its blocks, then the padding up to BlocksAvoid-v0's 5 blocks, then the gripper
    // and the table present, the floor (no rule object) not: the layout of an environment with 5
    // slots, which multi-task training reads.
    let present: Vec<f32> = (0..rows).map(|r| if r < touch || r == 5 || r == 6 { 1.0 } else { 0.0 }).collect();
    assert_eq!(first_obs_mask, present.as_slice());
    assert!(one.tensors.entities[touch * f..5 * f].iter().all(|&x| x == 0.0), "padding rows are zero");
    assert!(one.tensors.entities[7 * f..8 * f].iter().all(|&x| x == 0.0), "the floor's row is zero");
    let env = BlockEnv::new(EnvConfig {
        obs_mode: blockpuzzle::env::ObsMode::Entities,
        slots: 5,
        ..EnvConfig::new(blockpuzzle::env::registry::task("BlocksTouch-v0").unwrap())
    })
    .unwrap();
    let spec = env.obs_spec();
    let (mut env, seed) = (env, one.episodes[0].seed);
    let top = env.max_level();
    // Each episode records what reset takes to play it again: the level (the row's, by default the
    // top) and no distribution for a plain row.
    assert_eq!((one.episodes[0].level, one.episodes[0].distribution.as_deref()), (Some(top), None));
    env.set_level(one.episodes[0].level.unwrap()).unwrap();
    let (obs, _) = env.reset(Some(seed)).unwrap();
    assert_eq!(
        &one.tensors.entities[..rows * f],
        spec.all_rows(&obs).flatten().copied().collect::<Vec<_>>().as_slice()
    );
    assert_eq!(first_obs_mask, spec.mask(&obs).unwrap());
    // Each episode's last step ends it, and its outcome is what the suite evaluator counts.
    let mut start = 0;
    for e in &one.episodes {
        let last = start + e.steps - 1;
        assert!(one.tensors.terminations[last] + one.tensors.truncations[last] == 1.0, "{e:?}");
        assert_eq!(
            e.outcome == Outcome::Success,
            one.tensors.terminations[last] == 1.0 && one.tensors.rewards[last] == 0.0,
            "{e:?}"
        );
        assert_eq!(e.episode_return, one.tensors.rewards[start..=last].iter().sum::<f32>());
        start = last + 1;
    }
    let result =
        evaluate_suite(Subject::Baseline(Baseline::Scripted), &suite, 2, Harness::Cli, &mut |_, _, _, _| Ok(()))
            .unwrap();
    for (i, row) in result.splits[0].rows.iter().enumerate() {
        let ours = one.episodes.iter().filter(|e| e.row == i && e.outcome == Outcome::Success).count();
        assert_eq!(ours, row.evaluation.as_ref().unwrap().successes, "row {i}");
        assert!(one.episodes.iter().filter(|e| e.row == i).all(|e| e.task_sha256 == row.task_sha256));
    }
    // Written and read back intact, with what made it.
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("d.safetensors");
    one.write(&path).unwrap();
    let back = Demos::read(&path).unwrap();
    let again = dir.path().join("again.safetensors");
    two.write(&again).unwrap();
    assert_eq!(std::fs::read(&again).unwrap(), std::fs::read(&path).unwrap(), "the same episodes, the same bytes");
    assert_eq!(back, one);
    assert_eq!(back.provenance.suite.as_ref().unwrap().sha256, suite.sha256);
    assert_eq!(back.provenance.policy.name, "baseline:scripted");
    // Values no recording holds are refused by the reader, naming the tensor, the place and the rule
    // (Python's load_demos refuses the same: python/tests/test_datasets.py).
    let last0 = one.episodes[0].steps - 1;
    type Edit = fn(&mut Demos, usize);
    let edits: [(&str, Edit); 7] = [
        ("tensor \"entities\" holds 1e30 at episode 0, observation 0", |d, _| d.tensors.entities[3] = 1e30),
        ("tensor \"robot\" holds NaN at episode 0, observation 0", |d, _| d.tensors.robot[1] = f32::NAN),
        (
            "tensor \"actions\" holds 1e9 at episode 0, step 1 (row 1); an action's components are within [-1, 1]",
            |d, _| d.tensors.actions[5] = 1e9,
        ),
        ("tensor \"rewards\" holds 100 at episode 0, step 0 (row 0); the environment gives -1", |d, _| {
            d.tensors.rewards[0] = 100.0
        }),
        ("tensor \"mask\" holds 2 at episode 0, observation 0", |d, _| d.tensors.mask[0] = 2.0),
        ("tensor \"terminations\" holds 0.5 at episode 0, step", |d, last| d.tensors.terminations[last] = 0.5),
        ("episode 0's rewards sum to", |d, last| d.tensors.rewards[last] = -7.0),
    ];
    for (want, edit) in edits {
        let mut edited = one.clone();
        edit(&mut edited, last0);
        let file = dir.path().join("edited.safetensors");
        edited.write(&file).unwrap();
        let e = Demos::read(&file).unwrap_err().to_string();
        assert!(e.contains("is not a usable demos file") && e.contains(want), "{want}: {e}");
    }
    // An unknown split, and files that are not demos, are named.
    let e = demos::record(&suite, "valid", None, 1, Harness::Cli).unwrap_err().to_string();
    assert!(e.contains("no split \"valid\" (it has train, test)"), "{e}");
    // A recording beyond the file bound is refused before any episode is played.
    let e = demos::record(&suite, "train", Some(1_000_000), 1, Harness::Cli).unwrap_err().to_string();
    assert!(e.contains("1000000 episodes per row of split train would make a demos file of up to"), "{e}");
    assert!(e.contains("lower --episodes"), "{e}");
    let zoo = format!("{}/zoo/BlocksTouch-v0-ddpg.safetensors", env!("CARGO_MANIFEST_DIR"));
    let e = Demos::read(std::path::Path::new(&zoo)).unwrap_err().to_string();
    assert!(
        e.contains("is not a usable demos file: its metadata has no \"blockpuzzle-demos\" entry (it is a blockpuzzle-zoo/1 file)"),
        "{e}"
    );
    let bytes = std::fs::read(&path).unwrap();
    std::fs::write(&path, &bytes[..bytes.len() / 2]).unwrap();
    let e = Demos::read(&path).unwrap_err().to_string();
    assert!(e.contains("is not a usable demos file"), "{e}");
}

/// The command writes the file and says what it holds.
#[cfg(feature = "cli")]
#[test]
fn the_demos_command_writes_a_file() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("s.toml"), SUITE).unwrap();
    let out = dir.path().join("d.safetensors");
    let o = crate::common::blockpuzzle(&[
        "demos",
        "--suite",
        "s.toml",
        "--split",
        "test",
        "--threads",
        "1",
        "--out",
        "d.safetensors",
    ])
    .current_dir(dir.path())
    .output()
    .unwrap();
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(text.contains("1 episodes") && text.contains("split test"), "{text}");
    let d = Demos::read(&out).unwrap();
    assert_eq!((d.episodes.len(), d.episodes[0].seed, d.layout.rows), (1, 1000, 5));
    // The one writer: a folder is refused, before any episode is played.
    let o = crate::common::blockpuzzle(&["demos", "--suite", "s.toml", "--out", "."])
        .current_dir(dir.path())
        .output()
        .unwrap();
    assert!(String::from_utf8_lossy(&o.stderr).contains("is a folder"), "{}", String::from_utf8_lossy(&o.stderr));
}
