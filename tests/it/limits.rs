//! Hard limits and clean failures: absurd numbers are refused before any work
//! with the flag or field, the range and why; a failed command leaves the file
//! system as it found it; exit codes and messages tell the truth.
#![cfg(feature = "train")]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

const BP: &str = env!("CARGO_BIN_EXE_blockpuzzle");

/// Runs blockpuzzle in `cwd`.
fn bp_in(cwd: &Path, args: &[&str]) -> Output {
    crate::common::blockpuzzle(args).current_dir(cwd).output().expect("run blockpuzzle")
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
    let base = blockpuzzle::env::registry::REGISTRY.iter().find(|r| r.id == "BlocksTouch-v0").unwrap().toml;
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
    refused(&o, &[&format!("checkpoint {} is corrupt", ckpt.display()), "nothing was created", "another run"]);
    // A branch has no --resume to leave out (issue 60: the fix named one).
    assert!(!text(&o).contains("branched") && !text(&o).contains("--resume"), "{}", text(&o));
    assert_eq!(entries(dir.path()), vec!["parent"], "no child, no temporary copy");
}

#[test]
fn eval_writes_beside_runs_or_in_the_current_folder_named_by_policy_and_distribution() {
    let dir = tempfile::tempdir().unwrap();
    let run = tiny_run(dir.path(), "run");
    let cwd = dir.path().join("work");
    std::fs::create_dir(&cwd).unwrap();
    let zoo_before = entries(&blockpuzzle::benchmark::zoo::dir());
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
    assert_eq!(entries(&blockpuzzle::benchmark::zoo::dir()), zoo_before, "nothing written into the zoo");
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
    let o = crate::common::blockpuzzle(&["eval", "--checkpoint", "Nope"])
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
    refused(&o, &["the zoo zf is not a folder"]);

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

/// A dump of one random episode on BlocksTouch-v0, `d.jsonl` in `dir`.
fn random_dump(dir: &Path) -> PathBuf {
    let dump = dir.join("d.jsonl");
    let o = bp_in(
        dir,
        &["rollout", "--env", "BlocksTouch-v0", "--policy", "random", "--episodes", "1", "--out"]
            .into_iter()
            .chain([dump.to_str().unwrap()])
            .collect::<Vec<_>>(),
    );
    assert!(o.status.success(), "{}", text(&o));
    dump
}

/// Runs `script` (sh) in a private mount namespace with a small tmpfs at
/// `$M` (`opts` its mount options), so that full and read-only disks can be
/// made without touching the machine; None where this process may not mount
/// (not root, or no unshare), and the caller then skips.
fn on_small_fs(opts: &str, script: &str) -> Option<Output> {
    let Ok(probe) = Command::new("unshare").args(["-m", "sh", "-c", "mount -t tmpfs -o size=16k tmpfs /mnt"]).output()
    else {
        crate::common::skipped("no `unshare` to make a small file system");
        return None;
    };
    if !probe.status.success() {
        crate::common::skipped(&format!("cannot mount a tmpfs here ({})", text(&probe).trim()));
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
    let dump = random_dump(dir.path());
    let run = tiny_run(dir.path(), "run");
    let script = format!(
        "$BP render --traj {} --width 200 --height 200 --out $M/frames/; echo rc=$?; \
         $BP rollout --env BlocksTouch-v0 --policy random --episodes 20 --out $M/x.jsonl; echo rc=$?; \
         dd if=/dev/zero of=$M/fill bs=4k 2>/dev/null; \
         $BP train --env BlocksTouch-v0 --epochs 1 --cycles 1 --batches 1 --test-episodes 1 --workers 1 --run-dir $M/run; \
         echo rc=$?; \
         $BP zoo export --from BlocksTouch-v0-ddpg --name n --description d --trained-with t --zoo $M/z; echo rc=$?; \
         $BP plot --overlay {} --out $M/p.png; echo rc=$?; \
         rm $M/fill; echo left: $(ls -A $M)",
        dump.display(),
        run.display()
    );
    let Some(o) = on_small_fs("size=200k", &script) else { return };
    let t = text(&o);
    assert_eq!(t.matches("rc=1").count(), 5, "{t}");
    // The plot's full disk in the OS's words, not the drawing backend's debug text (issue 74).
    assert!(t.contains("p.png: No space left on device") && !t.contains("IOError") && !t.contains("Os {"), "{t}");
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
        crate::common::skipped("no `script` to give the command a terminal");
        return;
    };
    assert!(o.status.success() && text(&o).contains("reset 1/30"), "{}", text(&o));
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("e.json");
    let o = on_tty(&format!("eval --checkpoint BlocksTouch-v0-ddpg --episodes 3 --threads 1 --out {}", out.display()))
        .unwrap();
    assert!(text(&o).contains("episode 1/3") || text(&o).contains("episode 0/3"), "{}", text(&o));
    let suite = tiny_suite(dir.path());
    let demos = dir.path().join("d.safetensors");
    let o = on_tty(&format!("demos --suite {} --episodes 3 --threads 1 --out {}", suite.display(), demos.display()))
        .unwrap();
    assert!(text(&o).contains("episode 1/3") || text(&o).contains("episode 0/3"), "{}", text(&o));
}

/// A one-episode-a-split suite file in `dir`.
fn tiny_suite(dir: &Path) -> PathBuf {
    let path = dir.join("tiny-suite.toml");
    let text = "version = 1\nname = \"tiny\"\nsummary = \"one episode a split\"\n\
                [[splits.train]]\ntask = \"BlocksTouch-v0\"\nseed = 0\nepisodes = 1\n\
                [[splits.test]]\ntask = \"BlocksTouch-v0\"\nseed = 100\nepisodes = 1\n";
    std::fs::write(&path, text).unwrap();
    path
}

/// Every command that writes a file, with `T` where its output path goes
/// (`T` has the extension the command needs), run in a folder holding the
/// inputs it reads.
fn writers(inputs: &Path) -> Vec<(&'static str, Vec<String>)> {
    let i = |name: &str| inputs.join(name).display().to_string();
    let words = |s: &str| s.split(' ').map(str::to_owned).collect::<Vec<_>>();
    vec![
        ("json", words("eval --checkpoint BlocksTouch-v0-ddpg --episodes 1 --threads 1 --out T")),
        ("json", [words("eval --baseline scripted --threads 1 --out T --suite"), vec![i("tiny-suite.toml")]].concat()),
        ("md", words("table --episodes 1 --threads 1 --out T")),
        ("jsonl", words("rollout --env BlocksTouch-v0 --policy random --episodes 1 --out T")),
        ("gif", [words("render --width 64 --height 64 --out T --traj"), vec![i("d.jsonl")]].concat()),
        ("png", [words("render --width 64 --height 64 --filmstrip 2 --out T --traj"), vec![i("d.jsonl")]].concat()),
        ("png", words("task check BlocksTouch-v0 --samples 1 --width 64 --height 64 --render T")),
        ("png", [words("plot --out T --overlay"), vec![i("log.csv")]].concat()),
        ("md", [words("results leaderboard --out T"), vec![i("result.json")]].concat()),
        (
            "gif",
            [
                words(
                    "rollout --env BlocksTouch-v0 --policy random --episodes 1 --width 64 --height 64 --render T --out",
                ),
                vec![i("r.jsonl")],
            ]
            .concat(),
        ),
    ]
}

/// The inputs [`writers`] read.
fn writer_inputs(dir: &Path) {
    tiny_suite(dir);
    std::fs::write(dir.join("log.csv"), "epoch,time/env_steps,finals/success\n1,100,0.5\n2,200,0.75\n").unwrap();
    random_dump(dir);
    let suite = dir.join("tiny-suite.toml");
    let result = dir.join("result.json");
    let o = bp_in(
        dir,
        &[
            "eval",
            "--baseline",
            "scripted",
            "--threads",
            "1",
            "--suite",
            suite.to_str().unwrap(),
            "--out",
            result.to_str().unwrap(),
        ],
    );
    assert!(o.status.success(), "{}", text(&o));
}

/// `args` with `T` replaced by `target`.
fn with_target(args: &[String], target: &Path) -> Vec<String> {
    args.iter().map(|a| if a == "T" { target.display().to_string() } else { a.clone() }).collect()
}

fn run_args(cwd: &Path, args: &[String]) -> Output {
    crate::common::blockpuzzle(args).current_dir(cwd).output().expect("run blockpuzzle")
}

#[test]
fn no_writer_replaces_or_leaves_anything_beside_what_is_not_a_regular_file() {
    use std::os::unix::fs::FileTypeExt;
    let inputs = tempfile::tempdir().unwrap();
    writer_inputs(inputs.path());
    let mkfifo = |p: &Path| assert!(Command::new("mkfifo").arg(p).status().unwrap().success());
    // Character devices of our own (null and full, with the extension each command wants) where this
    // process may make them (root).
    let mknod = |dir: &Path, name: &str, minor: &str| {
        let p = dir.join(name);
        let made = Command::new("mknod").args([p.to_str().unwrap(), "c", "1", minor]).output();
        made.is_ok_and(|o| o.status.success()).then_some(p)
    };
    let probe = tempfile::tempdir().unwrap();
    let devices = mknod(probe.path(), "probe", "3").is_some();
    if !devices {
        crate::common::skipped("the character-device targets (this process may not make devices: not root)");
    }
    // One thread per command (each runs its cases in order; the commands are independent).
    std::thread::scope(|scope| {
        for (k, (ext, args)) in writers(inputs.path()).into_iter().enumerate() {
            let (mknod, mkfifo) = (&mknod, &mkfifo);
            scope.spawn(move || {
                let what = args[..2].join(" ");
                let dir = tempfile::tempdir().unwrap();
                let dev = tempfile::tempdir().unwrap();
                // A FIFO nobody reads: refused at once (a write would wait forever), still a FIFO.
                let fifo = dir.path().join(format!("fifo.{ext}"));
                mkfifo(&fifo);
                let o = run_args(dir.path(), &with_target(&args, &fifo));
                refused(&o, &[fifo.to_str().unwrap(), "FIFO that no process reads"]);
                assert!(std::fs::symlink_metadata(&fifo).unwrap().file_type().is_fifo(), "{what}: the FIFO stays");
                // A folder, and a read-only file: refused, both as they were.
                let folder = dir.path().join(format!("folder.{ext}"));
                std::fs::create_dir(&folder).unwrap();
                let o = run_args(dir.path(), &with_target(&args, &folder));
                refused(&o, &[folder.to_str().unwrap(), "is a folder"]);
                assert!(folder.is_dir() && entries(&folder).is_empty(), "{what}");
                let locked = dir.path().join(format!("locked.{ext}"));
                std::fs::write(&locked, "mine").unwrap();
                let mut perms = std::fs::metadata(&locked).unwrap().permissions();
                perms.set_readonly(true);
                std::fs::set_permissions(&locked, perms).unwrap();
                let o = run_args(dir.path(), &with_target(&args, &locked));
                refused(&o, &[locked.to_str().unwrap(), "read-only"]);
                assert_eq!(std::fs::read_to_string(&locked).unwrap(), "mine", "{what}");
                assert_eq!(
                    entries(dir.path()),
                    [format!("fifo.{ext}"), format!("folder.{ext}"), format!("locked.{ext}")],
                    "{what}: nothing left beside the targets"
                );
                if devices {
                    // A full device: the OS's words with the path, and the device stays.
                    let full = mknod(dev.path(), &format!("full.{ext}"), "7").unwrap();
                    let o = run_args(dir.path(), &with_target(&args, &full));
                    refused(&o, &[full.to_str().unwrap(), "No space left on device"]);
                    assert!(std::fs::symlink_metadata(&full).unwrap().file_type().is_char_device(), "{what}");
                    // A device is written in place: it stays one, and nothing appears beside it (no companion file).
                    let null = mknod(dev.path(), &format!("null.{ext}"), "3").unwrap();
                    let o = run_args(dir.path(), &with_target(&args, &null));
                    assert!(o.status.success(), "{what}: {}", text(&o));
                    assert!(std::fs::symlink_metadata(&null).unwrap().file_type().is_char_device(), "{what}: a device");
                    assert_eq!(entries(dev.path()), [format!("full.{ext}"), format!("null.{ext}")], "{what}");
                    std::fs::remove_file(full).unwrap();
                    std::fs::remove_file(null).unwrap();
                }
                // A FIFO a process reads gets the whole output: one writer of each kind (the JSON writer, the
                // streamed dump, a file an encoder writes by path), to keep the test short.
                if ![0, 3, 4].contains(&k) {
                    return;
                }
                let read = dir.path().join(format!("read.{ext}"));
                mkfifo(&read);
                let captured = dev.path().join("captured");
                let sink = std::fs::File::create(&captured).unwrap();
                let mut reader = Command::new("cat").arg(&read).stdout(sink).spawn().unwrap();
                std::thread::sleep(std::time::Duration::from_millis(200));
                let o = run_args(dir.path(), &with_target(&args, &read));
                if !o.status.success() {
                    // Nothing opened the FIFO: open it once so that the reader ends.
                    drop(std::fs::OpenOptions::new().write(true).open(&read));
                }
                reader.wait().unwrap();
                assert!(o.status.success(), "{what}: {}", text(&o));
                assert!(std::fs::metadata(&captured).unwrap().len() > 0, "{what}: the reader got the output");
                assert!(std::fs::symlink_metadata(&read).unwrap().file_type().is_fifo(), "{what}: the FIFO stays");
            });
        }
    });
}

#[test]
fn options_a_run_would_ignore_are_refused_from_flags_recipes_and_bench() {
    let dir = tempfile::tempdir().unwrap();
    let run = dir.path().join("run");
    let cases: &[(&[&str], &[&str])] = &[
        (&["--algo", "sac", "--noise-eps", "0.1"], &["--noise-eps is only used with --algo ddpg", "SAC"]),
        (&["--target-noise", "0.3"], &["--target-noise is only used with --algo ddpg --td3"]),
        (&["--algo", "pggd", "--beta0", "0.5"], &["--beta0 is only used with --expert"]),
        (&["--set-pooling", "attention"], &["--set-pooling is only used with --net set"]),
        (&["--hindsight-strategy", "pairs"], &["--hindsight-strategy is only used with --hindsight-colours"]),
        (&["--pg-lr", "0.01"], &["--pg-lr is only used with --algo pggd"]),
        (&["--algo", "pggd", "--lr-critic", "0.01"], &["--lr-critic is only used with --algo ddpg or --algo sac"]),
    ];
    for (extra, wanted) in cases {
        let o = bp_in(dir.path(), &tiny_args(&run, "1", extra));
        refused(&o, wanted);
        assert!(!run.exists(), "{extra:?}: nothing created");
    }
    // The same rule for a recipe, and several settings named at once.
    let recipe = dir.path().join("r.toml");
    std::fs::write(&recipe, "env = \"BlocksTouch-v0\"\nalgo = \"sac\"\nrandom-eps = 0.5\npolicy-delay = 3\n").unwrap();
    let o = bp_in(dir.path(), &["train", "--config", recipe.to_str().unwrap(), "--run-dir", run.to_str().unwrap()]);
    refused(&o, &["would ignore", "--random-eps", "--policy-delay"]);
    // A recipe's value of the wrong kind names the key and the file.
    std::fs::write(&recipe, "env = \"BlocksTouch-v0\"\ntd3 = \"yes\"\n").unwrap();
    let o = bp_in(dir.path(), &["train", "--config", recipe.to_str().unwrap()]);
    refused(&o, &["r.toml", "`td3` is a switch", "td3 = true or false"]);
    std::fs::write(&recipe, "env = \"BlocksTouch-v0\"\nepochs = true\n").unwrap();
    let o = bp_in(dir.path(), &["train", "--config", recipe.to_str().unwrap()]);
    refused(&o, &["r.toml", "`epochs` takes a value"]);
    // bench --train (and its older name, --ddpg) goes by the same table.
    let o = bp_in(dir.path(), &["bench", "--train", "--set-pooling", "attention", "--steps", "10", "--updates", "1"]);
    refused(&o, &["--set-pooling is only used with --net set"]);
    let o = bp_in(dir.path(), &["bench", "--ddpg", "--algo", "pggd", "--precision", "bf16", "--steps", "10"]);
    refused(&o, &["--precision is only used with --algo ddpg or --algo sac"]);
}

#[test]
fn cameras_that_show_nothing_are_refused_before_any_work() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("x.gif");
    let dump = dir.path().join("d.jsonl");
    for (flag, value, wanted) in [
        ("--distance", "NaN", "--distance NaN"),
        ("--distance", "0", "--distance 0"),
        ("--distance", "-1", "--distance -1"),
        ("--distance", "inf", "--distance inf"),
        ("--elevation", "100", "--elevation 100"),
        ("--azimuth", "NaN", "--azimuth NaN"),
    ] {
        let render = ["render", "--policy", "BlocksTouch-v0-ddpg", "--out", out.to_str().unwrap(), flag, value];
        refused(&bp_in(dir.path(), &render), &[wanted]);
        let rollout = [
            "rollout",
            "--env",
            "BlocksTouch-v0",
            "--policy",
            "random",
            "--episodes",
            "1",
            "--out",
            dump.to_str().unwrap(),
            "--render",
            out.to_str().unwrap(),
            flag,
            value,
        ];
        refused(&bp_in(dir.path(), &rollout), &[wanted]);
        let check = ["task", "check", "BlocksTouch-v0", "--samples", "1", "--render", "x.png", flag, value];
        refused(&bp_in(dir.path(), &check), &[wanted]);
        assert!(entries(dir.path()).is_empty(), "{flag} {value}: nothing written, no episode played");
    }
}

