//! Training under `mpirun` (Open MPI): ranks learn bit for bit what threads
//! learn, resume exactly, refuse another rank count, and a killed rank stops
//! the job without corrupting any checkpoint.
#![cfg(feature = "mpi")]

use blockpuzzle::benchmark::provenance::Build;
use blockpuzzle::learn::train::{checkpoint, rank_engines, RankBuild, RunDir, Span};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::time::{Duration, Instant};

const BP: &str = env!("CARGO_BIN_EXE_blockpuzzle");

/// A small DDPG run (TD3 and 3-step returns, so the per-shard noise streams are covered).
fn args(run: &Path, workers: usize, epochs: usize) -> Vec<String> {
    let s = format!(
        "train --algo ddpg --td3 --n-step 3 --env BlocksTouch-v0 --epochs {epochs} --cycles 3 --batches 4 \
         --batch-size 32 --test-episodes 2 --torch-threads 1 --seed 5 --workers {workers} --run-dir"
    );
    s.split_whitespace().map(str::to_owned).chain([run.display().to_string()]).collect()
}

fn mpirun(np: usize) -> Command {
    let mut c = Command::new("mpirun");
    // Root in containers and CI; more ranks than cores on small machines.
    c.env("OMPI_ALLOW_RUN_AS_ROOT", "1").env("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1");
    c.args(["--oversubscribe", "-np", &np.to_string(), BP]);
    c
}

