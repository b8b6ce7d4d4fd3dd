//! What the page reads and asks, as JSON: the built-in tasks, families and their draws, suites, the
//! zoo, the leaderboard and the files of the app's folders; task checks and saves. Every answer is
//! made by the library's own code (the registry, `Family::draw`, `suite::load`, `zoo::read_meta`,
//! `results::read_all`, `episode::check`, the one writer); a failure is an answer with a message,
//! never a blank page.

use super::files::Roots;
use crate::benchmark::{results, suite, zoo};
use crate::task::family::{Family, BUILTIN_FAMILIES};
use crate::task::Task;
use serde_json::{json, Value};
use std::path::PathBuf;
use std::sync::OnceLock;

/// The largest task or family text the page may send, in bytes (the built-in ones are under 4 kB).
pub const MAX_TEXT_BYTES: usize = 64 << 10;
/// Draws of each family the gallery shows.
pub const DRAWS: u64 = 3;
/// Resets per level and distribution when the editor checks a task (`task check` does 50).
pub const CHECK_SAMPLES: u64 = 4;

/// An answer: a status and a JSON body.
#[derive(Debug)]
pub struct Answer {
    /// HTTP status.
    pub status: u16,
    /// The body.
    pub body: Value,
}

impl Answer {
    /// 200 with `body`.
    pub fn ok(body: Value) -> Answer {
        Answer { status: 200, body }
    }
    /// `status` with `{"error": message}`.
    pub fn error(status: u16, message: impl Into<String>) -> Answer {
        Answer { status, body: json!({ "error": message.into() }) }
    }
}

/// What the API serves from: the folders, the policies and results the app was started with.
#[derive(Debug)]
pub struct Catalogue {
    /// The folders it may read.
    pub roots: Roots,
    /// `(label, what load::resolve takes)` of every policy offered.
    pub policies: Vec<(String, PathBuf)>,
    /// Folders of suite results.
    pub results: Vec<PathBuf>,
    leaderboard: OnceLock<Value>,
    suites: OnceLock<Value>,
    families: OnceLock<Value>,
}

impl Catalogue {
    /// The catalogue of `roots`, offering the solver, random actions, every zoo entry and
    /// `policies` (already checked to load).
    pub fn new(roots: Roots, policies: &[PathBuf], results: Vec<PathBuf>) -> Catalogue {
        let mut offered = vec![
            ("solver".to_owned(), PathBuf::from("scripted")),
            ("random".to_owned(), PathBuf::from("random")),
            ("obs-hash".to_owned(), PathBuf::from("obs-hash")),
        ];
        for name in zoo::names(&zoo::dir()) {
            offered.push((format!("zoo: {name}"), PathBuf::from(name)));
        }
        for p in policies {
            offered.push((p.display().to_string(), p.clone()));
        }
        Catalogue {
            roots,
            policies: offered,
            results,
            leaderboard: OnceLock::new(),
            suites: OnceLock::new(),
            families: OnceLock::new(),
        }
    }

    /// The policy the page names by label.
    pub fn policy(&self, label: &str) -> Option<&PathBuf> {
        self.policies.iter().find(|(l, _)| l == label).map(|(_, p)| p)
    }

    /// `GET /api/policies`.
    pub fn policies(&self) -> Answer {
        Answer::ok(json!(self.policies.iter().map(|(l, _)| l).collect::<Vec<_>>()))
    }

    /// `GET /api/scene`: what the editor's top-down view draws: the table's centre and half sides
    /// and where the gripper starts (x, y), metres.
    pub fn scene(&self) -> Answer {
        use crate::sim::scene::xml::{TABLE_CENTER, TABLE_HALF};
        let gripper = crate::env::registry::make("BlocksTouch-v0").and_then(|mut env| {
            env.reset(Some(0))?;
            Ok(env.gripper_position())
        });
        match gripper {
            Ok(g) => {
                Answer::ok(json!({ "table_center": TABLE_CENTER, "table_half": TABLE_HALF, "gripper": [g[0], g[1]] }))
            }
            Err(e) => Answer::error(500, e.to_string()),
        }
    }

    /// `GET /api/tasks`: every built-in task with its summary, shape and text.
    pub fn tasks(&self) -> Answer {
        let mut out = Vec::new();
        for id in crate::env::registry::ids() {
            match crate::env::registry::task(id) {
                Ok(t) => out.push(describe(&t)),
                Err(e) => out.push(json!({ "id": id, "error": e.to_string() })),
            }
        }
        Answer::ok(Value::Array(out))
    }

