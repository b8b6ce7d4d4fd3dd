//! The `blockpuzzle` binary end to end, bad input included.
#![cfg(feature = "train")]

use std::path::Path;
use std::process::Output;

fn bp(args: &[&str]) -> Output {
    crate::common::blockpuzzle(args).output().expect("run blockpuzzle")
}

fn text(o: &Output) -> String {
    format!("{}{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr))
}

#[test]
fn envs_lists_one_line_per_id() {
    let o = bp(&["envs"]);
    assert!(o.status.success());
    let out = String::from_utf8_lossy(&o.stdout).to_string();
    assert_eq!(out.lines().count(), blockpuzzle::env::registry::ids().len(), "{out}");
    for id in blockpuzzle::env::registry::ids() {
        assert!(out.contains(id), "{id} missing from {out}");
    }
}

/// Three scripted BlocksTouch-v0 episodes at level 0 from seed 5.
/// A reader that goes away (`blockpuzzle info | head -0`) ends the command quietly: killed by
/// SIGPIPE as `cat` would be, or done before it noticed; never a panic in `println!`. `info` runs in
/// the training half (it loads libtorch first, so the pipe is closed before it writes).
#[test]
fn a_closed_pipe_ends_the_command_line_quietly() {
    use std::os::unix::process::ExitStatusExt;
    for args in [["info"], ["envs"]] {
        let mut child = super::common::blockpuzzle(&args)
            .stdout(std::process::Stdio::piped())
            .stderr(std::process::Stdio::piped())
            .spawn()
            .unwrap();
        drop(child.stdout.take());
        let out = child.wait_with_output().unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!err.contains("panicked") && !err.contains("Broken pipe"), "{args:?}: {err}");
        assert!(out.status.success() || out.status.signal() == Some(libc::SIGPIPE), "{args:?}: {:?} {err}", out.status);
    }
}

fn scripted_rollout(out: &Path) -> Output {
    let out = out.to_str().unwrap();
    let args = "rollout --env BlocksTouch-v0 --policy scripted --episodes 3 --seed 5 --level 0 --out";
    bp(&args.split(' ').chain([out]).collect::<Vec<_>>())
}

#[test]
fn rollout_writes_a_replayable_dump() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("touch.jsonl");
    let o = scripted_rollout(&out);
    assert!(o.status.success(), "{}", text(&o));
    assert!(text(&o).contains("success 1.000"), "{}", text(&o));
    let eps = blockpuzzle::episode::rollout::read_dump(&out).unwrap();
    assert_eq!(eps.len(), 3);
    let ep = &eps[1];
    assert_eq!((ep.env_id.as_str(), ep.seed, ep.level), ("BlocksTouch-v0", 6, 0));
    assert_eq!(ep.objects.len(), 4);
    assert!(ep.success && ep.steps.last().unwrap().terminated);
    assert_eq!(ep.steps[0].state.qpos.len(), 29);
    // the dump replays: qpos of a step reproduces its block positions
    let mut env = blockpuzzle::make("BlocksTouch-v0").unwrap();
    env.reset(Some(0)).unwrap();
    let step = &ep.steps[2];
    env.data_mut().qpos_mut().copy_from_slice(&step.state.qpos);
    env.data_mut().forward().unwrap();
    let blocks = env.block_positions();
    for (b, rec) in blocks.iter().zip(&step.state.blocks) {
        assert_eq!(b, &rec.pos);
    }
    // the same command writes the same file
    let out2 = dir.path().join("again.jsonl");
    let o = scripted_rollout(&out2);
    assert!(o.status.success());
    assert_eq!(std::fs::read(&out).unwrap(), std::fs::read(&out2).unwrap());
}

#[test]
fn rollout_and_eval_count_why_episodes_did_not_succeed() {
    use blockpuzzle::episode::outcome::Outcomes;
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("random.jsonl");
    let args = "rollout --env BlocksChoose-v0 --policy random --episodes 4 --seed 3 --out";
    let o = bp(&args.split(' ').chain([out.to_str().unwrap()]).collect::<Vec<_>>());
    assert!(o.status.success(), "{}", text(&o));
    let eps = blockpuzzle::episode::rollout::read_dump(&out).unwrap();
    let tally: Outcomes = eps.iter().collect();
    assert_eq!(tally.total(), 4);
    assert_eq!(tally.success, eps.iter().filter(|e| e.success).count());
    assert!(text(&o).contains(&format!("not successful: {};", tally.summary())), "{}", text(&o));

    // eval: the JSON's outcome counts add up to the episodes, successes included.
    let json = dir.path().join("eval.json");
    let args = ["eval", "--checkpoint", "BlocksTouch-v0-ddpg", "--env", "BlocksChoose-v0", "--episodes", "6"];
    let o = bp(&args.into_iter().chain(["--out", json.to_str().unwrap()]).collect::<Vec<_>>());
    assert!(o.status.success(), "{}", text(&o));
    let v: serde_json::Value = serde_json::from_slice(&std::fs::read(&json).unwrap()).unwrap();
    let counts: Outcomes = serde_json::from_value(v["outcomes"].clone()).unwrap();
    assert_eq!(counts.total(), 6, "{v}");
    assert_eq!(counts.success as u64, v["successes"].as_u64().unwrap(), "{v}");
    assert!(text(&o).contains(&counts.summary()), "{}", text(&o));
}

#[test]
fn unknown_env_is_a_clear_error() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("x.jsonl");
    let o = bp(&["rollout", "--env", "Nope-v1", "--out", out.to_str().unwrap()]);
    assert!(!o.status.success());
    let t = text(&o);
    assert!(t.contains("unknown environment id") && t.contains("BlocksTouch-v0"), "{t}");
    assert!(!t.contains("panicked"), "{t}");
    assert!(!out.exists());
}

#[test]
fn level_beyond_max_is_a_clear_error() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("x.jsonl");
    let o = bp(&["rollout", "--env", "BlocksTouch-v0", "--level", "9", "--out", out.to_str().unwrap()]);
    assert!(!o.status.success());
    assert!(text(&o).contains("beyond the maximum level 5"), "{}", text(&o));
    assert!(!out.exists());
    let o = bp(&["rollout", "--env", "BlocksTouch-v0", "--challenge", "--out", out.to_str().unwrap()]);
    assert!(!o.status.success() && text(&o).contains("no challenge mode"), "{}", text(&o));
}

