//! Starting a run from a trained policy (issue 62): `train --init-from` takes the actor and the
//! normaliser from the policy, a critic warm-up holds the actor still, `--start-at-top` begins at
//! the curriculum's top, and whatever does not fit is refused before anything is written.
#![cfg(all(feature = "train", feature = "cli"))]

use blockpuzzle::benchmark::saved::SavedPolicy;
use blockpuzzle::benchmark::zoo;

/// A DDPG run of two epochs of one cycle of two updates each.
const TINY: &[&str] = &[
    "--algo",
    "ddpg",
    "--workers",
    "1",
    "--epochs",
    "2",
    "--cycles",
    "1",
    "--rollouts",
    "1",
    "--batches",
    "2",
    "--batch-size",
    "16",
    "--buffer-size",
    "1000",
    "--test-episodes",
    "1",
    "--torch-threads",
    "1",
    "--snapshot-every",
    "1",
];

fn train(dir: &std::path::Path, args: &[&str]) -> (bool, String) {
    let o = crate::common::blockpuzzle(&["train"]).args(TINY).args(args).arg("--run-dir").arg(dir).output().unwrap();
    (o.status.success(), format!("{}{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr)))
}

/// The generalist's network.
const ENTITY: [&str; 4] = ["--net", "entity", "--set-width", "64"];

/// Each case's run is refused with every one of its words, no panic, and no run directory left.
fn refused(tmp: &std::path::Path, cases: &[(&[&str], &[&str])]) {
    for (k, (args, words)) in cases.iter().enumerate() {
        let dir = tmp.join(format!("run-{k}"));
        let (ok, text) = train(&dir, args);
        assert!(!ok, "{args:?} was accepted: {text}");
        for w in *words {
            assert!(text.contains(w), "{args:?}: no {w:?} in: {text}");
        }
        assert!(!text.contains("panicked"), "{args:?}: {text}");
        assert!(!dir.exists(), "{args:?} left {}", dir.display());
    }
}

fn snapshot(dir: &std::path::Path, epoch: usize) -> SavedPolicy {
    blockpuzzle::benchmark::saved::read(&dir.join(format!("snapshots/epoch-{epoch:04}.json"))).unwrap()
}

#[test]
fn a_run_starts_from_the_policy_and_its_critics_warm_up_first() {
    let (_, generalist) = zoo::load(&zoo::dir().join("generalist-bc-entity.json")).unwrap();
    let tmp = tempfile::tempdir().unwrap();
    let held = tmp.path().join("held");
    let common =
        [&ENTITY[..], &["--env", "ToppleTower-v0", "--init-from", "generalist-bc-entity", "--start-at-top"]].concat();
    let (ok, text) = train(&held, &[&common[..], &["--critic-warmup", "2"]].concat());
    assert!(ok, "{text}");
    // The first epoch's two updates were the warm-up: the actor is still the generalist's, weight for
    // weight (a set network's weights do not depend on the task's rows); the second moved it.
    assert_eq!(snapshot(&held, 1).policy.net().layers, generalist.policy.net().layers);
    assert_ne!(snapshot(&held, 2).policy.net().layers, generalist.policy.net().layers);
    // Without the warm-up the first epoch's updates move it at once.
    let free = tmp.path().join("free");
    let (ok, text) = train(&free, &common);
    assert!(ok, "{text}");
    assert_ne!(snapshot(&free, 1).policy.net().layers, generalist.policy.net().layers);
    // IBRL and the anchor run (their learner keeps the generalist beside it), and resume.
    let ibrl = tmp.path().join("ibrl");
    let (ok, text) = train(&ibrl, &[&common[..], &["--ibrl", "--anchor-alpha", "0.5"]].concat());
    assert!(ok, "{text}");
    let (ok, text) =
        train(&ibrl, &[&common[..], &["--ibrl", "--anchor-alpha", "0.5", "--epochs", "3", "--resume"]].concat());
    assert!(ok, "{text}");
    // A branch of it may change what the learner does with the policy it started from (here a weaker
    // anchor and no IBRL proposal), recorded with the parent's start; not the start itself.
    let branch = |dir: &str, extra: &[&str]| {
        let from = ["--epochs", "4", "--branch-from", ibrl.to_str().unwrap()];
        train(&tmp.path().join(dir), &[&common[..], extra, &from[..]].concat())
    };
    let (ok, text) = branch("weaker", &["--anchor-alpha", "2.5"]);
    assert!(ok, "{text}");
    let config: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(tmp.path().join("weaker/config.json")).unwrap()).unwrap();
    let changed = config["branched_from"]["changed"].as_array().unwrap();
    assert_eq!(changed.len(), 2, "{changed:?}");
    assert!(changed.contains(&"--anchor-alpha".into()) && changed.contains(&"--ibrl".into()), "{changed:?}");
    let parent: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(ibrl.join("config.json")).unwrap()).unwrap();
    assert_eq!(config["finetune"]["init_policy"], parent["finetune"]["init_policy"]);
    assert_eq!(blockpuzzle::learn::train::read_progress(&tmp.path().join("weaker/progress.csv")).unwrap().len(), 4);
    let mut other = common.clone();
    let at = other.iter().position(|a| *a == "generalist-bc-entity").unwrap();
    other[at] = "ToppleTower-v0-td3-finetuned";
    let (ok, text) = train(
        &tmp.path().join("other"),
        &[&other[..], &["--ibrl", "--anchor-alpha", "0.5", "--epochs", "4", "--branch-from", ibrl.to_str().unwrap()]]
            .concat(),
    );
    assert!(!ok && text.contains("--init-from") && !tmp.path().join("other").exists(), "{text}");
    // SAC too: its saved policy (the mean action) is the generalist's after the warm-up.
    let sac = tmp.path().join("sac");
    let (ok, text) = train(&sac, &[&common[..], &["--algo", "sac", "--critic-warmup", "2"]].concat());
    assert!(ok, "{text}");
    assert_eq!(snapshot(&sac, 1).policy.net().layers, generalist.policy.net().layers);
    // The run records the policy it started from, by the hash results name it with, and began at the top level.
    let config: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(held.join("config.json")).unwrap()).unwrap();
    let id = generalist.policy_id("generalist-bc-entity");
    assert_eq!(config["finetune"]["init_policy"]["sha256"].as_str(), id.sha256.as_deref());
    let rows = blockpuzzle::learn::train::read_progress(&held.join("progress.csv")).unwrap();
    let top = blockpuzzle::env::registry::task("ToppleTower-v0").unwrap().max_level();
    assert_eq!(rows[0].level, top, "--start-at-top");
    // A resumed run keeps its own actor (the checkpoint's), and its record.
    let (ok, text) = train(&held, &[&common[..], &["--critic-warmup", "2", "--epochs", "3", "--resume"]].concat());
    assert!(ok, "{text}");
    let config: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(held.join("config.json")).unwrap()).unwrap();
    assert_eq!(config["finetune"]["init_policy"]["sha256"].as_str(), id.sha256.as_deref());
}

