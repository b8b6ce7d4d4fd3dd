//! `blockpuzzle serve`, the browser app: started as a user starts it (the binary, a free port), and
//! talked to over loopback as a browser does; then driven in headless Chromium (Debian's, through
//! its ChromeDriver) from the gallery to the editor.

use super::common::{blockpuzzle, skipped};
use serde_json::Value;
use std::io::{BufRead, BufReader, Read, Write};
use std::net::TcpStream;
use std::path::{Path, PathBuf};
use std::process::{Child, Stdio};
use std::time::{Duration, Instant};

/// A running app, stopped when dropped.
struct App {
    child: Child,
    port: u16,
    /// Its standard error (its log), in a file: a pipe nobody reads would stall it once full.
    log: tempfile::NamedTempFile,
}

impl App {
    fn start(args: &[&str]) -> App {
        let log = tempfile::NamedTempFile::new().unwrap();
        let mut cmd = blockpuzzle(&["serve", "--port", "0"]);
        cmd.args(args).stdout(Stdio::piped()).stderr(log.reopen().unwrap());
        let mut child = cmd.spawn().expect("serve starts");
        let mut line = String::new();
        BufReader::new(child.stdout.take().unwrap()).read_line(&mut line).unwrap();
        let port = line
            .rsplit_once("127.0.0.1:")
            .or_else(|| line.rsplit_once("]:"))
            .and_then(|(_, rest)| rest.split('/').next())
            .and_then(|p| p.parse().ok())
            .unwrap_or_else(|| {
                let err = std::fs::read_to_string(log.path()).unwrap_or_default();
                panic!("serve printed {line:?}, not its address; stderr: {err}")
            });
        App { child, port, log }
    }

    /// What it has logged so far.
    fn log(&self) -> String {
        std::fs::read_to_string(self.log.path()).unwrap_or_default()
    }

    fn url(&self, path: &str) -> String {
        format!("http://127.0.0.1:{}{path}", self.port)
    }

    /// One request (HTTP/1.0, so the answer ends with the connection): status and body.
    fn request(&self, method: &str, path: &str, body: &[u8]) -> (u16, Vec<u8>) {
        request(self.port, method, path, body)
    }

    fn json(&self, method: &str, path: &str, body: &str) -> (u16, Value) {
        let (status, bytes) = self.request(method, path, body.as_bytes());
        let v = serde_json::from_slice(&bytes)
            .unwrap_or_else(|e| panic!("{path}: {status} {e}: {}", String::from_utf8_lossy(&bytes)));
        (status, v)
    }

    fn get(&self, path: &str) -> (u16, Value) {
        self.json("GET", path, "")
    }
}