    /// `GET /api/families`: every built-in family with its summary, text and first draws.
    pub fn families(&self) -> Answer {
        Answer::ok(
            self.families
                .get_or_init(|| {
                    let all = BUILTIN_FAMILIES.iter().map(|(name, text)| {
                        let family = match Family::from_toml(text, &format!("families/{name}.toml (built in)")) {
                            Ok(f) => f,
                            Err(e) => return json!({ "name": name, "error": e.to_string() }),
                        };
                        let draws = draws(&family);
                        json!({
                            "name": name, "summary": family.spec.summary, "hash": family.hash, "text": text,
                            "draws": draws,
                        })
                    });
                    Value::Array(all.collect())
                })
                .clone(),
        )
    }

    /// `GET /api/suites`: every built-in suite, its splits and rows.
    pub fn suites(&self) -> Answer {
        Answer::ok(
            self.suites
                .get_or_init(|| {
                    let all = suite::BUILTIN.iter().map(|(name, _)| match suite::load(name) {
                        Ok(s) => json!({
                            "name": s.name, "summary": s.summary, "sha256": s.sha256,
                            "splits": s.splits.iter().map(|sp| json!({
                                "name": sp.name,
                                "rows": sp.rows.iter().map(|r| json!({
                                    "task": r.task.id(), "summary": r.task.spec.summary, "source": r.source,
                                    "distribution": r.distribution, "level": r.level, "seed": r.seed,
                                    "episodes": r.episodes,
                                })).collect::<Vec<_>>(),
                            })).collect::<Vec<_>>(),
                        }),
                        Err(e) => json!({ "name": name, "error": e.to_string() }),
                    });
                    Value::Array(all.collect())
                })
                .clone(),
        )
    }

    /// The task of row `row` of split `split` of built-in suite `name`.
    ///
    /// # Errors
    /// An unknown suite, split or row, named.
    pub fn suite_row(
        &self,
        name: &str,
        split: &str,
        row: usize,
    ) -> Result<(Task, crate::benchmark::suite::Row), String> {
        if !suite::BUILTIN.iter().any(|(n, _)| *n == name) {
            return Err(format!(
                "{name:?} is no built-in suite ({}); only those are played here",
                suite::builtin_names()
            ));
        }
        let s = suite::load(name).map_err(|e| e.to_string())?;
        let sp = s.splits.iter().find(|sp| sp.name == split).ok_or_else(|| {
            format!("suite {name} has no split {split:?} (it has {})", names(s.splits.iter().map(|x| x.name.as_str())))
        })?;
        let r = sp
            .rows
            .get(row)
            .ok_or_else(|| format!("split {split} of {name} has {} rows; no row {row}", sp.rows.len()))?;
        Ok((r.task.clone(), r.clone()))
    }

    /// `GET /api/zoo`: every entry with what it records.
    pub fn zoo(&self) -> Answer {
        let dir = zoo::dir();
        let entries = zoo::names(&dir).into_iter().map(|name| {
            let path = dir.join(format!("{name}.json"));
            match zoo::read_meta(&path) {
                Ok(m) => json!({
                    "name": name, "description": m.description, "algo": m.algo, "solver": m.solver,
                    "obs_mode": m.obs_mode, "trained_on": m.trained_on(), "epoch": m.epoch,
                    "evaluations": m.evaluations.iter().map(|e| json!({
                        "env": e.env, "distribution": e.distribution, "episodes": e.episodes,
                        "success_rate": e.success_rate, "mujoco": e.mujoco(),
                    })).collect::<Vec<_>>(),
                }),
                Err(e) => json!({ "name": name, "error": e.to_string() }),
            }
        });
        Answer::ok(Value::Array(entries.collect()))
    }

    /// `GET /api/leaderboard`: one board per suite and engine, each row recomputed from its file's
    /// outcome counts by `benchmark::results` (files that do not read are listed with their error).
    pub fn leaderboard(&self) -> Answer {
        Answer::ok(self.leaderboard.get_or_init(|| leaderboard(&self.results)).clone())
    }

    /// `GET /api/files`: the task and family files of the app's folders.
    pub fn files(&self) -> Answer {
        let folders: Vec<String> = self.roots.folders().iter().map(|f| f.display().to_string()).collect();
        let files: Vec<Value> =
            self.roots.list("toml").into_iter().map(|(i, p)| json!({ "folder": i, "path": p })).collect();
        Answer::ok(json!({ "folders": folders, "files": files }))
    }

