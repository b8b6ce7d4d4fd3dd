//! The model zoo: entries round-trip exactly, damaged or mismatched files and
//! absurd weights are clear errors, and the shipped entries act as the
//! policies they were exported from.
#![cfg(feature = "train")]

use blockpuzzle::benchmark::load::load_policy;
use blockpuzzle::benchmark::saved::{SavedPolicy, Trainer};
use blockpuzzle::benchmark::zoo::{self, ExportInfo};
use blockpuzzle::env::registry;
use blockpuzzle::learn::agents::arch::Arch;
use blockpuzzle::learn::agents::ddpg::{Ddpg, DdpgConfig};
use blockpuzzle::learn::agents::pggd::{Pggd, PggdConfig};
use blockpuzzle::learn::agents::shared::SharedConfig;
use blockpuzzle::policy::actor::{AnyPolicy, PolicyKind};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::path::Path;

const ENV: &str = "BlocksTouch-v0";

fn obs_dim() -> usize {
    registry::make(ENV).unwrap().observation_space().dim()
}

fn random_obs(rng: &mut ChaCha8Rng, n: usize) -> Vec<f32> {
    (0..n).map(|_| rng.gen_range(-2.0f32..2.0)).collect()
}

/// A DDPG policy with a fitted normaliser and its critic, recorded on BlocksTouch-v0.
fn ddpg_saved(seed: u64) -> SavedPolicy {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let d = obs_dim();
    let shared = SharedConfig { hidden: 32, layers: 2, ..SharedConfig::default() };
    let mut a = Ddpg::new(d, 4, shared, DdpgConfig::default(), &mut rng);
    let rows = random_obs(&mut rng, 50 * d);
    a.norm.update(&rows);
    SavedPolicy {
        env_id: ENV.into(),
        task: Some(registry::task(ENV).unwrap().source),
        tasks: Vec::new(),
        stream: None,
        epoch: 12,
        env_steps: Some(34_000),
        finals_success: 0.5,
        algo: Some(Trainer::Ddpg),
        obs_mode: None,
        fixtures: None,
        policy: AnyPolicy::Deterministic(a.policy()),
        critic: Some(a.critic.to_plain()),
        blend: None,
        started_from: None,
        solver: None,
    }
}

fn info(name: &str) -> ExportInfo {
    ExportInfo {
        name: name.into(),
        description: "a test entry".into(),
        trained_with: "none (made by tests/it/zoo.rs)".into(),
        exported_from: "tests/it/zoo.rs".into(),
        keep_critic: true,
        overwrite: false,
        ..ExportInfo::default()
    }
}

fn err_text(e: impl std::fmt::Display) -> String {
    e.to_string()
}

#[test]
fn ddpg_entry_round_trips_and_acts_identically() {
    let dir = tempfile::tempdir().unwrap();
    let saved = ddpg_saved(1);
    let path = zoo::export(dir.path(), &saved, &info("ddpg-test")).unwrap();
    assert_eq!(path, dir.path().join("ddpg-test.safetensors"));
    let (meta, loaded) = zoo::load(&path).unwrap();
    assert_eq!((meta.algo, meta.epoch, meta.task.id.as_str()), (Some(Trainer::Ddpg), 12, ENV));
    assert_eq!(meta.actor.sizes, vec![obs_dim(), 32, 32, 4]);
    assert_eq!(meta.critic.as_ref().unwrap().sizes, vec![obs_dim() + 4, 32, 32, 1]);
    assert_eq!(meta.probes.len(), 3);
    let mut rng = ChaCha8Rng::seed_from_u64(9);
    for _ in 0..20 {
        let obs = random_obs(&mut rng, obs_dim());
        assert_eq!(loaded.policy.act(&obs), saved.policy.act(&obs));
        let mut sa = obs.clone();
        sa.extend([0.1, -0.2, 0.3, 0.9]);
        assert_eq!(loaded.critic.as_ref().unwrap().forward(&sa), saved.critic.as_ref().unwrap().forward(&sa));
    }
    // The .json names the same entry; loading by name goes through the zoo folder.
    assert_eq!(zoo::load(&dir.path().join("ddpg-test.json")).unwrap().1, loaded);
    assert_eq!(zoo::names(dir.path()), vec!["ddpg-test".to_owned()]);
    // Without --critic the entry keeps the actor only.
    let lean = zoo::export(dir.path(), &saved, &ExportInfo { keep_critic: false, ..info("lean") }).unwrap();
    let (meta, loaded) = zoo::load(&lean).unwrap();
    assert!(meta.critic.is_none() && loaded.critic.is_none());
    assert!(std::fs::metadata(&lean).unwrap().len() < std::fs::metadata(&path).unwrap().len());
}

#[test]
fn pggd_entry_round_trips() {
    let dir = tempfile::tempdir().unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(2);
    let d = obs_dim();
    let mut p = Pggd::new(Arch::mlp(d), 4, (2, 16), (0.01, 5.0), PggdConfig::default(), &mut rng);
    p.norm.update(&random_obs(&mut rng, 20 * d));
    let saved =
        SavedPolicy { policy: AnyPolicy::Pggd(p.policy()), critic: None, algo: Some(Trainer::Pggd), ..ddpg_saved(1) };
    let path = zoo::export(dir.path(), &saved, &info("pggd-test")).unwrap();
    let (meta, loaded) = zoo::load(&path).unwrap();
    assert_eq!((meta.algo, meta.kind()), (Some(Trainer::Pggd), Some(PolicyKind::Gaussian)));
    // PGGD trains a Gaussian and nothing else does: a record that says otherwise is refused.
    let wrong = SavedPolicy { algo: Some(Trainer::Ddpg), ..saved.clone() };
    let e = err_text(zoo::export(dir.path(), &wrong, &info("pggd-wrong")).unwrap_err());
    assert!(e.contains("ddpg trains a deterministic"), "{e}");
    assert!(meta.sigma_min.is_some() && !meta.actor.tanh_out);
    let obs = random_obs(&mut rng, d);
    assert_eq!(loaded.policy.act(&obs), saved.policy.act(&obs));
    let (AnyPolicy::Pggd(a), AnyPolicy::Pggd(b)) = (&loaded.policy, &saved.policy) else { panic!("not PGGD") };
    assert_eq!(a.distribution(&obs), b.distribution(&obs));
}