#[test]
fn an_edited_trajectory_dump_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let dump = random_dump(dir.path());
    let line = std::fs::read_to_string(&dump).unwrap();
    let render = |d: &Path| {
        bp_in(
            dir.path(),
            &["render", "--traj", d.to_str().unwrap(), "--out", "x.gif", "--width", "64", "--height", "64"],
        )
    };
    let edit = |f: &dyn Fn(&mut serde_json::Value)| {
        let mut v: serde_json::Value = serde_json::from_str(line.trim()).unwrap();
        f(&mut v);
        let d = dir.path().join("edited.jsonl");
        std::fs::write(&d, serde_json::to_string(&v).unwrap()).unwrap();
        d
    };
    // The task's text edited, its hash left as it was.
    let d = edit(&|v| {
        let toml = v["task"]["toml"].as_str().unwrap().replace("max_episode_steps = 50", "max_episode_steps = 40");
        v["task"]["toml"] = toml.into();
    });
    refused(&render(&d), &["its text is not the task its hash"]);
    // The rule objects edited.
    let d = edit(&|v| v["objects"][2]["name"] = "purple".into());
    refused(&render(&d), &["not its task's rule objects", "edited"]);
    // A position edited to one no scene has.
    let d = edit(&|v| v["initial"]["qpos"][0] = 1e300.into());
    refused(&render(&d), &["joint position 0 as 1e300", "edited or damaged"]);
    assert!(!dir.path().join("x.gif").exists(), "nothing rendered");
}

