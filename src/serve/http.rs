//! The server: binds (127.0.0.1 unless told); accepts on one thread, which gives each connection
//! its time bounds and hands it to a fixed pool of workers through a bounded queue (a full queue
//! is answered 503 at once); a worker reads one request (its head and body bounded in size, the
//! whole read bounded in time), answers it and closes the connection. An episode's stream ends
//! when its connection closes. Requests are parsed by `httparse`; the rest is `std::net`.

use super::api::{Answer, Catalogue, MAX_TEXT_BYTES};
use super::play::{self, Job, Msg, Refused};
use super::{Options, ServeError};
use crate::task::family::{Family, BUILTIN_FAMILIES};
use crate::task::Task;
use serde_json::json;
use std::io::{Read, Write};
use std::net::{SocketAddr, TcpListener, TcpStream};
use std::path::PathBuf;
use std::sync::mpsc::{sync_channel, Receiver, RecvTimeoutError, SyncSender, TrySendError};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// Workers answering requests.
pub const WORKERS: usize = 8;
/// Connections that may wait for a worker; one more is answered 503.
pub const WAITING: usize = 512;
/// How long a connection may wait for each read or write.
pub const IO_TIMEOUT: Duration = Duration::from_secs(10);
/// How long a request may take to arrive whole (its head and body).
pub const REQUEST_TIME: Duration = Duration::from_secs(15);
/// How long an episode may wait in the render queue before its request gives up.
pub const QUEUE_WAIT: Duration = Duration::from_secs(120);
/// A worker's stack: workers compile scenes (a family's draws are reset once to be shown), as the
/// command line does on its 8 MiB main thread.
pub const WORKER_STACK_BYTES: usize = 16 << 20;
/// The longest request head (request line and headers), in bytes.
pub const MAX_HEAD_BYTES: usize = 16 << 10;
/// The longest URL read, in bytes.
pub const MAX_URL_BYTES: usize = 2048;

/// The running app.
pub struct Running {
    addr: SocketAddr,
    accept: std::thread::JoinHandle<()>,
}

impl Running {
    /// The address it listens on.
    pub fn addr(&self) -> SocketAddr {
        self.addr
    }
    /// Serves until the process ends.
    pub fn wait(self) {
        let _ = self.accept.join();
    }
}

/// See [`super::start`].
pub(super) fn start(options: Options) -> Result<Running, ServeError> {
    let roots = super::files::Roots::new(&options.dirs)?;
    let results = super::files::Roots::new(&options.results)?.folders().to_vec();
    for p in &options.policies {
        crate::benchmark::load::resolve(p).map_err(|source| ServeError::Policy { path: p.clone(), source })?;
    }
    let addr = SocketAddr::new(options.bind, options.port);
    let listener = TcpListener::bind(addr).map_err(|source| ServeError::Bind { addr, source })?;
    let addr = listener.local_addr().map_err(|source| ServeError::Bind { addr, source })?;
    let app =
        Arc::new(App { catalogue: Catalogue::new(roots, &options.policies, results), queue: play::Queue::start() });
    let (tx, rx) = sync_channel::<TcpStream>(WAITING);
    let rx = Arc::new(Mutex::new(rx));
    for k in 0..WORKERS {
        let (rx, app) = (Arc::clone(&rx), Arc::clone(&app));
        std::thread::Builder::new()
            .name(format!("serve-{k}"))
            .stack_size(WORKER_STACK_BYTES)
            .spawn(move || worker(&rx, &app))
            .expect("a thread can be started at startup");
    }
    let accept = std::thread::Builder::new()
        .name("accept".into())
        .spawn(move || accept(&listener, &tx))
        .expect("a thread can be started at startup");
    Ok(Running { addr, accept })
}

