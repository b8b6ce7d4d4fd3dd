//! Training checkpoints: one binary file holding a JSON header (run state,
//! hyperparameters, normaliser, the replay log) and a payload of
//! little-endian f32 arrays (networks, optimiser moments), guarded by a
//! CRC-32, written atomically (`crate::support::io`), so a crash never leaves a
//! half-written checkpoint.
//!
//! Replay buffers are kept as an append-only log beside it: every
//! checkpoint writes one segment per buffer, `replay/wS-FIRST.bin`, holding
//! the transitions stored since the previous one (written before the
//! checkpoint that lists it), and deletes segments no longer stored in the
//! buffer. An epoch writes megabytes instead of the whole buffer (about
//! 560 MB at a million BlocksChoose-v0 transitions), and the buffer is rebuilt
//! exactly. Checkpoints written before the log hold the buffers inline;
//! they load, and their next save starts the log.

use crate::learn::agents::algorithm::{Algorithm, Spec, StateDict};
use crate::learn::agents::registry::{Algo, AlgoConfigs};
use crate::learn::agents::replay::{Batch, ReplayBuffer};
use crate::learn::agents::shared::SharedConfig;
use crate::policy::actor::normalizer::Normalizer;
use serde::{Deserialize, Serialize};
use std::collections::{BTreeMap, HashMap};
use std::io::Write;
use std::path::{Path, PathBuf};
use thiserror::Error;

const MAGIC: &[u8; 8] = b"BPCKPT01";

/// Checkpoint errors: each names the file and what to do.
#[derive(Debug, Error)]
pub enum CheckpointError {
    /// Reading or writing failed.
    #[error("checkpoint {path}: {source}")]
    Io { path: PathBuf, source: std::io::Error },
    /// Not a checkpoint, truncated, or its checksum does not match.
    #[error("checkpoint {path} is corrupt ({reason}); restore it from a backup, or start a new run")]
    Corrupt { path: PathBuf, reason: String },
    /// A valid checkpoint of another environment or shape.
    #[error("checkpoint {path} does not fit this run: {reason}")]
    Mismatch { path: PathBuf, reason: String },
}

/// Everything about the run that is not an array.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RunState {
    /// Environment id.
    pub env_id: String,
    /// Observation size.
    pub obs_dim: usize,
    /// Action size.
    pub act_dim: usize,
    /// Epochs completed.
    pub epoch: usize,
    /// Curriculum level for the next epoch (a multi-task run: the sum of its tasks' levels).
    pub level: usize,
    /// Each task's curriculum level for the next epoch, in the run's task order (absent in
    /// checkpoints of one-task runs written before multi-task training: `[level]`).
    #[serde(default)]
    pub levels: Vec<usize>,
    /// Each task's test episodes since its level last moved or stayed: (successes, episodes).
    /// A task's level moves up when these reach `test_episodes` at a success rate of at least the
    /// threshold; a one-task run tests that many every epoch, the paper's rule.
    #[serde(default)]
    pub tallies: Vec<[u64; 2]>,
    /// Environment steps so far (all workers).
    pub env_steps: u64,
    /// Gradient updates so far.
    pub updates: u64,
    /// Episodes collected per worker so far (seeds the next ones).
    pub episodes_per_worker: u64,
    /// Wall-clock seconds of training so far.
    pub wall_seconds: f64,
    /// Best finals success so far.
    pub best_finals: f64,
    /// Ranks of the job that wrote it (1: one process; `mpirun -np P`: P).
    #[serde(default = "one")]
    pub ranks: usize,
    /// The rank that wrote it.
    #[serde(default)]
    pub rank: usize,
    /// The seal of the run's `config.json` this checkpoint was written with
    /// ([`crate::learn::train::config_seal`]): a resume refuses a config that is not it (an edited
    /// config, or another run's checkpoint). Absent in checkpoints written before it was recorded.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub config_seal: Option<String>,
}

fn one() -> usize {
    1
}

