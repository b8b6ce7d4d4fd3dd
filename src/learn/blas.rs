//! Run-time settings of the numeric libraries, which they read when they are
//! loaded (before `main`), so they are applied by re-executing the program
//! once with the environment set:
//!
//! * Debian's OpenBLAS picks its kernels from the CPU it detects. On some
//!   virtual machines (this project's CI among them) it fails to recognise
//!   the processor and falls back to the Prescott (SSE3) kernels, which makes
//!   libtorch's matrix products 3–4× slower: `OPENBLAS_CORETYPE` fixes that.
//!
//! OpenMP's wait policy is left to libgomp's default (threads spin a while
//! before they sleep): on an idle machine `OMP_WAIT_POLICY=PASSIVE` halves
//! the update rate (results/ddpg.md), while with another process on a core the
//! spinning threads slow updates down several times; there `--torch-threads
//! 1` (or `OMP_WAIT_POLICY=PASSIVE`, set by the user) is the remedy.
//!
//! Variables the user has set are left alone.

use std::ffi::CStr;

/// Kernel families that already use AVX2/FMA or better.
const FAST_CORES: &[&str] = &["haswell", "skylakex", "cooperlake", "sapphirerapids", "zen"];

/// The core type OpenBLAS selected, if OpenBLAS is loaded.
pub fn openblas_core() -> Option<String> {
    // SAFETY: dlsym with RTLD_DEFAULT only looks the symbol up among the
    // loaded libraries; the name is a NUL-terminated literal.
    let sym = unsafe { libc::dlsym(libc::RTLD_DEFAULT, c"openblas_get_corename".as_ptr()) };
    if sym.is_null() {
        return None;
    }
    // SAFETY: OpenBLAS exports `char *openblas_get_corename(void)`; the
    // pointer came from the loaded library under that name.
    let f: extern "C" fn() -> *const libc::c_char = unsafe { std::mem::transmute(sym) };
    let p = f();
    if p.is_null() {
        return None;
    }
    // SAFETY: OpenBLAS returns a pointer to a static NUL-terminated string.
    Some(unsafe { CStr::from_ptr(p) }.to_string_lossy().into_owned())
}

/// The best kernel family this CPU supports, by its instruction sets.
fn best_core() -> Option<&'static str> {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::is_x86_feature_detected as has;
        if has!("avx512f") && has!("avx512dq") && has!("avx512bw") && has!("avx512vl") && has!("avx512cd") {
            return Some("SkylakeX");
        }
        if has!("avx2") && has!("fma") {
            return Some("Haswell");
        }
    }
    None
}

/// The variables the numeric libraries should see and do not yet: every
/// (name, value) that [`ensure_fast_kernels`] sets. `get` reads the
/// environment (a parameter so that tests can pass their own).
pub fn missing_settings(get: impl Fn(&str) -> Option<std::ffi::OsString>) -> Vec<(&'static str, String)> {
    let mut out = Vec::new();
    if get("OPENBLAS_CORETYPE").is_none() {
        if let (Some(core), Some(best)) = (openblas_core(), best_core()) {
            if !FAST_CORES.iter().any(|c| core.to_lowercase().contains(c)) {
                out.push(("OPENBLAS_CORETYPE", best.to_owned()));
            }
        }
    }
    out
}

/// The commands whose speed rests on libtorch's matrix products, or that report its kernels: only
/// they are worth [`ensure_fast_kernels`]'s second start (about 0.9 s of CPU for the libraries'
/// initialisers). Every other command runs no libtorch product and starts once.
pub const KERNEL_COMMANDS: &[&str] = &["train", "bench", "info"];

/// Sets what [`missing_settings`] finds missing (OpenBLAS kernels slower
/// than the CPU supports) by re-executing the current program once with
/// those variables set. Variables the user set are left alone. Returns
/// normally when nothing needs doing or the re-execution fails.
pub fn ensure_fast_kernels() {
    let missing = missing_settings(|k| std::env::var_os(k));
    if missing.is_empty() {
        return;
    }
    let Ok(exe) = std::env::current_exe() else { return };
    use std::os::unix::process::CommandExt;
    // The name it was started by, kept (`blockpuzzle`, when that started `blockpuzzle-train`).
    let name = std::env::args_os().next().unwrap_or_else(|| exe.clone().into_os_string());
    let err = std::process::Command::new(exe)
        .arg0(name)
        .args(std::env::args_os().skip(1))
        .envs(missing.iter().cloned())
        .exec();
    let names: Vec<String> = missing.iter().map(|(k, v)| format!("{k}={v}")).collect();
    eprintln!("note: restarting with {} failed ({err}); training may be slower", names.join(" "));
}

/// The number of libtorch threads for `--torch-threads n` (0: one per core).
///
/// # Errors
/// More threads than this machine has cores: libtorch's OpenMP pool would
/// oversubscribe the CPU (and a very large count makes it hang while the
/// threads are created), so it is refused naming the core count.
pub fn torch_threads(n: usize) -> Result<i32, String> {
    let cores = std::thread::available_parallelism().map_or(1, |c| c.get());
    match n {
        0 => Ok(cores as i32),
        n if n <= cores => Ok(n as i32),
        n => Err(format!(
            "--torch-threads {n} is more than this machine's {cores} cores; give at most {cores} (0: one per core)"
        )),
    }
}