#[test]
fn unwritable_out_leaves_nothing_behind() {
    let o = bp(&["rollout", "--env", "GripperTouch-v0", "--episodes", "1", "--out", "/nonexistent-dir/x.jsonl"]);
    assert!(!o.status.success());
    assert!(text(&o).contains("cannot write trajectory dump /nonexistent-dir/x.jsonl"), "{}", text(&o));
    let dir = tempfile::tempdir().unwrap();
    let o = bp(&["rollout", "--env", "GripperTouch-v0", "--episodes", "1", "--out", dir.path().to_str().unwrap()]);
    assert!(!o.status.success(), "{}", text(&o));
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0, "no temporary file left");
}

/// `rollout --env BlocksTouch-v0 --out DIR/x.jsonl` with `BLOCKPUZZLE_MODELS_DIR=DIR`.
fn rollout_with_models_dir(dir: &Path) -> Output {
    crate::common::blockpuzzle(&["rollout", "--env", "BlocksTouch-v0", "--out"])
        .arg(dir.join("x.jsonl"))
        .env("BLOCKPUZZLE_MODELS_DIR", dir)
        .output()
        .expect("run blockpuzzle")
}

#[test]
fn missing_assets_name_the_setup_command() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::copy(Path::new(env!("CARGO_MANIFEST_DIR")).join("models/scene.xml"), dir.path().join("scene.xml"))
        .unwrap();
    let o = rollout_with_models_dir(dir.path());
    assert!(!o.status.success());
    let t = text(&o);
    assert!(t.contains("make setup") && t.contains("gymnasium_robotics"), "{t}");
    assert!(!t.contains("panicked"), "{t}");
}

#[test]
fn corrupt_scene_xml_reports_mujocos_message() {
    let dir = tempfile::tempdir().unwrap();
    let models = Path::new(env!("CARGO_MANIFEST_DIR")).join("models");
    std::os::unix::fs::symlink(models.join("gymnasium_robotics"), dir.path().join("gymnasium_robotics")).unwrap();
    let template = std::fs::read_to_string(models.join("scene.xml")).unwrap();
    std::fs::write(
        dir.path().join("scene.xml"),
        template.replace("</worldbody>", "<body><geom type=\"box\" size=\"x\"/></body></worldbody>"),
    )
    .unwrap();
    let o = rollout_with_models_dir(dir.path());
    assert!(!o.status.success());
    let t = text(&o);
    assert!(t.contains("MuJoCo could not load") && t.contains("blockpuzzle_generated.xml"), "{t}");
    assert!(!dir.path().join("x.jsonl").exists());
}

