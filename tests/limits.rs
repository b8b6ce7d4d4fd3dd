//! Hard limits and clean failures: absurd numbers are refused before any work
//! with the flag or field, the range and why; a failed command leaves the file
//! system as it found it; exit codes and messages tell the truth.
#![cfg(feature = "train")]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

const BP: &str = env!("CARGO_BIN_EXE_blockpuzzle");

/// Runs blockpuzzle in `cwd`.
fn bp_in(cwd: &Path, args: &[&str]) -> Output {
    Command::new(BP).current_dir(cwd).args(args).output().expect("run blockpuzzle")
}

fn text(o: &Output) -> String {
    format!("{}{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr))
}

/// The names in a folder, sorted.
fn entries(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .map(|rd| rd.map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect())
        .unwrap_or_default();
    v.sort();
    v
}

/// Fails with a message holding every one of `wanted`, and without a panic.
#[track_caller]
fn refused(o: &Output, wanted: &[&str]) {
    let t = text(o);
    assert!(!o.status.success(), "expected a failure: {t}");
    assert!(!t.contains("panicked"), "{t}");
    for w in wanted {
        assert!(t.contains(w), "{w:?} missing from: {t}");
    }
}

/// The training command of a tiny DDPG run on BlocksTouch-v0 to `epochs`, then `extra` flags.
fn tiny_args<'a>(run: &'a Path, epochs: &'a str, extra: &[&'a str]) -> Vec<&'a str> {
    let args = "train --env BlocksTouch-v0 --cycles 1 --batches 2 --test-episodes 1 --hidden 16 --workers 1 --epochs";
    let mut v: Vec<&str> = args.split(' ').chain([epochs, "--run-dir", run.to_str().unwrap()]).collect();
    v.extend(extra);
    v
}

/// A tiny DDPG run of one epoch, made once per test that needs it.
fn tiny_run(dir: &Path, name: &str) -> PathBuf {
    let run = dir.join(name);
    let o = bp_in(dir, &tiny_args(&run, "1", &[]));
    assert!(o.status.success(), "{}", text(&o));
    run
}

#[test]
fn numbers_without_an_upper_limit_are_refused_before_anything_is_created() {
    let dir = tempfile::tempdir().unwrap();
    let cwd = dir.path();
    let cases: &[(&str, &[&str])] = &[
        ("train --env BlocksTouch-v0 --batch-size 1000000000", &["--batch-size", "1 to 65,536"]),
        ("train --env BlocksTouch-v0 --workers 100000", &["--workers", "1 to 256", "MPI ranks"]),
        ("bench --ddpg --batch-size 1000000000", &["--batch-size", "1 to 65,536"]),
        ("eval --checkpoint BlocksTouch-v0-ddpg --episodes 18446744073709551615", &["--episodes", "1 to 1,000,000"]),
        ("task check BlocksTouch-v0 --samples 1000000000000", &["--samples", "1 to 100,000"]),
        (
            "eval --checkpoint BlocksTouch-v0-ddpg --episodes 2 --seed 18446744073709551615",
            &["passes the largest seed", "give --seed 18446744073709551614 or less"],
        ),
        (
            "rollout --env BlocksTouch-v0 --seed 18446744073709551615 --episodes 2 --out x.jsonl",
            &["--seed 18446744073709551614"],
        ),
        ("render --traj x.jsonl --out x.png --filmstrip 100000", &["--filmstrip", "1 to 64"]),
        ("report --target 2 run", &["--target", "from 0 to 1"]),
        ("report --target NaN run", &["--target", "from 0 to 1"]),
        // Negative numbers name the flag and its range instead of reading as a flag.
        ("eval --checkpoint BlocksTouch-v0-ddpg --episodes -3", &["'-3' for '--episodes", "1 to 1,000,000"]),
        (
            "rollout --env BlocksTouch-v0 --seed -1 --out x.jsonl",
            &["'-1' for '--seed", "0 to 18,446,744,073,709,551,615"],
        ),
        ("train --env BlocksTouch-v0 --epochs -5", &["'-5' for '--epochs", "1 to 100,000"]),
    ];
    for (args, wanted) in cases {
        let o = bp_in(cwd, &args.split(' ').collect::<Vec<_>>());
        refused(&o, wanted);
        assert!(entries(cwd).is_empty(), "`{args}` left {:?}", entries(cwd));
    }
    // A run that would not fit in memory is refused by its size, naming what to lower.
    let o = bp_in(cwd, &["train", "--env", "BlocksTouch-v0", "--workers", "256", "--buffer-size", "100000000"]);
    refused(&o, &["would need", "GB of memory", "lower --buffer-size"]);
    let o = bp_in(cwd, &["train", "--env", "BlocksTouch-v0", "--hidden", "8192", "--layers", "32"]);
    refused(&o, &["would need", "--layers 32 x --hidden 8192"]);
    assert!(entries(cwd).is_empty(), "{:?}", entries(cwd));
}

