//! Every result says what made it (crate::benchmark::provenance), and results of
//! different engines, suites or task contents are never put in one column:
//! the writers' provenance blocks, the task hash of a suite row, `results
//! compare` and `results leaderboard`, and the committed leaderboard is what
//! its result files give.
#![cfg(feature = "train")]

use blockpuzzle::benchmark::evaluate::{evaluate_suite, Baseline, Subject, SuiteResult};
use blockpuzzle::benchmark::provenance::Harness;
use blockpuzzle::benchmark::results::{self, ResultFile};
use std::path::{Path, PathBuf};
use std::process::Output;

fn bp(args: &[&str]) -> Output {
    crate::common::blockpuzzle(args).output().unwrap()
}

fn text(o: &Output) -> String {
    format!("{}{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr))
}

/// A suite of one row each way on the task file `task.toml` beside it.
const SUITE: &str = r#"
version = 1
name = "edited"
summary = "A task file that may change under the suite."
[[splits.train]]
task = "task.toml"
seed = 3000000
episodes = 3
[[splits.test]]
task = "task.toml"
seed = 1000000
episodes = 3
"#;

fn obs_hash_on(suite: &Path) -> SuiteResult {
    let suite = blockpuzzle::benchmark::suite::load(suite.to_str().unwrap()).unwrap();
    evaluate_suite(Subject::Baseline(Baseline::ObsHash), &suite, 2, Harness::Cli, &mut |_, _, _, _| Ok(())).unwrap()
}

#[test]
fn a_suite_result_names_engine_package_policy_suite_and_each_task() {
    let dir = tempfile::tempdir().unwrap();
    let task =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("tasks/BlocksTouch-v0.toml")).unwrap();
    std::fs::write(dir.path().join("task.toml"), &task).unwrap();
    let suite = dir.path().join("edited.toml");
    std::fs::write(&suite, SUITE).unwrap();
    let a = obs_hash_on(&suite);
    let p = &a.provenance;
    assert_eq!(p.build.mujoco, blockpuzzle::sim::mj::version());
    assert_eq!(p.build.blockpuzzle, env!("CARGO_PKG_VERSION"));
    assert_eq!(
        (p.harness, p.policy.name.as_str(), p.policy.sha256.as_deref()),
        (Harness::Cli, "baseline:obs-hash", None)
    );
    assert_eq!(p.suite.as_ref(), Some(&a.suite));
    let built_in = blockpuzzle::env::registry::task("BlocksTouch-v0").unwrap().source.hash;
    for row in a.splits.iter().flat_map(|s| &s.rows) {
        // A file with the built-in's content is the built-in task, by content.
        assert_eq!(row.task_sha256, built_in);
        assert_eq!(row.evaluation.as_ref().unwrap().task_sha256, built_in);
    }

    // The task file edited (one more step per episode), the suite's text untouched: the suite hash
    // stays, the rows' task hash changes, and the two results are refused in one column.
    std::fs::write(dir.path().join("task.toml"), task.replace("max_episode_steps = 50", "max_episode_steps = 51"))
        .unwrap();
    let b = obs_hash_on(&suite);
    assert_eq!(a.suite, b.suite);
    assert_ne!(a.splits[0].rows[0].task_sha256, b.splits[0].rows[0].task_sha256);
    let m = results::comparable(&a, &b).unwrap_err();
    assert!(m.field.contains("task_sha256") && m.field.contains("train"), "{m}");
    assert!(results::comparable(&a, &a.clone()).is_ok());
}