/// Accepts for ever: a failed accept (a connection reset before it was taken, no file descriptor
/// left) is logged and the loop goes on, after a pause when the process is out of descriptors.
fn accept(listener: &TcpListener, tx: &SyncSender<TcpStream>) {
    loop {
        let stream = match listener.accept() {
            Ok((s, _)) => s,
            Err(e) => {
                eprintln!("serve: accepting a connection: {e}");
                if matches!(e.raw_os_error(), Some(libc::EMFILE | libc::ENFILE)) {
                    std::thread::sleep(Duration::from_millis(100));
                }
                continue;
            }
        };
        if stream.set_read_timeout(Some(IO_TIMEOUT)).is_err() || stream.set_write_timeout(Some(IO_TIMEOUT)).is_err() {
            continue;
        }
        if let Err(TrySendError::Full(mut stream)) = tx.try_send(stream) {
            let busy = Answer::error(503, format!("the app is busy ({WAITING} connections waiting); try again"));
            eprintln!("serve: {}", busy.body["error"]);
            let _ = write_json(&mut stream, &busy, false);
            // Off the accept thread: lingering takes up to LINGER_TIME.
            let _ = std::thread::Builder::new().name("linger".into()).spawn(move || linger(stream));
        }
    }
}

/// How much of a refused request's unread body is read and dropped before its connection closes.
pub const LINGER_BYTES: u64 = 1 << 20;
/// How long that may take.
pub const LINGER_TIME: Duration = Duration::from_secs(2);

/// Closes a connection whose request was answered without being read whole (a body over the bound,
/// a busy server): the answer is sent, then what the client still sends is read and dropped, up to
/// [`LINGER_BYTES`] or [`LINGER_TIME`]. Closing with unread input would make the kernel reset the
/// connection, and the client would lose the answer before it read it.
fn linger(mut stream: TcpStream) {
    let _ = stream.shutdown(std::net::Shutdown::Write);
    let _ = stream.set_read_timeout(Some(LINGER_TIME));
    let _ = std::io::copy(&mut (&mut stream).take(LINGER_BYTES), &mut std::io::sink());
}

struct App {
    catalogue: Catalogue,
    queue: play::Queue,
}

fn worker(rx: &Mutex<Receiver<TcpStream>>, app: &App) {
    loop {
        let next = rx.lock().unwrap_or_else(|p| p.into_inner()).recv();
        let Ok(stream) = next else { return };
        let request = match read_request(stream) {
            Ok(r) => r,
            Err(None) => continue,
            Err(Some((mut stream, a))) => {
                eprintln!("serve: a request refused: {} {}", a.status, a.body["error"]);
                let _ = write_json(&mut stream, &a, false);
                linger(stream);
                continue;
            }
        };
        let url = request.url.chars().take(200).collect::<String>();
        // A handler that panics drops its connection unanswered; the worker goes on.
        if std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| handle(request, app))).is_err() {
            eprintln!("serve: {url}: the handler failed; the server goes on");
        }
    }
}

/// One request, read whole.
struct Request {
    method: String,
    url: String,
    body: Vec<u8>,
    stream: TcpStream,
}

/// A refused request: where to answer and what (None: the connection closed or stayed silent,
/// and there is nobody to answer).
type Refusal = Option<(TcpStream, Answer)>;