fn ok(out: Output) -> Output {
    assert!(
        out.status.success(),
        "failed: {}\n{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

fn text(out: &Output) -> String {
    format!("{}{}", String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr))
}

/// progress.csv without the columns that measure time.
fn progress(run: &Path) -> Vec<Vec<String>> {
    let text = std::fs::read_to_string(run.join("progress.csv")).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    lines
        .map(|l| {
            l.split(',')
                .zip(&header)
                .filter(|(_, h)| !h.starts_with("time/") || **h == "time/env_steps" || **h == "time/updates")
                .map(|(v, _)| v.to_owned())
                .collect()
        })
        .collect()
}

fn policy_weights(run: &Path) -> serde_json::Value {
    let v: serde_json::Value = serde_json::from_slice(&std::fs::read(run.join("policy.json")).unwrap()).unwrap();
    v["policy"].clone()
}

/// The same per-epoch numbers (success, losses, steps) and the same weights, bit for bit.
fn assert_same_run(a: &Path, b: &Path, what: &str) {
    assert_eq!(progress(a), progress(b), "per-epoch numbers: {what}");
    assert_eq!(policy_weights(a), policy_weights(b), "weights: {what}");
}

#[test]
fn two_ranks_of_one_worker_learn_exactly_what_one_process_of_two_workers_learns() {
    let dir = tempfile::tempdir().unwrap();
    let (threads, ranks) = (dir.path().join("threads"), dir.path().join("ranks"));
    ok(Command::new(BP).args(args(&threads, 2, 2)).output().unwrap());
    ok(mpirun(2).args(args(&ranks, 1, 2)).output().unwrap());
    assert_same_run(&threads, &ranks, "2 ranks × 1 worker");
    // Rank 0 writes the run's files; rank 1 only its own checkpoint.
    assert!(ranks.join("rank-1/checkpoint.bin").exists());
    assert!(!ranks.join("rank-1/progress.csv").exists() && !ranks.join("rank-1/policy.json").exists());
    let s = checkpoint::peek_state(&ranks.join("rank-1/checkpoint.bin")).unwrap();
    assert_eq!((s.ranks, s.rank, s.epoch), (2, 1, 2));
    // Both ranks ran this build's engine: the run's record is one process's, with no per-rank engines.
    let spans = RunDir { dir: ranks.clone() }.read_provenance().unwrap();
    assert_eq!(spans, RunDir { dir: threads }.read_provenance().unwrap());
    assert!(spans.len() == 1 && spans[0].rank_engines.is_empty(), "{spans:?}");
}

/// The ranks of one job may run different engines (`mpirun -np 1 BIN : -np 1 BIN_MUJOCO3`): the
/// run's provenance then names each rank's engine. Different code is refused, naming both builds.
#[test]
fn a_job_may_mix_engines_but_not_code_and_records_each_ranks_engine() {
    let rank = |mujoco: &str, commit: &str, solver: u32, sources: &str| RankBuild {
        build: Build {
            blockpuzzle: "0.1.0".to_owned(),
            commit: Some(commit.to_owned()),
            mujoco: mujoco.to_owned(),
            solver: Some(solver),
        },
        sources: sources.to_owned(),
    };
    let build = |mujoco: &str, commit: &str, solver: u32| rank(mujoco, commit, solver, "0123");
    let one = [build("2.2.2", "abc", 5), build("2.2.2", "abc", 5)];
    assert_eq!(rank_engines(&one).unwrap(), Vec::<String>::new());
    let mixed = [build("2.2.2", "abc", 5), build("3.11.0", "abc", 5), build("2.2.2", "abc", 5)];
    let engines = rank_engines(&mixed).unwrap();
    assert_eq!(engines, ["2.2.2", "3.11.0", "2.2.2"]);
    let span = Span { from_epoch: 0, build: mixed[0].build.clone(), replay: None, rank_engines: engines };
    assert!(span
        .describe()
        .starts_with("MuJoCo 2.2.2 on rank 0, 3.11.0 on rank 1, 2.2.2 on rank 2 by blockpuzzle 0.1.0"));
    let back: Span = serde_json::from_str(&serde_json::to_string(&span).unwrap()).unwrap();
    assert_eq!(back, span);
    for (other, names) in [(build("3.11.0", "def", 5), "commit `def`"), (build("3.11.0", "abc", 4), "solver version 4")]
    {
        let err = rank_engines(&[mixed[0].clone(), other]).unwrap_err().to_string();
        assert!(err.contains("rank 1") && err.contains(names) && err.contains("one checkout"), "{err}");
    }
    // Two `-dirty` builds of one commit whose uncommitted changes differ: their sources tell them apart.
    let dirty = |mujoco: &str, sources: &str| rank(mujoco, "abc-dirty", 5, sources);
    assert_eq!(rank_engines(&[dirty("2.2.2", "0a"), dirty("3.11.0", "0a")]).unwrap(), ["2.2.2", "3.11.0"]);
    let err = rank_engines(&[dirty("2.2.2", "0a"), dirty("3.11.0", "0b")]).unwrap_err().to_string();
    assert!(err.contains("rank 1") && err.contains("different sources") && err.contains("0b"), "{err}");
    // What a rank sends is what rank 0 reads back.
    let me = RankBuild::current();
    assert_eq!(serde_json::from_slice::<RankBuild>(&serde_json::to_vec(&me).unwrap()).unwrap(), me);
    assert_eq!(me.sources.len(), 16, "{me:?}");
}

/// SAC, added through the algorithm trait, splits over ranks the same way:
/// its per-shard noise streams, temperature and twin critics included.
#[test]
fn sac_over_two_ranks_learns_exactly_what_one_process_of_two_workers_learns() {
    let dir = tempfile::tempdir().unwrap();
    let (threads, ranks) = (dir.path().join("threads"), dir.path().join("ranks"));
    let sac = |run: &Path, workers| {
        let mut a = args(run, workers, 2);
        let i = a.iter().position(|x| x == "--td3").unwrap();
        a.splice(i - 1..=i, ["sac".to_owned()]);
        a
    };
    ok(Command::new(BP).args(sac(&threads, 2)).output().unwrap());
    ok(mpirun(2).args(sac(&ranks, 1)).output().unwrap());
    assert_same_run(&threads, &ranks, "SAC, 2 ranks × 1 worker");
}

/// A stream of generated tasks over two ranks: rank 0 draws the pool and sends it, every rank
/// builds the same active set each epoch (a new one every epoch here), and the run is bit for bit
/// the one process's (the documented tolerance is none). The stream cache is a folder of the test's.
#[test]
fn a_stream_over_two_ranks_learns_exactly_what_one_process_of_two_workers_learns() {
    let dir = tempfile::tempdir().unwrap();
    let (threads, ranks) = (dir.path().join("threads"), dir.path().join("ranks"));
    let stream = |run: &Path, workers: usize| {
        let s = format!(
            "train --algo dagger --net entity --families gripper,push --generator-seeds 0..3 --active-tasks 2 \
             --epochs 2 --cycles 2 --batches 3 --batch-size 32 --test-episodes 2 --torch-threads 1 --seed 5 \
             --workers {workers} --run-dir"
        );
        s.split_whitespace().map(str::to_owned).chain([run.display().to_string()]).collect::<Vec<_>>()
    };
    let cache = dir.path().join("cache");
    let out = ok(Command::new(BP).args(stream(&threads, 2)).env("BLOCKPUZZLE_CACHE_DIR", &cache).output().unwrap());
    // Off a terminal (here, a pipe) the pool says how far it has come, a line per family.
    let err = String::from_utf8_lossy(&out.stderr);
    for line in ["stream pool: family gripper (1 of 2): 3 generator seeds, 3 checked", "family push (2 of 2)"] {
        assert!(err.contains(line), "{line:?} missing from: {err}");
    }
    // An empty cache on the ranks' side: rank 0 works the pool out again, the others receive it.
    let fresh = dir.path().join("cache-ranks");
    ok(mpirun(2).args(stream(&ranks, 1)).env("BLOCKPUZZLE_CACHE_DIR", &fresh).output().unwrap());
    assert_same_run(&threads, &ranks, "a stream, 2 ranks × 1 worker");
    let config = |run: &Path| -> serde_json::Value {
        serde_json::from_slice(&std::fs::read(run.join("config.json")).unwrap()).unwrap()
    };
    assert_eq!(config(&threads)["stream"], config(&ranks)["stream"]);
    assert!(config(&ranks)["stream"]["tasks"].as_array().unwrap().len() >= 4);
}

/// With three or four shards the order of the gradient sum matters in
/// floating point: it is the global shard order for any split into ranks.
#[test]
fn any_split_of_the_same_shards_into_ranks_learns_the_same_weights() {
    let dir = tempfile::tempdir().unwrap();
    // A multi-task run too: the task drawn per episode, the tasks tested in turn over the shards and
    // each task's test tally (summed over ranks) moving its own level, whatever the split.
    let two_tasks = |mut a: Vec<String>| {
        a.iter_mut().filter(|x| *x == "BlocksTouch-v0").for_each(|x| *x = "BlocksTouch-v0,BlocksChoose-v0".into());
        a.extend(["--success-threshold", "0"].map(String::from));
        a
    };
    for (np, workers, epochs, multi) in [(2, 2, 2, true), (3, 1, 1, false)] {
        let shards = np * workers;
        let threads = dir.path().join(format!("threads-{shards}"));
        let ranks = dir.path().join(format!("ranks-{np}x{workers}"));
        let tasks = |a: Vec<String>| if multi { two_tasks(a) } else { a };
        ok(Command::new(BP).args(tasks(args(&threads, shards, epochs))).output().unwrap());
        ok(mpirun(np).args(tasks(args(&ranks, workers, epochs))).output().unwrap());
        assert_same_run(&threads, &ranks, &format!("{np} ranks × {workers} workers"));
        if multi {
            let levels: Vec<usize> = progress(&ranks).iter().map(|row| row[1].parse().unwrap()).collect();
            assert_eq!(levels, [0, 2], "each task moved up after the first epoch");
        }
    }
}

#[test]
fn mpi_resume_is_exact_and_another_rank_count_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let (whole, split) = (dir.path().join("whole"), dir.path().join("split"));
    ok(mpirun(2).args(args(&whole, 1, 2)).output().unwrap());
    ok(mpirun(2).args(args(&split, 1, 1)).output().unwrap());
    ok(mpirun(2).args(args(&split, 1, 2)).arg("--resume").output().unwrap());
    assert_same_run(&whole, &split, "resumed");

    // One process cannot continue a two-rank run, nor can three ranks.
    let out = Command::new(BP).args(args(&split, 1, 3)).arg("--resume").output().unwrap();
    assert!(!out.status.success());
    assert!(text(&out).contains("mpirun -np 2"), "{}", text(&out));
    // Three ranks are told the job size that wrote the run, and the third rank creates nothing.
    let out = mpirun(3).args(args(&split, 1, 3)).arg("--resume").output().unwrap();
    assert!(!out.status.success());
    assert!(
        text(&out).contains("written by a job of 2 rank(s)") && text(&out).contains("mpirun -np 2"),
        "{}",
        text(&out)
    );
    assert!(!split.join("rank-2").exists(), "a refused rank leaves no folder");
}