#[test]
fn task_files_bound_their_numbers_and_ids_with_file_line_and_field() {
    let dir = tempfile::tempdir().unwrap();
    let base = blockpuzzle::env::REGISTRY.iter().find(|r| r.id == "BlocksTouch-v0").unwrap().toml;
    let cases: &[(&str, &str, &[&str])] = &[
        (
            "max_episode_steps = 50",
            "max_episode_steps = 1000000000000",
            &["max_episode_steps = 1,000,000,000,000", "1 to 10,000"],
        ),
        ("id = \"BlocksTouch-v0\"", "id = \"../../escaped\"", &["id = \"../../escaped\"", "versioned id"]),
    ];
    for (from, to, wanted) in cases {
        assert!(base.contains(from), "{from}");
        let path = dir.path().join("t.toml");
        std::fs::write(&path, base.replacen(from, to, 1)).unwrap();
        let line = base.lines().position(|l| l.starts_with(from)).unwrap() + 1;
        let o = bp_in(dir.path(), &["task", "check", path.to_str().unwrap()]);
        refused(&o, wanted);
        assert!(text(&o).contains(&format!("t.toml:{line}:")), "line {line}: {}", text(&o));
    }
    // Sizes and masses: the message blames the object, not a later symptom.
    let green_at = base.find("colour = \"green\"").unwrap();
    for field in ["half_extents = [1e308, 0.025, 0.025]", "mass = 1e308", "friction = [1e308, 0.005, 0.0001]"] {
        let mut task = base.to_owned();
        task.insert_str(green_at, &format!("{field}\n"));
        let e = blockpuzzle::task::Task::from_toml(&task, None).unwrap_err().to_string();
        let name = field.split(' ').next().unwrap();
        assert!(e.contains("object \"green\"") && e.contains(name) && e.contains(" to "), "{e}");
    }
    assert!(blockpuzzle::task::is_safe_id("BlocksTouch-v0") && !blockpuzzle::task::is_safe_id("a/b-v0"));
}

#[test]
fn failed_training_commands_create_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let cwd = dir.path();
    let o = bp_in(cwd, &["train", "--env", "BlocksTouch-v0", "--resume", "--run-dir", "gone"]);
    refused(&o, &["--resume: gone holds no run", "without --resume"]);
    let o =
        bp_in(cwd, &["train", "--algo", "pggd", "--env", "BlocksChoose-v0", "--expert", "nothere", "--run-dir", "r"]);
    refused(&o, &["loading the expert nothere"]);
    std::fs::write(cwd.join("bad.json"), "{}").unwrap();
    let o =
        bp_in(cwd, &["train", "--algo", "pggd", "--env", "BlocksChoose-v0", "--expert", "bad.json", "--run-dir", "r"]);
    refused(&o, &["bad.json is not a blockpuzzle policy file"]);
    assert_eq!(entries(cwd), vec!["bad.json"]);
}