#[derive(Serialize, Deserialize)]
struct Header {
    state: RunState,
    /// Absent in checkpoints written before PGGD existed: DDPG.
    #[serde(default)]
    algo: Algo,
    /// The settings the agent is built from: the shared ones ([`Spec`]) and
    /// every algorithm's own (one group each, by name; headers written before
    /// that held the shared ones in `ddpg`: [`crate::learn::agents::shared::upgrade_legacy`]).
    #[serde(default)]
    shared: SharedConfig,
    #[serde(flatten)]
    algos: AlgoConfigs,
    normalizer: Normalizer,
    /// The agent's counters by name ([`StateDict::counters`]); the arrays are blobs.
    #[serde(default)]
    counters: BTreeMap<String, u64>,
    /// Checkpoints written before algorithms declared their state kept
    /// these counters instead: the Adam step counts and, for TD3, the second
    /// critic's and the smoothing noise's seed.
    #[serde(default, skip_serializing)]
    actor_adam_t: u64,
    #[serde(default, skip_serializing)]
    critic_adam_t: u64,
    #[serde(default, skip_serializing)]
    twin: Option<(u64, u64)>,
    /// The first replay buffer's capacity and next write position.
    replay_capacity: usize,
    replay_next: usize,
    /// The same for each further buffer (one per worker with `--replay per-worker`).
    #[serde(default)]
    more_replays: Vec<(usize, usize)>,
    /// The replay log, one per buffer (empty: buffers inline, an older checkpoint).
    #[serde(default)]
    replay_log: Vec<ShardLog>,
    blobs: Vec<(String, usize)>,
    payload_crc32: u32,
}

/// One buffer's log: its capacity, history length, and the segments that
/// hold its stored transitions.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct ShardLog {
    capacity: usize,
    /// History index of the next transition (see `ReplayBuffer::pushed`).
    pushed: u64,
    /// Transitions stored.
    len: usize,
    segments: Vec<Segment>,
    /// Where the previous checkpoint's stored transitions began: segments
    /// before it are deleted (under MPI the previous checkpoint stays usable).
    #[serde(skip)]
    kept_from: u64,
}

/// A file of the replay log: transitions `first..first + count` of one buffer.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
struct Segment {
    file: String,
    first: u64,
    count: u64,
    crc32: u32,
}

/// The replay logs of a run's buffers, carried from one save to the next.
#[derive(Debug, Clone, Default)]
pub struct ReplayLog {
    shards: Vec<ShardLog>,
}

const SEGMENT_MAGIC: &[u8; 8] = b"BPRLOG01";

/// The widths of a transition's seven arrays in file order (obs, act, rew,
/// next_obs, done, extra, discount).
fn widths(obs_dim: usize, act_dim: usize) -> [usize; 7] {
    [obs_dim, act_dim, 1, obs_dim, 1, 1, 1]
}

/// Appends the transitions each buffer stored since the last save to the
/// log in `dir`, returning the logs to record (old segments are deleted by
/// [`prune_log`] once the checkpoint that no longer needs them is written).
fn append_log(dir: &Path, replays: &[ReplayBuffer], log: &mut ReplayLog) -> Result<Vec<ShardLog>, CheckpointError> {
    let folder = dir.join("replay");
    std::fs::create_dir_all(&folder).map_err(io(&folder))?;
    log.shards.resize_with(replays.len(), ShardLog::default);
    for (w, (replay, shard)) in replays.iter().zip(&mut log.shards).enumerate() {
        let start = replay.pushed() - replay.len() as u64;
        let logged = shard.segments.last().map_or(0, |g| g.first + g.count);
        // Nothing logged yet, or a gap (a buffer loaded from an older checkpoint): log everything stored.
        if shard.segments.is_empty() || logged < start || logged > replay.pushed() {
            shard.segments.clear();
            shard.kept_from = start;
        }
        let from = shard.segments.last().map_or(start, |g| g.first + g.count);
        let to = replay.pushed();
        if to > from {
            let b = replay.history(from, to).unwrap_or_default();
            let mut payload = Vec::with_capacity(4 * (b.obs.len() * 2 + b.act.len() + 4 * b.rew.len()));
            for column in [&b.obs, &b.act, &b.rew, &b.next_obs, &b.terminated, &b.return_to_go, &b.discount] {
                for x in column {
                    payload.extend_from_slice(&x.to_le_bytes());
                }
            }
            let file = format!("w{w}-{from:012}.bin");
            let path = folder.join(&file);
            let count = to - from;
            crate::support::io::write_atomic(&path, |f| {
                f.write_all(SEGMENT_MAGIC)?;
                f.write_all(&count.to_le_bytes())?;
                f.write_all(&payload)
            })
            .map_err(io(&path))?;
            shard.segments.push(Segment { file, first: from, count, crc32: crc32fast::hash(&payload) });
        }
        shard.capacity = replay.capacity();
        shard.pushed = to;
        shard.len = replay.len();
    }
    // What this checkpoint records: the segments holding its stored transitions.
    Ok(log
        .shards
        .iter()
        .map(|s| {
            let start = s.pushed - s.len as u64;
            let segments = s.segments.iter().filter(|g| g.first + g.count > start).cloned().collect();
            ShardLog { segments, ..s.clone() }
        })
        .collect())
}