#[test]
fn a_shortened_run_says_so_and_is_never_ranked() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::copy(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("tasks/BlocksTouch-v0.toml"),
        dir.path().join("task.toml"),
    )
    .unwrap();
    let path = dir.path().join("edited.toml");
    std::fs::write(&path, SUITE).unwrap();
    // The library: rows cut to 2 episodes, the result's suite id says so, each row is reported once.
    let suite = blockpuzzle::benchmark::suite::load(path.to_str().unwrap()).unwrap();
    assert!(suite.clone().first_episodes(0).is_err());
    let short = suite.first_episodes(2).unwrap();
    let mut heard = Vec::new();
    let r = evaluate_suite(
        Subject::Baseline(Baseline::ObsHash),
        &short,
        2,
        Harness::Cli,
        &mut |split, row, done, total| {
            heard.push((split.to_owned(), row.episodes, done, total));
            Ok(())
        },
    )
    .unwrap();
    assert_eq!(heard, [("train".to_owned(), 2, 1, 2), ("test".to_owned(), 2, 2, 2)]);
    // The callback's error stops the evaluation after its row (Python's KeyboardInterrupt does so).
    let mut rows = 0;
    let stopped = evaluate_suite(Subject::Baseline(Baseline::ObsHash), &short, 2, Harness::Cli, &mut |_, _, _, _| {
        rows += 1;
        Err("stop".into())
    });
    assert_eq!((stopped.unwrap_err().to_string(), rows), ("stop".to_owned(), 1));
    assert_eq!((r.suite.episodes_per_row, r.provenance.suite.as_ref().unwrap().episodes_per_row), (Some(2), Some(2)));
    assert!(r.splits.iter().flat_map(|s| &s.rows).all(|row| row.evaluation.as_ref().unwrap().episodes == 2));
    // The command line: --episodes-per-row writes it, and `results` refuses to rank or compare it.
    let a = dir.path().join("short.json");
    let o = bp(&[
        "eval",
        "--suite",
        path.to_str().unwrap(),
        "--baseline",
        "obs-hash",
        "--episodes-per-row",
        "1",
        "--out",
        a.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", text(&o));
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&a).unwrap()).unwrap();
    assert_eq!(v["suite"]["episodes_per_row"], 1);
    assert_eq!(v["splits"][0]["rows"][0]["episodes"], 1);
    let t = text(&bp(&["results", "leaderboard", a.to_str().unwrap()]));
    assert!(t.contains("shortened run") && t.contains("at most 1 episodes per row"), "{t}");
    let o = bp(&["eval", "--suite", path.to_str().unwrap(), "--baseline", "obs-hash", "--episodes-per-row", "0"]);
    assert!(!o.status.success() && text(&o).contains("episodes-per-row"), "{}", text(&o));
}