#[test]
fn shared_replay_under_mpirun_is_refused_and_stops_every_rank() {
    let dir = tempfile::tempdir().unwrap();
    let started = Instant::now();
    let out = mpirun(2).args(args(&dir.path().join("r"), 1, 1)).args(["--replay", "shared"]).output().unwrap();
    assert!(!out.status.success());
    assert!(text(&out).contains("--replay per-worker"), "{}", text(&out));
    assert!(started.elapsed() < Duration::from_secs(60));
}

/// The rank processes started by `mpirun` (children carrying OMPI_COMM_WORLD_RANK).
fn rank_pid(mpirun_pid: u32, rank: usize) -> Option<i32> {
    let want = format!("OMPI_COMM_WORLD_RANK={rank}");
    let mut stack = vec![mpirun_pid as i32];
    while let Some(p) = stack.pop() {
        let Ok(children) = std::fs::read_to_string(format!("/proc/{p}/task/{p}/children")) else { continue };
        for c in children.split_whitespace().filter_map(|c| c.parse::<i32>().ok()) {
            let env = std::fs::read(format!("/proc/{c}/environ")).unwrap_or_default();
            if env.split(|&b| b == 0).any(|kv| kv == want.as_bytes()) {
                return Some(c);
            }
            stack.push(c);
        }
    }
    None
}