/// Reads one request from `stream` within [`REQUEST_TIME`], its head at most [`MAX_HEAD_BYTES`]
/// and its body at most [`MAX_TEXT_BYTES`].
fn read_request(mut stream: TcpStream) -> Result<Request, Refusal> {
    let started = Instant::now();
    let mut buf = Vec::with_capacity(1024);
    let mut chunk = [0u8; 4096];
    // Each read waits at most what is left of the request's time.
    let read = |stream: &mut TcpStream, chunk: &mut [u8]| -> Option<usize> {
        let left = REQUEST_TIME.saturating_sub(started.elapsed());
        if left.is_zero() || stream.set_read_timeout(Some(left.min(IO_TIMEOUT))).is_err() {
            return None;
        }
        stream.read(chunk).ok().filter(|&n| n > 0)
    };
    let head_end = loop {
        if let Some(i) = buf.windows(4).position(|w| w == b"\r\n\r\n") {
            break i + 4;
        }
        if buf.len() > MAX_HEAD_BYTES {
            return Err(Some((stream, Answer::error(431, format!("the request head is over {MAX_HEAD_BYTES} bytes")))));
        }
        match read(&mut stream, &mut chunk) {
            Some(n) => buf.extend_from_slice(&chunk[..n]),
            None => return Err(None),
        }
    };
    let mut headers = [httparse::EMPTY_HEADER; 64];
    let mut parsed = httparse::Request::new(&mut headers);
    if !matches!(parsed.parse(&buf[..head_end]), Ok(httparse::Status::Complete(_))) {
        return Err(Some((stream, Answer::error(400, "a malformed HTTP request"))));
    }
    let (method, url) = (parsed.method.unwrap_or("").to_owned(), parsed.path.unwrap_or("").to_owned());
    let header = |name: &str| {
        let h = parsed.headers.iter().find(|h| h.name.eq_ignore_ascii_case(name))?;
        Some(String::from_utf8_lossy(h.value).trim().to_owned())
    };
    if header("transfer-encoding").is_some() {
        return Err(Some((stream, Answer::error(411, "send the body with a Content-Length, not chunked"))));
    }
    let length = match header("content-length").map(|v| v.parse::<usize>()) {
        None => 0,
        Some(Ok(n)) => n,
        Some(Err(_)) => return Err(Some((stream, Answer::error(400, "the Content-Length is not a number")))),
    };
    if length > MAX_TEXT_BYTES {
        return Err(Some((stream, Answer::error(413, format!("the request body is over {MAX_TEXT_BYTES} bytes")))));
    }
    let mut body = buf[head_end..].to_vec();
    while body.len() < length {
        match read(&mut stream, &mut chunk) {
            Some(n) => body.extend_from_slice(&chunk[..n]),
            None => return Err(Some((stream, Answer::error(408, "the request body did not arrive whole in time")))),
        }
    }
    body.truncate(length);
    let _ = stream.set_read_timeout(Some(IO_TIMEOUT));
    Ok(Request { method, url, body, stream })
}

fn reason(status: u16) -> &'static str {
    match status {
        200 => "OK",
        400 => "Bad Request",
        403 => "Forbidden",
        404 => "Not Found",
        405 => "Method Not Allowed",
        408 => "Request Timeout",
        409 => "Conflict",
        411 => "Length Required",
        413 => "Payload Too Large",
        414 => "URI Too Long",
        422 => "Unprocessable Entity",
        431 => "Request Header Fields Too Large",
        503 => "Service Unavailable",
        _ => "Internal Server Error",
    }
}

/// Writes a response head; with `length` the body's size, else the body ends with the connection.
fn write_head(stream: &mut TcpStream, status: u16, content_type: &str, length: Option<usize>) -> std::io::Result<()> {
    let length = length.map_or(String::new(), |n| format!("Content-Length: {n}\r\n"));
    let head = format!(
        "HTTP/1.1 {status} {}\r\nContent-Type: {content_type}\r\n{length}Cache-Control: no-store\r\n\
         X-Content-Type-Options: nosniff\r\nConnection: close\r\n\r\n",
        reason(status)
    );
    stream.write_all(head.as_bytes())
}

fn write_body(
    stream: &mut TcpStream,
    status: u16,
    content_type: &str,
    body: &[u8],
    head_only: bool,
) -> std::io::Result<()> {
    write_head(stream, status, content_type, Some(body.len()))?;
    if !head_only {
        stream.write_all(body)?;
    }
    stream.flush()
}

fn write_json(stream: &mut TcpStream, a: &Answer, head_only: bool) -> std::io::Result<()> {
    write_body(stream, a.status, "application/json; charset=utf-8", a.body.to_string().as_bytes(), head_only)
}

/// Answers `request` with `a`, logging an error answer.
fn answer(mut request: Request, a: Answer) {
    if a.status >= 400 {
        let url: String = request.url.chars().take(200).collect();
        let message = a.body.get("error").and_then(|e| e.as_str()).unwrap_or("");
        eprintln!("serve: {} {url}: {} {message}", request.method, a.status);
    }
    let head_only = request.method == "HEAD";
    let _ = write_json(&mut request.stream, &a, head_only);
}