/// The largest difference between two networks' weights and biases (of the same shape).
fn largest_change(a: &blockpuzzle::policy::actor::mlp::PlainNet, b: &blockpuzzle::policy::actor::mlp::PlainNet) -> f32 {
    assert_eq!(a.layers.len(), b.layers.len());
    let pairs = a.layers.iter().zip(&b.layers).flat_map(|(x, y)| x.w.iter().zip(&y.w).chain(x.b.iter().zip(&y.b)));
    pairs.map(|(x, y)| (x - y).abs()).fold(0.0, f32::max)
}

#[test]
fn dagger_goes_on_from_the_generalist() {
    let (_, generalist) = zoo::load(&zoo::dir().join("generalist-bc-entity.json")).unwrap();
    let tmp = tempfile::tempdir().unwrap();
    // A learning rate so small that two updates leave every weight within 1e-6 of where it began.
    let dagger = [&ENTITY[..], &["--env", "ToppleTower-v0", "--algo", "dagger", "--lr-actor", "1e-9"]].concat();
    let from = tmp.path().join("from");
    let (ok, text) = train(&from, &[&dagger[..], &["--init-from", "generalist-bc-entity"]].concat());
    assert!(ok, "{text}");
    let near = largest_change(snapshot(&from, 1).policy.net(), generalist.policy.net());
    assert!(near < 1e-6, "DAgger from the generalist moved a weight by {near}");
    // Without --init-from the same run starts from its own random weights, far from the generalist's.
    let fresh = tmp.path().join("fresh");
    let (ok, text) = train(&fresh, &dagger);
    assert!(ok, "{text}");
    let far = largest_change(snapshot(&fresh, 1).policy.net(), generalist.policy.net());
    assert!(far > 0.01, "a fresh DAgger run is within {far} of the generalist");
}