#[test]
fn bench_prints_json() {
    let o = bp(&["bench", "--env", "GripperTouch-v0", "--steps", "200", "--json"]);
    assert!(o.status.success(), "{}", text(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert!(v["env_steps_per_s"].as_f64().unwrap() > 0.0);
    assert!(v["mj_steps_per_s"].as_f64().unwrap() > v["env_steps_per_s"].as_f64().unwrap());
}

#[test]
fn ddpg_bench_collects_whole_episodes_and_times_updates() {
    let o = bp(&[
        "bench",
        "--ddpg",
        "--env",
        "GripperTouch-v0",
        "--workers",
        "2",
        "--steps",
        "120",
        "--updates",
        "5",
        "--batch-size",
        "32",
        "--json",
    ]);
    assert!(o.status.success(), "{}", text(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["workers"], 2);
    assert_eq!(v["updates"], 5);
    // Whole episodes: at least the requested steps, and the warm-up's too in the buffer.
    let steps = v["steps"].as_u64().unwrap();
    assert!(steps >= 120, "{v}");
    assert!(v["buffer_transitions"].as_u64().unwrap() >= steps + 200, "{v}");
    assert!(v["updates_per_s"].as_f64().unwrap() > 0.0);
    let f = v["forward_fraction"].as_f64().unwrap();
    assert!(f > 0.0 && f < 1.0, "{v}");
}

#[test]
fn ddpg_bench_times_set_network_options_and_refuses_them_without_a_set_network() {
    // `--set-norm` (the pooled features layer-normalised) and `--flat-critic` (MLP critics).
    for (flag, named) in
        [("--set-norm", "set network, layer-normalised"), ("--flat-critic", "set network, flat critics")]
    {
        let args = |net: &'static str| {
            ["bench", "--ddpg", "--env", "BlocksTouch-v0", "--net", net, flag, "--steps", "60", "--updates", "2"]
                .into_iter()
                .chain(["--batch-size", "16", "--json"])
                .collect::<Vec<_>>()
        };
        let o = bp(&args("set"));
        assert!(o.status.success(), "{}", text(&o));
        let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        assert_eq!(v["net"].as_str().unwrap(), named, "{v}");
        let o = bp(&args("mlp"));
        assert!(!o.status.success());
        assert!(text(&o).contains(flag) && text(&o).contains("--net set"), "{}", text(&o));
    }
}

#[test]
fn training_bench_options_need_train() {
    let o = bp(&["bench", "--updates", "5"]);
    assert!(!o.status.success());
    assert!(text(&o).contains("--train"), "{}", text(&o));
    // `--ddpg` is the flag's older name.
    let o = bp(&["bench", "--ddpg", "--updates", "5", "--steps", "1", "--algo", "ppo"]);
    assert!(text(&o).contains("invalid value 'ppo' for '--algo"), "{}", text(&o));
}

#[test]
fn bench_without_steps_or_threads_is_refused() {
    for args in [["--steps", "0"], ["--threads", "0"]] {
        let o = bp(&["bench", args[0], args[1]]);
        assert!(!o.status.success(), "{}", text(&o));
        let range = if args[0] == "--steps" { "1 to 10,000,000" } else { "1 to 256" };
        assert!(text(&o).contains(&format!("'0' for '{} <", args[0])) && text(&o).contains(range), "{}", text(&o));
    }
}

#[test]
fn table_runs_end_to_end_and_reports_missing_rows() {
    let dir = tempfile::tempdir().unwrap();
    let (expert, pggd) = (dir.path().join("expert"), dir.path().join("pggd"));
    let small = ["--epochs", "1", "--cycles", "1", "--batches", "2", "--test-episodes", "1", "--hidden", "16"];
    let mut args = vec!["train", "--env", "BlocksTouch-v0", "--run-dir", expert.to_str().unwrap()];
    args.extend(small);
    let o = bp(&args);
    assert!(o.status.success(), "{}", text(&o));
    let mut args = vec!["train", "--algo", "pggd", "--env", "BlocksChoose-v0", "--expert", expert.to_str().unwrap()];
    args.extend(["--run-dir", pggd.to_str().unwrap()]);
    args.extend(small);
    let o = bp(&args);
    assert!(o.status.success(), "{}", text(&o));

    let out = dir.path().join("table.md");
    let table = |extra: &[&str]| {
        let (e, p, o) = (expert.to_str().unwrap(), pggd.to_str().unwrap(), out.to_str().unwrap());
        let mut args = vec!["table", "--expert", e, "--pggd", p, "--pggd-alone", "/nonexistent/run"];
        args.extend(["--episodes", "3", "--out", o]);
        args.extend(extra);
        bp(&args)
    };
    // A row asked for that cannot be built fails the command, and nothing is written ...
    let o = table(&[]);
    assert!(!o.status.success(), "{}", text(&o));
    assert!(text(&o).contains("missing row PGGD alone (/nonexistent/run)"), "{}", text(&o));
    assert!(text(&o).contains("--allow-missing") && !out.exists(), "{}", text(&o));
    // ... unless --allow-missing.
    let o = table(&["--allow-missing"]);
    assert!(o.status.success(), "{}", text(&o));
    let md = std::fs::read_to_string(&out).unwrap();
    assert_eq!(md, String::from_utf8_lossy(&o.stdout));
    let rows: Vec<&str> = md.lines().filter(|l| l.starts_with("| ") && !l.starts_with("| Method")).collect();
    assert_eq!(rows.len(), 4, "{md}");
    assert!(
        rows[0].starts_with("| DDPG (2 blocks)") && rows[0].contains("paper 0.44") && rows[0].contains("grey removed")
    );
    assert!(rows[0].contains("paper 0.24"), "{md}");
    assert!(rows[1].contains("not trained (paper 0.97)"), "{md}");
    assert!(
        rows[2].starts_with("| PGGD + AggreVaTeD")
            && rows[2].contains("paper 0.64")
            && rows[2].contains("(epoch 1, 0.00 M env steps)")
    );
    assert!(rows[3].contains("missing") && rows[3].contains("/nonexistent/run"), "{md}");
    // Why the unsuccessful episodes ended, for the evaluated rows only.
    let why: Vec<&str> = md.lines().filter(|l| l.starts_with("- ")).collect();
    assert_eq!(why.len(), 2, "{md}");
    assert!(why[0].starts_with("- DDPG (2 blocks), grey removed from its view: Normal failure "), "{md}");
    assert!(why[1].starts_with("- PGGD + AggreVaTeD: Normal failure ") && why[1].contains("; Challenge failure "));

    // The time to a result of the two runs.
    let o = bp(&["report", expert.to_str().unwrap(), pggd.to_str().unwrap(), "--target", "0.5"]);
    let t = text(&o);
    assert!(
        o.status.success()
            && t.contains("DDPG (2 batches per cycle) on BlocksTouch-v0 (2 workers")
            && t.contains("PGGD + AggreVaTeD (2 batches per cycle) on"),
        "{t}"
    );
    assert!(t.contains("seconds per epoch") && t.contains("updates"), "{t}");

    // A row takes the policy its method trained from scratch on its task (issue 74): the zoo's TD3
    // fine-tuned on ToppleTower-v0 is no "DDPG (3 blocks)", nor the BlocksTouch-v0 expert.
    for (policy, wanted) in [
        ("ToppleTower-v0-td3-finetuned", "stands for ddpg, and ToppleTower-v0-td3-finetuned was trained by td3"),
        (expert.to_str().unwrap(), "stands for an agent trained on BlocksChoose-v0, and"),
    ] {
        let o = bp(&["table", "--ddpg", policy, "--episodes", "1", "--allow-missing", "--out", out.to_str().unwrap()]);
        assert!(o.status.success(), "{}", text(&o));
        let row = text(&o).lines().find(|l| l.starts_with("| DDPG (3 blocks) |")).unwrap_or_default().to_owned();
        assert!(row.contains(wanted), "{policy}: {row}");
    }

    // --zoo takes every row from the zoo by its standard name: here a zoo holding only the expert.
    let zoo = dir.path().join("zoo");
    let o = bp(&[
        "zoo",
        "export",
        "--from",
        expert.to_str().unwrap(),
        "--name",
        "BlocksTouch-v0-ddpg",
        "--description",
        "tiny",
        "--trained-with",
        "tests/it/cli.rs",
        "--zoo",
        zoo.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", text(&o));
    let o = crate::common::blockpuzzle(&["table", "--zoo", "--episodes", "3", "--allow-missing"])
        .env("BLOCKPUZZLE_ZOO", &zoo)
        .output()
        .unwrap();
    let md = text(&o);
    assert!(o.status.success(), "{md}");
    let rows: Vec<&str> = md.lines().filter(|l| l.starts_with("| ") && !l.starts_with("| Method")).collect();
    assert_eq!(rows.len(), 5, "{md}");
    assert!(rows[0].contains("| BlocksTouch-v0-ddpg (epoch 1, 0.00 M env steps, grey removed) |"), "{md}");
    assert!(rows[1].contains("| BlocksChoose-v0-ddpg: not in the zoo yet"), "{md}");
    assert!(!md.contains(&*zoo.to_string_lossy()), "no machine paths in the table: {md}");
    assert!(rows[2].starts_with("| DDPG (3 blocks), ours | missing"), "{md}");

    // The same policies on the shuffled task (a generalisation test); a task without a challenge is refused.
    let o = bp(&["table", "--env", "BlocksChooseShuffled-v0", "--pggd", pggd.to_str().unwrap(), "--episodes", "3"]);
    let md = text(&o);
    assert!(o.status.success() && md.contains("Final evaluation on BlocksChooseShuffled-v0"), "{md}");
    assert!(
        md.contains("paper's number on BlocksChoose-v0 for comparison") && md.contains("(epoch 1, 0.00 M env steps)"),
        "{md}"
    );
    let o = bp(&["table", "--env", "BlocksTouch-v0", "--episodes", "3"]);
    assert!(!o.status.success() && text(&o).contains("does not define"), "{}", text(&o));
    // A row takes the kind of policy it names (issue 60): a PGGD policy fills no DDPG row, a deterministic
    // actor no PGGD row, and a multi-task policy no row at all.
    for (row, policy, wanted) in [
        ("--ddpg", pggd.to_str().unwrap(), "takes a deterministic (DDPG) actor"),
        ("--pggd", expert.to_str().unwrap(), "takes a PGGD policy"),
        ("--ddpg", "cross-task-v2-dagger-entity", "trained on several tasks (cross-task-v2-train)"),
    ] {
        let o = bp(&["table", row, policy, "--episodes", "2", "--out", out.to_str().unwrap()]);
        assert!(!o.status.success() && text(&o).contains(wanted), "{row} {policy}: {}", text(&o));
    }

    // The runs' finals curves in one figure.
    let png = dir.path().join("overlay.png");
    let o =
        bp(&["plot", "--overlay", expert.to_str().unwrap(), pggd.to_str().unwrap(), "--out", png.to_str().unwrap()]);
    assert!(o.status.success(), "{}", text(&o));
    assert!(std::fs::read(&png).unwrap().starts_with(b"\x89PNG"));
    // With a suite result's test score as a dashed level (issue 62: the solver's line).
    let solver = format!(
        "solver:{}/results/generalization/mujoco-2.2.2/baseline-scripted.colour.json",
        env!("CARGO_MANIFEST_DIR")
    );
    let o = bp(&["plot", "--overlay", expert.to_str().unwrap(), "--level", &solver, "--out", png.to_str().unwrap()]);
    assert!(o.status.success(), "{}", text(&o));
    let o = bp(&["plot", "--overlay", expert.to_str().unwrap(), "--level", "solver", "--out", png.to_str().unwrap()]);
    assert!(!o.status.success() && text(&o).contains("give LABEL:FILE"), "{}", text(&o));
    let o = bp(&["plot", "--overlay", expert.to_str().unwrap()]);
    assert!(!o.status.success() && text(&o).contains("--out"), "{}", text(&o));
    let o = bp(&["plot", "--overlay", "/nonexistent/run", "--out", png.to_str().unwrap()]);
    assert!(!o.status.success() && text(&o).contains("there is no run directory /nonexistent/run"), "{}", text(&o));
}

#[test]
fn task_files_work_wherever_an_id_does_and_task_check_reports() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("mine.toml");
    let source = blockpuzzle::env::registry::REGISTRY.iter().find(|r| r.id == "BlocksChoose-v0").unwrap().toml;
    std::fs::write(&file, source.replace("BlocksChoose-v0", "Mine-v0")).unwrap();
    let (f, out) = (file.to_str().unwrap(), dir.path().join("x.jsonl"));
    let o =
        bp(&["rollout", "--env", f, "--distribution", "challenge", "--episodes", "2", "--out", out.to_str().unwrap()]);
    assert!(o.status.success() && text(&o).contains("(challenge)"), "{}", text(&o));
    let ep = &blockpuzzle::episode::rollout::read_dump(&out).unwrap()[0];
    assert_eq!((ep.env_id.as_str(), ep.distribution.as_deref()), ("Mine-v0", Some("challenge")));
    assert!(ep.task.as_ref().unwrap().toml.contains("Mine-v0"), "the dump carries the task");
    let o = bp(&["scene", "--env", f]);
    assert!(o.status.success() && text(&o).contains("block2"), "{}", text(&o));
    let o = bp(&["task", "check", f, "--samples", "5"]);
    assert!(o.status.success(), "{}", text(&o));
    let t = text(&o);
    assert!(
        t.contains("task Mine-v0 is valid") && t.contains("level 10") && t.contains("distribution challenge"),
        "{t}"
    );
    let o = bp(&["rollout", "--env", f, "--distribution", "nope", "--out", out.to_str().unwrap()]);
    assert!(
        !o.status.success() && text(&o).contains("has no distribution \"nope\" (it has: challenge)"),
        "{}",
        text(&o)
    );

    // A bad file: the error names the file and line.
    std::fs::write(&file, source.replace("colour = \"grey\"\nstart", "colour = \"gray\"\nstart")).unwrap();
    let o = bp(&["task", "check", f]);
    assert!(!o.status.success(), "{}", text(&o));
    assert!(text(&o).contains(&format!("{f}:34: unknown variant `gray`")), "{}", text(&o));
    let o = bp(&["rollout", "--env", "NoSuch-v0", "--out", out.to_str().unwrap()]);
    assert!(text(&o).contains("or give the path of a task file"), "{}", text(&o));
}

#[test]
fn bad_dumps_are_named_read_and_decode_errors() {
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("missing.jsonl");
    let o = bp(&["render", "--traj", missing.to_str().unwrap(), "--out", dir.path().join("x.gif").to_str().unwrap()]);
    let t = text(&o);
    assert!(t.contains("cannot read trajectory dump") && !t.contains("write"), "{t}");
    assert_eq!(t.matches("os error 2").count(), 1, "{t}");
    let bad = dir.path().join("bad.jsonl");
    scripted_rollout(&bad);
    let good = std::fs::read_to_string(&bad).unwrap();
    let first = good.lines().next().unwrap();
    std::fs::write(&bad, format!("{first}\n{}\n", &first[..first.len() / 2])).unwrap();
    let o = bp(&["render", "--traj", bad.to_str().unwrap(), "--out", dir.path().join("x.gif").to_str().unwrap()]);
    let t = text(&o);
    assert!(t.contains("bad.jsonl line 2 is not an episode record") && !t.contains("encode"), "{t}");
}

#[test]
fn the_openmp_wait_policy_is_left_to_libgomp_unless_the_user_set_it() {
    // blockpuzzle does not set OMP_WAIT_POLICY (PASSIVE halves the update rate on an idle
    // machine, results/ddpg.md); a value the user set reaches the process unchanged.
    let info = |value: Option<&str>| {
        let mut c = std::process::Command::new(crate::common::CLI);
        c.arg("info");
        match value {
            Some(v) => c.env("OMP_WAIT_POLICY", v),
            None => c.env_remove("OMP_WAIT_POLICY"),
        };
        let o = c.output().unwrap();
        assert!(o.status.success(), "{}", text(&o));
        String::from_utf8_lossy(&o.stdout).into_owned()
    };
    assert!(info(None).contains("\nOMP_WAIT_POLICY=(unset)\n"), "{}", info(None));
    assert!(info(Some("PASSIVE")).contains("\nOMP_WAIT_POLICY=PASSIVE\n"));
    let missing = blockpuzzle::learn::blas::missing_settings(|_| None);
    assert!(missing.iter().all(|(k, _)| *k == "OPENBLAS_CORETYPE"), "{missing:?}");
    let set = blockpuzzle::learn::blas::missing_settings(|k| (k == "OPENBLAS_CORETYPE").then(|| "Haswell".into()));
    assert!(set.is_empty(), "a value the user set is left alone: {set:?}");
    // Only the commands that run or report libtorch's products start a second time for them.
    let wants = |line: &str| blockpuzzle::cli::wants_fast_kernels(&line.split(' ').map(Into::into).collect::<Vec<_>>());
    assert!(wants("blockpuzzle train --env BlocksTouch-v0") && wants("blockpuzzle bench --train") && wants("bp info"));
    assert!(!wants("blockpuzzle eval --suite layout") && !wants("blockpuzzle envs") && !wants("blockpuzzle --help"));
}

/// `align` replays a reference file (here a made-up one: no joints set, so
/// the episode starts from the scene's own state) and reports per episode;
/// `--plot` draws it; `--bench-steps` measures that scene instead.
#[test]
fn align_replays_plots_and_benches_a_reference() {
    let dir = tempfile::tempdir().unwrap();
    let r = dir.path().join("ref.json");
    let ep = r#"{"kind": "random", "seed": 7, "joints": {}, "actions": [[0.5, 0, 0, 0], [0, 0.5, 0, 0]],
        "grip": [[1.3, 0.75, 0.42], [1.3, 0.75, 0.42], [1.3, 0.75, 0.42]], "object": [[0, 0, 0], [0, 0, 0], [0, 0, 0]]}"#;
    let text_of =
        format!(r#"{{"env": "FetchPush-v4", "mujoco": "3.11.0", "gymnasium_robotics": "1.4.2", "episodes": [{ep}]}}"#);
    std::fs::write(&r, text_of).unwrap();
    let (r, png) = (r.to_str().unwrap(), dir.path().join("a.png"));
    let o = bp(&["align", "--reference", r, "--plot", png.to_str().unwrap()]);
    assert!(o.status.success(), "{}", text(&o));
    assert!(text(&o).contains("| random 7 | 3 |"), "{}", text(&o));
    assert!(image::open(&png).is_ok());
    let o = bp(&["align", "--reference", r, "--bench-steps", "30"]);
    assert!(o.status.success(), "{}", text(&o));
    let json: serde_json::Value =
        serde_json::from_slice(o.stdout.trim_ascii_end().rsplit(|&b| b == b'\n').next().unwrap()).unwrap();
    assert_eq!(json["env"], "FetchPush-like");
    assert!(json["env_steps_per_s"].as_f64().unwrap() > 0.0);
    let o = bp(&["align", "--reference", r, "--bench-steps", "30", "--plot", png.to_str().unwrap()]);
    assert!(!o.status.success() && text(&o).contains("--plot draws the replay"), "{}", text(&o));
    let o = bp(&["align", "--reference", dir.path().join("none.json").to_str().unwrap()]);
    assert!(!o.status.success() && text(&o).contains("bench/align_fetchpush.sh"), "{}", text(&o));
}

/// `train --branch-from`: a refused change is named before anything is
/// written, a branch reports where it came from and trains on, and it
/// cannot be combined with --resume or go without --run-dir.
#[test]
fn train_branch_from_names_refused_changes_and_continues_the_parent() {
    let dir = tempfile::tempdir().unwrap();
    let (parent, child) = (dir.path().join("parent"), dir.path().join("child"));
    let train = |run: &Path, epochs: &str, extra: &[&str]| {
        let mut args =
            vec!["train", "--env", "GripperTouch-v0", "--run-dir", run.to_str().unwrap(), "--epochs", epochs];
        args.extend(["--cycles", "1", "--batches", "2", "--test-episodes", "1", "--hidden", "16"]);
        args.extend(extra);
        bp(&args)
    };
    let o = train(&parent, "1", &[]);
    assert!(o.status.success(), "{}", text(&o));
    let from = ["--branch-from", parent.to_str().unwrap()];
    let o = train(&child, "2", &[&from[..], &["--gamma", "0.9"]].concat());
    assert!(!o.status.success() && text(&o).contains("--gamma") && !child.exists(), "{}", text(&o));
    let o = train(&child, "2", &[&from[..], &["--resume"]].concat());
    assert!(!o.status.success() && text(&o).contains("--resume"), "{}", text(&o));
    let o = bp(&["train", "--env", "GripperTouch-v0", "--branch-from", parent.to_str().unwrap()]);
    assert!(!o.status.success() && text(&o).contains("--run-dir"), "{}", text(&o));
    // A branch refused when it starts (a setting out of range) leaves no run directory behind.
    let o = train(&child, "2", &[&from[..], &["--level-replay", "2"]].concat());
    assert!(!o.status.success() && text(&o).contains("--level-replay"), "{}", text(&o));
    assert!(!child.exists(), "the failed branch was left behind");
    // (GripperTouch-v0 has one level: level replay would do nothing there, and is refused.)
    let o = train(&child, "2", &[&from[..], &["--level-replay", "0.5"]].concat());
    assert!(!o.status.success() && text(&o).contains("one curriculum level") && !child.exists(), "{}", text(&o));
    let o = train(&child, "2", &[&from[..], &["--success-threshold", "0.5"]].concat());
    assert!(o.status.success(), "{}", text(&o));
    assert!(text(&o).contains("branched from") && text(&o).contains("at epoch 1"), "{}", text(&o));
    let rows = std::fs::read_to_string(child.join("progress.csv")).unwrap();
    assert_eq!(rows.lines().count(), 3, "the parent's epoch and the branch's own: {rows}");
}

/// `train --resume --run-dir DIR`, given no recipe: the run's own settings (its config.json) with
/// the epochs given; any other flag still has to match the run's.
#[test]
fn train_resume_with_only_the_run_dir_takes_the_runs_own_settings() {
    let dir = tempfile::tempdir().unwrap();
    let run = dir.path().join("run");
    let r = run.to_str().unwrap();
    let mut args = vec!["train", "--env", "GripperTouch-v0", "--run-dir", r, "--epochs", "1", "--gamma", "0.9"];
    args.extend(["--cycles", "1", "--batches", "2", "--test-episodes", "1", "--hidden", "16", "--seed", "3"]);
    let o = bp(&args);
    assert!(o.status.success(), "{}", text(&o));
    let config = std::fs::read_to_string(run.join("config.json")).unwrap();
    // Without the run's flags: before, this compared the defaults with the run's settings and refused.
    let o = bp(&["train", "--resume", "--run-dir", r, "--epochs", "2", "--torch-threads", "1"]);
    assert!(o.status.success(), "{}", text(&o));
    assert!(text(&o).contains("GripperTouch-v0: 2 epochs"), "{}", text(&o));
    let rows = std::fs::read_to_string(run.join("progress.csv")).unwrap();
    assert_eq!(rows.lines().count(), 3, "the first epoch and the resumed one: {rows}");
    let after: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(run.join("config.json")).unwrap()).unwrap();
    let before: serde_json::Value = serde_json::from_str(&config).unwrap();
    for key in ["env", "seed", "cycles", "batches", "shared", "net"] {
        assert_eq!(after[key], before[key], "{key} kept");
    }
    assert_eq!(after["epochs"], 2);
    // A flag beyond the epochs, threads and snapshots: compared with the run's, as before.
    let o = bp(&["train", "--resume", "--run-dir", r, "--epochs", "3", "--env", "GripperTouch-v0", "--gamma", "0.99"]);
    assert!(!o.status.success() && text(&o).contains("--gamma"), "{}", text(&o));
    // ...and without the run's task, that is what the error asks for.
    let o = bp(&["train", "--resume", "--run-dir", r, "--epochs", "3", "--gamma", "0.9"]);
    assert!(!o.status.success() && text(&o).contains("given --gamma") && text(&o).contains("--env"), "{}", text(&o));
    // The checkpoint records its config's seal: an edited config.json (a seed here), or another run's
    // checkpoint, is refused before anything is written (issue 74).
    let good = std::fs::read_to_string(run.join("config.json")).unwrap();
    let mut v: serde_json::Value = serde_json::from_str(&good).unwrap();
    v["seed"] = 4.into();
    std::fs::write(run.join("config.json"), serde_json::to_vec_pretty(&v).unwrap()).unwrap();
    let o = bp(&["train", "--resume", "--run-dir", r, "--epochs", "3"]);
    assert!(!o.status.success() && text(&o).contains("is not the configuration") && text(&o).contains("edited"));
    std::fs::write(run.join("config.json"), &good).unwrap();
    let other = dir.path().join("other");
    let mut args = vec!["train", "--env", "GripperTouch-v0", "--epochs", "1", "--gamma", "0.9", "--seed", "5"];
    args.extend(["--cycles", "1", "--batches", "2", "--test-episodes", "1", "--hidden", "16", "--run-dir"]);
    args.push(other.to_str().unwrap());
    assert!(bp(&args).status.success());
    let ours = std::fs::read(run.join("checkpoint.bin")).unwrap();
    std::fs::copy(other.join("checkpoint.bin"), run.join("checkpoint.bin")).unwrap();
    let o = bp(&["train", "--resume", "--run-dir", r, "--epochs", "3"]);
    assert!(!o.status.success() && text(&o).contains("the checkpoint is another run's"), "{}", text(&o));
    std::fs::write(run.join("checkpoint.bin"), ours).unwrap();
    let o = bp(&["train", "--resume", "--run-dir", r, "--epochs", "3"]);
    assert!(o.status.success(), "the run's own files resume: {}", text(&o));
    // No run directory: refused, naming the fix.
    let o = bp(&["train", "--resume", "--epochs", "3"]);
    assert!(!o.status.success() && text(&o).contains("give --run-dir DIR"), "{}", text(&o));
    // No run there: refused, naming the fix.
    let none = dir.path().join("none");
    let o = bp(&["train", "--resume", "--run-dir", none.to_str().unwrap()]);
    assert!(!o.status.success() && text(&o).contains("holds no run"), "{}", text(&o));
    assert!(!none.exists(), "nothing written");
}

#[test]
fn training_commands_are_named_once() {
    use blockpuzzle::cli::{check_args, training_command, TRAINING_COMMANDS};
    let line = |words: &[&str]| -> Vec<std::ffi::OsString> {
        std::iter::once("blockpuzzle").chain(words.iter().copied()).map(Into::into).collect()
    };
    assert_eq!(training_command(&line(&["zoo", "export", "--from", "x"])), Some("zoo export"));
    assert_eq!(training_command(&line(&["train", "--env", "BlocksTouch-v0"])), Some("train"));
    assert_eq!(training_command(&line(&["zoo", "list"])), None);
    // The paper's table evaluates saved policies: no libtorch, so the Python package's command has it too.
    assert_eq!(training_command(&line(&["table", "--zoo"])), None);
    assert_eq!(training_command(&line(&["--version"])), None);
    // Of them, those that run libtorch start `blockpuzzle-train`; `plot`, `report` and `align` run in
    // `blockpuzzle`, as does every core command.
    use blockpuzzle::cli::{runs_in_training_half, TRAINING_HALF};
    assert_eq!(runs_in_training_half(&line(&["zoo", "export", "--from", "x"])), Some("zoo export"));
    assert_eq!(runs_in_training_half(&line(&["info"])), Some("info"));
    for core in ["plot", "report", "align", "rollout", "zoo", "--help"] {
        assert_eq!(runs_in_training_half(&line(&[core])), None, "{core}");
    }
    assert!(TRAINING_HALF.iter().all(|c| *c == "info" || TRAINING_COMMANDS.contains(c)));
    // Every entry is a command of this (the training) build: its help prints.
    for c in TRAINING_COMMANDS {
        let mut words: Vec<&str> = c.split(' ').collect();
        words.push("--help");
        let e = check_args(line(&words)).expect_err("--help ends the parse");
        let kind = e.downcast_ref::<clap::Error>().map(clap::Error::kind);
        assert_eq!(kind, Some(clap::error::ErrorKind::DisplayHelp), "{c}: {e}");
    }
    // The build without them (the Python package's command) says which build has them:
    // python/tests/test_cli.py.
}

/// The shared libraries an executable names (`readelf -d`), and whether lld linked it (its
/// `.comment`): rust-lld, Rust's default linker on x86-64 Linux since 1.90, drops a library that
/// only unreachable code refers to; GNU ld keeps it.
fn needed_libraries(exe: &str) -> (Vec<String>, bool) {
    let run = |args: &[&str]| {
        let o = std::process::Command::new("readelf").args(args).arg(exe).output().expect("readelf (binutils)");
        assert!(o.status.success(), "readelf {args:?} {exe}: {}", String::from_utf8_lossy(&o.stderr));
        String::from_utf8_lossy(&o.stdout).into_owned()
    };
    let needed = run(&["-d"])
        .lines()
        .filter(|l| l.contains("(NEEDED)"))
        .filter_map(|l| l.split('[').nth(1)?.split(']').next().map(str::to_owned))
        .collect();
    (needed, run(&["-p", ".comment"]).contains("LLD"))
}

/// `blockpuzzle` links no libtorch (the commands without it start in milliseconds) and hands the
/// training commands to `blockpuzzle-train` beside it, in its place; one of another build, or none,
/// is refused, naming the fix, before anything is written.
#[test]
fn the_command_line_starts_without_libtorch_and_hands_training_to_its_other_half() {
    let front = crate::common::CLI;
    let back = env!("CARGO_BIN_EXE_blockpuzzle-train");
    let (needed, lld) = needed_libraries(front);
    let torch = |libs: &[String]| libs.iter().any(|l| l.starts_with("libtorch") || l.starts_with("libc10"));
    if lld {
        assert!(!torch(&needed), "blockpuzzle links libtorch: {needed:?}");
    } else {
        eprintln!("note: blockpuzzle was not linked by lld, which alone drops libtorch from it: {needed:?}");
    }
    assert!(torch(&needed_libraries(back).0), "blockpuzzle-train links no libtorch");
    // Through the front: the training commands' help and a refusal of theirs, as the whole command
    // line gives them; the top-level help lists them.
    let o = bp(&["train", "--help"]);
    assert!(
        o.status.success() && text(&o).contains("--algo") && text(&o).contains("Usage: blockpuzzle train"),
        "{}",
        text(&o)
    );
    let o = bp(&["--help"]);
    assert!(o.status.success() && text(&o).contains("train") && text(&o).contains("rollout"), "{}", text(&o));
    let o = bp(&["info"]);
    assert!(o.status.success() && text(&o).contains("OpenBLAS kernels"), "{}", text(&o));
    let dir = tempfile::tempdir().unwrap();
    let run = dir.path().join("run");
    let run = run.to_str().unwrap();
    // The other half from another build: refused before anything is written.
    let o = std::process::Command::new(back)
        .args(["train", "--env", "GripperTouch-v0", "--epochs", "1", "--run-dir", run])
        .env("BLOCKPUZZLE_FRONT_BUILD", "0000000000000000")
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    for want in ["built from other sources", "0000000000000000", blockpuzzle::cli::BUILD_ID, "cargo build --release"] {
        assert!(text(&o).contains(want), "{want:?} missing from: {}", text(&o));
    }
    assert!(!Path::new(run).exists(), "nothing written");
    // Alone, without its other half: the core's commands run, the training ones name what is missing.
    let alone = dir.path().join("alone");
    std::fs::create_dir(&alone).unwrap();
    let copy = alone.join("blockpuzzle");
    std::fs::copy(front, &copy).unwrap();
    let o = std::process::Command::new(&copy).arg("envs").output().unwrap();
    assert!(o.status.success(), "{}", text(&o));
    let o = std::process::Command::new(&copy)
        .args(["train", "--env", "GripperTouch-v0", "--run-dir", run])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    let missing = alone.join("blockpuzzle-train").display().to_string();
    for want in [
        "`train` runs in blockpuzzle-train",
        &missing,
        "does not exist",
        "cargo build --release",
        "cargo install --path .",
    ] {
        assert!(text(&o).contains(want), "{want:?} missing from: {}", text(&o));
    }
    assert!(!Path::new(run).exists(), "nothing written");
}

/// `plot --scaling`: suite results against a number (the Procgen curve), with a table of the points;
/// malformed points, an x the logarithmic axis cannot take, and results of several suites refused.
#[test]
fn plot_scaling_draws_results_against_a_count_and_refuses_what_it_cannot_draw() {
    let dir = tempfile::tempdir().unwrap();
    let png = dir.path().join("curve.png");
    let shipped = |name: &str| format!("{}/results/generalization/mujoco-2.2.2/{name}", env!("CARGO_MANIFEST_DIR"));
    let (solver, multi) =
        (shipped("baseline-scripted.procgen.json"), shipped("cross-task-v2-dagger-entity.procgen.json"));
    let point = |x: &str, f: &str| format!("{x}:{f}");
    let args = |points: &[String], extra: &[&str]| {
        let mut a = vec!["plot".to_owned(), "--scaling".to_owned()];
        a.extend(points.iter().cloned());
        a.extend(["--out".to_owned(), png.display().to_string()]);
        a.extend(extra.iter().map(|s| (*s).to_owned()));
        a
    };
    let run = |a: &[String]| bp(&a.iter().map(String::as_str).collect::<Vec<_>>());
    let o = run(&args(&[point("16", &multi), point("64", &solver)], &["--reference", &solver]));
    assert!(o.status.success(), "{}", text(&o));
    assert!(std::fs::read(&png).unwrap().starts_with(b"\x89PNG"));
    let table = text(&o);
    // The solver's procgen numbers, as its result file holds them.
    let r: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&solver).unwrap()).unwrap();
    let (score, gap) = (r["score"].as_f64().unwrap(), r["gap"].as_f64().unwrap());
    let row = format!("| 64 | {:.3} | {score:.3} | {gap:.3} |", score + gap);
    assert!(table.contains(&row) && table.contains("| reference |"), "{row} in {table}");
    std::fs::remove_file(&png).unwrap();
    for (bad, wanted) in [
        (args(std::slice::from_ref(&multi), &[]), "X:FILE"),
        (args(&[point("0", &multi)], &[]), "logarithmic"),
        (args(&[point("abc", &multi)], &[]), "not a number"),
        (args(&[point("4", &multi), point("8", &shipped("baseline-scripted.layout.json"))], &[]), "several suites"),
        // Another engine's result of the same suite: one figure holds one engine, as `results compare`.
        (
            args(
                &[
                    point("4", &multi),
                    point("8", &shipped("baseline-scripted.procgen.json").replace("2.2.2", "3.11.0")),
                ],
                &[],
            ),
            "provenance.mujoco",
        ),
    ] {
        let o = run(&bad);
        assert!(!o.status.success() && text(&o).contains(wanted), "{bad:?}: {}", text(&o));
        assert!(!png.exists());
    }
}