#[test]
fn damaged_or_mismatched_entries_are_clear_errors() {
    let dir = tempfile::tempdir().unwrap();
    let a = zoo::export(dir.path(), &ddpg_saved(1), &info("a")).unwrap();
    let b = zoo::export(dir.path(), &ddpg_saved(2), &info("b")).unwrap();
    // A flipped byte in the tensors.
    let mut bytes = std::fs::read(&a).unwrap();
    let mid = bytes.len() / 2;
    bytes[mid] ^= 0x40;
    std::fs::write(&a, &bytes).unwrap();
    let e = err_text(zoo::load(&a).unwrap_err());
    assert!(e.contains("checksum") && e.contains("a.safetensors"), "{e}");
    // The tensors of another entry under this entry's metadata.
    std::fs::copy(&b, &a).unwrap();
    let e = err_text(zoo::load(&a).unwrap_err());
    assert!(e.contains("tensors of another entry"), "{e}");
    // Truncated metadata.
    let json = b.with_extension("json");
    let text = std::fs::read_to_string(&json).unwrap();
    std::fs::write(&json, &text[..text.len() / 2]).unwrap();
    let e = err_text(zoo::load(&b).unwrap_err());
    assert!(e.contains("bad metadata") && e.contains("b.json"), "{e}");
    // Not a zoo name, not a file: the error lists what the zoo has.
    let e = err_text(zoo::find(dir.path(), "c").unwrap_err());
    assert!(e.contains("\"c\"") && e.contains("a, b"), "{e}");
}

/// Rewrites the entry's first weight to `value` and fixes the checksum and the seal, so
/// that only the value check can refuse it.
fn poison_first_weight(entry: &Path, value: f32) {
    use sha2::Digest;
    let mut bytes = std::fs::read(entry).unwrap();
    let header_len = u64::from_le_bytes(bytes[..8].try_into().unwrap()) as usize;
    let header: serde_json::Value = serde_json::from_slice(&bytes[8..8 + header_len]).unwrap();
    let start = header["actor.0.weight"]["data_offsets"][0].as_u64().unwrap() as usize + 8 + header_len;
    bytes[start..start + 4].copy_from_slice(&value.to_le_bytes());
    std::fs::write(entry, &bytes).unwrap();
    let json = entry.with_extension("json");
    let mut meta = zoo::read_meta(&json).unwrap();
    meta.tensors_sha256 = format!("sha256:{:x}", sha2::Sha256::digest(&bytes));
    meta.meta_sha256 = Some(meta.seal()); // resealed too
    std::fs::write(&json, serde_json::to_vec(&meta).unwrap()).unwrap();
}

#[test]
fn absurd_or_non_finite_weights_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    // A zoo entry holding an infinite weight (checksum made to match).
    let entry = zoo::export(dir.path(), &ddpg_saved(1), &info("inf")).unwrap();
    poison_first_weight(&entry, f32::INFINITY);
    let e = err_text(zoo::load(&entry).unwrap_err());
    assert!(e.contains("layer 0 holds inf"), "{e}");
    let entry = zoo::export(dir.path(), &ddpg_saved(1), &info("huge")).unwrap();
    poison_first_weight(&entry, 1e30);
    let e = err_text(zoo::load(&entry).unwrap_err());
    assert!(e.contains("layer 0 holds 1000000000000000000000000000000"), "{e}");

    // A policy.json whose first layer is all 1e308 (infinite as f32) and one with 1e9.
    let saved = ddpg_saved(1);
    for (value, shown) in [("1e308", "inf"), ("1e9", "1000000000")] {
        let mut v = serde_json::to_value(&saved).unwrap();
        let w = v["policy"]["net"]["layers"][0]["w"].as_array_mut().unwrap();
        for x in w.iter_mut() {
            *x = serde_json::from_str(value).unwrap();
        }
        let file = dir.path().join(format!("policy-{value}.json"));
        std::fs::write(&file, serde_json::to_vec(&v).unwrap()).unwrap();
        let e = format!("{:#}", load_policy(&file).unwrap_err());
        assert!(e.contains("is not usable") && e.contains(&format!("layer 0 holds {shown}")), "{e}");
    }
    // A normaliser with a zero standard deviation, and a critic of the wrong shape.
    let mut v = serde_json::to_value(&saved).unwrap();
    v["policy"]["norm"]["std"][3] = 0.0.into();
    let file = dir.path().join("std.json");
    std::fs::write(&file, serde_json::to_vec(&v).unwrap()).unwrap();
    let e = format!("{:#}", load_policy(&file).unwrap_err());
    assert!(e.contains("normaliser standard deviation 3 is 0"), "{e}");
    let mut bad = saved.clone();
    bad.critic.as_mut().unwrap().layers.pop();
    assert!(bad.check().unwrap_err().contains("critic: the network has 32 outputs, 1 expected"));
    // Export refuses them too.
    let e = err_text(zoo::export(dir.path(), &bad, &info("bad")).unwrap_err());
    assert!(e.contains("critic"), "{e}");
    let e = err_text(zoo::export(dir.path(), &saved, &info("no/slash")).unwrap_err());
    assert!(e.contains("letters, digits"), "{e}");
}

#[test]
fn an_entry_on_another_task_is_a_clear_error() {
    let dir = tempfile::tempdir().unwrap();
    let entry = zoo::export(dir.path(), &ddpg_saved(1), &info("touch")).unwrap();
    let out = crate::common::blockpuzzle(&[
        "eval",
        "--checkpoint",
        entry.to_str().unwrap(),
        "--env",
        "GripperTouch-v0",
        "--episodes",
        "2",
    ])
    .output()
    .unwrap();
    let text = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(text.contains("expects 48-dimensional") && text.contains("GripperTouch-v0"), "{text}");
}