/// The query parameters of a URL, percent-decoded.
pub fn query(url: &str) -> Vec<(String, String)> {
    let Some((_, q)) = url.split_once('?') else { return Vec::new() };
    q.split('&')
        .filter(|p| !p.is_empty())
        .map(|p| {
            let (k, v) = p.split_once('=').unwrap_or((p, ""));
            (decode(k), decode(v))
        })
        .collect()
}

/// Percent-decoding (`+` a space); a broken escape is kept as written.
fn decode(s: &str) -> String {
    let b = s.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        match b[i] {
            b'+' => out.push(b' '),
            b'%' if i + 2 < b.len() => {
                match u8::from_str_radix(std::str::from_utf8(&b[i + 1..i + 3]).unwrap_or("zz"), 16) {
                    Ok(v) => {
                        out.push(v);
                        i += 2;
                    }
                    Err(_) => out.push(b'%'),
                }
            }
            c => out.push(c),
        }
        i += 1;
    }
    String::from_utf8_lossy(&out).into_owned()
}

struct Params(Vec<(String, String)>);

impl Params {
    fn get(&self, k: &str) -> Option<&str> {
        self.0.iter().find(|(n, _)| n == k).map(|(_, v)| v.as_str())
    }
    fn num<T: std::str::FromStr>(&self, k: &str, what: &str) -> Result<Option<T>, String> {
        match self.get(k) {
            None | Some("") => Ok(None),
            Some(v) => v.parse().map(Some).map_err(|_| format!("{k}={v:?} is not {what}")),
        }
    }
}

fn handle(mut request: Request, app: &App) {
    if request.url.len() > MAX_URL_BYTES {
        return answer(request, Answer::error(414, format!("the URL is longer than {MAX_URL_BYTES} bytes")));
    }
    let url = request.url.clone();
    let path = url.split('?').next().unwrap_or("").to_owned();
    let params = Params(query(&url));
    let method = request.method.clone();
    if let Some(asset) = super::assets::get(&path) {
        if method != "GET" && method != "HEAD" {
            return answer(request, Answer::error(405, "pages are read with GET"));
        }
        let _ = write_body(&mut request.stream, 200, asset.content_type, asset.body.as_bytes(), method == "HEAD");
        return;
    }
    let body = match method.as_str() {
        "POST" => match String::from_utf8(std::mem::take(&mut request.body)) {
            Ok(b) => Some(b),
            Err(_) => return answer(request, Answer::error(400, "the request body is not UTF-8 text")),
        },
        "GET" | "HEAD" => None,
        _ => return answer(request, Answer::error(405, format!("{method} is not served; use GET or POST"))),
    };
    let c = &app.catalogue;
    let a = match (path.as_str(), body.as_deref()) {
        ("/api/health", None) => Answer::ok(json!({ "ok": true, "engine": crate::sim::mj::version() })),
        ("/api/policies", None) => c.policies(),
        ("/api/scene", None) => c.scene(),
        ("/api/tasks", None) => c.tasks(),
        ("/api/families", None) => c.families(),
        ("/api/suites", None) => c.suites(),
        ("/api/zoo", None) => c.zoo(),
        ("/api/leaderboard", None) => c.leaderboard(),
        ("/api/files", None) => c.files(),
        ("/api/file", None) => match params.num::<usize>("folder", "a folder number") {
            Ok(f) => c.file(f.unwrap_or(0), params.get("path").unwrap_or("")),
            Err(e) => Answer::error(400, e),
        },
        ("/api/check", Some(text)) => match params.num::<u64>("samples", "a count") {
            Ok(s) => Answer::ok(super::api::check_text(
                text,
                "the editor's task",
                s.unwrap_or(super::api::CHECK_SAMPLES).min(50),
            )),
            Err(e) => Answer::error(400, e),
        },
        ("/api/save", Some(text)) => match params.get("name") {
            Some(name) => c.save(name, text, params.get("overwrite") == Some("1")),
            None => Answer::error(400, "give the file name: /api/save?name=NAME.toml"),
        },
        ("/api/play" | "/api/still", body) => {
            let still = path == "/api/still";
            return play(request, app, &params, body, still);
        }
        ("/api/check" | "/api/save", None) => Answer::error(405, format!("{path} takes the text by POST")),
        (p, _) if p.starts_with("/api/") => Answer::error(404, format!("{p}: no such API (see /api/health)")),
        (p, _) => Answer::error(404, format!("{p}: no such page; the app starts at /")),
    };
    answer(request, a)
}

