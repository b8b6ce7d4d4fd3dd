//! The tasks a run trains on: one (`--env ID`), several (`--env A,B,C`), or a suite's split
//! (`--suite procgen --split train`, generated tasks included). A multi-task run presents every
//! task in one observation layout (the most block slots of any, the others' padded with absent
//! rows), draws a task per exploration episode, and keeps a curriculum level per task.

use super::rundir::RunDir;
use super::{run_task, Result, TrainConfig};
use crate::env::registry;
use crate::task::{Task, TaskSource};

/// Whether `config` names more than one task (a list, or a suite split).
pub(crate) fn is_multi(config: &TrainConfig) -> bool {
    config.suite.is_some() || config.families.is_some() || config.env.contains(',')
}

/// The pool of a stream run (`--families`, `--generator-seeds`): generated on `threads` threads or
/// taken from the stream cache; on resume, checked against the pool recorded in `config.json`.
///
/// # Errors
/// An unknown family, held-out seeds, a stream without tasks, another pool than the recorded one.
fn stream_tasks(
    config: &TrainConfig,
    run: &RunDir,
    saved: Option<&TrainConfig>,
) -> Result<(Vec<Task>, crate::benchmark::stream::StreamRecord)> {
    let (Some(list), Some(range)) = (&config.families, config.generator_seeds) else {
        refuse!("--families and --generator-seeds go together: give both");
    };
    if let Some(saved) = saved.filter(|s| s.families.is_some()) {
        if saved.families != config.families || saved.generator_seeds != config.generator_seeds {
            let (f, g) = (saved.families.as_deref().unwrap_or(""), saved.generator_seeds.map(|r| r.to_string()));
            refuse!(
                "--resume: {} trains on the stream --families {f} --generator-seeds {}; this command asks for \
                 --families {list} --generator-seeds {range}; resume with the run's stream, or start a new run with \
                 another --run-dir",
                run.dir.display(),
                g.unwrap_or_default()
            );
        }
    }
    let families = match saved.and_then(|s| s.stream.as_ref()) {
        Some(recorded) => crate::benchmark::stream::recorded_families(list, recorded)?,
        None => crate::benchmark::stream::families(list)?,
    };
    let started = std::time::Instant::now();
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    let pool = crate::benchmark::stream::pool(
        &families,
        range,
        threads,
        crate::benchmark::stream::cache_dir().as_deref(),
        true,
    )?;
    eprintln!(
        "stream: {} tasks from {} famil{} × seeds {range} ({} seeds from the cache, {} checked by the solver, {} \
         without a task, {} left out as a suite's held-out task by content) in {:.1} s",
        pool.tasks.len(),
        families.len(),
        if families.len() == 1 { "y" } else { "ies" },
        pool.cached,
        pool.checked,
        pool.record.seeds_without_task,
        pool.record.seeds_held_out,
        started.elapsed().as_secs_f64()
    );
    if let Some(recorded) = saved.and_then(|s| s.stream.as_ref()) {
        let changed = recorded.differences(&pool.record);
        if !changed.is_empty() && recorded.same_families(&pool.record) {
            refuse!(
                "--resume: the stream's pool differs from the one recorded in {} ({}), though the families' files \
                 are unchanged: the solver's check kept other candidates than when the run started (another \
                 solver version or engine; provenance.json names the build that started it); resume with that \
                 build, or start a new run with another --run-dir",
                run.config().display(),
                changed.join("; ")
            );
        }
        if !changed.is_empty() {
            refuse!(
                "--resume: the stream's pool differs from the one recorded in {} ({}); restore the families' files, \
                 or start a new run with another --run-dir",
                run.config().display(),
                changed.join("; ")
            );
        }
    }
    Ok((pool.tasks, pool.record))
}

/// The ids or files of a comma-separated `--env` list, trimmed.
fn env_list(env: &str) -> Vec<&str> {
    env.split(',').map(str::trim).filter(|s| !s.is_empty()).collect()
}

/// The tasks `config` names today (a suite's rows of the split, each task once, in row order).
fn resolve(config: &TrainConfig) -> Result<Vec<Task>> {
    let tasks = match &config.suite {
        Some(name) => {
            if config.split == "test" || config.split == "validation" {
                refuse!(
                    "--split {0}: the {0} split is what a suite's score (a validation suite's: the choice of recipe) \
                     is measured on, so no policy trains on it (docs/suites.md); train on --split train (the default), \
                     or list the tasks you mean with --env A,B,... (its numbers on that suite are then no score to report)",
                    config.split
                );
            }
            let suite = crate::benchmark::suite::load(name)?;
            let Some(split) = suite.splits.iter().find(|s| s.name == config.split) else {
                let names: Vec<&str> = suite.splits.iter().map(|s| s.name.as_str()).collect();
                refuse!(
                    "--split {}: the suite {} has the splits {}; pass one of them",
                    config.split,
                    suite.name,
                    names.join(", ")
                );
            };
            let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
            suite.check_pinned(Some(&split.name), threads)?;
            split.rows.iter().map(|r| r.task.clone()).collect::<Vec<_>>()
        }
        None => {
            // A list means what it says: no empty item, no task twice (by id or by content).
            let items: Vec<&str> = config.env.split(',').map(str::trim).collect();
            if let Some(k) = items.iter().position(|s| s.is_empty()) {
                refuse!(
                    "--env {:?}: item {} of the list is empty; list task ids or files separated by single commas",
                    config.env,
                    k + 1
                );
            }
            let tasks = items.iter().map(|e| registry::task(e)).collect::<Result<Vec<_>, _>>()?;
            for (i, t) in tasks.iter().enumerate() {
                if let Some(j) = tasks[..i].iter().position(|u| u.source.hash == t.source.hash) {
                    refuse!(
                        "--env lists one task twice: {} and {} ({}) have the same content; list each task once",
                        items[j],
                        items[i],
                        t.id()
                    );
                }
            }
            tasks
        }
    };
    let mut unique: Vec<Task> = Vec::new();
    for t in tasks {
        if !unique.iter().any(|u| u.source.hash == t.source.hash) {
            unique.push(t);
        }
    }
    if unique.is_empty() {
        refuse!("--env {:?} names no task; give an id or task file (several comma-separated)", config.env);
    }
    Ok(unique)
}