#[test]
fn damaged_runs_are_named_and_branching_from_one_creates_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let run = tiny_run(dir.path(), "parent");
    let child = dir.path().join("child");
    let (r, c) = (run.to_str().unwrap(), child.to_str().unwrap());

    // Resuming with another task names the run's task and the flag to pass.
    let mut args = tiny_args(&run, "2", &["--resume"]);
    args[2] = "BlocksChoose-v0";
    let o = bp_in(dir.path(), &args);
    refused(&o, &["was trained on BlocksTouch-v0 (--env BlocksTouch-v0)", "pass --env BlocksTouch-v0"]);

    // A deleted replay segment: named once, with the fix.
    let segment = std::fs::read_dir(run.join("replay")).unwrap().next().unwrap().unwrap().path();
    let saved = std::fs::read(&segment).unwrap();
    std::fs::remove_file(&segment).unwrap();
    let o = bp_in(dir.path(), &tiny_args(&run, "2", &["--resume"]));
    refused(&o, &["replay segment", "is missing: restore that file"]);
    assert!(!text(&o).contains("os error"), "{}", text(&o));
    std::fs::write(&segment, saved).unwrap();

    // A truncated checkpoint: the branch names the parent's file and creates nothing.
    let ckpt = run.join("checkpoint.bin");
    let bytes = std::fs::read(&ckpt).unwrap();
    std::fs::write(&ckpt, &bytes[..bytes.len() / 2]).unwrap();
    let mut args = tiny_args(&run, "2", &["--branch-from", r]);
    let at = args.iter().position(|a| *a == "--run-dir").unwrap();
    args[at + 1] = c;
    let o = bp_in(dir.path(), &args);
    refused(&o, &[&format!("checkpoint {} is corrupt", ckpt.display()), "nothing was created"]);
    assert!(!text(&o).contains("branched"), "{}", text(&o));
    assert_eq!(entries(dir.path()), vec!["parent"], "no child, no temporary copy");
}

#[test]
fn eval_writes_beside_runs_or_in_the_current_folder_named_by_policy_and_distribution() {
    let dir = tempfile::tempdir().unwrap();
    let run = tiny_run(dir.path(), "run");
    let cwd = dir.path().join("work");
    std::fs::create_dir(&cwd).unwrap();
    let zoo_before = entries(&blockpuzzle::zoo::dir());
    let o = bp_in(&cwd, &["eval", "--checkpoint", "BlocksTouch-v0-ddpg", "--episodes", "2"]);
    assert!(o.status.success(), "{}", text(&o));
    let o = bp_in(&cwd, &["eval", "--checkpoint", "BlocksTouch-v0-ddpg-epoch60", "--episodes", "2"]);
    assert!(o.status.success(), "{}", text(&o));
    assert_eq!(
        entries(&cwd),
        vec![
            "eval-BlocksTouch-v0-ddpg-BlocksTouch-v0-normal.json",
            "eval-BlocksTouch-v0-ddpg-epoch60-BlocksTouch-v0-normal.json"
        ],
        "two policies on one task: two files"
    );
    assert_eq!(entries(&blockpuzzle::zoo::dir()), zoo_before, "nothing written into the zoo");
    let o = bp_in(
        &cwd,
        &["eval", "--checkpoint", run.join("policy.json").to_str().unwrap(), "--episodes", "2", "--level", "0"],
    );
    assert!(o.status.success(), "{}", text(&o));
    assert!(run.join("eval-policy-BlocksTouch-v0-level0.json").is_file(), "{:?}", entries(&run));
}