    /// `GET /api/file?folder=I&path=P`: a file's text and its check.
    pub fn file(&self, folder: usize, path: &str) -> Answer {
        let file = match self.roots.resolve(folder, path) {
            Ok(f) => f,
            Err(e @ super::files::FileError::Missing { .. }) => return Answer::error(404, e.to_string()),
            Err(e) => return Answer::error(403, e.to_string()),
        };
        match crate::support::io::read_text(&file, "task or family file", MAX_TEXT_BYTES as u64) {
            Ok(text) => {
                let check = check_text(&text, &file.display().to_string(), 0);
                Answer::ok(json!({ "path": path, "text": text, "check": check }))
            }
            Err(e) => Answer::error(400, format!("{}: {e}", file.display())),
        }
    }

    /// `POST /api/save?name=N`: saves a task or family text as `N` in the first folder, through the
    /// one writer, after checking that it parses as the command line will read it. An existing file
    /// is replaced only with `overwrite`.
    pub fn save(&self, name: &str, text: &str, overwrite: bool) -> Answer {
        let path = match self.roots.save_path(name) {
            Ok(p) => p,
            Err(e) => return Answer::error(400, e.to_string()),
        };
        let check = check_text(text, name, 0);
        if check["ok"] != json!(true) {
            return Answer {
                status: 422,
                body: json!({ "error": "not saved: the text does not check", "check": check }),
            };
        }
        // Only a plain file of the folder is replaced: a link (which may lead out of the folder), a
        // pipe or a device in its place is left alone.
        if let Ok(meta) = std::fs::symlink_metadata(&path) {
            if !meta.file_type().is_file() {
                return Answer::error(
                    409,
                    format!("{} exists and is not a regular file (a link, folder, pipe or device): it is left alone; give another name", path.display()),
                );
            }
        }
        if path.exists() && !overwrite {
            return Answer::error(
                409,
                format!("{} exists; tick overwrite to replace it, or give another name", path.display()),
            );
        }
        match crate::support::io::write_file(&path, text.as_bytes()) {
            Ok(()) => Answer::ok(json!({ "saved": path.display().to_string(), "check": check })),
            Err(e) => Answer::error(500, format!("not saved: {e}")),
        }
    }
}

/// The task a family's generator seed gives the page: its first candidate that compiles and
/// resets (what `task generate` keeps is the first that also passes the solver's check, which
/// takes seconds; the page shows a draw at once), and that candidate's number.
///
/// # Errors
/// No candidate of the family's `max_candidates` compiles and resets: the first one's message.
pub fn first_draw(f: &Family, seed: u64) -> Result<(Task, usize), String> {
    let mut first = None;
    for c in 0..f.spec.check.max_candidates.max(1) {
        let resets = f.draw(seed, c).map_err(|e| e.to_string()).and_then(|d| {
            let mut env =
                crate::env::BlockEnv::new(crate::env::EnvConfig::new(d.task.clone())).map_err(|e| e.to_string())?;
            env.set_level(env.max_level()).map_err(|e| e.to_string())?;
            env.reset(Some(0)).map_err(|e| e.to_string())?;
            Ok(d.task)
        });
        match resets {
            Ok(task) => return Ok((task, c)),
            Err(e) => {
                first.get_or_insert(e);
            }
        }
    }
    Err(first.unwrap_or_else(|| "the family draws no task".into()))
}

/// The first [`DRAWS`] draws of `f` (generator seeds 1, 2, ...), as the page lists them.
fn draws(f: &Family) -> Vec<Value> {
    (1..=DRAWS)
        .map(|seed| match first_draw(f, seed) {
            Ok((t, c)) => json!({ "seed": seed, "id": t.id(), "candidate": c, "summary": t.spec.summary }),
            Err(e) => json!({ "seed": seed, "error": e }),
        })
        .collect()
}

/// A task as the page shows it.
pub fn describe(t: &Task) -> Value {
    json!({
        "id": t.id(), "summary": t.spec.summary, "objects": t.object_count(), "max_level": t.max_level(),
        "distributions": t.distribution_names(), "hash": t.source.hash, "text": t.source.toml,
        "max_steps": t.spec.max_episode_steps,
    })
}

fn names<'a>(it: impl Iterator<Item = &'a str>) -> String {
    it.collect::<Vec<_>>().join(", ")
}