fn wait_timeout(child: &mut Child, limit: Duration) -> Option<std::process::ExitStatus> {
    let started = Instant::now();
    while started.elapsed() < limit {
        if let Some(s) = child.try_wait().unwrap() {
            return Some(s);
        }
        std::thread::sleep(Duration::from_millis(50));
    }
    None
}

#[test]
fn a_killed_rank_stops_the_job_leaves_valid_checkpoints_and_resume_continues() {
    let dir = tempfile::tempdir().unwrap();
    let (run, whole) = (dir.path().join("killed"), dir.path().join("whole"));
    let mut job = mpirun(2).args(args(&run, 1, 5)).stdout(Stdio::null()).stderr(Stdio::piped()).spawn().unwrap();
    // Once the first epoch is on disk, kill rank 1 in the middle of a later one.
    let started = Instant::now();
    while !run.join("rank-1/checkpoint.bin").exists() {
        assert!(started.elapsed() < Duration::from_secs(120), "the job never finished an epoch");
        std::thread::sleep(Duration::from_millis(20));
    }
    std::thread::sleep(Duration::from_millis(300));
    let pid = rank_pid(job.id(), 1).expect("rank 1's process");
    // SAFETY: kill(2) with a pid we just read and SIGKILL; no memory is involved.
    assert_eq!(unsafe { libc::kill(pid, libc::SIGKILL) }, 0);
    let status = wait_timeout(&mut job, Duration::from_secs(60)).expect("the job stops within 60 s of a rank's death");
    assert!(!status.success());
    let mut stderr = String::new();
    std::io::Read::read_to_string(job.stderr.as_mut().unwrap(), &mut stderr).unwrap();
    assert!(stderr.contains("signal 9") || stderr.contains("Killed") || stderr.contains("killed"), "{stderr}");

    // Every checkpoint left behind is whole (the previous ones too).
    let mut epochs = Vec::new();
    for f in [run.join("checkpoint.bin"), run.join("rank-1/checkpoint.bin")] {
        for path in [f.clone(), checkpoint::previous(&f)].into_iter().filter(|p| p.exists()) {
            let loaded = checkpoint::load(&path, "BlocksTouch-v0", 0, 0);
            assert!(!matches!(loaded, Err(checkpoint::CheckpointError::Corrupt { .. })), "{}", path.display());
        }
        epochs.push(checkpoint::peek_state(&f).unwrap().epoch);
    }
    assert!(epochs.iter().max().unwrap() - epochs.iter().min().unwrap() <= 1, "{epochs:?}");

    // --resume continues from the last epoch every rank completed, exactly.
    ok(mpirun(2).args(args(&run, 1, 5)).arg("--resume").output().unwrap());
    ok(mpirun(2).args(args(&whole, 1, 5)).output().unwrap());
    assert_same_run(&whole, &run, "resumed");
}