/// Deletes the segments that neither this checkpoint nor (under MPI, where
/// a resume may go back one epoch) the previous one needs.
fn prune_log(dir: &Path, log: &mut ReplayLog, keep_previous: bool) {
    for shard in &mut log.shards {
        let start = shard.pushed - shard.len as u64;
        let keep_from = if keep_previous { shard.kept_from.min(start) } else { start };
        shard.segments.retain(|g| {
            let needed = g.first + g.count > keep_from;
            if !needed {
                let _ = std::fs::remove_file(dir.join("replay").join(&g.file));
            }
            needed
        });
        shard.kept_from = start;
    }
}

/// Rebuilds the buffers from the log in `dir`.
fn read_log(
    dir: &Path,
    logs: &[ShardLog],
    obs_dim: usize,
    act_dim: usize,
    corrupt: &dyn Fn(&str) -> CheckpointError,
) -> Result<Vec<ReplayBuffer>, CheckpointError> {
    let widths = widths(obs_dim, act_dim);
    let row: usize = widths.iter().sum();
    let mut out = Vec::new();
    for shard in logs {
        let start = shard.pushed - shard.len as u64;
        let mut data = Batch::default();
        let mut next = start;
        for g in shard.segments.iter().filter(|g| g.first + g.count > start) {
            let path = dir.join("replay").join(&g.file);
            let bytes = std::fs::read(&path).map_err(|e| match e.kind() {
                std::io::ErrorKind::NotFound => corrupt(&format!(
                    "its replay segment {} is missing: restore that file from a backup of the run, or resume \
                     with --rebuild-replay to collect the buffers again from the run's seeds",
                    path.display()
                )),
                _ => io(&path)(e),
            })?;
            let bad = |r: &str| corrupt(&format!("replay segment {}: {r}", path.display()));
            let count = g.count as usize;
            if bytes.len() != 16 + 4 * row * count || &bytes[..8] != SEGMENT_MAGIC {
                return Err(bad("wrong size or not a replay segment"));
            }
            let payload = &bytes[16..];
            if crc32fast::hash(payload) != g.crc32 {
                return Err(bad("checksum mismatch"));
            }
            if g.first > next {
                return Err(bad("the segment before it is missing"));
            }
            let values: Vec<f32> =
                payload.chunks_exact(4).map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]])).collect();
            // Only the transitions this checkpoint stores (the first segment may begin earlier).
            let skip = (next - g.first) as usize;
            let end = (shard.pushed.min(g.first + g.count) - g.first) as usize;
            let dst = [
                &mut data.obs,
                &mut data.act,
                &mut data.rew,
                &mut data.next_obs,
                &mut data.terminated,
                &mut data.return_to_go,
                &mut data.discount,
            ];
            let mut off = 0;
            for (d, w) in dst.into_iter().zip(widths) {
                d.extend_from_slice(&values[off + skip * w..off + end * w]);
                off += w * count;
            }
            next = g.first + end as u64;
        }
        if next != shard.pushed {
            return Err(corrupt("the replay log ends before the buffer's last transition"));
        }
        let buffer = ReplayBuffer::from_history(obs_dim, act_dim, shard.capacity, shard.pushed, data);
        out.push(buffer.map_err(|e| corrupt(&e))?);
    }
    Ok(out)
}