#[test]
fn shipped_entries_load_and_act_as_their_source() {
    // zoo::load replays each entry's probes: the exported policy's actions
    // on reset states of its task, recorded at export, must come out exactly.
    let names = zoo::names(&zoo::dir());
    assert!(names.len() >= 4, "{names:?}");
    for name in &names {
        let (meta, saved) = zoo::load(&zoo::find(&zoo::dir(), name).unwrap()).unwrap();
        assert_eq!(meta.name, *name);
        assert!(!meta.probes.is_empty() && !meta.trained_with.is_empty(), "{name}");
        // The probes are reset observations of the recorded task.
        let task = registry::recorded(&meta.task).unwrap();
        // In the observation the policy reads (a set network's is the `objects` or `entities` one), in
        // its own layout (a multi-task entry's rows are those of its tasks' most blocks).
        let (obs_mode, slots) = (saved.obs_mode(), saved.policy.block_slots(saved.obs_mode()));
        let config = blockpuzzle::EnvConfig { obs_mode, slots, ..blockpuzzle::EnvConfig::new(task) };
        let mut env = blockpuzzle::BlockEnv::new(config).unwrap();
        let level = env.max_level();
        env.set_level(level).unwrap();
        assert_eq!(env.reset(Some(0)).unwrap().0.to_vec(), meta.probes[0].obs, "{name}");
        assert_eq!(saved.policy.act(&meta.probes[0].obs), meta.probes[0].action, "{name}");
    }
}