#[test]
fn what_cannot_start_a_run_is_refused_before_anything_is_written() {
    let tmp = tempfile::tempdir().unwrap();
    let corrupt = tmp.path().join("corrupt.json");
    std::fs::write(&corrupt, "{").unwrap();
    let corrupt = corrupt.to_str().unwrap();
    // SAC from the generalist, with what only DDPG keeps of it.
    let sac =
        [&ENTITY[..], &["--env", "ToppleTower-v0", "--algo", "sac", "--init-from", "generalist-bc-entity"]].concat();
    let (sac_ibrl, sac_anchor) = ([&sac[..], &["--ibrl"]].concat(), [&sac[..], &["--anchor-alpha", "1"]].concat());
    let cases: &[(&[&str], &[&str])] = &[
        (&["--env", "ToppleTower-v0", "--init-from", "/nonexistent/policy.json"], &["--init-from", "cannot load"]),
        (&["--env", "ToppleTower-v0", "--init-from", corrupt], &["--init-from", "corrupt.json"]),
        // Another observation: both named, and the network that reads the policy's.
        (
            &["--env", "BlocksTouch-v0", "--init-from", "BlocksTouch-v0-ddpg", "--net", "entity"],
            &["reads the `flat` observation", "`entities`", "--net mlp"],
        ),
        // Another network: both sides described.
        (
            &["--env", "ToppleTower-v0", "--init-from", "generalist-bc-entity", "--net", "entity", "--set-width", "32"],
            &["the policy's actor is a set network", "this run's is a set network", "[64, 64,"],
        ),
        // A flat policy of another task layout: its observation's length and the run's.
        (
            &["--env", "BlocksChoose-v0", "--init-from", "BlocksTouch-v0-ddpg"],
            &[
                "the policy's actor is an MLP over 48 observation features",
                "this run's is an MLP over 67",
                "--net set or entity",
            ],
        ),
        (&["--env", "BlocksChoose-v0", "--init-from", "BlocksChoose-v0-pggd"], &["PGGD", "deterministic"]),
        (
            &["--env", "ToppleTower-v0", "--algo", "pggd", "--init-from", "generalist-bc-entity"],
            &["pggd cannot start from a trained policy", "--algo ddpg, sac, bc, dagger"],
        ),
        // An imitation learner has no critic to warm up.
        (
            &[
                "--env",
                "ToppleTower-v0",
                "--algo",
                "dagger",
                "--init-from",
                "generalist-bc-entity",
                "--net",
                "entity",
                "--set-width",
                "64",
                "--critic-warmup",
                "1",
            ],
            &["--critic-warmup 1", "dagger imitates the solver and has no critic"],
        ),
        // Two epochs of one cycle of two updates: a warm-up of 4 leaves the actor nothing.
        (
            &["--env", "ToppleTower-v0", "--init-from", "generalist-bc-entity", "--critic-warmup", "4"],
            &["--critic-warmup 4", "make 4 updates", "more --epochs"],
        ),
        // TD3 steps the actor on even updates only: after a warm-up of 3, the next would be update 4 of 4.
        (
            &["--env", "ToppleTower-v0", "--init-from", "generalist-bc-entity", "--td3", "--critic-warmup", "3"],
            &["--critic-warmup 3 with TD3's --policy-delay 2", "never learn", "at most 2 warm-up updates"],
        ),
        (&["--env", "ToppleTower-v0", "--critic-warmup", "4"], &["--init-from"]),
        (&sac_ibrl, &["--ibrl", "sac cannot"]),
        (&sac_anchor, &["--anchor-alpha", "sac cannot"]),
    ];
    refused(tmp.path(), cases);
}