fn io(path: &Path) -> impl Fn(std::io::Error) -> CheckpointError + '_ {
    move |source| CheckpointError::Io { path: path.to_owned(), source }
}

/// Saves the agent, the replay buffer and the run state to `path`
/// atomically; `settings` are those the agent was built from.
///
/// # Errors
/// [`CheckpointError::Io`].
pub fn save(
    path: &Path,
    state: &RunState,
    agent: &mut dyn Algorithm,
    (shared, algos): (&SharedConfig, &AlgoConfigs),
    replays: &[ReplayBuffer],
    log: &mut ReplayLog,
) -> Result<(), CheckpointError> {
    let StateDict { tensors, counters } = agent.state();
    let blobs: Vec<(String, Vec<f32>)> = tensors.into_iter().collect();
    let positions: Vec<(usize, usize)> = replays.iter().map(|r| (r.capacity(), r.parts().1)).collect();
    let (replay_capacity, replay_next) = positions.first().copied().unwrap_or((1, 0));

    let mut payload = Vec::with_capacity(blobs.iter().map(|b| 4 * b.1.len()).sum());
    for (_, v) in &blobs {
        for x in v {
            payload.extend_from_slice(&x.to_le_bytes());
        }
    }
    let dir = path.parent().unwrap_or(Path::new("."));
    let replay_log = append_log(dir, replays, log)?;
    let header = Header {
        state: state.clone(),
        algo: Algo::named(agent.name())
            .map_err(|e| CheckpointError::Io { path: path.to_owned(), source: std::io::Error::other(e) })?,
        shared: shared.clone(),
        algos: algos.clone(),
        normalizer: agent.norm().clone(),
        counters,
        actor_adam_t: 0,
        critic_adam_t: 0,
        twin: None,
        replay_capacity,
        replay_next,
        more_replays: positions.get(1..).unwrap_or_default().to_vec(),
        replay_log,
        blobs: blobs.iter().map(|(n, v)| (n.clone(), v.len())).collect(),
        payload_crc32: crc32fast::hash(&payload),
    };
    let json = serde_json::to_vec(&header).map_err(|e| io(path)(std::io::Error::other(e)))?;

    let mut bytes = Vec::with_capacity(16 + json.len() + payload.len());
    bytes.extend_from_slice(MAGIC);
    bytes.extend_from_slice(&(json.len() as u64).to_le_bytes());
    bytes.extend_from_slice(&json);
    bytes.extend_from_slice(&payload);
    // A job of several ranks keeps the previous checkpoint too: a rank that
    // stopped before writing this epoch's leaves the others one epoch ahead,
    // and a resume goes back to the epoch every rank has.
    if state.ranks > 1 && path.exists() {
        std::fs::rename(path, previous(path)).map_err(io(path))?;
    }
    crate::support::io::write_atomic(path, |f| f.write_all(&bytes)).map_err(io(path))?;
    prune_log(dir, log, state.ranks > 1);
    Ok(())
}

/// `checkpoint.prev.bin` beside `checkpoint.bin`: the one before it (jobs of several ranks).
pub fn previous(path: &Path) -> PathBuf {
    path.with_extension("prev.bin")
}

/// The blob name prefix of replay buffer `i` (the first keeps the name of one-buffer checkpoints).
fn replay_prefix(i: usize) -> String {
    if i == 0 {
        "replay".to_owned()
    } else {
        format!("replay-{i}")
    }
}