#[test]
fn odd_logs_suites_and_entries_are_named_not_used() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // A progress log that is a folder, has only its header, or holds a success that is not a rate.
    let run = tiny_run(d, "run");
    let progress = run.join("progress.csv");
    let good = std::fs::read_to_string(&progress).unwrap();
    let header = good.lines().next().unwrap().to_owned();
    std::fs::write(&progress, format!("{header}\n")).unwrap();
    refused(&bp_in(d, &["report", run.to_str().unwrap()]), &["progress.csv has no rows"]);
    let nan = good.lines().enumerate().map(|(i, l)| {
        if i == 1 {
            let cols: Vec<&str> = header.split(',').collect();
            let k = cols.iter().position(|c| *c == "finals/success").unwrap();
            l.split(',').enumerate().map(|(j, v)| if j == k { "NaN" } else { v }).collect::<Vec<_>>().join(",")
        } else {
            l.to_owned()
        }
    });
    std::fs::write(&progress, nan.collect::<Vec<_>>().join("\n")).unwrap();
    refused(&bp_in(d, &["report", run.to_str().unwrap()]), &["finals/success is NaN, not a rate"]);
    std::fs::remove_file(&progress).unwrap();
    std::fs::create_dir(&progress).unwrap();
    refused(&bp_in(d, &["plot", "--run-dir", run.to_str().unwrap()]), &["progress.csv", "is a folder"]);
    // plot --overlay given a JSON file, or an output that is not a PNG.
    let json = d.join("r.json");
    std::fs::write(&json, "{\"a\": 1}\n").unwrap();
    refused(&bp_in(d, &["plot", "--overlay", json.to_str().unwrap(), "--out", "o.png"]), &["r.json has no rows"]);
    refused(&bp_in(d, &["plot", "--overlay", json.to_str().unwrap(), "--out", "o.jpg"]), &["o.jpg: plots are PNG"]);
    // Suites: a name that cannot be a file name, and rows that play the same episodes twice.
    let suite = tiny_suite(d);
    let text_of = std::fs::read_to_string(&suite).unwrap();
    std::fs::write(&suite, text_of.replace("name = \"tiny\"", "name = \"a/b\"")).unwrap();
    let eval = ["eval", "--baseline", "scripted", "--suite", suite.to_str().unwrap()];
    refused(&bp_in(d, &eval), &["name \"a/b\"", "goes into file names"]);
    let twice = format!("{text_of}[[splits.test]]\ntask = \"BlocksTouch-v0\"\nseed = 100\nepisodes = 1\n");
    std::fs::write(&suite, twice).unwrap();
    refused(&bp_in(d, &eval), &["splits.test[0] and splits.test[1] play the same episodes"]);
    std::fs::write(&suite, &text_of).unwrap();
    let onto_md = [&eval[..], &["--out", "r.md"]].concat();
    refused(&bp_in(d, &onto_md), &["--out r.md", "give NAME.json"]);
    assert!(!d.join("r.md").exists());
    // A task file's fixed-length list with an element too many.
    let task = d.join("t.toml");
    let builtin = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/tasks/BlocksAvoid-v0.toml")).unwrap();
    std::fs::write(&task, builtin.replace("count = [1, 3]", "count = [1, 3, 9]")).unwrap();
    refused(&bp_in(d, &["task", "check", task.to_str().unwrap()]), &["t.toml", "expected a list of exactly 2"]);
    // A zoo entry whose set layout holds a field no network has.
    let zoo = d.join("zoo");
    std::fs::create_dir(&zoo).unwrap();
    let src = concat!(env!("CARGO_MANIFEST_DIR"), "/zoo/BlocksChoose-v0-ddpg-set");
    std::fs::copy(format!("{src}.safetensors"), zoo.join("s.safetensors")).unwrap();
    let meta = std::fs::read_to_string(format!("{src}.json")).unwrap();
    let mut v: serde_json::Value = serde_json::from_str(&meta).unwrap();
    v["actor"]["set"]["pooling"] = "max".into();
    std::fs::write(zoo.join("s.json"), serde_json::to_string(&v).unwrap()).unwrap();
    refused(&bp_in(d, &["zoo", "check", "--zoo", zoo.to_str().unwrap()]), &["s.json", "unknown field `pooling`"]);
    // A layout edit is reported against the metadata's field (before the seal, which catches the rest).
    v["actor"]["set"].as_object_mut().unwrap().remove("pooling");
    v["actor"]["layers"][1][0] = 255.into();
    std::fs::write(zoo.join("s.json"), serde_json::to_string(&v).unwrap()).unwrap();
    refused(&bp_in(d, &["zoo", "check", "--zoo", zoo.to_str().unwrap()]), &["s.json", "actor.layers[1]", "[255, 256]"]);
    v["actor"]["layers"][1][0] = 256.into();
    v["norm_clip"] = (-1.0).into();
    std::fs::write(zoo.join("s.json"), serde_json::to_string(&v).unwrap()).unwrap();
    refused(&bp_in(d, &["zoo", "check", "--zoo", zoo.to_str().unwrap()]), &["s.json", "norm_clip: -1"]);
}