#[test]
fn compare_refuses_other_engines_and_suites_naming_the_field() {
    let dir = tempfile::tempdir().unwrap();
    let suite = dir.path().join("edited.toml");
    std::fs::copy(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("tasks/BlocksTouch-v0.toml"),
        dir.path().join("task.toml"),
    )
    .unwrap();
    std::fs::write(&suite, SUITE).unwrap();
    let a = dir.path().join("a.json");
    let o = bp(&["eval", "--suite", suite.to_str().unwrap(), "--baseline", "scripted", "--out", a.to_str().unwrap()]);
    assert!(o.status.success(), "{}", text(&o));
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&a).unwrap()).unwrap();
    assert_eq!(v["provenance"]["harness"], "cli");
    assert_eq!(v["provenance"]["mujoco"], blockpuzzle::sim::mj::version().as_str());
    assert_eq!(v["provenance"]["policy"]["name"], "baseline:scripted");
    let md = std::fs::read_to_string(a.with_extension("md")).unwrap();
    assert!(md.contains(&format!("Made on MuJoCo {}", blockpuzzle::sim::mj::version())), "{md}");

    // The same file twice compares; the copy claiming another engine or suite text is refused.
    let o = bp(&["results", "compare", a.to_str().unwrap(), a.to_str().unwrap()]);
    assert!(o.status.success() && text(&o).contains("**score**"), "{}", text(&o));
    for (field, value, named) in [("mujoco", "9.9.9", "provenance.mujoco"), ("suite", "x", "provenance.suite.sha256")] {
        let mut w = v.clone();
        match field {
            "mujoco" => w["provenance"]["mujoco"] = value.into(),
            _ => {
                w["provenance"]["suite"]["sha256"] = value.into();
                w["suite"]["sha256"] = value.into();
            }
        }
        let b = dir.path().join(format!("{field}.json"));
        std::fs::write(&b, serde_json::to_vec(&w).unwrap()).unwrap();
        let o = bp(&["results", "compare", a.to_str().unwrap(), b.to_str().unwrap()]);
        let t = text(&o);
        assert!(!o.status.success() && t.contains(named) && t.contains(value), "{field}: {t}");
        // The leaderboard keeps them apart: another engine, or another suite text, is another table.
        let board = bp(&["results", "leaderboard", a.to_str().unwrap(), b.to_str().unwrap()]);
        assert!(board.status.success(), "{}", text(&board));
        assert_eq!(String::from_utf8_lossy(&board.stdout).matches("\n## `edited`").count(), 2, "{field}");
    }
    // Rows played at another level, on the challenge draw or with grey hidden are other measurements.
    for (field, value) in [("level", serde_json::json!(99)), ("challenge", true.into()), ("grey_blind", true.into())] {
        let mut w = v.clone();
        w["splits"][0]["rows"][0]["evaluation"][field] = value;
        let b = dir.path().join(format!("{field}.json"));
        std::fs::write(&b, serde_json::to_vec(&w).unwrap()).unwrap();
        let t = text(&bp(&["results", "compare", a.to_str().unwrap(), b.to_str().unwrap()]));
        assert!(t.contains(&format!("splits[train].rows[0].evaluation.{field}")), "{field}: {t}");
    }
    // A file whose provenance and suite disagree is refused as edited.
    let mut edited = v.clone();
    edited["suite"]["sha256"] = "y".into();
    let b = dir.path().join("edited.json");
    std::fs::write(&b, serde_json::to_vec(&edited).unwrap()).unwrap();
    let t = text(&bp(&["results", "compare", a.to_str().unwrap(), b.to_str().unwrap()]));
    assert!(t.contains("provenance names another suite"), "{t}");
    // A file without provenance (written before results carried it) is refused with the fix.
    let mut old = v.clone();
    old.as_object_mut().unwrap().remove("provenance");
    let b = dir.path().join("old.json");
    std::fs::write(&b, serde_json::to_vec(&old).unwrap()).unwrap();
    let t = text(&bp(&["results", "compare", a.to_str().unwrap(), b.to_str().unwrap()]));
    assert!(t.contains("records no provenance") && t.contains("eval --suite"), "{t}");
    // The same policy with other numbers on one engine and suite: the leaderboard refuses it.
    // (One success made a timeout, every derived number made to agree: a file whose numbers hold together.)
    let mut other = v.clone();
    let e = &mut other["splits"][1]["rows"][0]["evaluation"];
    let (n, s) = (e["episodes"].as_u64().unwrap() as usize, e["successes"].as_u64().unwrap() as usize - 1);
    e["outcomes"]["success"] = s.into();
    e["outcomes"]["timeout"] = (e["outcomes"]["timeout"].as_u64().unwrap() + 1).into();
    e["successes"] = s.into();
    let rate = s as f64 / n as f64;
    e["success_rate"] = rate.into();
    e["ci95"] = serde_json::json!(blockpuzzle::episode::outcome::wilson95(s, n));
    if s == 0 {
        e["mean_steps_to_success"] = serde_json::Value::Null;
    }
    other["splits"][1]["mean_success"] = rate.into();
    other["score"] = rate.into();
    other["gap"] = (other["splits"][0]["mean_success"].as_f64().unwrap() - rate).into();
    let b = dir.path().join("other.json");
    std::fs::write(&b, serde_json::to_vec(&other).unwrap()).unwrap();
    let t = text(&bp(&["results", "leaderboard", a.to_str().unwrap(), b.to_str().unwrap()]));
    assert!(t.contains("different outcome counts"), "{t}");

    // The app's leaderboard groups as the command line does: two copies of one result are one row
    // naming both files; a conflicting third makes that board an error naming the files.
    #[cfg(feature = "serve")]
    {
        use blockpuzzle::serve::{api::Catalogue, files::Roots};
        let served = dir.path().join("served");
        std::fs::create_dir(&served).unwrap();
        std::fs::copy(&a, served.join("a.json")).unwrap();
        std::fs::copy(&a, served.join("a-again.json")).unwrap();
        let board = || {
            let roots = Roots::new(std::slice::from_ref(&served)).unwrap();
            Catalogue::new(roots, &[], vec![served.clone()]).leaderboard().body
        };
        let lb = board();
        assert_eq!(lb["errors"], serde_json::json!([]), "{lb}");
        let rows = lb["boards"][0]["rows"].as_array().unwrap();
        assert_eq!(rows.len(), 1, "{lb}");
        assert_eq!(rows[0]["files"], serde_json::json!(["a-again.json", "a.json"]), "{lb}");
        std::fs::copy(&b, served.join("other.json")).unwrap();
        let lb = board();
        assert_eq!(lb["boards"], serde_json::json!([]), "{lb}");
        let e = lb["errors"][0].as_str().unwrap();
        assert!(e.contains("different outcome counts") && e.contains("other.json"), "{lb}");
    }
}