/// The run state of a checkpoint, read from its header only (the payload is not checked).
///
/// # Errors
/// [`CheckpointError::Io`] or [`CheckpointError::Corrupt`].
pub fn peek_state(path: &Path) -> Result<RunState, CheckpointError> {
    Ok(read_header(path)?.state)
}

/// Reads a checkpoint whole, as a resume would (checksums, network shapes,
/// every replay segment it needs), without knowing the run: a check before a
/// copy of it is made.
///
/// # Errors
/// As [`load`].
pub fn verify(path: &Path) -> Result<RunState, CheckpointError> {
    let s = peek_state(path)?;
    Ok(load(path, &s.env_id, s.obs_dim, s.act_dim)?.state)
}

/// The replay segment files (relative to the checkpoint's folder) a
/// checkpoint needs, from its header only.
///
/// # Errors
/// [`CheckpointError::Io`] or [`CheckpointError::Corrupt`].
pub fn segment_files(path: &Path) -> Result<Vec<PathBuf>, CheckpointError> {
    let header = read_header(path)?;
    Ok(header.replay_log.iter().flat_map(|s| &s.segments).map(|g| Path::new("replay").join(&g.file)).collect())
}

/// A checkpoint's header, without reading its payload.
fn read_header(path: &Path) -> Result<Header, CheckpointError> {
    use std::io::Read;
    let corrupt = |reason: &str| CheckpointError::Corrupt { path: path.to_owned(), reason: reason.to_owned() };
    let mut f = std::fs::File::open(path).map_err(io(path))?;
    let mut head = Vec::with_capacity(16);
    (&mut f).take(16).read_to_end(&mut head).map_err(io(path))?;
    if head.len() < 8 || &head[..8] != MAGIC {
        return Err(corrupt("not a blockpuzzle checkpoint"));
    }
    if head.len() < 16 {
        return Err(corrupt("truncated"));
    }
    let hlen = u64::from_le_bytes(head[8..16].try_into().map_err(|_| corrupt("truncated"))?);
    let mut json = Vec::new();
    f.take(hlen).read_to_end(&mut json).map_err(io(path))?;
    header_from(&json).map_err(|e| corrupt(&format!("bad header: {e}")))
}

/// What [`load`] returns.
pub struct Loaded {
    /// The run state.
    pub state: RunState,
    /// The agent, exactly as saved.
    pub agent: Box<dyn Algorithm>,
    /// The replay buffers, exactly as saved.
    pub replays: Vec<ReplayBuffer>,
    /// Their log, for the next [`save`].
    pub log: ReplayLog,
    /// How many transitions each buffer had received when the checkpoint was written (its history
    /// length, [`ReplayBuffer::pushed`]), also where the buffers are not read back.
    pub pushed: Vec<u64>,
}

/// Loads a checkpoint and checks it against the expected environment and sizes.
///
/// # Errors
/// [`CheckpointError::Corrupt`] for a damaged file, [`CheckpointError::Mismatch`]
/// for another environment or other dimensions.
pub fn load(path: &Path, env_id: &str, obs_dim: usize, act_dim: usize) -> Result<Loaded, CheckpointError> {
    load_with(path, env_id, obs_dim, act_dim, true)
}

/// As [`load`], but without the replay buffers: they come back empty, at their recorded capacities,
/// and their log is not read (it need not exist). For a run carried to another machine with its
/// weights and optimiser state but not its replay log (`train --resume --rebuild-replay`).
///
/// # Errors
/// As [`load`], less the replay log's.
pub fn load_without_replay(
    path: &Path,
    env_id: &str,
    obs_dim: usize,
    act_dim: usize,
) -> Result<Loaded, CheckpointError> {
    load_with(path, env_id, obs_dim, act_dim, false)
}