/// The run's tasks: `--env` or `--suite` resolved; on resume of a multi-task run, checked against
/// the copies recorded in its `config.json` (`saved`): the same tasks, by content, in the same order.
///
/// # Errors
/// An unknown id, suite or split, a bad task file, a task that changed since the run started, or
/// settings that apply to one task only (`--counts`, `--expert`).
pub(crate) fn run_tasks(
    config: &TrainConfig,
    run: &RunDir,
    saved: Option<&TrainConfig>,
) -> Result<(Vec<Task>, Option<crate::benchmark::stream::StreamRecord>)> {
    if !is_multi(config) {
        return Ok((vec![run_task(config, run, saved)?], None));
    }
    if config.counts.is_some() {
        refuse!(
            "--counts applies to one task; a multi-task run (--suite or an --env list) takes each task's own counts"
        );
    }
    if config.aggrevated.expert.is_some() {
        refuse!("--expert: AggreVaTeD's expert plays one task; train it with one --env");
    }
    if config.families.is_some() {
        let (tasks, record) = stream_tasks(config, run, saved)?;
        return Ok((tasks, Some(record)));
    }
    let tasks = resolve(config)?;
    if let Some(recorded) = saved.map(|s| &s.tasks).filter(|r| !r.is_empty()) {
        let now: Vec<&TaskSource> = tasks.iter().map(|t| &t.source).collect();
        if now.len() != recorded.len() || now.iter().zip(recorded).any(|(a, b)| a.hash != b.hash) {
            let changed: Vec<String> = recorded
                .iter()
                .filter(|r| !now.iter().any(|n| n.hash == r.hash))
                .map(|r| r.id.clone())
                .chain(now.iter().filter(|n| !recorded.iter().any(|r| r.hash == n.hash)).map(|n| n.id.clone()))
                .collect();
            refuse!(
                "--resume: the tasks of {} differ from those recorded in {} ({}); resume with the run's tasks, or \
                 start a new run with another --run-dir",
                config.task_id(),
                run.config().display(),
                if changed.is_empty() { "their order".to_owned() } else { changed.join(", ") }
            );
        }
    }
    Ok((tasks, None))
}

/// A multi-task run's name for its tasks: `SUITE-SPLIT`, `FAMILIES-FIRST-END` for a stream (the
/// families joined by `+`), or the ids joined by `+`.
pub(crate) fn label(config: &TrainConfig) -> String {
    if let (Some(families), Some(range)) = (&config.families, config.generator_seeds) {
        let names: Vec<String> = families.split(',').map(str::trim).filter(|s| !s.is_empty()).map(env_name).collect();
        return format!("{}-{}-{}", names.join("+"), range.0[0], range.0[1]);
    }
    match &config.suite {
        Some(s) => {
            let stem = std::path::Path::new(s).file_stem().map_or(s.clone(), |x| x.to_string_lossy().into_owned());
            format!("{stem}-{}", config.split)
        }
        None if !config.tasks.is_empty() => config.tasks.iter().map(|t| t.id.as_str()).collect::<Vec<_>>().join("+"),
        None => env_list(&config.env).into_iter().map(env_name).collect::<Vec<_>>().join("+"),
    }
}

/// How a run names an `--env` value before its task is resolved: the id, or a task file's stem.
pub(crate) fn env_name(env: &str) -> String {
    if registry::is_path(env) {
        std::path::Path::new(env).file_stem().map_or(env.to_owned(), |x| x.to_string_lossy().into_owned())
    } else {
        env.to_owned()
    }
}

/// The task of exploration episode `seed` among `n` (uniform, from a stream of its own; 0 for one task).
pub(crate) fn draw_task(seed: u64, n: usize) -> usize {
    use rand::{Rng, SeedableRng};
    if n <= 1 {
        return 0;
    }
    rand_chacha::ChaCha8Rng::seed_from_u64(super::stream_seed(seed, &[7])).gen_range(0..n)
}

/// The task of test (or finals) episode `k` of global worker `shard` in `epoch`: the tasks in turn,
/// continuing from epoch to epoch, so every task is tested as often as any other.
pub(crate) fn test_task(epoch: usize, shards: usize, per_worker: usize, shard: usize, k: usize, n: usize) -> usize {
    (epoch * shards * per_worker + shard * per_worker + k) % n.max(1)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tasks_are_drawn_uniformly_and_tested_in_turn() {
        let mut counts = [0usize; 4];
        for s in 0..4000 {
            counts[draw_task(s, 4)] += 1;
        }
        assert!(counts.iter().all(|&c| (900..1100).contains(&c)), "{counts:?}");
        assert!((0..100).all(|s| draw_task(s, 1) == 0));
        // 2 workers × 3 episodes per epoch over 4 tasks: every task once before any twice.
        let order: Vec<usize> =
            (0..2).flat_map(|e| (0..2).flat_map(move |w| (0..3).map(move |k| test_task(e, 2, 3, w, k, 4)))).collect();
        assert_eq!(order, [0, 1, 2, 3, 0, 1, 2, 3, 0, 1, 2, 3]);
    }
}