/// `plot --curve` (issue 62): a run's snapshots, each scored on a suite, drawn against the env steps
/// each had trained for (recorded by the result; for an older result, read from its policy file if
/// that is still the policy evaluated), with the policy it started from and the solver's level; what
/// it cannot draw is refused, nothing written.
#[test]
fn plot_curve_draws_evaluated_snapshots_against_env_steps_and_refuses_what_it_cannot_draw() {
    let dir = tempfile::tempdir().unwrap();
    let (run, png) = (dir.path().join("run"), dir.path().join("curve.png"));
    let suite = dir.path().join("tiny.toml");
    std::fs::write(
        &suite,
        "version = 1\nname = \"tiny\"\nsummary = \"three episodes\"\n\n[[splits.train]]\ntask = \"GripperTouch-v0\"\n\
         seed = 1\nepisodes = 1\n\n[[splits.test]]\ntask = \"GripperTouch-v0\"\nseed = 100\nepisodes = 3\n",
    )
    .unwrap();
    let o = bp(&[
        "train",
        "--env",
        "GripperTouch-v0",
        "--run-dir",
        run.to_str().unwrap(),
        "--epochs",
        "2",
        "--cycles",
        "1",
        "--batches",
        "2",
        "--test-episodes",
        "1",
        "--hidden",
        "16",
        "--snapshot-every",
        "1",
    ]);
    assert!(o.status.success(), "{}", text(&o));
    let eval = |policy: &str, out: &Path, extra: &[&str]| {
        let mut a = vec!["eval", "--suite", suite.to_str().unwrap(), "--threads", "1", "--out", out.to_str().unwrap()];
        a.extend(if policy.is_empty() { vec![] } else { vec!["--checkpoint", policy] });
        a.extend(extra);
        let o = bp(&a);
        assert!(o.status.success(), "{}", text(&o));
        out.to_str().unwrap().to_owned()
    };
    let snap = |e: usize| run.join(format!("snapshots/epoch-{e:04}.json"));
    let (e1, e2) = (dir.path().join("e1.json"), dir.path().join("e2.json"));
    let (e1, e2) = (eval(snap(1).to_str().unwrap(), &e1, &[]), eval(snap(2).to_str().unwrap(), &e2, &[]));
    let solver = eval("", &dir.path().join("solver.json"), &["--baseline", "scripted"]);
    let steps = |f: &str| {
        serde_json::from_str::<serde_json::Value>(&std::fs::read_to_string(f).unwrap()).unwrap()["env_steps"]
            .as_u64()
            .unwrap()
    };
    let (s1, s2) = (steps(snap(1).to_str().unwrap()), steps(snap(2).to_str().unwrap()));
    assert!(0 < s1 && s1 < s2);
    let plot = |extra: &[&str]| {
        let mut a = vec!["plot", "--out", png.to_str().unwrap()];
        a.extend(extra);
        bp(&a)
    };
    // Given in any order, drawn by env steps; the start's point is first, at 0 (a baseline trained nowhere).
    // Labels may hold colons: LABEL:FILE splits at the last one.
    let level = format!("solver: scripted:{solver}");
    let start = format!("run: s0:{solver}");
    let o = plot(&["--curve", "run: s0", &e2, &e1, "--start", &start, "--level", &level]);
    assert!(o.status.success(), "{}", text(&o));
    assert!(std::fs::read(&png).unwrap().starts_with(b"\x89PNG"));
    let table: Vec<String> = text(&o).lines().filter(|l| l.starts_with("| run: s0 |")).map(str::to_owned).collect();
    assert_eq!(table.len(), 3, "{}", text(&o));
    assert!(table[0].contains("| 0 |") && table[0].contains("solver.json"), "{table:?}");
    assert!(table[1].contains(&format!("| {s1} |")) && table[2].contains(&format!("| {s2} |")), "{table:?}");
    std::fs::remove_file(&png).unwrap();

    // A result written before results recorded the env steps: read from its policy file, while that is the
    // policy it evaluated; refused once it is not there.
    let mut old: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&e1).unwrap()).unwrap();
    assert_eq!(old["policy_env_steps"].as_u64(), Some(s1));
    old.as_object_mut().unwrap().remove("policy_env_steps");
    let older = dir.path().join("older.json");
    std::fs::write(&older, old.to_string()).unwrap();
    let o = plot(&["--curve", "run", older.to_str().unwrap()]);
    assert!(o.status.success() && text(&o).contains(&format!("| run | {s1} |")), "{}", text(&o));
    std::fs::remove_file(&png).unwrap();
    std::fs::rename(snap(1), dir.path().join("moved.json")).unwrap();
    let other_suite =
        format!("{}/results/generalization/mujoco-2.2.2/baseline-scripted.colour.json", env!("CARGO_MANIFEST_DIR"));
    for (args, wanted) in [
        (vec!["--curve", "run", older.to_str().unwrap()], "records no env steps"),
        (vec!["--curve", &e1, &e2], "a curve starts with its label"),
        (vec!["--curve", "run", &e2, "--level", &format!("solver:{other_suite}")], "cannot be drawn in one figure"),
        (vec!["--curve", "run", &e2, "--start", "other:x.json"], "the LABEL of a --curve"),
        (vec!["--curve", "run: s0", &e2, "--start", &start, "--start", &start], "give one"),
    ] {
        let o = plot(&args);
        assert!(!o.status.success() && text(&o).contains(wanted), "{args:?}: {}", text(&o));
        assert!(!png.exists(), "{args:?}");
    }
}