/// A rank that fails alone (its checkpoint is gone) stops the job with its reason instead of hanging.
#[test]
fn one_rank_failing_alone_stops_the_job_with_its_reason() {
    let dir = tempfile::tempdir().unwrap();
    let run: PathBuf = dir.path().join("r");
    ok(mpirun(2).args(args(&run, 1, 1)).output().unwrap());
    std::fs::remove_file(run.join("rank-1/checkpoint.bin")).unwrap();
    let mut job =
        mpirun(2).args(args(&run, 1, 2)).arg("--resume").stderr(Stdio::piped()).stdout(Stdio::null()).spawn().unwrap();
    let status = wait_timeout(&mut job, Duration::from_secs(60)).expect("no hang");
    assert!(!status.success());
    let mut stderr = String::new();
    std::io::Read::read_to_string(job.stderr.as_mut().unwrap(), &mut stderr).unwrap();
    assert!(stderr.contains("no checkpoint for rank 1"), "{stderr}");
}

/// A rank stopped after setting its checkpoint aside and before writing the
/// next one has only `checkpoint.prev.bin`: the job resumes from it, exactly.
#[test]
fn a_checkpoint_set_aside_but_not_yet_replaced_still_resumes() {
    let dir = tempfile::tempdir().unwrap();
    let (whole, cut) = (dir.path().join("whole"), dir.path().join("cut"));
    ok(mpirun(2).args(args(&whole, 1, 2)).output().unwrap());
    ok(mpirun(2).args(args(&cut, 1, 1)).output().unwrap());
    let latest = cut.join("rank-1/checkpoint.bin");
    std::fs::rename(&latest, checkpoint::previous(&latest)).unwrap();
    ok(mpirun(2).args(args(&cut, 1, 2)).arg("--resume").output().unwrap());
    assert_same_run(&whole, &cut, "resumed");
}

/// `--branch-from` under mpirun: rank 0 copies the parent (its rank
/// directories included) and every rank continues from its own checkpoint;
/// with nothing changed that is the parent's run continued, exactly.
#[test]
fn a_branch_under_mpirun_continues_every_rank_exactly() {
    let dir = tempfile::tempdir().unwrap();
    let (whole, parent, child) = (dir.path().join("whole"), dir.path().join("parent"), dir.path().join("child"));
    ok(mpirun(2).args(args(&whole, 1, 2)).output().unwrap());
    ok(mpirun(2).args(args(&parent, 1, 1)).output().unwrap());
    let out = ok(mpirun(2).args(args(&child, 1, 2)).arg("--branch-from").arg(&parent).output().unwrap());
    assert!(text(&out).contains("branched from"), "{}", text(&out));
    assert!(child.join("rank-1/checkpoint.bin").exists());
    assert_same_run(&whole, &child, "branched under mpirun");
    assert_eq!(progress(&parent).len(), 1, "the parent is left as it was");
}