#[test]
fn eval_table_and_zoo_evaluations_carry_provenance() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("e.json");
    let o = bp(&["eval", "--checkpoint", "ReachAvoid-v0-ddpg", "--episodes", "2", "--out", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", text(&o));
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
    let (meta, saved) = blockpuzzle::benchmark::zoo::load(
        &blockpuzzle::benchmark::zoo::find(&blockpuzzle::benchmark::zoo::dir(), "ReachAvoid-v0-ddpg").unwrap(),
    )
    .unwrap();
    assert_eq!(v["task_sha256"], meta.task.hash.as_str());
    assert_eq!(v["provenance"]["policy"]["sha256"], saved.policy_id("x").sha256.unwrap().as_str());
    assert_eq!(v["provenance"]["mujoco"], blockpuzzle::sim::mj::version().as_str());

    // The paper's table says which engine, and each policy by content.
    let table = dir.path().join("t.md");
    let o = bp(&["table", "--ddpg", "BlocksChoose-v0-ddpg", "--episodes", "2", "--out", table.to_str().unwrap()]);
    assert!(o.status.success(), "{}", text(&o));
    let md = std::fs::read_to_string(&table).unwrap();
    assert!(
        md.contains(&format!("Made on MuJoCo {}", blockpuzzle::sim::mj::version())) && md.contains("sha256:"),
        "{md}"
    );

    // A zoo entry exported with an evaluation records it with its engine; `zoo evaluate` plays it
    // again on this engine and replaces it; a record without provenance with the same numbers is
    // confirmed as this engine's.
    let z = dir.path().join("zoo");
    let mut args = vec!["zoo", "export", "--from", "ReachAvoid-v0-ddpg", "--name", "r", "--description", "d"];
    args.extend(["--trained-with", "t", "--evaluate", "3", "--zoo", z.to_str().unwrap()]);
    assert!(bp(&args).status.success());
    let entry = z.join("r.json");
    let (meta, _) = blockpuzzle::benchmark::zoo::load(&entry).unwrap();
    let recorded = meta.evaluations.len();
    let first = meta.evaluations[0].clone();
    assert_eq!(first.mujoco(), Some(blockpuzzle::sim::mj::version().as_str()));
    assert_eq!(first.task_sha256.as_deref(), Some(meta.task.hash.as_str()));
    let mut v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&entry).unwrap()).unwrap();
    v["evaluations"][0].as_object_mut().unwrap().remove("provenance");
    std::fs::write(&entry, serde_json::to_vec(&v).unwrap()).unwrap();
    let o = bp(&["zoo", "evaluate", "r", "--zoo", z.to_str().unwrap()]);
    assert!(o.status.success(), "{}", text(&o));
    let (meta, _) = blockpuzzle::benchmark::zoo::load(&entry).unwrap();
    assert_eq!(meta.evaluations.len(), recorded, "confirmed, not added: {:?}", meta.evaluations);
    assert!(meta.evaluations.contains(&first), "{:?}", meta.evaluations);
    // `zoo list` shows this engine's evaluations, and names the others.
    let mut v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&entry).unwrap()).unwrap();
    // The other engine's record (a consistent one: every record is checked), with other numbers.
    let engine = blockpuzzle::sim::mj::version();
    let theirs = blockpuzzle::benchmark::provenance::ENGINES.into_iter().find(|e| **e != engine).unwrap();
    let mut other = v["evaluations"][0].clone();
    other["provenance"]["mujoco"] = theirs.into();
    let episodes = other["episodes"].as_u64().unwrap();
    other["outcomes"] = serde_json::json!({"success": 0, "failure": 0, "unstable": 0, "no_contact": 0,
        "off_table": 0, "blue_met_grey": 0, "timeout": episodes});
    other["success_rate"] = 0.0.into();
    let ci = blockpuzzle::episode::outcome::wilson95(0, episodes as usize);
    other["ci95"] = serde_json::json!([ci.0, ci.1]);
    v["evaluations"].as_array_mut().unwrap().push(other);
    std::fs::write(&entry, serde_json::to_vec(&v).unwrap()).unwrap();
    let listed = text(&bp(&["zoo", "list", "--zoo", z.to_str().unwrap()]));
    assert!(
        listed.contains(&format!("r.json also has MuJoCo {theirs}")) && !listed.contains("normal: 0.000"),
        "{listed}"
    );
}