fn load_with(
    path: &Path,
    env_id: &str,
    obs_dim: usize,
    act_dim: usize,
    replay: bool,
) -> Result<Loaded, CheckpointError> {
    let bytes = std::fs::read(path).map_err(io(path))?;
    let (header, payload) = parse(path, &bytes)?;
    let mismatch = |reason: String| CheckpointError::Mismatch { path: path.to_owned(), reason };
    let s = &header.state;
    if s.env_id != env_id {
        return Err(mismatch(format!("it was trained on {}, this run is {env_id}", s.env_id)));
    }
    if (s.obs_dim, s.act_dim) != (obs_dim, act_dim) {
        return Err(mismatch(format!(
            "observation/action sizes {}/{} differ from this environment's {obs_dim}/{act_dim}",
            s.obs_dim, s.act_dim
        )));
    }
    // Replay arrays (in checkpoints that kept them inline) apart from the agent's.
    let (replay_blobs, agent_blobs): (HashMap<_, _>, HashMap<_, _>) =
        blobs(&header, payload).into_iter().partition(|(name, _)| name.starts_with("replay"));
    let agent = load_agent(path, &header, agent_blobs, obs_dim, act_dim)?;
    if !replay {
        if header.replay_log.is_empty() {
            return Err(mismatch(
                "it holds its replay buffers itself (a checkpoint from before replay logs): resume without \
                 --rebuild-replay"
                    .into(),
            ));
        }
        let pushed = header.replay_log.iter().map(|s| s.pushed).collect();
        let replays = header.replay_log.iter().map(|s| ReplayBuffer::new(obs_dim, act_dim, s.capacity)).collect();
        return Ok(Loaded { state: header.state, agent, replays, log: ReplayLog::default(), pushed });
    }
    let (replays, log) = load_replays(path, &header, &replay_blobs, obs_dim, act_dim)?;
    let pushed = replays.iter().map(ReplayBuffer::pushed).collect();
    Ok(Loaded { state: header.state, agent, replays, log, pushed })
}

/// The header and payload of a checkpoint file's bytes, checked (magic, sizes, checksum).
/// A header from its JSON, older layouts included.
fn header_from(json: &[u8]) -> Result<Header, serde_json::Error> {
    let mut value: serde_json::Value = serde_json::from_slice(json)?;
    crate::learn::agents::shared::upgrade_legacy(&mut value);
    serde_json::from_value(value)
}

fn parse<'b>(path: &Path, bytes: &'b [u8]) -> Result<(Header, &'b [u8]), CheckpointError> {
    let corrupt = |reason: &str| CheckpointError::Corrupt { path: path.to_owned(), reason: reason.to_owned() };
    if bytes.len() < 16 || &bytes[..8] != MAGIC {
        return Err(corrupt("not a blockpuzzle checkpoint"));
    }
    let hlen = u64::from_le_bytes(bytes[8..16].try_into().map_err(|_| corrupt("truncated"))?) as usize;
    let body = bytes.get(16..).ok_or_else(|| corrupt("truncated"))?;
    if hlen > body.len() {
        return Err(corrupt("truncated header"));
    }
    let header = header_from(&body[..hlen]).map_err(|e| corrupt(&format!("bad header: {e}")))?;
    let payload = &body[hlen..];
    let expected: usize = header.blobs.iter().map(|b| 4 * b.1).sum();
    if payload.len() != expected {
        return Err(corrupt(&format!("payload has {} bytes, expected {expected}", payload.len())));
    }
    if crc32fast::hash(payload) != header.payload_crc32 {
        return Err(corrupt("checksum mismatch"));
    }
    Ok((header, payload))
}

/// The payload's arrays by name (sizes checked by [`parse`]).
fn blobs(header: &Header, payload: &[u8]) -> HashMap<String, Vec<f32>> {
    let mut blobs = HashMap::new();
    let mut off = 0;
    for (name, len) in &header.blobs {
        let v: Vec<f32> =
            payload[off..off + 4 * len].chunks_exact(4).map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]])).collect();
        off += 4 * len;
        blobs.insert(name.clone(), v);
    }
    blobs
}

/// The arrays `prefix.0`, `prefix.1`, ... in order.
fn take(blobs: &HashMap<String, Vec<f32>>, prefix: &str) -> Vec<Vec<f32>> {
    (0..).map_while(|i| blobs.get(&format!("{prefix}.{i}")).cloned()).collect()
}