/// What a suite's row plays beside its task: its first seed, level and distribution.
struct RowSetting {
    seed: u64,
    level: Option<usize>,
    distribution: Option<String>,
}

/// The task a play or still request names: `task=ID` (built in), `family=NAME&draw=SEED` (built
/// in), `folder=I&path=P` (a task or family file of the app's folders, a family's draw by `draw`),
/// `suite=S&split=T&row=K`, or the text sent (the editor's).
fn task_of(app: &App, p: &Params, body: Option<&str>) -> Result<(Task, Option<RowSetting>), Answer> {
    let bad = |m: String| Answer::error(400, m);
    let draw = p.num::<u64>("draw", "a generator seed").map_err(bad)?;
    let family_draw = |f: Family| -> Result<Task, Answer> {
        let seed =
            draw.ok_or_else(|| bad(format!("{} is a family: give draw=SEED for one of its tasks", f.spec.family)))?;
        super::api::first_draw(&f, seed).map(|(task, _)| task).map_err(|e| Answer::error(422, e))
    };
    if let Some(text) = body {
        if super::api::is_family(text) {
            let f = Family::from_toml(text, "the editor's family").map_err(|e| Answer::error(422, e.to_string()))?;
            return Ok((family_draw(f)?, None));
        }
        return Task::parse(text, "the editor's task", None)
            .map(|t| (t, None))
            .map_err(|e| Answer::error(422, e.to_string()));
    }
    if let Some(id) = p.get("task") {
        if !crate::env::registry::ids().contains(&id) {
            return Err(bad(format!(
                "{id:?} is no built-in task (see /api/tasks); files are named by folder and path"
            )));
        }
        return crate::env::registry::task(id).map(|t| (t, None)).map_err(|e| Answer::error(500, e.to_string()));
    }
    if let Some(name) = p.get("family") {
        let Some((_, text)) = BUILTIN_FAMILIES.iter().find(|(n, _)| *n == name) else {
            return Err(bad(format!("{name:?} is no built-in family (see /api/families)")));
        };
        let f = Family::from_toml(text, name).map_err(|e| Answer::error(500, e.to_string()))?;
        return Ok((family_draw(f)?, None));
    }
    if let Some(path) = p.get("path") {
        let folder = p.num::<usize>("folder", "a folder number").map_err(bad)?.unwrap_or(0);
        let file = app.catalogue.roots.resolve(folder, path).map_err(|e| Answer::error(403, e.to_string()))?;
        let text = crate::support::io::read_text(&file, "task or family file", MAX_TEXT_BYTES as u64)
            .map_err(|e| bad(format!("{path}: {e}")))?;
        if super::api::is_family(&text) {
            return Ok((family_draw(Family::read(&file).map_err(|e| Answer::error(422, e.to_string()))?)?, None));
        }
        return Task::from_file(&file).map(|t| (t, None)).map_err(|e| Answer::error(422, e.to_string()));
    }
    if let Some(suite) = p.get("suite") {
        let row = p.num::<usize>("row", "a row number").map_err(bad)?.unwrap_or(0);
        let (task, r) = app.catalogue.suite_row(suite, p.get("split").unwrap_or("test"), row).map_err(bad)?;
        return Ok((task, Some(RowSetting { seed: r.seed, level: r.level, distribution: r.distribution })));
    }
    Err(bad("name the task: task=ID, family=NAME&draw=SEED, folder=I&path=P, suite=S&split=T&row=K, or POST its text"
        .into()))
}