/// The committed leaderboard and the result files it is drawn from.
fn committed() -> (PathBuf, Vec<PathBuf>) {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let folders = std::fs::read_dir(root.join("results/generalization"))
        .unwrap()
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.is_dir() && p.file_name().is_some_and(|n| n.to_string_lossy().starts_with("mujoco-")))
        .collect::<Vec<_>>();
    (root.join("results/leaderboard.md"), folders)
}

#[test]
fn the_committed_leaderboard_is_what_its_result_files_give() {
    let (board, mut folders) = committed();
    folders.sort();
    assert!(folders.len() >= 2, "results for both engines: {folders:?}");
    let files: Vec<ResultFile> = results::read_all(&folders).unwrap();
    // Rebuilt with the command make leaderboard runs (paths relative to the checkout).
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let files: Vec<ResultFile> = files
        .into_iter()
        .map(|f| ResultFile { path: f.path.strip_prefix(root).unwrap().to_owned(), result: f.result })
        .collect();
    let md = results::leaderboard(&files).unwrap();
    let now = std::fs::read_to_string(&board).unwrap();
    assert!(now == md, "results/leaderboard.md is stale: run `make leaderboard`");
    for engine in ["2.2.2", "3.11.0"] {
        assert!(md.contains(&format!("` on MuJoCo {engine}")), "no table for MuJoCo {engine}");
    }
}

/// A validation suite's table says what its score is (the validation split's mean), and only a
/// validation suite's does.
#[test]
fn the_leaderboard_names_a_validation_suites_scored_split() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let files = results::read_all(&[root.join("results/generalist/validation")]).unwrap();
    assert!(files.len() >= 2 && files.iter().all(|f| f.result.scored_split() == "validation"));
    let md = results::leaderboard(&files).unwrap();
    assert!(md.contains("A validation suite: the score is the `validation` split's mean"), "{md}");
    let tests = results::read_all(&[root.join("results/generalization/mujoco-2.2.2")]).unwrap();
    assert!(!results::leaderboard(&tests).unwrap().contains("A validation suite"));
}