/// Whether a text is a family file (it names its family) rather than a task file.
pub fn is_family(text: &str) -> bool {
    text.parse::<toml::Table>().is_ok_and(|t| t.contains_key("family"))
}

/// The check of a task or family text, as `task check` and `task generate` make it: the compiler's
/// error with its line, or for a task the resets of every level and distribution (`samples` each;
/// 0: compile only), for a family its first draws.
pub fn check_text(text: &str, origin: &str, samples: u64) -> Value {
    if text.len() > MAX_TEXT_BYTES {
        return json!({ "ok": false, "error": format!("{origin}: longer than {MAX_TEXT_BYTES} bytes") });
    }
    if is_family(text) {
        return match Family::from_toml(text, origin) {
            Ok(f) => {
                json!({ "ok": true, "kind": "family", "id": f.spec.family, "summary": f.spec.summary, "draws": draws(&f) })
            }
            Err(e) => json!({ "ok": false, "kind": "family", "error": e.to_string() }),
        };
    }
    let task = match Task::parse(text, origin, None) {
        Ok(t) => t,
        Err(e) => return json!({ "ok": false, "kind": "task", "error": e.to_string() }),
    };
    let id = task.id().to_owned();
    let summary = task.spec.summary.clone();
    if samples == 0 {
        return json!({ "ok": true, "kind": "task", "id": id, "summary": summary });
    }
    match crate::episode::check::check(task, samples, 0, &mut || {}) {
        Ok(report) => json!({
            "ok": report.ok(), "kind": "task", "id": id, "summary": summary,
            "lines": report.levels.iter().map(|l| l.line()).collect::<Vec<_>>(),
            "error": report.levels.iter().find_map(|l| l.error.as_ref().map(|e| format!("{}: {e}", l.label))),
        }),
        Err(e) => json!({ "ok": false, "kind": "task", "id": id, "error": e.to_string() }),
    }
}

/// One policy's row of a board: its numbers (recomputed from the first of its files, which all agree),
/// the files and the test episodes it failed.
fn board_row(same: &[&results::ResultFile]) -> Value {
    let r = &same[0].result;
    let (done, all) = r.coverage();
    let train = r.train_mean();
    let ci = results::score_interval(r);
    let failures: Vec<Value> = r
        .splits
        .iter()
        .filter(|s| s.name == r.scored_split())
        .flat_map(|s| {
            s.rows.iter().enumerate().filter_map(move |(k, row)| {
                let e = row.evaluation.as_ref()?;
                (e.successes < e.episodes).then(|| {
                    json!({ "split": s.name, "row": k, "task": row.task, "seed": row.seed,
                            "episodes": e.episodes, "successes": e.successes })
                })
            })
        })
        .collect();
    let files: Vec<String> =
        same.iter().filter_map(|f| f.path.file_name().map(|n| n.to_string_lossy().into_owned())).collect();
    json!({
        "policy": r.policy, "score": r.score, "ci": ci.map(|(lo, hi)| [lo, hi]), "train": train, "gap": r.gap,
        "rows": done, "of": all, "files": files, "failures": failures,
    })
}

fn leaderboard(folders: &[PathBuf]) -> Value {
    let mut errors = Vec::new();
    let mut files = Vec::new();
    for f in folders {
        // One folder per engine below a results folder, or result files in it directly.
        let mut dirs = vec![f.clone()];
        if let Ok(rd) = std::fs::read_dir(f) {
            let mut subs: Vec<PathBuf> = rd.flatten().map(|e| e.path()).filter(|p| p.is_dir()).collect();
            subs.sort();
            dirs.extend(subs);
        }
        for d in dirs {
            match results::read_all(std::slice::from_ref(&d)) {
                Ok(v) => files.extend(v),
                Err(results::ResultsError::NoFiles { .. }) => {}
                Err(e) => errors.push(format!("{}: {e}", d.display())),
            }
        }
    }
    // The leaderboard's own grouping and ranking, conflict check included: a board whose policy has
    // two different numbers is an error here as on the command line; the other boards stand.
    let mut boards = Vec::new();
    for board in results::boards(&files) {
        match board {
            Ok(b) => boards.push(json!({
                "suite": b.suite, "engine": b.mujoco, "sha256": b.sha256,
                "rows": b.policies.iter().map(|same| board_row(same)).collect::<Vec<_>>(),
            })),
            Err(e) => errors.push(e.to_string()),
        }
    }
    json!({ "boards": boards, "errors": errors, "folders": folders })
}