impl Drop for App {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

fn request(port: u16, method: &str, path: &str, body: &[u8]) -> (u16, Vec<u8>) {
    let mut s = TcpStream::connect(("127.0.0.1", port)).expect("the app accepts");
    s.set_read_timeout(Some(Duration::from_secs(120))).unwrap();
    let head = format!("{method} {path} HTTP/1.0\r\nHost: 127.0.0.1\r\nContent-Length: {}\r\n\r\n", body.len());
    s.write_all(head.as_bytes()).unwrap();
    s.write_all(body).unwrap();
    let mut out = Vec::new();
    s.read_to_end(&mut out).expect("an answer");
    let split = out.windows(4).position(|w| w == b"\r\n\r\n").unwrap_or_else(|| {
        panic!("{method} {path}: no answer, {} bytes: {:?}", out.len(), String::from_utf8_lossy(&out))
    });
    let status: u16 = String::from_utf8_lossy(&out[9..12]).parse().expect("a status");
    (status, out[split + 4..].to_vec())
}

/// The lines of an episode's stream.
fn episode(app: &App, query: &str) -> Vec<Value> {
    let (status, body) = app.request("GET", &format!("/api/play?{query}"), b"");
    let text = String::from_utf8(body).unwrap();
    assert_eq!(status, 200, "{query}: {text}");
    text.lines().map(|l| serde_json::from_str(l).unwrap()).collect()
}

fn temp() -> tempfile::TempDir {
    tempfile::tempdir().unwrap()
}

#[test]
fn the_app_serves_its_page_and_the_libraries_catalogue() {
    let dir = temp();
    let app = App::start(&["--dir", dir.path().to_str().unwrap()]);
    let (status, page) = app.request("GET", "/", b"");
    assert_eq!(status, 200);
    let page = String::from_utf8(page).unwrap();
    assert!(page.contains("<title>BlockPuzzle</title>") && page.contains("/app.js"), "{page}");
    for asset in ["/app.js", "/app.css"] {
        let (status, body) = app.request("GET", asset, b"");
        assert!(status == 200 && body.len() > 1000, "{asset}: {status}");
    }
    let (_, tasks) = app.get("/api/tasks");
    let ids: Vec<&str> = tasks.as_array().unwrap().iter().map(|t| t["id"].as_str().unwrap()).collect();
    assert_eq!(ids, blockpuzzle::env::registry::ids());
    let (_, families) = app.get("/api/families");
    let families = families.as_array().unwrap();
    assert_eq!(families.len(), blockpuzzle::task::family::BUILTIN_FAMILIES.len());
    for f in families {
        let draws = f["draws"].as_array().unwrap();
        assert_eq!(draws.len(), 3, "{f}");
        assert!(draws.iter().all(|d| d["id"].as_str().is_some_and(|id| id.ends_with("-v0"))), "{f}");
    }
    let (_, suites) = app.get("/api/suites");
    let names: Vec<&str> = suites.as_array().unwrap().iter().map(|s| s["name"].as_str().unwrap()).collect();
    assert_eq!(names, blockpuzzle::benchmark::suite::BUILTIN.iter().map(|(n, _)| *n).collect::<Vec<_>>());
    let (_, zoo) = app.get("/api/zoo");
    let zoo_dir = blockpuzzle::benchmark::zoo::dir();
    assert_eq!(zoo.as_array().unwrap().len(), blockpuzzle::benchmark::zoo::names(&zoo_dir).len());
    assert!(zoo.as_array().unwrap().iter().all(|z| z.get("error").is_none()), "{zoo}");
    let (_, policies) = app.get("/api/policies");
    assert_eq!(policies[0], "solver");
    let (status, scene) = app.get("/api/scene");
    assert_eq!(status, 200);
    assert_eq!(scene["table_center"], serde_json::json!([1.3, 0.75]));
    // A thumbnail is a PNG of the asked side.
    let (status, png) = app.request("GET", "/api/still?task=BlocksAvoid-v0&side=64", b"");
    assert_eq!(status, 200);
    assert!(png.starts_with(b"\x89PNG"), "not a PNG");
    assert_eq!(u32::from_be_bytes(png[16..20].try_into().unwrap()), 64);
}

#[test]
fn an_episode_streams_frame_by_frame_to_its_verdict() {
    let dir = temp();
    let app = App::start(&["--dir", dir.path().to_str().unwrap()]);
    let lines = episode(&app, "task=BlocksTouch-v0&policy=solver&seed=0&side=48");
    let (start, end) = (&lines[0], lines.last().unwrap());
    assert_eq!(start["type"], "start");
    assert_eq!(start["task"], "BlocksTouch-v0");
    assert_eq!(start["engine"], blockpuzzle::sim::mj::version());
    assert_eq!(end["type"], "end");
    assert_eq!(end["outcome"], "success");
    let frames: Vec<&Value> = lines.iter().filter(|l| l["type"] == "frame").collect();
    assert_eq!(frames.len() as u64, end["steps"].as_u64().unwrap());
    assert_eq!(end["decided_at"], end["steps"], "the solver's episode ends when it is decided");
    assert!(
        end["contacts"].as_array().unwrap().iter().any(|p| p[0] == "blue" && p[1] == "green"),
        "the contact that decided it is named: {end}"
    );
    for l in lines.iter().filter(|l| l.get("image").is_some()) {
        assert!(l["image"].as_str().unwrap().starts_with("data:image/png;base64,iVBOR"));
    }
    // The episode is the library's: the same seed gives the same steps and outcome as `rollout`.
    let mut env = blockpuzzle::make("BlocksTouch-v0").unwrap();
    env.set_level(env.max_level()).unwrap();
    let mut solver = blockpuzzle::policy::ScriptedPolicy::solver(env.obs_spec().max_objects);
    let ep = blockpuzzle::episode::rollout::run_episode(&mut env, &mut solver, 0).unwrap();
    assert_eq!(ep.steps.len(), frames.len());
    // A failure is reported with its step: random actions on ReachAvoid-v0 from some seed touch red.
    let mut failed = false;
    for seed in 0..20 {
        let lines = episode(&app, &format!("task=ReachAvoid-v0&policy=random&seed={seed}&side=32"));
        let end = lines.last().unwrap();
        if end["outcome"] == "failure" {
            assert!(end["decided_at"].as_u64().is_some(), "{end}");
            failed = true;
            break;
        }
    }
    assert!(failed, "random actions never touched red in 20 episodes of ReachAvoid-v0");
    // A family's draw and a suite's row play too.
    let end = episode(&app, "family=push&draw=1&policy=solver&side=32").pop().unwrap();
    assert_eq!(end["type"], "end");
    let lines = episode(&app, "suite=layout&split=test&row=0&policy=solver&side=32");
    assert_eq!(lines[0]["type"], "start");
}

#[test]
fn paths_outside_the_apps_folders_are_refused() {
    let dir = temp();
    std::fs::write(dir.path().join("mine.toml"), blockpuzzle::env::registry::REGISTRY[0].toml).unwrap();
    std::fs::create_dir(dir.path().join("sub")).unwrap();
    std::fs::write(dir.path().join("sub/bad.toml"), "version = 1\nid = \"Bad-v0\"\nsurprise = 3\n").unwrap();
    let outside = temp();
    std::fs::write(outside.path().join("secret.toml"), "version = 1\n").unwrap();
    std::os::unix::fs::symlink(outside.path().join("secret.toml"), dir.path().join("link.toml")).unwrap();
    let app = App::start(&["--dir", dir.path().to_str().unwrap()]);
    let (_, files) = app.get("/api/files");
    let listed: Vec<&str> = files["files"].as_array().unwrap().iter().map(|f| f["path"].as_str().unwrap()).collect();
    assert_eq!(listed, ["mine.toml", "sub/bad.toml"], "links are not listed");
    let (status, file) = app.get("/api/file?folder=0&path=mine.toml");
    assert_eq!(status, 200);
    assert_eq!(file["check"]["ok"], true);
    // An invalid file is shown with its error, not a blank page.
    let (status, file) = app.get("/api/file?folder=0&path=sub/bad.toml");
    assert_eq!(status, 200);
    assert_eq!(file["check"]["ok"], false);
    assert!(file["check"]["error"].as_str().unwrap().contains("surprise"), "{file}");
    let secret = outside.path().join("secret.toml");
    for (path, why) in [
        ("../x.toml", "`..`"),
        ("sub/../../x.toml", "`..`"),
        (secret.to_str().unwrap(), "absolute"),
        ("link.toml", "a link in it leads out"),
    ] {
        let (status, v) = app.get(&format!("/api/file?folder=0&path={path}"));
        assert_eq!(status, 403, "{path}: {v}");
        assert!(v["error"].as_str().unwrap().contains(why), "{path}: {v}");
    }
    let (status, v) = app.get("/api/file?folder=0&path=nothing.toml");
    assert_eq!(status, 404, "{v}");
    let (status, v) = app.get("/api/file?folder=3&path=mine.toml");
    assert_eq!(status, 403, "{v}");
    // Playing names files the same way: no built-in id is a path.
    let (status, v) = app.get(&format!("/api/play?task={}", secret.display()));
    assert_eq!(status, 400, "{v}");
    let (status, v) = app.get("/api/play?folder=0&path=link.toml");
    assert_eq!(status, 403, "{v}");
    let (status, _) = app.request("GET", "/api/play?folder=0&path=mine.toml&side=32", b"");
    assert_eq!(status, 200);
}

#[test]
fn the_editor_checks_and_saves_what_the_command_line_accepts() {
    let dir = temp();
    let app = App::start(&["--dir", dir.path().to_str().unwrap()]);
    let task = "version = 1\nid = \"Edited-v0\"\nsummary = \"push blue to green\"\n\n[[objects]]\nname = \"blue\"\ncolour = \"blue\"\nstart = { around = \"table\", offset = [0, -0.05] }\n\n[[objects]]\nname = \"green\"\ncolour = \"green\"\nstart = { around = \"table\", offset = [0.12, 0.08], distance = [0, 0.02], density = \"area\" }\n";
    let (status, check) = app.json("POST", "/api/check?samples=2", task);
    assert_eq!(status, 200);
    assert_eq!(check["ok"], true, "{check}");
    assert_eq!(check["id"], "Edited-v0");
    assert!(!check["lines"].as_array().unwrap().is_empty());
    // The command line's own messages: an unknown key with its line, a NaN.
    let (_, bad) = app.json("POST", "/api/check", &task.replace("summary =", "sumary ="));
    assert_eq!(bad["ok"], false);
    assert!(bad["error"].as_str().unwrap().contains("task:3: unknown field `sumary`"), "{bad}");
    let (_, nan) = app.json("POST", "/api/check", &task.replace("[0, -0.05]", "[nan, -0.05]"));
    assert_eq!(nan["ok"], false, "{nan}");
    // Saved where the app was told, through the one writer, and `task check` takes it unchanged.
    let (status, saved) = app.json("POST", "/api/save?name=edited.toml", task);
    assert_eq!(status, 200, "{saved}");
    let file = dir.path().join("edited.toml");
    assert_eq!(std::fs::read_to_string(&file).unwrap(), task);
    let out = blockpuzzle(&["task", "check", file.to_str().unwrap(), "--samples", "2"]).output().unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    // An existing file needs overwrite; an invalid text, a name with a folder: nothing written.
    let (status, v) = app.json("POST", "/api/save?name=edited.toml", &task.replace("Edited", "Other"));
    assert_eq!(status, 409, "{v}");
    assert_eq!(std::fs::read_to_string(&file).unwrap(), task);
    let (status, _) = app.json("POST", "/api/save?name=edited.toml&overwrite=1", &task.replace("Edited", "Other"));
    assert_eq!(status, 200);
    let (status, v) = app.json("POST", "/api/save?name=broken.toml", "version = 1\nid = 3\n");
    assert_eq!(status, 422, "{v}");
    for name in ["../up.toml", "sub%2Fx.toml", "x.txt", ".hidden.toml"] {
        let (status, v) = app.json("POST", &format!("/api/save?name={name}"), task);
        assert_eq!(status, 400, "{name}: {v}");
    }
    // A link in the folder is not written through, even with overwrite.
    let outside = temp();
    let target = outside.path().join("target.toml");
    std::fs::write(&target, "kept\n").unwrap();
    std::os::unix::fs::symlink(&target, dir.path().join("link.toml")).unwrap();
    let (status, v) = app.json("POST", "/api/save?name=link.toml&overwrite=1", task);
    assert_eq!(status, 409, "{v}");
    assert!(v["error"].as_str().unwrap().contains("not a regular file"), "{v}");
    assert_eq!(std::fs::read_to_string(&target).unwrap(), "kept\n");
    std::fs::remove_file(dir.path().join("link.toml")).unwrap();
    let mut left: Vec<String> =
        std::fs::read_dir(dir.path()).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
    left.sort();
    assert_eq!(left, ["edited.toml"], "nothing else written, no temporary file left");
    // The editor's text plays as sent; a family's draw too.
    let (status, body) = app.request("POST", "/api/play?policy=solver&side=32", task.as_bytes());
    assert_eq!(status, 200);
    let last: Value = serde_json::from_str(String::from_utf8(body).unwrap().lines().last().unwrap()).unwrap();
    assert_eq!(last["type"], "end");
    let family = blockpuzzle::task::family::BUILTIN_FAMILIES[0].1;
    let (status, check) = app.json("POST", "/api/check", family);
    assert_eq!((status, check["kind"].as_str()), (200, Some("family")), "{check}");
    let (status, v) = app.json("POST", "/api/play?policy=solver", family);
    assert_eq!(status, 400, "a family needs a draw: {v}");
}

#[test]
fn bad_requests_get_their_message_and_the_app_keeps_serving() {
    let dir = temp();
    let app = App::start(&["--dir", dir.path().to_str().unwrap()]);
    let cases: &[(&str, &str, &[u8], u16, &str)] = &[
        ("GET", "/api/play?task=BlocksTouch-v0&policy=nobody", b"", 400, "not a policy this app offers"),
        ("GET", "/api/play?task=NoSuch-v0", b"", 400, "no built-in task"),
        ("GET", "/api/play?family=push", b"", 400, "give draw=SEED"),
        ("GET", "/api/play?task=BlocksTouch-v0&seed=-1", b"", 400, "seed=\"-1\""),
        ("GET", "/api/play?task=BlocksTouch-v0&side=100000", b"", 400, "frame side"),
        ("GET", "/api/play?task=BlocksTouch-v0&level=99", b"", 422, "level"),
        ("GET", "/api/play?task=BlocksTouch-v0&distribution=nope", b"", 422, "nope"),
        ("GET", "/api/play?suite=layout&split=test&row=100000", b"", 400, "no row"),
        (
            "POST",
            "/api/play?policy=solver",
            b"version = 1\nid = \"X-v0\"\n[[objects]]\nname = 3\n",
            422,
            "task:4: invalid type",
        ),
        ("GET", "/api/nothing", b"", 404, "no such API"),
        ("GET", "/elsewhere", b"", 404, "no such page"),
        ("GET", "/api/check", b"", 405, "POST"),
        ("DELETE", "/api/tasks", b"", 405, "GET or POST"),
        ("POST", "/api/check", &[0xff, 0xfe], 400, "not UTF-8"),
    ];
    for (method, path, body, want, says) in cases {
        let (status, bytes) = app.request(method, path, body);
        let v: Value = serde_json::from_slice(&bytes).unwrap();
        assert_eq!(status, *want, "{method} {path}: {v}");
        assert!(v["error"].as_str().unwrap().contains(says), "{method} {path}: {v}");
    }
    // A body over the bound is refused, unread.
    let big = vec![b'#'; blockpuzzle::serve::api::MAX_TEXT_BYTES + 1];
    let (status, _) = app.request("POST", "/api/check", &big);
    assert_eq!(status, 413);
    // A policy of another observation: a zoo entry of the flat observation on a task it does not fit.
    let flat = blockpuzzle::benchmark::zoo::names(&blockpuzzle::benchmark::zoo::dir())
        .into_iter()
        .find(|n| n.starts_with("BlocksChoose-v0-ddpg"))
        .expect("the zoo ships BlocksChoose-v0's DDPG policies");
    let (status, v) = app.get(&format!("/api/play?task=BlocksGather-v0&policy=zoo:%20{flat}"));
    assert_eq!(status, 422, "{v}");
    // A page that goes away mid-episode: the renderer stops, the app goes on.
    {
        let mut s = TcpStream::connect(("127.0.0.1", app.port)).unwrap();
        s.write_all(b"GET /api/play?task=BlocksAvoid-v0&policy=random&side=320 HTTP/1.0\r\n\r\n").unwrap();
        let mut first = [0u8; 4096];
        let n = s.read(&mut first).unwrap();
        assert!(n > 0);
    }
    let end = episode(&app, "task=BlocksTouch-v0&policy=solver&side=32").pop().unwrap();
    assert_eq!(end["outcome"], "success");
}

#[test]
fn two_hundred_concurrent_requests_and_it_still_answers_correctly() {
    let dir = temp();
    let app = App::start(&["--dir", dir.path().to_str().unwrap()]);
    let port = app.port;
    // Pages, catalogue and checks are all answered; thumbnails beyond the render queue's bound are
    // told so (503, with the reason), and the ones queued are drawn.
    let threads: Vec<_> = (0..240)
        .map(|k| {
            std::thread::spawn(move || {
                let (status, body) = match k % 4 {
                    0 => request(port, "GET", "/api/tasks", b""),
                    1 => request(port, "GET", "/", b""),
                    2 => request(
                        port,
                        "POST",
                        "/api/check?samples=0",
                        blockpuzzle::env::registry::REGISTRY[0].toml.as_bytes(),
                    ),
                    _ => request(port, "GET", "/api/still?task=BlocksTouch-v0&side=32", b""),
                };
                (k % 4, status, body)
            })
        })
        .collect();
    let mut stills = std::collections::BTreeMap::<u16, usize>::new();
    for t in threads {
        let (kind, status, body) = t.join().expect("every request is answered");
        let text = String::from_utf8_lossy(&body);
        match kind {
            0 => assert!(status == 200 && text.contains("BlocksTouch-v0"), "{status}: {text}"),
            1 => assert!(status == 200 && text.contains("<title>BlockPuzzle</title>"), "{status}: {text}"),
            2 => assert!(status == 200 && text.contains("\"ok\":true"), "{status}: {text}"),
            _ => {
                assert!(
                    (status == 200 && body.starts_with(b"\x89PNG"))
                        || (status == 503 && text.contains("render queue is full")),
                    "{status}: {text}"
                );
                *stills.entry(status).or_default() += 1;
            }
        }
    }
    assert!(stills.get(&200).is_some_and(|&n| n >= blockpuzzle::serve::play::QUEUE), "{stills:?}");
    // Afterwards: the same answers as before.
    let (status, tasks) = app.get("/api/tasks");
    assert_eq!(status, 200);
    assert_eq!(tasks.as_array().unwrap().len(), blockpuzzle::env::registry::ids().len());
    let end = episode(&app, "task=BlocksTouch-v0&policy=solver&side=32").pop().unwrap();
    assert_eq!(end["outcome"], "success");
}

#[test]
fn a_silent_connection_is_closed_and_another_address_is_warned_about() {
    let dir = temp();
    let app = App::start(&["--dir", dir.path().to_str().unwrap()]);
    let mut s = TcpStream::connect(("127.0.0.1", app.port)).unwrap();
    s.write_all(b"GET /api/tasks HTTP/1.1\r\nHost: x\r\n").unwrap();
    s.set_read_timeout(Some(blockpuzzle::serve::http::IO_TIMEOUT * 4)).unwrap();
    let started = Instant::now();
    let mut buf = Vec::new();
    let read = s.read_to_end(&mut buf);
    assert!(
        read.is_ok() || started.elapsed() < blockpuzzle::serve::http::IO_TIMEOUT * 3,
        "the connection was kept: {read:?}"
    );
    assert!(started.elapsed() < blockpuzzle::serve::http::IO_TIMEOUT * 3, "closed after {:?}", started.elapsed());
    drop(app);
    let mut app = App::start(&["--dir", dir.path().to_str().unwrap(), "--bind", "0.0.0.0"]);
    let (status, _) = app.get("/api/health");
    assert_eq!(status, 200);
    let _ = app.child.kill();
    let _ = app.child.wait();
    let err = app.log();
    assert!(err.contains("not on loopback") && err.contains("every machine"), "{err}");
    // A folder that is not one is refused at startup, naming it.
    let out = blockpuzzle(&["serve", "--port", "0", "--dir", "/nonexistent/folder"]).output().unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("/nonexistent/folder"));
}