#[test]
fn zoo_commands_fail_loudly_and_never_overwrite_silently() {
    let dir = tempfile::tempdir().unwrap();
    let cwd = dir.path();
    let o = bp_in(cwd, &["zoo", "list", "--zoo", "/missing-zoo"]);
    refused(&o, &["the zoo folder /missing-zoo does not exist"]);
    let o = Command::new(BP)
        .args(["eval", "--checkpoint", "Nope"])
        .env("BLOCKPUZZLE_ZOO", "/missing-zoo")
        .output()
        .unwrap();
    refused(&o, &["the zoo folder /missing-zoo does not exist"]);
    std::fs::create_dir(cwd.join("empty")).unwrap();
    let o = bp_in(cwd, &["zoo", "list", "--zoo", "empty"]);
    assert!(o.status.success() && text(&o).contains("the zoo in empty has no entries"), "{}", text(&o));

    // Export refuses to replace an entry unless --force.
    let export = |force: bool| {
        let mut args = vec!["zoo", "export", "--from", "BlocksTouch-v0-ddpg", "--name", "E", "--description", "d"];
        args.extend(["--trained-with", "t", "--zoo", "z"]);
        if force {
            args.push("--force");
        }
        bp_in(cwd, &args)
    };
    assert!(export(false).status.success());
    refused(&export(false), &["already has an entry", "--force"]);
    assert!(export(true).status.success());
    std::fs::write(cwd.join("zf"), b"").unwrap();
    let o = bp_in(
        cwd,
        &[
            "zoo",
            "export",
            "--from",
            "BlocksTouch-v0-ddpg",
            "--name",
            "E",
            "--description",
            "d",
            "--trained-with",
            "t",
            "--zoo",
            "zf",
        ],
    );
    refused(&o, &["the zoo zf is a file"]);

    // An entry whose task text was edited but whose hash was not is refused on load.
    let json = cwd.join("z/E.json");
    let meta = std::fs::read_to_string(&json).unwrap();
    assert!(meta.contains("max_episode_steps = 50"));
    std::fs::write(&json, meta.replacen("max_episode_steps = 50", "max_episode_steps = 49", 1)).unwrap();
    let o = bp_in(cwd, &["zoo", "check", "--zoo", "z"]);
    refused(&o, &["its text is not the task its hash", "restore"]);
    let o = bp_in(cwd, &["eval", "--checkpoint", "z/E.safetensors", "--episodes", "1"]);
    refused(&o, &["its text is not the task its hash"]);
}

#[test]
fn align_refuses_references_it_cannot_compare_and_names_a_missing_file_once() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("r.json");
    let head = r#"{"env": "FetchPush-v4", "mujoco": "3.11.0", "gymnasium_robotics": "1.4.2", "episodes": "#;
    std::fs::write(&p, format!("{head}[]}}")).unwrap();
    refused(&bp_in(dir.path(), &["align", "--reference", "r.json"]), &["holds no episodes"]);
    let ep = r#"{"kind": "random", "seed": 0, "joints": {"object0:joint": {"qpos": [1.3, 0.7], "qvel": [0, 0, 0, 0, 0, 0]}}, "actions": [], "grip": [[0, 0, 0]], "object": [[0, 0, 0]]}"#;
    std::fs::write(&p, format!("{head}[{ep}]}}")).unwrap();
    refused(
        &bp_in(dir.path(), &["align", "--reference", "r.json"]),
        &["\"object0:joint\" has 2 position", "the scene's has 7 and 6"],
    );
    let o = bp_in(dir.path(), &["align", "--reference", "none.json"]);
    refused(&o, &["cannot read the alignment reference none.json"]);
    assert_eq!(text(&o).matches("No such file").count(), 1, "{}", text(&o));
}

#[test]
fn commands_show_only_the_flags_they_use() {
    let o = bp_in(Path::new("."), &["task", "check", "BlocksTouch-v0", "--filmstrip", "3"]);
    refused(&o, &["unexpected argument '--filmstrip'"]);
    let help = text(&bp_in(Path::new("."), &["task", "check", "--help"]));
    assert!(!help.contains("--fps") && !help.contains("--filmstrip") && help.contains("--width"), "{help}");
    let help = text(&bp_in(Path::new("."), &["render", "--help"]));
    assert!(help.contains("--fps") && help.contains("--filmstrip"), "{help}");
}

#[test]
fn a_weight_out_of_range_is_named_by_its_element() {
    let dir = tempfile::tempdir().unwrap();
    let run = tiny_run(dir.path(), "run");
    let policy = std::fs::read_to_string(run.join("policy.json")).unwrap();
    let mut v: serde_json::Value = serde_json::from_str(&policy).unwrap();
    // 1e39 is beyond f32: the weight reads as inf.
    let w = v.pointer_mut("/policy/net/layers/0/w/0").expect("the actor's first weight");
    *w = serde_json::json!(1e39);
    let bad = dir.path().join("bad.json");
    std::fs::write(&bad, serde_json::to_string(&v).unwrap()).unwrap();
    let o = bp_in(dir.path(), &["eval", "--checkpoint", bad.to_str().unwrap(), "--episodes", "1"]);
    refused(&o, &["holds inf (element 0)"]);
}