/// Issue 60: the readers recompute every derived number from the outcome counts and refuse a file whose
/// stored numbers disagree, naming the file and the field; rows must be the suite's own.
#[test]
fn results_recompute_every_number_and_refuse_edited_files() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let good = root.join("results/generalization/mujoco-2.2.2/baseline-scripted.cross-task-v2.json");
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&good).unwrap()).unwrap();
    assert!(results::read(&good).is_ok());
    let dir = tempfile::tempdir().unwrap();
    type Edit = fn(&mut serde_json::Value);
    let cases: [(&str, Edit, &str); 10] = [
        ("score", |v| v["score"] = 0.123.into(), "score: stored 0.123"),
        ("gap", |v| v["gap"] = (-5.0).into(), "gap: stored -5"),
        ("mean", |v| v["splits"][1]["mean_success"] = 1.0.into(), "splits[test].mean_success"),
        (
            "rate",
            |v| v["splits"][1]["rows"][0]["evaluation"]["success_rate"] = (-0.5).into(),
            "rows[0] (ReachAvoid-v0 normal).evaluation.success_rate",
        ),
        (
            "successes",
            |v| v["splits"][0]["rows"][1]["evaluation"]["successes"] = 0.into(),
            "evaluation.successes: 0, but the row says",
        ),
        (
            "episodes",
            |v| {
                v["splits"][0]["rows"][0]["episodes"] = 1_000_000_000_000_000u64.into();
                v["splits"][0]["rows"][0]["evaluation"]["episodes"] = 1_000_000_000_000_000u64.into();
            },
            "is not an evaluation's (1 to 1000000)",
        ),
        ("no splits", |v| v["splits"] = serde_json::json!([]), "no train split"),
        (
            "interval",
            |v| v["splits"][1]["rows"][2]["evaluation"]["ci95"] = serde_json::json!([0.0, 1.0]),
            "evaluation.ci95",
        ),
        (
            "outcomes",
            |v| v["splits"][1]["rows"][1]["evaluation"]["outcomes"]["timeout"] = 1000.into(),
            "outcomes (their sum)",
        ),
        (
            "a row dropped, the means made to agree",
            |v| {
                let rows = v["splits"][1]["rows"].as_array_mut().unwrap();
                rows.remove(2);
                let rates: Vec<f64> = rows.iter().map(|r| r["evaluation"]["success_rate"].as_f64().unwrap()).collect();
                let mean = rates.iter().sum::<f64>() / rates.len() as f64;
                let train = v["splits"][0]["mean_success"].as_f64().unwrap();
                v["splits"][1]["mean_success"] = mean.into();
                v["score"] = mean.into();
                v["gap"] = (train - mean).into();
            },
            "splits[test].rows: 2 rows, but the suite cross-task-v2's split has 3",
        ),
    ];
    for (name, edit, wanted) in cases {
        let mut w = v.clone();
        edit(&mut w);
        let f = dir.path().join(format!("{}.json", name.replace(' ', "-")));
        std::fs::write(&f, serde_json::to_vec(&w).unwrap()).unwrap();
        for command in ["leaderboard", "compare"] {
            let o = bp(&["results", command, f.to_str().unwrap()]);
            let t = text(&o);
            assert!(!o.status.success(), "{name} was accepted by results {command}: {t}");
            assert!(t.contains(wanted) && t.contains(f.to_str().unwrap()) && t.contains("eval --suite"), "{name}: {t}");
        }
    }
}