fn play(request: Request, app: &App, p: &Params, body: Option<&str>, still: bool) {
    let job = (|| -> Result<Job, Answer> {
        let bad = |m: String| Answer::error(400, m);
        let (task, row) = task_of(app, p, body)?;
        let label = p.get("policy").unwrap_or("solver").to_owned();
        let policy: PathBuf = app
            .catalogue
            .policy(&label)
            .cloned()
            .ok_or_else(|| bad(format!("{label:?} is not a policy this app offers (see /api/policies)")))?;
        let side = p.num::<usize>("side", "a frame side in pixels").map_err(bad)?.unwrap_or(play::DEFAULT_SIDE);
        if !(32..=play::MAX_SIDE).contains(&side) {
            return Err(bad(format!("side={side}: give a frame side from 32 to {} pixels", play::MAX_SIDE)));
        }
        let seed = p.num::<u64>("seed", "a seed").map_err(bad)?.or(row.as_ref().map(|r| r.seed)).unwrap_or(0);
        let level = p.num::<usize>("level", "a level").map_err(bad)?.or(row.as_ref().and_then(|r| r.level));
        let distribution = match p.get("distribution").filter(|d| !d.is_empty()) {
            Some(d) => Some(d.to_owned()),
            None => row.and_then(|r| r.distribution),
        };
        Ok(Job { task, policy, policy_label: label, seed, level, distribution, side, still })
    })();
    let job = match job {
        Ok(j) => j,
        Err(a) => return answer(request, a),
    };
    let rx = match app.queue.submit(job) {
        Ok(rx) => rx,
        Err(Refused::Full) => {
            return answer(
                request,
                Answer::error(
                    503,
                    format!(
                        "the render queue is full ({} episodes waiting); press play again when one has played",
                        play::QUEUE
                    ),
                ),
            )
        }
        Err(Refused::Stopped) => return answer(request, Answer::error(500, "the renderer has stopped; restart serve")),
    };
    // The wait for the renderer and the stream are on a thread of their own, so that the workers
    // answer pages while episodes play: the queue's bound bounds these threads too.
    let spawned = std::thread::Builder::new().name("stream".into()).spawn(move || deliver(request, rx));
    if let Err(e) = spawned {
        eprintln!("serve: cannot start a thread for an episode: {e}");
    }
}

/// Answers a queued job's request with what the renderer sends: its failure, the thumbnail, or the
/// episode's stream, one line as each frame is made. A page gone away ends the stream (the renderer
/// sees its next send fail).
fn deliver(mut request: Request, rx: Receiver<Msg>) {
    let first = match rx.recv_timeout(QUEUE_WAIT) {
        Ok(m) => m,
        Err(RecvTimeoutError::Timeout) => {
            return answer(request, Answer::error(503, "the episode waited two minutes in the render queue; try again"))
        }
        Err(RecvTimeoutError::Disconnected) => {
            return answer(request, Answer::error(500, "the renderer dropped the episode"))
        }
    };
    let line = match first {
        Msg::Failed(m) => return answer(request, Answer::error(422, m)),
        Msg::Png(bytes) => {
            let _ = write_body(&mut request.stream, 200, "image/png", &bytes, false);
            return;
        }
        Msg::Line(line) => line,
    };
    let stream = &mut request.stream;
    let mut sent = write_head(stream, 200, "application/x-ndjson", None).and_then(|()| writeln!(stream, "{line}"));
    while sent.is_ok() {
        sent = match rx.recv() {
            Ok(Msg::Line(l)) => writeln!(stream, "{l}"),
            Ok(Msg::Failed(m)) => writeln!(stream, "{}", json!({ "type": "error", "message": m })),
            Ok(Msg::Png(_)) | Err(_) => break,
        };
    }
    if let Err(e) = sent {
        eprintln!("serve: the page closed an episode's stream: {e}");
    }
}