/// One request to ChromeDriver, which speaks HTTP/1.1 only: the answer's body is read to its
/// `Content-Length`.
fn webdriver(port: u16, method: &str, path: &str, body: &[u8]) -> (u16, Vec<u8>) {
    let mut s = TcpStream::connect(("127.0.0.1", port)).expect("chromedriver accepts");
    s.set_read_timeout(Some(Duration::from_secs(120))).unwrap();
    let head = format!(
        "{method} {path} HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\nContent-Type: application/json\r\nConnection: close\r\nContent-Length: {}\r\n\r\n",
        body.len()
    );
    s.write_all(head.as_bytes()).unwrap();
    s.write_all(body).unwrap();
    let mut reader = BufReader::new(s);
    let mut status_line = String::new();
    reader.read_line(&mut status_line).unwrap();
    let status: u16 = status_line.split(' ').nth(1).and_then(|c| c.parse().ok()).expect("a status");
    let mut length = 0usize;
    loop {
        let mut line = String::new();
        reader.read_line(&mut line).unwrap();
        if line.trim().is_empty() {
            break;
        }
        if let Some((k, v)) = line.split_once(':') {
            if k.eq_ignore_ascii_case("content-length") {
                length = v.trim().parse().unwrap();
            }
        }
    }
    let mut out = vec![0u8; length];
    reader.read_exact(&mut out).unwrap();
    (status, out)
}