#[test]
fn huge_or_binary_inputs_are_refused_by_size_and_kind_with_short_messages() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // Sparse files: large to the reader, no disk used.
    let big = d.join("big.toml");
    std::fs::File::create(&big).unwrap().set_len(1 << 30).unwrap();
    for args in [
        vec!["eval", "--baseline", "scripted", "--suite", big.to_str().unwrap()],
        vec!["task", "check", big.to_str().unwrap()],
        vec!["train", "--config", big.to_str().unwrap()],
        vec!["results", "compare", big.to_str().unwrap(), big.to_str().unwrap()],
    ] {
        let o = bp_in(d, &args);
        refused(&o, &["big.toml", "1.0 GiB"]);
        assert!(text(&o).len() < 2_000, "{args:?}: a short message: {}", text(&o).len());
    }
    // NUL bytes within the bound: not text.
    let nul = d.join("nul.toml");
    std::fs::write(&nul, vec![0u8; 1000]).unwrap();
    refused(&bp_in(d, &["task", "check", nul.to_str().unwrap()]), &["not a text file (a NUL byte at offset 0)"]);
    // One long line within the bound: the parser's excerpt is cut short.
    let long = d.join("long.toml");
    std::fs::write(&long, "a".repeat(3_000_000)).unwrap();
    let o = bp_in(d, &["eval", "--baseline", "scripted", "--suite", long.to_str().unwrap()]);
    refused(&o, &["more characters)"]);
    assert!(text(&o).len() < 5_000, "{}", text(&o).len());
}