#[test]
fn cli_takes_zoo_names() {
    let bp = |args: &[&str]| crate::common::blockpuzzle(args).output().unwrap();
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("eval.json");
    let o = bp(&["eval", "--checkpoint", "ReachAvoid-v0-ddpg", "--episodes", "4", "--out", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
    assert_eq!(v["env"], "ReachAvoid-v0");
    let dump = dir.path().join("r.jsonl");
    let o = bp(&[
        "rollout",
        "--env",
        "ReachAvoid-v0",
        "--policy",
        "ReachAvoid-v0-ddpg",
        "--episodes",
        "2",
        "--out",
        dump.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    // AggreVaTeD's expert by zoo name: the run keeps its own copy.
    let run = dir.path().join("aggrevated");
    let o = bp(&[
        "train",
        "--algo",
        "pggd",
        "--env",
        "BlocksChoose-v0",
        "--expert",
        "BlocksTouch-v0-ddpg",
        "--epochs",
        "1",
        "--cycles",
        "1",
        "--batches",
        "2",
        "--test-episodes",
        "1",
        "--hidden",
        "16",
        "--run-dir",
        run.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(run.join("expert_policy.json").exists());
    let o = bp(&["zoo", "list"]);
    assert!(String::from_utf8_lossy(&o.stdout).contains("ReachAvoid-v0-ddpg"));
    let o = bp(&["eval", "--checkpoint", "NoSuchEntry", "--episodes", "2"]);
    let text = String::from_utf8_lossy(&o.stderr);
    // The zoo's first names, and a count of the rest (issue 74: not the whole zoo).
    assert!(
        !o.status.success() && text.contains("NoSuchEntry") && text.contains("BlocksChoose-v0-dagger-entity"),
        "{text}"
    );
    assert!(text.contains(" more (`zoo list`)") && !text.contains("topple-20003-v0-td3-finetuned"), "{text}");
}

#[test]
fn evaluations_keep_their_outcomes_and_format_1_entries_still_load() {
    let bp = |args: &[&str]| crate::common::blockpuzzle(args).output().unwrap();
    let dir = tempfile::tempdir().unwrap();
    let (z, eval) = (dir.path().join("zoo"), dir.path().join("eval.json"));
    let o = bp(&["eval", "--checkpoint", "ReachAvoid-v0-ddpg", "--episodes", "3", "--out", eval.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let mut args = vec!["zoo", "export", "--from", "ReachAvoid-v0-ddpg", "--name", "r", "--description", "d"];
    args.extend([
        "--trained-with",
        "t",
        "--evaluate",
        "4",
        "--eval",
        eval.to_str().unwrap(),
        "--zoo",
        z.to_str().unwrap(),
    ]);
    let o = bp(&args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));

    // Both the recorded `eval` file and the export's own evaluation keep their outcome counts.
    let entry = z.join("r.json");
    let (meta, _) = zoo::load(&entry).unwrap();
    assert_eq!(meta.format, zoo::FORMAT);
    assert_eq!(meta.evaluations.len(), 2, "{:?}", meta.evaluations);
    for (e, n) in meta.evaluations.iter().zip([3, 4]) {
        let o = e.outcomes.expect("outcome counts recorded");
        assert_eq!((e.episodes, o.total()), (n, n), "{e:?}");
        assert_eq!(o.success as f64 / n as f64, e.success_rate, "{e:?}");
    }
    let o = bp(&["zoo", "list", "--zoo", z.to_str().unwrap()]);
    let listed = String::from_utf8_lossy(&o.stdout);
    assert_eq!(listed.matches("the others: failure ").count(), 2, "{listed}");

    // An entry relabelled as an older format keeping what a newer one introduced is refused, naming
    // the field and the format (issue 74: its unsealed fields could be forged, and `zoo upgrade`
    // would seal them).
    let mut v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&entry).unwrap()).unwrap();
    v["format"] = "blockpuzzle-zoo/5".into();
    v.as_object_mut().unwrap().remove("meta_sha256");
    std::fs::write(&entry, serde_json::to_vec(&v).unwrap()).unwrap();
    let e = err_text(zoo::load(&entry).unwrap_err());
    assert!(
        e.contains("says format \"blockpuzzle-zoo/5\", and carries kind, which blockpuzzle-zoo/7 introduced"),
        "{e}"
    );
    let o = bp(&["zoo", "upgrade", "r", "--zoo", z.to_str().unwrap()]);
    assert!(!o.status.success(), "zoo upgrade seals no relabelled entry");
    // An entry of format 1, as format 1 was written (no outcome counts, no record of what made an
    // evaluation, no record of what the policy is), loads; an unknown format is refused, naming those read.
    v["format"] = "blockpuzzle-zoo/1".into();
    for field in ["kind", "obs_mode", "colour_feature", "fixtures"] {
        v.as_object_mut().unwrap().remove(field);
    }
    for e in v["evaluations"].as_array_mut().unwrap() {
        for field in ["outcomes", "provenance", "task_sha256"] {
            e.as_object_mut().unwrap().remove(field);
        }
    }
    std::fs::write(&entry, serde_json::to_vec(&v).unwrap()).unwrap();
    let (meta, _) = zoo::load(&entry).unwrap();
    assert!(meta.evaluations.iter().all(|e| e.outcomes.is_none()));
    v["format"] = "blockpuzzle-zoo/9".into();
    std::fs::write(&entry, serde_json::to_vec(&v).unwrap()).unwrap();
    let e = err_text(zoo::load(&entry).unwrap_err());
    assert!(
        e.contains("\"blockpuzzle-zoo/9\"") && e.contains("blockpuzzle-zoo/1, blockpuzzle-zoo/2, blockpuzzle-zoo/3"),
        "{e}"
    );
}

/// Issue 74: evaluations lie outside the seal (`zoo evaluate` adds to them), so each is checked as a
/// suite result's rows are: recomputed from its outcome counts and bounded, on a task and an engine
/// that exist. `zoo check` and every loader (`zoo list`, Python's through the extension) refuse an
/// edited one, naming the field, the recorded and the recomputed value, and the fix.
#[test]
fn evaluation_records_are_recomputed_and_bounded() {
    let dir = tempfile::tempdir().unwrap();
    for ext in ["json", "safetensors"] {
        let from = zoo::dir().join(format!("ReachAvoid-v0-ddpg.{ext}"));
        std::fs::copy(from, dir.path().join(format!("r.{ext}"))).unwrap();
    }
    let entry = dir.path().join("r.json");
    let original: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&entry).unwrap()).unwrap();
    zoo::load(&entry).unwrap();
    type Edit = fn(&mut serde_json::Value);
    let edits: [(&str, Edit); 9] = [
        ("success_rate 0.5, but its outcomes give 0.99 (198 of 200 episodes)", |e| e["success_rate"] = 0.5.into()),
        ("success_rate -0.1, but its outcomes give", |e| e["success_rate"] = (-0.1).into()),
        ("its outcomes count 102 episodes, and it records 200", |e| e["outcomes"]["success"] = 100.into()),
        ("episodes 1000000000000000 is outside what an evaluation plays, 1 to 1,000,000", |e| {
            e["episodes"] = 1_000_000_000_000_000u64.into()
        }),
        ("ci95 (0.0, 1.0), but 198 of 200 episodes give (0.96", |e| e["ci95"] = serde_json::json!([0.0, 1.0])),
        ("env \"BlocksNowhere-v0\" is neither a built-in task nor this entry's own (ReachAvoid-v0)", |e| {
            e["env"] = "BlocksNowhere-v0".into()
        }),
        ("and task BlocksTouch-v0's hash is", |e| e["env"] = "BlocksTouch-v0".into()),
        ("MuJoCo \"9.9.9\" is no engine this project runs (2.2.2, 3.11.0)", |e| {
            e["provenance"]["mujoco"] = "9.9.9".into()
        }),
        ("distribution \"hard\" is neither normal nor challenge", |e| e["distribution"] = "hard".into()),
    ];
    for (want, edit) in edits {
        let mut v = original.clone();
        edit(&mut v["evaluations"][0]);
        std::fs::write(&entry, serde_json::to_vec_pretty(&v).unwrap()).unwrap();
        let e = err_text(zoo::load(&entry).unwrap_err());
        assert!(e.contains("evaluations[0] (") && e.contains(want) && e.contains("zoo evaluate"), "{want}: {e}");
    }
    // A format-1 record (no outcome counts) is still checked: its rate must be a count of its episodes.
    let mut v = original.clone();
    v["evaluations"][0].as_object_mut().unwrap().remove("outcomes");
    v["evaluations"][0]["success_rate"] = 0.9951.into();
    std::fs::write(&entry, serde_json::to_vec_pretty(&v).unwrap()).unwrap();
    let e = err_text(zoo::load(&entry).unwrap_err());
    assert!(e.contains("success_rate 0.9951 is not a count of 200 episodes"), "{e}");
    let o = crate::common::blockpuzzle(&["zoo", "check", "r", "--zoo", dir.path().to_str().unwrap()]).output().unwrap();
    assert!(!o.status.success() && String::from_utf8_lossy(&o.stderr).contains("is not a count of"));
}

/// Issue 60: an entry is checked as a whole. Its metadata is sealed by its hash (format 6), so a dropped
/// `multi_task`, an emptied task list, a label that is a path or an edited layout is refused; every
/// evaluation it records names this policy; `zoo export` records no other policy's evaluation; `zoo
/// upgrade` seals an older entry that loads.
#[test]
fn entries_are_checked_as_a_whole() {
    let bp = |args: &[&str]| crate::common::blockpuzzle(args).output().unwrap();
    let dir = tempfile::tempdir().unwrap();
    let z = dir.path().join("zoo");
    std::fs::create_dir(&z).unwrap();
    for ext in ["json", "safetensors"] {
        let from = zoo::dir().join(format!("cross-task-v2-dagger-entity.{ext}"));
        std::fs::copy(from, z.join(format!("x.{ext}"))).unwrap();
    }
    let entry = z.join("x.json");
    let original: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&entry).unwrap()).unwrap();
    assert_eq!(original["format"], zoo::FORMAT, "the shipped entries are sealed (zoo upgrade)");
    let check = |v: &serde_json::Value| {
        std::fs::write(&entry, serde_json::to_vec_pretty(v).unwrap()).unwrap();
        let o = bp(&["zoo", "check", "x", "--zoo", z.to_str().unwrap()]);
        (o.status.success(), format!("{}{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr)))
    };
    assert!(check(&original).0);
    type Edit = fn(&mut serde_json::Value);
    let edits: [(&str, Edit); 9] = [
        ("colour_feature edited", |v| v["colour_feature"] = 3.into()),
        ("obs_mode edited", |v| v["obs_mode"] = "flat".into()),
        ("the set layout's slots edited", |v| v["actor"]["set"]["slots"] = 11.into()),
        ("the set layout's encoder edited", |v| v["actor"]["set"]["encoder_layers"] = 9.into()),
        ("multi_task dropped", |v| {
            v.as_object_mut().unwrap().remove("multi_task");
        }),
        ("tasks emptied", |v| v["multi_task"]["tasks"] = serde_json::json!([])),
        ("a label that is a path", |v| v["multi_task"]["label"] = "../../x y".into()),
        ("actor.sizes edited", |v| v["actor"]["sizes"][1] = 128.into()),
        ("the seal removed", |v| {
            v.as_object_mut().unwrap().remove("meta_sha256");
        }),
    ];
    for (what, edit) in edits {
        let mut v = original.clone();
        edit(&mut v);
        let (ok, t) = check(&v);
        if what.contains("set layout") {
            // Checked with the tensors, which the error names.
            assert!(!ok && t.contains("x.safetensors") && t.contains("layout `set`") && t.contains("restore"), "{t}");
            continue;
        }
        assert!(!ok && t.contains("x.json") && t.contains("restore"), "{what}: {t}");
    }
    // An unsealed label that is a path is refused by itself (an entry of format 5, before the seal).
    let mut v = original.clone();
    v["format"] = "blockpuzzle-zoo/5".into();
    v["algo"] = "ddpg".into(); // before format 7, `algo` said what acts
    for k in ["meta_sha256", "kind", "obs_mode", "colour_feature", "fixtures"] {
        v.as_object_mut().unwrap().remove(k);
    }
    assert!(check(&v).0, "a format 5 entry as it was loads");
    v["multi_task"]["label"] = "../../x y".into();
    let (ok, t) = check(&v);
    assert!(!ok && t.contains("multi_task.label"), "{t}");
    // Another policy's evaluation is refused, whether edited into the entry or given to zoo export.
    let mut v = original.clone();
    v["evaluations"][0]["provenance"]["policy"]["sha256"] = format!("sha256:{}", "0".repeat(64)).into();
    let (ok, t) = check(&v);
    assert!(!ok && t.contains("evaluations[0]") && t.contains("not this one"), "{t}");
    let eval = dir.path().join("other.json");
    let o = bp(&["eval", "--checkpoint", "ReachAvoid-v0-ddpg", "--episodes", "2", "--out", eval.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let mut args = vec!["zoo", "export", "--from", "BlocksTouch-v0-ddpg", "--name", "y", "--description", "d"];
    args.extend(["--trained-with", "t", "--eval", eval.to_str().unwrap(), "--zoo", z.to_str().unwrap()]);
    let o = bp(&args);
    let t = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && t.contains("not by this policy"), "{t}");
    assert!(!z.join("y.json").exists() && !z.join("y.safetensors").exists());
    // zoo upgrade seals an older entry that loads, and the sealed entry checks.
    let mut v = original.clone();
    v["format"] = "blockpuzzle-zoo/5".into();
    v["algo"] = "ddpg".into();
    for k in ["meta_sha256", "kind", "obs_mode", "colour_feature", "fixtures"] {
        v.as_object_mut().unwrap().remove(k);
    }
    check(&v);
    let o = bp(&["zoo", "upgrade", "x", "--algo", "dagger", "--zoo", z.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let (meta, _) = zoo::load(&entry).unwrap();
    assert_eq!((meta.format.as_str(), meta.meta_sha256.as_deref()), (zoo::FORMAT, original["meta_sha256"].as_str()));
}

/// An entry's metadata without its tensors, and a name too long for a file, are named as such (issue 60).
#[test]
fn a_lone_metadata_file_and_a_long_name_are_named() {
    let dir = tempfile::tempdir().unwrap();
    let z = dir.path().join("zoo");
    std::fs::create_dir(&z).unwrap();
    std::fs::copy(zoo::dir().join("BlocksTouch-v0-ddpg.json"), z.join("x.json")).unwrap();
    let run = |args: &[&str]| {
        let o = crate::common::blockpuzzle(args).env("BLOCKPUZZLE_ZOO", &z).output().unwrap();
        (o.status.success(), String::from_utf8_lossy(&o.stderr).into_owned())
    };
    let json = z.join("x.json");
    for args in [
        vec!["zoo", "check", "x"],
        vec!["eval", "--checkpoint", "x", "--episodes", "1"],
        vec!["eval", "--checkpoint", json.to_str().unwrap(), "--episodes", "1"],
    ] {
        let (ok, e) = run(&args);
        assert!(
            !ok && e.contains("x.safetensors") && e.contains("are missing") && e.contains("copy both"),
            "{args:?}: {e}"
        );
    }
    let long = "a".repeat(300);
    let from = zoo::dir().join("BlocksTouch-v0-ddpg.safetensors");
    let mut args = vec!["zoo", "export", "--from", from.to_str().unwrap(), "--name", &long, "--description", "d"];
    args.extend(["--trained-with", "t", "--zoo", z.to_str().unwrap()]);
    let (ok, e) = run(&args);
    assert!(!ok && e.contains("1 to 100 letters") && !e.contains(&long), "{e}");
    assert_eq!(std::fs::read_dir(&z).unwrap().count(), 1, "nothing written");
}

/// One resolver turns every policy name into a policy (issue 61): `random`, the baselines, a zoo
/// name, a zoo file, a run directory, a policy file; a command that needs a trained policy names
/// what a baseline is; `eval --suite --checkpoint scripted` is `--baseline scripted`.
#[test]
fn one_resolver_names_every_policy() {
    use blockpuzzle::benchmark::evaluate::Baseline;
    use blockpuzzle::benchmark::load::{load_policy, resolve, Named};
    use std::path::Path;
    assert!(matches!(resolve(Path::new("random")).unwrap(), Named::Random));
    assert!(matches!(resolve(Path::new("scripted")).unwrap(), Named::Baseline(Baseline::Scripted)));
    assert!(matches!(resolve(Path::new("obs-hash")).unwrap(), Named::Baseline(Baseline::ObsHash)));
    let by_name = match resolve(Path::new("BlocksTouch-v0-ddpg")).unwrap() {
        Named::Saved(_, s) => s,
        other => panic!("{other:?}"),
    };
    let file = zoo::dir().join("BlocksTouch-v0-ddpg.json");
    let Named::Saved(_, by_file) = resolve(&file).unwrap() else { panic!("a zoo file is a trained policy") };
    assert_eq!(by_name.policy_id("x"), by_file.policy_id("x"));
    let e = format!("{:#}", load_policy(Path::new("scripted")).unwrap_err());
    assert!(e.contains("baseline") && e.contains("--baseline scripted"), "{e}");
    assert!(format!("{:#}", resolve(Path::new("no-such-policy")).unwrap_err()).contains("no policy file or zoo entry"));
    // The CLI resolves with it: a suite evaluated by --checkpoint scripted and by --baseline scripted.
    let dir = tempfile::tempdir().unwrap();
    let suite = dir.path().join("s.toml");
    std::fs::write(
        &suite,
        "version = 1\nname = \"s\"\nsummary = \"s\"\n[[splits.train]]\ntask = \"BlocksTouch-v0\"\nseed = 0\n\
         episodes = 2\n[[splits.test]]\ntask = \"BlocksTouch-v0\"\nseed = 10\nepisodes = 2\n",
    )
    .unwrap();
    let run = |how: &[&str], out: &str| {
        let out = dir.path().join(out);
        let o = crate::common::blockpuzzle(&[&["eval", "--suite", suite.to_str().unwrap()][..], how].concat())
            .args(["--threads", "1", "--out", out.to_str().unwrap()])
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(out).unwrap()).unwrap();
        (v["provenance"]["policy"].clone(), v["score"].clone())
    };
    assert_eq!(run(&["--checkpoint", "scripted"], "a.json"), run(&["--baseline", "scripted"], "b.json"));
}

/// Format 7 records what a policy reads and is and the algorithm that trained it, and readers take
/// them from the fields; an older entry is read as before and `zoo upgrade` records them, `--algo`
/// the one thing it cannot know (issue 61).
#[test]
fn an_entry_records_its_mode_kind_and_algorithm() {
    use blockpuzzle::env::ObsMode;
    let (meta, saved) = zoo::load(&zoo::dir().join("generalist-bc-entity.json")).unwrap();
    assert_eq!(
        (meta.version(), meta.obs_mode, meta.kind(), meta.trained_by()),
        (7, Some(ObsMode::Entities), Some(PolicyKind::Deterministic), Some(Trainer::Bc))
    );
    assert_eq!(saved.algo, Some(Trainer::Bc));
    assert_eq!(meta.colour_feature, Some(blockpuzzle::env::COLOUR_FEATURE));
    assert_eq!(meta.fixtures.as_deref(), Some(&blockpuzzle::env::Fixture::ALL[..]));
    assert_eq!(zoo::load(&zoo::dir().join("BlocksChoose-v0-pggd.json")).unwrap().0.kind(), Some(PolicyKind::Gaussian));
    // Exported: the policy file's record; an --algo that disagrees with it is refused.
    let dir = tempfile::tempdir().unwrap();
    let path = zoo::export(dir.path(), &ddpg_saved(3), &info("e")).unwrap();
    let (meta, _) = zoo::load(&path).unwrap();
    assert_eq!((meta.trained_by(), meta.obs_mode), (Some(Trainer::Ddpg), Some(ObsMode::Flat)));
    let e = err_text(
        zoo::export(dir.path(), &ddpg_saved(3), &ExportInfo { algo: Some(Trainer::Sac), ..info("f") }).unwrap_err(),
    );
    assert!(e.contains("records that ddpg trained it"), "{e}");
    // A policy file written before it recorded its observation: exported with the one its network reads.
    let legacy = SavedPolicy { obs_mode: None, fixtures: None, ..ddpg_saved(3) };
    let meta = zoo::read_meta(&zoo::export(dir.path(), &legacy, &info("legacy")).unwrap()).unwrap();
    assert_eq!((meta.obs_mode, meta.fixtures.as_deref()), (Some(ObsMode::Flat), Some(&[][..])));
    // A format-6 entry (sealed as format 6 was): read as before, then upgraded.
    let z = dir.path().join("z");
    std::fs::create_dir(&z).unwrap();
    std::fs::copy(zoo::dir().join("BlocksTouch-v0-ddpg.safetensors"), z.join("old.safetensors")).unwrap();
    let mut old = zoo::read_meta(&zoo::dir().join("BlocksTouch-v0-ddpg.json")).unwrap();
    (old.format, old.algo, old.kind, old.obs_mode, old.colour_feature, old.fixtures, old.name) =
        ("blockpuzzle-zoo/6".into(), Some(Trainer::Ddpg), None, None, None, None, "old".into());
    old.meta_sha256 = Some(old.seal());
    std::fs::write(z.join("old.json"), serde_json::to_vec_pretty(&old).unwrap()).unwrap();
    let (meta, saved) = zoo::load(&z.join("old.json")).unwrap();
    assert_eq!(
        (meta.version(), meta.kind(), meta.trained_by(), saved.algo),
        (6, Some(PolicyKind::Deterministic), None, None)
    );
    let bp = |args: &[&str]| crate::common::blockpuzzle(args).output().unwrap();
    let o = bp(&["zoo", "upgrade", "old", "--zoo", z.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let meta = zoo::read_meta(&z.join("old.json")).unwrap();
    assert_eq!((meta.version(), meta.algo, meta.obs_mode), (7, None, Some(ObsMode::Flat)));
    assert!(std::fs::read_to_string(z.join("old.json")).unwrap().contains("\"algo\": \"unrecorded\""));
    assert_eq!(meta.colour_feature, Some(blockpuzzle::env::COLOUR_FEATURE));
    assert_eq!(meta.fixtures.as_deref(), Some(&[][..]));
    // An algorithm that does not train this kind of policy is refused, and the entry stays as it was
    // (issue 74: it was overwritten with one that `zoo check` refuses).
    let before = std::fs::read(z.join("old.json")).unwrap();
    let o = bp(&["zoo", "upgrade", "old", "--algo", "pggd", "--zoo", z.to_str().unwrap()]);
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && e.contains("--algo pggd: pggd trains a gaussian policy, and this one is deterministic"),
        "{e}"
    );
    assert_eq!(std::fs::read(z.join("old.json")).unwrap(), before);
    assert!(bp(&["zoo", "check", "old", "--zoo", z.to_str().unwrap()]).status.success());
    // The records of one upgrade go in one rewrite: where one is refused, none is written (an
    // acceptable --algo beside a --started-from of another network).
    let other = zoo::dir().join("generalist-bc-entity.json");
    let o = bp(&[
        "zoo",
        "upgrade",
        "old",
        "--algo",
        "ddpg",
        "--started-from",
        other.to_str().unwrap(),
        "--zoo",
        z.to_str().unwrap(),
    ]);
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && e.contains("a policy is fine-tuned from one of its own network"), "{e}");
    assert_eq!(std::fs::read(z.join("old.json")).unwrap(), before);
    let o = bp(&["zoo", "upgrade", "old", "--algo", "ddpg", "--zoo", z.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(zoo::load(&z.join("old.json")).unwrap().0.trained_by(), Some(Trainer::Ddpg));
    let o = bp(&["zoo", "upgrade", "old", "--algo", "td3", "--zoo", z.to_str().unwrap()]);
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && e.contains("records ddpg"), "{e}");
    // The solver version a policy learned from (issue 73), recorded once: a version no build has had,
    // a change of record and an upgrade of every entry at once are refused, and nothing is written.
    let z_arg = z.to_str().unwrap();
    let before = std::fs::read(z.join("old.json")).unwrap();
    for (args, want) in [
        (&["old", "--solver", "99"][..], "solver 99 is no solver version this build knows (1 to"),
        (&["--solver", "1"][..], "--solver records the solver one policy learned from: name the entries"),
    ] {
        let o = bp(&[&["zoo", "upgrade", "--zoo", z_arg][..], args].concat());
        let e = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success() && e.contains(want), "{args:?}: {e}");
        assert_eq!(std::fs::read(z.join("old.json")).unwrap(), before);
    }
    assert!(bp(&["zoo", "upgrade", "old", "--solver", "1", "--zoo", z_arg]).status.success());
    assert_eq!(zoo::load(&z.join("old.json")).unwrap().0.solver, Some(1));
    let o = bp(&["zoo", "upgrade", "old", "--solver", "2", "--zoo", z_arg]);
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && e.contains("learned from solver version 1; --solver 2 would change"), "{e}");
    let o = bp(&["zoo", "list", "--zoo", z_arg]);
    assert!(String::from_utf8_lossy(&o.stdout).contains("ddpg of solver version 1"));
    // An entry whose fixtures are not this build's is refused, naming both lists.
    let mut edited = zoo::read_meta(&zoo::dir().join("generalist-bc-entity.json")).unwrap();
    edited.fixtures = Some(blockpuzzle::env::Fixture::ALL[..2].to_vec());
    edited.meta_sha256 = Some(edited.seal());
    std::fs::copy(zoo::dir().join("generalist-bc-entity.safetensors"), z.join("fx.safetensors")).unwrap();
    std::fs::write(z.join("fx.json"), serde_json::to_vec_pretty(&edited).unwrap()).unwrap();
    let e = err_text(zoo::load(&z.join("fx.json")).unwrap_err());
    assert!(e.contains("fixtures records [gripper, table]") && e.contains("[gripper, table, floor]"), "{e}");
}

/// A description carries no result figures (issue 74: they were recorded once and went stale beside
/// the recomputed evaluations): the shipped entries carry none, export and `zoo describe` refuse one,
/// and `zoo describe` rewrites an entry that still loads and checks.
#[test]
fn descriptions_carry_no_figures() {
    for name in zoo::names(&zoo::dir()) {
        let meta = zoo::read_meta(&zoo::find(&zoo::dir(), &name).unwrap()).unwrap();
        assert_eq!(zoo::figure_in(&meta.description), None, "{name}: {}", meta.description);
    }
    assert_eq!(zoo::figure_in("0.978 on ToppleTower-v0").as_deref(), Some("0.978"));
    assert_eq!(zoo::figure_in("0.79x the generalist's").as_deref(), Some("0.79x"));
    assert_eq!(zoo::figure_in("a gain of 12%").as_deref(), Some("12%"));
    assert_eq!(zoo::figure_in("0.3 x generalist + 0.7 x fine-tuned, epoch 15 (46,496 env steps), v0.1"), None);
    let dir = tempfile::tempdir().unwrap();
    let z = dir.path();
    for ext in ["json", "safetensors"] {
        std::fs::copy(zoo::dir().join(format!("BlocksTouch-v0-ddpg.{ext}")), z.join(format!("e.{ext}"))).unwrap();
    }
    let bp = |args: &[&str]| crate::common::blockpuzzle(args).output().unwrap();
    let zs = z.to_str().unwrap();
    let o = bp(&["zoo", "describe", "e", "--description", "solves 0.95 of episodes", "--zoo", zs]);
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && e.contains("carries the figure \"0.95\"") && e.contains("zoo list"), "{e}");
    let o = bp(&["zoo", "describe", "e", "--description", "the 2-block expert (results/headline.md)", "--zoo", zs]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(zoo::read_meta(&z.join("e.json")).unwrap().description, "the 2-block expert (results/headline.md)");
    assert!(bp(&["zoo", "check", "e", "--zoo", zs]).status.success());
    let o = bp(&[
        "zoo",
        "export",
        "--from",
        "BlocksTouch-v0-ddpg",
        "--name",
        "f",
        "--description",
        "50% better",
        "--trained-with",
        "t",
        "--zoo",
        zs,
        "--evaluate",
        "5",
    ]);
    assert!(!o.status.success() && String::from_utf8_lossy(&o.stderr).contains("\"50%\""));
    // Refused before its evaluations are played, not after.
    assert!(!String::from_utf8_lossy(&o.stdout).contains("normal"), "{}", String::from_utf8_lossy(&o.stdout));
    assert!(!z.join("f.json").exists());
}

/// A hash that is not of a hash's form is named as such, not called an edit of the content it
/// guards (issue 74, misworded): a task record's, a zoo entry's seal.
#[test]
fn malformed_hashes_are_named_as_such() {
    let mut source = registry::task("BlocksTouch-v0").unwrap().source.clone();
    assert!(source.compile().is_ok());
    source.hash = "sha256:zz".into();
    let e = source.compile().unwrap_err().to_string();
    assert!(e.contains("\"sha256:zz\" is not a content hash") && !e.contains("edited"), "{e}");
    let dir = tempfile::tempdir().unwrap();
    for ext in ["json", "safetensors"] {
        std::fs::copy(zoo::dir().join(format!("BlocksTouch-v0-ddpg.{ext}")), dir.path().join(format!("e.{ext}")))
            .unwrap();
    }
    let entry = dir.path().join("e.json");
    let mut v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&entry).unwrap()).unwrap();
    v["meta_sha256"] = "d41d8cd98f00b204".into();
    std::fs::write(&entry, serde_json::to_vec(&v).unwrap()).unwrap();
    let e = err_text(zoo::load(&entry).unwrap_err());
    assert!(e.contains("meta_sha256 \"d41d8cd98f00b204\" is not a content hash") && !e.contains("edited"), "{e}");
}

/// Issue 74: a fine-tuned entry exported before policy files recorded their start records it by
/// `zoo upgrade --started-from` (the shipped ones do): only a policy of its own network, never over
/// another record; and `blend` of it with its start gives the shipped blend's policy again.
#[test]
fn a_fine_tuned_entry_records_the_policy_it_started_from() {
    let bp = |args: &[&str]| {
        let o = crate::common::blockpuzzle(args).output().unwrap();
        (o.status.success(), format!("{}{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr)))
    };
    let (_, generalist) = zoo::load(&zoo::dir().join("generalist-bc-entity.json")).unwrap();
    for shipped in ["ToppleTower-v0-td3-finetuned", "topple-20003-v0-td3-finetuned"] {
        let (meta, saved) = zoo::load(&zoo::dir().join(format!("{shipped}.json"))).unwrap();
        let start = meta.started_from.clone().unwrap();
        assert_eq!((start.name.as_str(), &start.sha256), ("generalist-bc-entity", &generalist.policy_id("x").sha256));
        assert_eq!(saved.started_from, meta.started_from, "{shipped}");
    }
    let tmp = tempfile::tempdir().unwrap();
    let copy = |name: &str| {
        for ext in ["json", "safetensors"] {
            std::fs::copy(zoo::dir().join(format!("{name}.{ext}")), tmp.path().join(format!("{name}.{ext}"))).unwrap();
        }
        tmp.path().join(format!("{name}.json"))
    };
    let folder = tmp.path().to_str().unwrap();
    // A start of another network is refused (an entry that records none), and the entry is left as it was.
    let blend = copy("ToppleTower-v0-td3-finetuned-blend");
    let before = std::fs::read(&blend).unwrap();
    let args = ["zoo", "upgrade", "ToppleTower-v0-td3-finetuned-blend", "--started-from", "BlocksTouch-v0-ddpg"];
    let (ok, text) = bp(&[&args[..], &["--zoo", folder]].concat());
    assert!(!ok && text.contains("a policy is fine-tuned from one of its own network"), "{text}");
    assert_eq!(std::fs::read(&blend).unwrap(), before);
    let (ok, text) = bp(&["zoo", "upgrade", "--started-from", "generalist-bc-entity", "--zoo", folder]);
    assert!(!ok && text.contains("name the entries"), "{text}");
    // The same start again changes nothing; another over the record is refused.
    let name = "ToppleTower-v0-td3-finetuned";
    let entry = copy(name);
    let sealed = std::fs::read(&entry).unwrap();
    assert!(bp(&["zoo", "upgrade", name, "--started-from", "generalist-bc-entity", "--zoo", folder]).0);
    assert_eq!(std::fs::read(&entry).unwrap(), sealed);
    let (ok, text) = bp(&["zoo", "upgrade", name, "--started-from", "topple-20003-v0-td3-finetuned", "--zoo", folder]);
    assert!(!ok && text.contains("would change a record"), "{text}");
    assert_eq!(std::fs::read(&entry).unwrap(), sealed);
    // The shipped blend is this entry and its start at 0.7: blend makes it again.
    let out = tmp.path().join("made.json");
    let (ok, text) = bp(&[
        "blend",
        "--base",
        "generalist-bc-entity",
        "--tuned",
        entry.to_str().unwrap(),
        "--weight",
        "0.7",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(ok, "{text}");
    let made = blockpuzzle::benchmark::saved::read(&out).unwrap();
    let (_, shipped) = zoo::load(&zoo::dir().join(format!("{name}-blend.json"))).unwrap();
    assert_eq!(made.policy.net().layers, shipped.policy.net().layers, "the shipped blend's weights");
}