/// The agent, exactly as saved: built from the saved settings, then its
/// state restored by name.
fn load_agent(
    path: &Path,
    header: &Header,
    tensors: HashMap<String, Vec<f32>>,
    obs_dim: usize,
    act_dim: usize,
) -> Result<Box<dyn Algorithm>, CheckpointError> {
    let mismatch = |reason: String| CheckpointError::Mismatch { path: path.to_owned(), reason };
    if header.normalizer.dim() != obs_dim {
        return Err(mismatch("normaliser size differs".into()));
    }
    // Network shapes come from the saved settings; the seed does not matter
    // because every value is overwritten.
    let mut rng = <rand_chacha::ChaCha8Rng as rand::SeedableRng>::seed_from_u64(0);
    // A set network's layout is its normaliser's (a set network's normaliser always has one).
    let arch = crate::learn::agents::arch::Arch { obs_dim, set: header.normalizer.set_layout() };
    let spec = Spec { arch, act_dim, shared: &header.shared };
    let mut agent = header.algo.build(&spec, &header.algos, &mut rng);
    let state = StateDict { tensors: tensors.into_iter().collect(), counters: counters(header) };
    agent.load_state(&state).map_err(|e| mismatch(e.to_string()))?;
    *agent.norm_mut() = header.normalizer.clone();
    Ok(agent)
}

/// The agent's counters: the header's, or (older checkpoints) its fixed fields under their names.
fn counters(header: &Header) -> BTreeMap<String, u64> {
    if !header.counters.is_empty() {
        return header.counters.clone();
    }
    let mut c = BTreeMap::from([
        ("actor_adam.t".to_owned(), header.actor_adam_t),
        ("critic_adam.t".to_owned(), header.critic_adam_t),
    ]);
    if let Some((adam_t, noise_seed)) = header.twin {
        c.insert("critic2_adam.t".into(), adam_t);
        c.insert("critic2.noise_seed".into(), noise_seed);
    }
    c
}

/// The replay buffers, exactly as saved, and their log for the next [`save`].
fn load_replays(
    path: &Path,
    header: &Header,
    blobs: &HashMap<String, Vec<f32>>,
    obs_dim: usize,
    act_dim: usize,
) -> Result<(Vec<ReplayBuffer>, ReplayLog), CheckpointError> {
    let corrupt = |reason: &str| CheckpointError::Corrupt { path: path.to_owned(), reason: reason.to_owned() };
    let take = |prefix: &str| take(blobs, prefix);
    let d = &header.shared;
    if !header.replay_log.is_empty() {
        let dir = path.parent().unwrap_or(Path::new("."));
        let replays = read_log(dir, &header.replay_log, obs_dim, act_dim, &corrupt)?;
        let shards = header.replay_log.iter().map(|s| ShardLog { kept_from: s.pushed - s.len as u64, ..s.clone() });
        return Ok((replays, ReplayLog { shards: shards.collect() }));
    }
    let positions: Vec<(usize, usize)> = std::iter::once((header.replay_capacity, header.replay_next))
        .chain(header.more_replays.iter().copied())
        .collect();
    let mut replays = Vec::new();
    for (i, (capacity, next)) in positions.into_iter().enumerate() {
        let r = take(&replay_prefix(i));
        if r.len() != 6 && r.len() != 7 {
            return Err(corrupt("replay buffer missing"));
        }
        let mut r = r.into_iter();
        let mut next_array = || r.next().unwrap_or_default();
        let mut data = Batch {
            obs: next_array(),
            act: next_array(),
            rew: next_array(),
            next_obs: next_array(),
            terminated: next_array(),
            return_to_go: next_array(),
            discount: next_array(),
        };
        // Checkpoints from before n-step returns: every transition is one step.
        if data.discount.is_empty() {
            data.discount = vec![d.gamma as f32; data.rew.len()];
        }
        replays.push(ReplayBuffer::from_parts(obs_dim, act_dim, capacity, data, next).map_err(|e| corrupt(&e))?);
    }
    Ok((replays, ReplayLog::default()))
}