#[test]
fn messages_name_the_setting_and_exports_leave_nothing_half_made() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // A resume that changes --counts names --counts (not its entries).
    let run = d.join("run");
    let touch = |extra: &[&str]| {
        let mut a = vec![
            "train",
            "--env",
            "BlocksChooseN-v0",
            "--cycles",
            "1",
            "--batches",
            "1",
            "--test-episodes",
            "1",
            "--hidden",
            "8",
            "--workers",
            "1",
            "--run-dir",
            run.to_str().unwrap(),
        ];
        a.extend_from_slice(extra);
        bp_in(d, &a)
    };
    let o = touch(&["--epochs", "1", "--counts", "grey=0-2"]);
    assert!(o.status.success(), "{}", text(&o));
    let o = touch(&["--epochs", "2", "--counts", "grey=1-2", "--resume"]);
    refused(&o, &["--counts"]);
    assert!(!text(&o).contains("--grey"), "{}", text(&o));
    // An entry name that cannot be one is worded as such, not as a broken entry.
    let export = ["zoo", "export", "--from", "BlocksTouch-v0-ddpg", "--description", "d", "--trained-with", "t"];
    let o = bp_in(d, &[&export[..], &["--name", "a/b", "--zoo", "z"]].concat());
    refused(&o, &["--name \"a/b\"", "letters, digits"]);
    assert!(!text(&o).contains("not usable"), "{}", text(&o));
    assert!(!d.join("z").exists(), "no zoo folder made");
}