/// Demonstrations beside the run's experience: recorded with `blockpuzzle demos`, checked against
/// the run (its observation, its tasks, the share), recorded by hash; a resumed run refuses another file.
#[test]
fn demonstrations_join_a_run_of_their_task_and_nothing_else() {
    let tmp = tempfile::tempdir().unwrap();
    let demos = tmp.path().join("topple.safetensors");
    let suite = format!("{}/experiments/beyond-teacher/suites/ToppleTower-v0.toml", env!("CARGO_MANIFEST_DIR"));
    let o = crate::common::blockpuzzle(&["demos", "--suite", &suite, "--episodes", "2", "--threads", "1", "--out"])
        .arg(&demos)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let d = demos.to_str().unwrap();
    let cases: &[(&[&str], &[&str])] = &[
        (
            &["--env", "BlocksStack-v0", "--net", "entity", "--demos", d],
            &["episode 0 is of task ToppleTower-v0", "(BlocksStack-v0)"],
        ),
        (
            &["--env", "ToppleTower-v0", "--demos", d],
            &["`entities` observation", "mlp (--net's default)", "--net entity"],
        ),
        (
            &["--env", "ToppleTower-v0", "--net", "entity", "--demos", d, "--demos-ratio", "1.5"],
            &["--demos-ratio 1.5", "from 0 to 1"],
        ),
        (
            &["--env", "ToppleTower-v0", "--net", "entity", "--demos", "/nonexistent/d.safetensors"],
            &["--demos", "cannot read"],
        ),
    ];
    refused(tmp.path(), cases);
    // The same file as the solver of version 1 made it (no solver version in its provenance, the
    // header's length kept): its actions are not this solver's labels, so training refuses it.
    let bytes = std::fs::read(&demos).unwrap();
    let field = format!(",\\\"solver\\\":{}", blockpuzzle::policy::SOLVER_VERSION);
    let at =
        bytes.windows(field.len()).position(|w| w == field.as_bytes()).expect("the demos record the solver version");
    let mut older = bytes.clone();
    older[at..at + field.len()].fill(b' ');
    let old_demos = tmp.path().join("solver-v1.safetensors");
    std::fs::write(&old_demos, older).unwrap();
    let od = old_demos.to_str().unwrap();
    refused(
        tmp.path(),
        &[(
            &["--env", "ToppleTower-v0", "--net", "entity", "--demos", od],
            &["recorded by solver version 1", "record the demos again", "blockpuzzle demos --suite"],
        )],
    );
    // A file whose episode names another task than its hash's (an edit), and demos of a suite's
    // test split: both refused, naming the fix.
    let field = "\\\"task\\\":\\\"ToppleTower-v0\\\"";
    let at = bytes.windows(field.len()).position(|w| w == field.as_bytes()).expect("the demos name their task");
    let mut renamed = bytes.clone();
    renamed[at + field.len() - 3] = b'9';
    let renamed_demos = tmp.path().join("renamed.safetensors");
    std::fs::write(&renamed_demos, renamed).unwrap();
    let test_demos = tmp.path().join("test-split.safetensors");
    let o = crate::common::blockpuzzle(&["demos", "--suite", &suite, "--split", "test", "--episodes", "1"])
        .args(["--threads", "1", "--out"])
        .arg(&test_demos)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    refused(
        tmp.path(),
        &[
            (
                &["--env", "ToppleTower-v0", "--net", "entity", "--demos", renamed_demos.to_str().unwrap()],
                &["episode 0 names task ToppleTower-v9", "is task ToppleTower-v0's", "record the demos again"],
            ),
            (
                &["--env", "ToppleTower-v0", "--net", "entity", "--demos", test_demos.to_str().unwrap()],
                &["recorded on the test split of suite", "--split train"],
            ),
        ],
    );
    let run = tmp.path().join("run");
    let args = ["--env", "ToppleTower-v0", "--net", "entity", "--demos", d, "--demos-ratio", "1"];
    let (ok, text) = train(&run, &args);
    assert!(ok, "{text}");
    let config: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(run.join("config.json")).unwrap()).unwrap();
    let bytes = std::fs::read(&demos).unwrap();
    assert_eq!(
        config["finetune"]["demos_sha256"].as_str(),
        Some(blockpuzzle::benchmark::provenance::sha256(&bytes).as_str())
    );
    // Another file under the same name: a resumed run refuses it.
    let o = crate::common::blockpuzzle(&["demos", "--suite", &suite, "--episodes", "3", "--threads", "1", "--out"])
        .arg(&demos)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let (ok, text) = train(&run, &[&args[..], &["--epochs", "3", "--resume"]].concat());
    assert!(!ok && text.contains("not the file this run started with"), "{text}");
}