/// Issue 60: only like with like is ranked. A policy that skips rows is listed after every policy that
/// plays them all, unranked, whatever its score over the rows it played.
#[test]
fn the_leaderboard_ranks_only_policies_that_play_every_row() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("results/generalization/mujoco-2.2.2");
    let files: Vec<PathBuf> = ["BlocksChoose-v0-ddpg-ours", "BlocksChoose-v0-dagger-entity", "baseline-obs-hash"]
        .iter()
        .map(|p| root.join(format!("{p}.compose.json")))
        .collect();
    let read: Vec<ResultFile> = files.iter().map(|f| results::read(f).unwrap()).collect();
    let (partial, full) = (&read[0].result, &read[1].result);
    assert!(partial.coverage().0 < partial.coverage().1 && partial.score > full.score, "the case this tests");
    let md = results::leaderboard(&read).unwrap();
    let rows: Vec<&str> = md.lines().filter(|l| l.starts_with("| ") && l.contains("`[^")).collect();
    assert_eq!(rows.len(), 3, "{md}");
    assert!(rows[0].starts_with("| 1 | `BlocksChoose-v0-dagger-entity`") && rows[0].contains("| 32/32 |"), "{md}");
    assert!(rows[1].starts_with("| 2 | `baseline:obs-hash`"), "{md}");
    assert!(rows[2].starts_with("| – | `BlocksChoose-v0-ddpg-ours`") && rows[2].contains("| 12/32 |"), "{md}");
}

/// Results of the solver made by two solver versions are never put in one column; a policy's result
/// beside either solver's is (the policy's numbers are its own), and the footnote names the version.
#[test]
fn two_solver_versions_are_not_compared() {
    use blockpuzzle::benchmark::provenance::{PolicyId, Provenance, SOLVER_POLICY};
    let solver = |version: Option<u32>| {
        let mut p = Provenance::new(Harness::Cli, PolicyId { name: SOLVER_POLICY.to_owned(), sha256: None }, None);
        p.build.solver = version;
        p
    };
    assert_eq!(solver(None).build.solver_version(), 1, "a result without a solver version is version 1's");
    let now = solver(Some(blockpuzzle::policy::SOLVER_VERSION));
    let m = now.comparable(&solver(None)).unwrap_err();
    let current = blockpuzzle::policy::SOLVER_VERSION.to_string();
    assert!(m.field.contains("solver") && m.left == current && m.right == "1", "{m}");
    assert!(now.comparable(&now.clone()).is_ok());
    let mut policy = solver(None);
    policy.policy = PolicyId { name: "generalist-bc-entity".to_owned(), sha256: Some("sha256:00".to_owned()) };
    assert!(now.comparable(&policy).is_ok(), "a policy's result stands beside the solver of any version");
    assert!(now.markdown().contains(&format!("solver version {current}")), "{}", now.markdown());
    // What this build writes records its solver.
    let json = serde_json::to_value(&now).unwrap();
    assert_eq!(json["solver"], serde_json::json!(blockpuzzle::policy::SOLVER_VERSION));
}

/// Every file under `dir`, recursively, in sorted order.
fn files_under(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_owned()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else {
                out.push(p);
            }
        }
    }
    out.sort();
    out
}

/// Whether `text` names a commit of a build with uncommitted changes (40 hex digits, then `-dirty`).
fn names_a_dirty_build(text: &str) -> bool {
    text.match_indices("-dirty")
        .any(|(at, _)| at >= 40 && text[..at].bytes().rev().take(40).all(|b| b.is_ascii_hexdigit()))
}