/// Issue 60: an input given as a pipe or device that gives nothing (a FIFO without a writer, /dev/null)
/// is refused as such, not read as an empty text ("missing field `version`").
#[test]
fn empty_pipes_and_devices_are_refused_as_inputs() {
    let dir = tempfile::tempdir().unwrap();
    let fifo = dir.path().join("task.toml");
    assert!(Command::new("mkfifo").arg(&fifo).status().unwrap().success());
    for (args, wanted) in [
        (vec!["task", "check", fifo.to_str().unwrap()], "is a pipe (FIFO) that gave no data"),
        (vec!["eval", "--suite", "/dev/null", "--baseline", "scripted"], "is a device that gave no data"),
        (vec!["task", "generate", "/dev/null", "--out", dir.path().join("o").to_str().unwrap()], "gave no data"),
        // --demos reads through the one bounded reader (issue 74: it read the whole file first, and
        // blocked forever on a FIFO).
        (
            vec![
                "train",
                "--env",
                "BlocksTouch-v0",
                "--net",
                "entity",
                "--demos",
                fifo.to_str().unwrap(),
                "--run-dir",
                "o",
            ],
            "is a pipe (FIFO) that gave no data",
        ),
    ] {
        let o = bp_in(dir.path(), &args);
        refused(&o, &[wanted, "start its writer first"]);
        assert!(!text(&o).contains("missing field"), "{args:?}: {}", text(&o));
    }
    assert!(!dir.path().join("o").exists());
}