/// The help of every command that takes `--suite` lists every built-in suite (issue 60: `eval --help`
/// listed 5 of 8), from the one list the suites are loaded from.
#[test]
fn suite_help_lists_every_built_in_suite() {
    for cmd in ["eval", "demos"] {
        let o = crate::common::blockpuzzle(&[cmd, "--help"]).output().unwrap();
        let help = String::from_utf8_lossy(&o.stdout);
        for (name, _) in blockpuzzle::benchmark::suite::BUILTIN {
            let listed = [" ", "("].iter().any(|b| [",", ")"].iter().any(|a| help.contains(&format!("{b}{name}{a}"))));
            assert!(listed, "{cmd}: {name}: {help}");
        }
    }
}

/// docs/cli.md names every command `blockpuzzle --help` lists (issue 74: `blend` was missing), and
/// `train`'s summary names every algorithm `--algo` takes.
#[test]
fn the_command_line_reference_names_every_command_and_algorithm() {
    let doc = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/docs/cli.md")).unwrap();
    let help = text(&bp(&["--help"]));
    let commands: Vec<&str> = help
        .lines()
        .skip_while(|l| !l.starts_with("Commands:"))
        .skip(1)
        .take_while(|l| l.starts_with("  "))
        .filter_map(|l| l.split_whitespace().next())
        .filter(|c| *c != "help")
        .collect();
    assert!(commands.len() > 10, "{help}");
    for c in commands {
        assert!(
            doc.contains(&format!("`{c}")) || doc.contains(&format!("blockpuzzle {c}")),
            "docs/cli.md names no {c}"
        );
    }
    let train = help.lines().find(|l| l.trim_start().starts_with("train ")).unwrap().to_lowercase();
    for algo in blockpuzzle::benchmark::saved::Trainer::ALL.map(|t| t.name()) {
        assert!(train.contains(algo), "`train`'s summary omits {algo}: {train}");
    }
}