/// A WebDriver session with Debian's headless Chromium.
struct Browser {
    driver: Child,
    port: u16,
    session: String,
}

impl Browser {
    fn start() -> Option<Browser> {
        let (chromium, driver) = (Path::new("/usr/bin/chromium"), Path::new("/usr/bin/chromedriver"));
        if !chromium.exists() || !driver.exists() {
            let missing = "Debian's chromium and chromium-driver are not installed (scripts/setup.sh installs them)";
            assert!(std::env::var_os("CI").is_none(), "{missing}");
            skipped(&format!("the browser test: {missing}"));
            return None;
        }
        let port = std::net::TcpListener::bind("127.0.0.1:0").unwrap().local_addr().unwrap().port();
        let driver = std::process::Command::new(driver)
            .arg(format!("--port={port}"))
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .unwrap();
        let deadline = Instant::now() + Duration::from_secs(30);
        while TcpStream::connect(("127.0.0.1", port)).is_err() {
            assert!(Instant::now() < deadline, "chromedriver did not start");
            std::thread::sleep(Duration::from_millis(100));
        }
        let caps = serde_json::json!({"capabilities": {"alwaysMatch": {"browserName": "chrome", "goog:chromeOptions": {
            "binary": chromium, "args": ["--headless=new", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage", "--window-size=1280,1000"]}}}});
        let mut b = Browser { driver, port, session: String::new() };
        let v = b.call("POST", "/session", &caps);
        b.session = v["sessionId"].as_str().unwrap_or_else(|| panic!("no session: {v}")).to_owned();
        Some(b)
    }

    fn call(&self, method: &str, path: &str, body: &Value) -> Value {
        let body = body.to_string();
        let (status, bytes) = webdriver(self.port, method, path, if body == "null" { b"" } else { body.as_bytes() });
        let v: Value = serde_json::from_slice(&bytes).unwrap();
        assert_eq!(status, 200, "{method} {path}: {v}");
        v["value"].clone()
    }

    fn go(&self, url: &str) {
        self.call("POST", &format!("/session/{}/url", self.session), &serde_json::json!({ "url": url }));
    }

    fn js(&self, script: &str) -> Value {
        self.call(
            "POST",
            &format!("/session/{}/execute/sync", self.session),
            &serde_json::json!({ "script": script, "args": [] }),
        )
    }

    /// Waits until `script` returns true, failing with what `describe` returns and the app's log.
    fn until(&self, app: &App, what: &str, script: &str, describe: &str) {
        let deadline = Instant::now() + Duration::from_secs(90);
        while self.js(script) != Value::Bool(true) {
            assert!(Instant::now() < deadline, "{what}: {}\nthe app's log:\n{}", self.js(describe), app.log());
            std::thread::sleep(Duration::from_millis(200));
        }
    }

    fn screenshot(&self, dir: &Path, name: &str) {
        use base64::Engine as _;
        let v = self.call("GET", &format!("/session/{}/screenshot", self.session), &Value::Null);
        let png = base64::engine::general_purpose::STANDARD.decode(v.as_str().unwrap()).unwrap();
        assert!(png.starts_with(b"\x89PNG"));
        std::fs::write(dir.join(format!("{name}.png")), png).unwrap();
    }
}

impl Drop for Browser {
    fn drop(&mut self) {
        if !self.session.is_empty() {
            let _ = webdriver(self.port, "DELETE", &format!("/session/{}", self.session), b"");
        }
        let _ = self.driver.kill();
        let _ = self.driver.wait();
    }
}

/// Where the browser test's screenshots are kept (a test artefact).
fn screenshots() -> PathBuf {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("target/serve-screenshots");
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

#[test]
fn a_browser_browses_the_gallery_plays_builds_and_watches_a_leaderboard_row() {
    let Some(browser) = Browser::start() else { return };
    let dir = temp();
    let shots = screenshots();
    let results = Path::new(env!("CARGO_MANIFEST_DIR")).join("results/generalization");
    let app = App::start(&["--dir", dir.path().to_str().unwrap(), "--results", results.to_str().unwrap()]);
    // The gallery: every built-in task's picture and the families' draws.
    browser.go(&app.url("/"));
    let n = blockpuzzle::env::registry::ids().len();
    browser.until(
        &app,
        "the gallery shows every task's picture",
        &format!("return [...document.querySelectorAll('#task-grid img')].filter(i => i.src.startsWith('blob:') && i.complete).length === {n}"),
        "return document.body.innerText.slice(0, 2000)",
    );
    browser.screenshot(&shots, "1-gallery");
    // A built-in task, played by the solver to its verdict.
    browser.js("document.querySelector('#task-grid figure').click(); return true");
    browser.until(
        &app,
        "the solver's episode reaches its verdict",
        "return document.getElementById('play-outcome').textContent.startsWith('Outcome: success')",
        "return document.getElementById('play-status').textContent + ' | ' + document.getElementById('play-outcome').textContent",
    );
    browser.screenshot(&shots, "2-played");
    // The editor: a task built, checked as the user edits, saved, and valid for `task check`.
    browser.js("document.querySelector('[data-tab=editor]').click(); return true");
    browser.until(
        &app,
        "the editor checks its task",
        "return document.getElementById('ed-status').textContent.startsWith('valid task')",
        "return document.getElementById('ed-status').textContent",
    );
    browser.js("document.getElementById('ed-add').click(); const b = ed.blocks[ed.blocks.length - 1]; b.colour = 'red'; b.name = 'wall'; refresh(); document.getElementById('ed-name').value = 'built.toml'; return true");
    browser.until(&app, "the edited task checks", "return document.getElementById('ed-toml').value.includes('name = \"wall\"') && document.getElementById('ed-status').textContent.startsWith('valid task')", "return document.getElementById('ed-status').textContent");
    browser.js("document.getElementById('ed-save').click(); return true");
    browser.until(
        &app,
        "the task is saved",
        "return document.getElementById('ed-status').textContent.startsWith('saved')",
        "return document.getElementById('ed-status').textContent",
    );
    browser.screenshot(&shots, "3-editor");
    let saved = dir.path().join("built.toml");
    let text = std::fs::read_to_string(&saved).unwrap();
    assert!(text.contains("colour = \"red\""), "{text}");
    let out = blockpuzzle(&["task", "check", saved.to_str().unwrap(), "--samples", "2"]).output().unwrap();
    assert!(out.status.success(), "{}\n{text}", String::from_utf8_lossy(&out.stderr));
    // The same blocks as a family (size ranges, counts, `[check]`), saved and generated from.
    browser.js("ed.blocks = ed.blocks.filter(b => b.name !== 'wall'); document.getElementById('ed-kind').value = 'family'; refresh(); document.getElementById('ed-name').value = 'built-family.toml'; return true");
    browser.until(
        &app,
        "the family checks",
        "return document.getElementById('ed-status').textContent.startsWith('valid family')",
        "return document.getElementById('ed-status').textContent",
    );
    browser.js("document.getElementById('ed-save').click(); return true");
    browser.until(
        &app,
        "the family is saved",
        "return document.getElementById('ed-status').textContent.startsWith('saved')",
        "return document.getElementById('ed-status').textContent",
    );
    let family = dir.path().join("built-family.toml");
    let generated = temp();
    let out = blockpuzzle(&["task", "generate", family.to_str().unwrap(), "--seed", "1", "--count", "1", "--out"])
        .arg(generated.path())
        .output()
        .unwrap();
    let text = std::fs::read_to_string(&family).unwrap();
    assert!(out.status.success(), "{}\n{text}", String::from_utf8_lossy(&out.stderr));
    assert!(text.contains("[check]") && text.contains("size = ["), "{text}");
    // A leaderboard row: the solver's failures on a suite, watched.
    browser.js("document.querySelector('[data-tab=leaderboard]').click(); return true");
    browser.until(
        &app,
        "the leaderboard shows",
        "return document.querySelectorAll('table.board').length > 0",
        "return document.getElementById('boards').innerText.slice(0, 2000)",
    );
    browser.screenshot(&shots, "4-leaderboard");
    browser.js(
        &format!("const board = document.querySelector('div.board[data-suite=colour][data-engine=\"{}\"]'); const row = [...board.querySelectorAll('tr')].find(r => r.children[1] && r.children[1].textContent === 'baseline:scripted' && r.querySelector('button')); row.querySelector('button').click(); return true", blockpuzzle::sim::mj::version()),
    );
    browser.until(
        &app,
        "a failure of the solver is played",
        "return /Outcome: (failure|neither)/.test(document.getElementById('play-outcome').textContent)",
        "return document.getElementById('play-status').textContent + ' | ' + document.getElementById('play-outcome').textContent",
    );
    browser.screenshot(&shots, "5-leaderboard-failure");
}