/// Issue 74: a published figure comes from a clean build. No result file behind the leaderboard
/// (results/generalization/), the leaderboard itself, a zoo entry or a results file the README
/// links names a dirty build; every older log under results/ that does is listed as such in
/// results/dirty-builds.md, and that list names no file that is clean or gone.
#[test]
fn published_figures_come_from_clean_builds() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    assert!(names_a_dirty_build("commit `4752ce5bd11fe70324ce376264de90ca1702b188-dirty`"));
    assert!(!names_a_dirty_build("no `-dirty` commit") && !names_a_dirty_build("ab-dirty"));
    let read = |p: &Path| String::from_utf8_lossy(&std::fs::read(p).unwrap()).into_owned();
    let mut headline: Vec<PathBuf> = files_under(&root.join("results/generalization"));
    headline.push(root.join("results/leaderboard.md"));
    headline.extend(files_under(&root.join("zoo")).into_iter().filter(|p| p.extension().is_some_and(|e| e == "json")));
    let readme = read(&root.join("README.md"));
    for link in readme.split("](").skip(1).filter_map(|l| l.split(')').next()) {
        if link.starts_with("results/") && root.join(link).is_file() {
            headline.push(root.join(link));
        }
    }
    assert!(headline.len() > 300, "the published files were found: {}", headline.len());
    let dirty: Vec<&PathBuf> = headline.iter().filter(|p| names_a_dirty_build(&read(p))).collect();
    assert!(dirty.is_empty(), "published figures from a dirty build (re-make them from a clean one): {dirty:?}");

    let listed_in = root.join("results/dirty-builds.md");
    let list = read(&listed_in);
    let listed: std::collections::BTreeSet<String> = list
        .lines()
        .filter_map(|l| l.strip_prefix("- `").and_then(|l| l.split('`').next()))
        .map(str::to_owned)
        .collect();
    let found: std::collections::BTreeSet<String> = files_under(&root.join("results"))
        .into_iter()
        .filter(|p| *p != listed_in && names_a_dirty_build(&read(p)))
        .map(|p| p.strip_prefix(root).unwrap().to_string_lossy().into_owned())
        .collect();
    let unlisted: Vec<&String> = found.difference(&listed).collect();
    let stale: Vec<&String> = listed.difference(&found).collect();
    assert!(unlisted.is_empty(), "files naming a dirty build, not listed in results/dirty-builds.md: {unlisted:?}");
    assert!(stale.is_empty(), "results/dirty-builds.md lists files that are gone or name no dirty build: {stale:?}");
}

/// Issue 74: one result made by two builds (the command line's and the Python package's, say) keeps
/// each file's own build in its leaderboard footnote, not the first file's for all.
#[test]
fn a_leaderboard_footnote_names_each_files_build() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let good = root.join("results/generalization/mujoco-2.2.2/baseline-scripted.cross-task-v2.json");
    let first = results::read(&good).unwrap();
    let mut second = first.clone();
    second.path = PathBuf::from("elsewhere/baseline-scripted.cross-task-v2.json");
    second.result.provenance.build.commit = Some("0123456789abcdef0123456789abcdef01234567".to_owned());
    let md = results::leaderboard(&[first.clone(), second]).unwrap();
    let note = md.lines().find(|l| l.starts_with("[^")).unwrap();
    let own = first.result.provenance.build.maker();
    assert!(note.contains(&format!("made by {own}; `{}`", good.display())), "{note}");
    assert!(note.contains("(commit `0123456789abcdef0123456789abcdef01234567`); `elsewhere/"), "{note}");
}

/// Issue 75, one truth: the Python package's zoo reader, run without the extension, reads the core's
/// facts from python/blockpuzzle/facts.json (with the extension, `_native.facts()` gives the same
/// document); the file is the core's, byte for byte.
/// `BLOCKPUZZLE_WRITE_FACTS=1 cargo test --test it provenance::the_python` writes it.
#[test]
fn the_python_packages_facts_file_is_the_cores() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("python/blockpuzzle/facts.json");
    let want = blockpuzzle::benchmark::facts::facts_file().unwrap();
    if std::env::var_os("BLOCKPUZZLE_WRITE_FACTS").is_some() {
        std::fs::write(&path, &want).unwrap();
    }
    let have = std::fs::read_to_string(&path).unwrap_or_default();
    assert!(
        have == want,
        "{} is not the core's facts: write it with `BLOCKPUZZLE_WRITE_FACTS=1 cargo test --test it \
         provenance::the_python` (a new built-in task, format or engine changes it)",
        path.display()
    );
    let facts: serde_json::Value = serde_json::from_str(&want).unwrap();
    assert_eq!(facts["tasks"].as_object().unwrap().len(), blockpuzzle::env::registry::ids().len());
    assert_eq!(facts["zoo_format"], blockpuzzle::benchmark::zoo::FORMAT);
}