/// Issue 60's misworded errors: each names the problem and the fix.
#[test]
fn misworded_errors_of_round_5_name_the_problem_and_the_fix() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("file");
    std::fs::write(&file, "x").unwrap();
    // --run-dir onto a file (was "File exists").
    let o = bp_in(dir.path(), &tiny_args(&file, "1", &[]));
    refused(&o, &["--run-dir", "is a file, not a folder", "new folder"]);
    // DAgger or BC with --expert (was told to "train with --net mlp").
    let run = dir.path().join("run");
    let o = bp_in(dir.path(), &tiny_args(&run, "1", &["--algo", "dagger", "--net", "entity", "--expert", "x"]));
    refused(&o, &["DAgger imitates the built-in solver", "drop --expert"]);
    assert!(!text(&o).contains("--net mlp"), "{}", text(&o));
    // report FILE (was "config.json/config.json").
    let o = bp_in(dir.path(), &["report", file.to_str().unwrap()]);
    refused(&o, &["is a file; give its run directory"]);
    assert!(!text(&o).contains("file/config.json"), "{}", text(&o));
    // BLOCKPUZZLE_ZOO set to a file (was "does not exist").
    let o = Command::new(crate::common::CLI).args(["zoo", "list"]).env("BLOCKPUZZLE_ZOO", &file).output().unwrap();
    refused(&o, &["is not a folder", "$BLOCKPUZZLE_ZOO"]);
    // The largest seed: the range is printed first to last (was "…615..0").
    let args = ["task", "generate", "push", "--seed", "18446744073709551615", "--count", "1", "--out", "gen"];
    let o = bp_in(dir.path(), &args);
    let t = text(&o);
    assert!(!t.contains("..0"), "{t}");
    assert!(t.contains("seed 18446744073709551615"), "{t}");
}