/// Runs `script` (sh) in a private mount namespace with a small tmpfs at
/// `$M` (`opts` its mount options), so that full and read-only disks can be
/// made without touching the machine; None where this process may not mount
/// (not root, or no unshare), and the caller then skips.
fn on_small_fs(opts: &str, script: &str) -> Option<Output> {
    let probe =
        Command::new("unshare").args(["-m", "sh", "-c", "mount -t tmpfs -o size=16k tmpfs /mnt"]).output().ok()?;
    if !probe.status.success() {
        eprintln!("skipped: cannot mount a tmpfs here ({})", text(&probe).trim());
        return None;
    }
    let m = tempfile::tempdir().unwrap().keep();
    let full = format!("mount -t tmpfs -o {opts} tmpfs {m} && export M={m} BP={BP} && {script}", m = m.display());
    let out = Command::new("unshare").args(["-m", "sh", "-c", &full]).output().unwrap();
    let _ = std::fs::remove_dir_all(&m);
    Some(out)
}

#[test]
fn a_full_or_read_only_disk_fails_cleanly_naming_the_path() {
    let dir = tempfile::tempdir().unwrap();
    let dump = dir.path().join("d.jsonl");
    let o = bp_in(
        dir.path(),
        &[
            "rollout",
            "--env",
            "BlocksTouch-v0",
            "--policy",
            "random",
            "--episodes",
            "1",
            "--out",
            dump.to_str().unwrap(),
        ],
    );
    assert!(o.status.success(), "{}", text(&o));
    let run = tiny_run(dir.path(), "run");
    let script = format!(
        "$BP render --traj {} --width 200 --height 200 --out $M/frames/; echo rc=$?; \
         $BP rollout --env BlocksTouch-v0 --policy random --episodes 20 --out $M/x.jsonl; echo rc=$?; \
         dd if=/dev/zero of=$M/fill bs=4k 2>/dev/null; \
         $BP train --env BlocksTouch-v0 --epochs 1 --cycles 1 --batches 1 --test-episodes 1 --workers 1 --run-dir $M/run; \
         echo rc=$?; rm $M/fill; echo left: $(ls -A $M)",
        dump.display()
    );
    let Some(o) = on_small_fs("size=200k", &script) else { return };
    let t = text(&o);
    assert_eq!(t.matches("rc=1").count(), 3, "{t}");
    assert!(t.contains("frames") && t.contains("No space left on device"), "{t}");
    assert!(t.contains("cannot write trajectory dump") && t.contains("x.jsonl: No space left on device"), "{t}");
    let last = String::from_utf8_lossy(&o.stdout).lines().last().map(str::to_owned);
    assert_eq!(last.as_deref(), Some("left:"), "the disk is as it was: {t}");

    // A read-only folder: the OS's words, with the path.
    let script = format!("$BP plot --overlay {} --out $M/o.png; echo rc=$?", run.display());
    let Some(o) = on_small_fs("ro", &script) else { return };
    let t = text(&o);
    assert!(t.contains("rc=1") && t.contains("/o.png: Read-only file system"), "{t}");
    assert!(!t.contains("BackendError"), "{t}");
}

#[test]
fn long_commands_show_progress_on_a_terminal() {
    // `script` gives the command a terminal (indicatif draws nothing elsewhere).
    let on_tty = |args: &str| Command::new("script").args(["-qec", &format!("{BP} {args}"), "/dev/null"]).output();
    let Ok(o) = on_tty("task check BlocksTouch-v0 --samples 5") else {
        eprintln!("skipped: no `script` to give the command a terminal");
        return;
    };
    assert!(o.status.success() && text(&o).contains("reset 1/30"), "{}", text(&o));
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("e.json");
    let o = on_tty(&format!("eval --checkpoint BlocksTouch-v0-ddpg --episodes 3 --threads 1 --out {}", out.display()))
        .unwrap();
    assert!(text(&o).contains("episode 1/3") || text(&o).contains("episode 0/3"), "{}", text(&o));
}