#[test]
fn a_blend_lies_between_a_fine_tuned_policy_and_its_start() {
    let (_, generalist) = zoo::load(&zoo::dir().join("generalist-bc-entity.json")).unwrap();
    let tmp = tempfile::tempdir().unwrap();
    let run = tmp.path().join("tuned");
    let (ok, text) =
        train(&run, &[&ENTITY[..], &["--env", "ToppleTower-v0", "--init-from", "generalist-bc-entity"]].concat());
    assert!(ok, "{text}");
    let tuned_file = run.join("snapshots/epoch-0002.json");
    let tuned = snapshot(&run, 2);
    assert_ne!(tuned.policy.net().layers, generalist.policy.net().layers, "the run moved the actor");
    let blend = |weight: &str, base: &str, out: &std::path::Path| {
        let o = crate::common::blockpuzzle(&["blend", "--base", base, "--weight", weight])
            .arg("--tuned")
            .arg(&tuned_file)
            .arg("--out")
            .arg(out)
            .output()
            .unwrap();
        (o.status.success(), format!("{}{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr)))
    };
    // Weight 0 is the starting policy's weights and 1 the tuned one's, exactly.
    for (weight, expected) in [("0", &generalist), ("1", &tuned)] {
        let out = tmp.path().join(format!("w{weight}.json"));
        let (ok, text) = blend(weight, "generalist-bc-entity", &out);
        assert!(ok, "{text}");
        let b = blockpuzzle::benchmark::saved::read(&out).unwrap();
        assert_eq!(b.policy.net().layers, expected.policy.net().layers, "weight {weight}");
    }
    // Between, each weight is (1 - w) x base + w x tuned; the rest is the tuned policy's, and the blend is recorded.
    let out = tmp.path().join("w025.json");
    let (ok, text) = blend("0.25", "generalist-bc-entity", &out);
    assert!(ok, "{text}");
    let b = blockpuzzle::benchmark::saved::read(&out).unwrap();
    let layers = |p: &SavedPolicy| p.policy.net().layers.clone();
    for ((q, g), t) in layers(&b).iter().zip(layers(&generalist)).zip(layers(&tuned)) {
        for ((&q, &g), &t) in q.w.iter().chain(&q.b).zip(g.w.iter().chain(&g.b)).zip(t.w.iter().chain(&t.b)) {
            assert!((q - (0.75 * g + 0.25 * t)).abs() <= 1e-6 * (1.0 + g.abs() + t.abs()), "{q} from {g} and {t}");
        }
    }
    let record = b.blend.as_ref().expect("the blend is recorded");
    assert_eq!(record.weight, 0.25);
    assert_eq!(record.base, generalist.policy_id("generalist-bc-entity"));
    assert_eq!(record.tuned, tuned.policy_id(&tuned_file.display().to_string()));
    assert_eq!((b.env_id.as_str(), b.epoch, b.algo), (tuned.env_id.as_str(), tuned.epoch, tuned.algo));
    assert!(b.critic.is_none());
    assert_eq!(b.policy.act(&vec![0.1; b.policy.obs_dim()]).len(), 4);
    // A zoo entry made from it keeps the record, sealed with the rest of its metadata.
    let shelf = tmp.path().join("zoo");
    let info = zoo::ExportInfo {
        name: "blend".into(),
        description: "a blend".into(),
        trained_with: "blockpuzzle blend ...".into(),
        exported_from: out.display().to_string(),
        env_steps: None,
        evaluations: Vec::new(),
        keep_critic: false,
        overwrite: false,
        algo: None,
    };
    let entry = zoo::export(&shelf, &b, &info).unwrap();
    let (meta, loaded) = zoo::load(&entry).unwrap();
    assert_eq!((meta.blend.as_ref(), loaded.blend.as_ref()), (Some(record), Some(record)));
    let json = entry.with_extension("json");
    let edited = std::fs::read_to_string(&json).unwrap().replace("\"weight\": 0.25", "\"weight\": 0.5");
    assert_ne!(edited, std::fs::read_to_string(&json).unwrap());
    std::fs::write(&json, edited).unwrap();
    let e = zoo::load(&entry).unwrap_err().to_string();
    assert!(e.contains("meta_sha256"), "{e}");
    // It plays as any policy file does.
    let o = crate::common::blockpuzzle(&["eval", "--env", "ToppleTower-v0", "--episodes", "2", "--checkpoint"])
        .arg(&out)
        .arg("--out")
        .arg(tmp.path().join("eval.json"))
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    // An edited policy file is refused by every command that reads one (eval, --init-from, blend):
    // an algorithm the zoo refuses or one that trains another kind, a task text that is not its
    // hash's, a blend record that names another base than the policy's start.
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
    let zeros = format!("sha256:{}", "0".repeat(64));
    type Edit = fn(&mut serde_json::Value, &str);
    let edits: [(&str, Edit); 4] = [
        ("unknown variant `ppo`, expected one of `bc`, `dagger`", |v, _| v["algo"] = "ppo".into()),
        ("algo: pggd trains a gaussian policy, and this one is deterministic", |v, _| v["algo"] = "pggd".into()),
        ("its text is not the task its hash", |v, z| v["task"]["hash"] = z.into()),
        ("blend.base records sha256:000", |v, z| v["blend"]["base"]["sha256"] = z.into()),
    ];
    for (want, edit) in edits {
        let mut edited = v.clone();
        edit(&mut edited, &zeros);
        let file = tmp.path().join("edited.json");
        std::fs::write(&file, serde_json::to_vec(&edited).unwrap()).unwrap();
        let o = crate::common::blockpuzzle(&["eval", "--env", "ToppleTower-v0", "--episodes", "1", "--checkpoint"])
            .arg(&file)
            .output()
            .unwrap();
        let text = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success() && text.contains(want), "{want}: {text}");
    }
    // Refused, naming the problem, with nothing written: a weight outside [0, 1], a policy of another
    // observation or network, a missing policy.
    let cases: &[(&str, &str, &[&str])] = &[
        ("1.5", "generalist-bc-entity", &["--weight", "from 0 to 1"]),
        ("0.5", "BlocksChoose-v0-ddpg", &["BlocksChoose-v0-ddpg reads `flat` observations", "entities"]),
        (
            "0.5",
            "cross-task-v2-dagger-entity",
            &["was fine-tuned from generalist-bc-entity", "not from cross-task-v2-dagger-entity", "--base"],
        ),
        ("0.5", "no-such-policy", &["no-such-policy"]),
    ];
    for (k, (weight, base, words)) in cases.iter().enumerate() {
        let out = tmp.path().join(format!("refused-{k}.json"));
        let (ok, text) = blend(weight, base, &out);
        assert!(!ok, "{base} at {weight} was accepted: {text}");
        for w in *words {
            assert!(text.contains(w), "{base} at {weight}: no {w:?} in {text}");
        }
        assert!(!text.contains("panicked") && !out.exists(), "{text}");
    }
}