/// Issue 74's misworded classes: a folder, a pipe or an empty file given where a name, a run or a
/// policy is wanted is named as what it is (not as an unknown zoo entry or id, nor in the OS's bare
/// words), and a setting the user may not have given is not presented as a flag they passed.
#[test]
fn misworded_errors_of_round_6_name_what_was_given() {
    let dir = tempfile::tempdir().unwrap();
    let (folder, fifo, empty) = (dir.path().join("d"), dir.path().join("f"), dir.path().join("empty.json"));
    std::fs::create_dir(&folder).unwrap();
    assert!(Command::new("mkfifo").arg(&fifo).status().unwrap().success());
    std::fs::write(&empty, "").unwrap();
    let cases: &[(&[&str], &[&str])] = &[
        // A FIFO or folder here was called a zoo entry the zoo lacks, and the whole zoo listed.
        (&["zoo", "check", "f"], &["\"f\" is a pipe (FIFO) here, not the name of a zoo entry", "`zoo list`"]),
        (&["zoo", "upgrade", "d"], &["\"d\" is a folder here", "`zoo upgrade` takes the names"]),
        (&["zoo", "describe", "d", "--description", "x"], &["\"d\" is a folder here"]),
        // A folder as a task was "unknown environment id".
        (&["task", "check", "d"], &["it is a folder; give the task file itself"]),
        (&["train", "--env", "d", "--run-dir", "r"], &["it is a folder; give the task file itself"]),
        // A folder without a policy was "No such file or directory" about a file never named.
        (
            &["eval", "--env", "BlocksTouch-v0", "--checkpoint", "d"],
            &["d is a folder with neither", "not a run directory"],
        ),
        (&["plot", "--run-dir", "d", "--out", "p.png"], &["d holds no run", "`blockpuzzle train --run-dir`"]),
        (&["report", "nowhere"], &["there is no run directory nowhere"]),
        // An empty policy file was "EOF while parsing".
        (&["eval", "--env", "BlocksTouch-v0", "--checkpoint", "empty.json"], &["empty.json is empty", "policy.json"]),
        // --net was never given: the default is named as the default.
        (&["train", "--env", "BlocksTouch-v0", "--demos", "d", "--run-dir", "r"], &["mlp (--net's default)"]),
    ];
    for (args, wanted) in cases {
        let o = bp_in(dir.path(), args);
        refused(&o, wanted);
        let t = text(&o);
        for bare in ["os error", "EOF while parsing", "unknown environment id", "BlocksTouch-v0-ddpg-epoch60"] {
            assert!(!t.contains(bare), "{args:?}: {t}");
        }
    }
    // A name the zoo lacks lists a dozen entries at most, then a count.
    let o = bp_in(dir.path(), &["zoo", "check", "no-such-entry"]);
    refused(&o, &["no policy file or zoo entry named \"no-such-entry\""]);
    let t = text(&o);
    let listed = t.split("has: ").nth(1).and_then(|l| l.split("; pass").next()).map_or(0, |l| l.split(", ").count());
    assert!(listed <= 13 && (listed < 13 || t.contains("more (`zoo list`)")), "{t}");
    assert_eq!(entries(dir.path()), ["d", "empty.json", "f"], "nothing was written");
}
