//! Generates bindings to MuJoCo's C API with bindgen and links `libmujoco`.
//!
//! Debian's `libmujoco-dev` ships no pkg-config file, so the headers and the
//! library are searched for in the usual places. Override with
//! `MUJOCO_INCLUDE_DIR` (the folder that holds `mujoco/mujoco.h`) and
//! `MUJOCO_LIB_DIR` (the folder that holds `libmujoco.so`).
//!
//! With the `mujoco3` feature the bindings are made from MuJoCo 3.11.0 instead:
//! `MUJOCO_DIR` (default: `engines/mujoco-3.11.0` of this checkout, filled by
//! `make setup-mujoco3`) holds `include/mujoco/mujoco.h` and `lib/libmujoco.so`.
//! The library folder is passed on as `DEP_MUJOCO_LIB_DIR` so that the crates
//! that link binaries can give them an rpath to it.
//!
//! With the `mujoco-wheel` feature (the Python package's build) the headers and
//! the library are those of the `mujoco==3.11.0` PyPI package installed for the
//! Python that builds (`PYO3_PYTHON`, else `python3`): `mujoco/include/mujoco/`
//! and `mujoco/libmujoco.so.3.11.0`, linked by that exact file name, which the
//! extension then finds at run time through an rpath into the installed package.
//! libclang for bindgen comes from the `libclang` PyPI package of that Python
//! when it has one (the build requirements install it), so no system package is
//! needed.

use std::env;
use std::path::{Path, PathBuf};

const INCLUDE_CANDIDATES: &[&str] = &["/usr/include", "/usr/local/include", "/opt/mujoco/include"];
const LIB_CANDIDATES: &[&str] =
    &["/usr/lib/x86_64-linux-gnu", "/usr/lib/aarch64-linux-gnu", "/usr/lib", "/usr/local/lib", "/opt/mujoco/lib"];
const SETUP_HINT: &str = "install it with `apt-get install libmujoco-dev libclang-dev` (or run `make setup`), \
     or point MUJOCO_INCLUDE_DIR / MUJOCO_LIB_DIR at a MuJoCo 2.2.2 installation";

fn find_dir(var: &str, candidates: &[&str], probe: &str) -> PathBuf {
    println!("cargo:rerun-if-env-changed={var}");
    if let Some(dir) = env::var_os(var) {
        let dir = PathBuf::from(dir);
        if dir.join(probe).exists() {
            return dir;
        }
        panic!("{var}={} does not contain {probe}; {SETUP_HINT}", dir.display());
    }
    candidates
        .iter()
        .map(Path::new)
        .find(|d| d.join(probe).exists())
        .map(Path::to_path_buf)
        .unwrap_or_else(|| panic!("MuJoCo not found: no {probe} under {candidates:?}; {SETUP_HINT}"))
}

const MUJOCO3_VERSION: &str = "3.11.0";

/// The MuJoCo 3 engine folder: `MUJOCO_DIR`, or the one `make setup-mujoco3` fills.
fn mujoco3_dirs() -> (PathBuf, PathBuf) {
    println!("cargo:rerun-if-env-changed=MUJOCO_DIR");
    let manifest = PathBuf::from(env::var("CARGO_MANIFEST_DIR").expect("cargo sets CARGO_MANIFEST_DIR"));
    let (dir, from_env) = match env::var_os("MUJOCO_DIR") {
        Some(d) => (PathBuf::from(d), true),
        None => (manifest.join("..").join("engines").join(format!("mujoco-{MUJOCO3_VERSION}")), false),
    };
    let dir = dir.canonicalize().unwrap_or(dir);
    let (include, lib) = (dir.join("include"), dir.join("lib"));
    let header = include.join("mujoco/mujoco.h");
    println!("cargo:rerun-if-changed={}", header.display());
    if !header.exists() || !lib.join("libmujoco.so").exists() {
        let hint = if from_env {
            format!("MUJOCO_DIR={} must hold include/mujoco/mujoco.h and lib/libmujoco.so", dir.display())
        } else {
            format!("run `make setup-mujoco3` (bash scripts/setup_mujoco3.sh) to fetch MuJoCo {MUJOCO3_VERSION}, or set MUJOCO_DIR")
        };
        panic!("the `mujoco3` feature needs MuJoCo 3 but {} has none: {hint}", dir.display());
    }
    (include, lib)
}

/// The Python that builds the extension module: maturin sets `PYO3_PYTHON`.
fn python() -> String {
    println!("cargo:rerun-if-env-changed=PYO3_PYTHON");
    env::var("PYO3_PYTHON").unwrap_or_else(|_| "python3".into())
}

/// Runs a snippet in [`python`]; its stdout lines, or `None` if it failed.
fn ask_python(code: &str) -> Option<Vec<String>> {
    let out = std::process::Command::new(python()).args(["-c", code]).output().ok()?;
    out.status.success().then(|| String::from_utf8_lossy(&out.stdout).lines().map(str::to_owned).collect())
}

/// The installed `mujoco` PyPI package: its folder (headers under `include/`, the library beside
/// them), and the extra clang arguments bindgen needs with the `libclang` PyPI package.
fn mujoco_wheel_dir() -> (PathBuf, Vec<String>) {
    let hint = format!("install it for {} with `pip install mujoco=={MUJOCO3_VERSION}`", python());
    let lines = ask_python(
        "import importlib.util as u, importlib.metadata as m\n\
         s = u.find_spec('mujoco')\n\
         print(s.submodule_search_locations[0] if s else '')\n\
         print(m.version('mujoco') if s else '')",
    )
    .unwrap_or_else(|| panic!("cannot run {} to find the `mujoco` package; set PYO3_PYTHON to a Python 3", python()));
    let (dir, version) = (lines.first().cloned().unwrap_or_default(), lines.get(1).cloned().unwrap_or_default());
    if dir.is_empty() {
        panic!("the `mujoco-wheel` feature builds against the `mujoco` PyPI package, which is not installed: {hint}");
    }
    if version != MUJOCO3_VERSION {
        panic!("the `mujoco` package installed is {version}, this build needs exactly {MUJOCO3_VERSION}: {hint}");
    }
    let dir = PathBuf::from(dir);
    for need in [dir.join("include/mujoco/mujoco.h"), dir.join(format!("libmujoco.so.{MUJOCO3_VERSION}"))] {
        println!("cargo:rerun-if-changed={}", need.display());
        if !need.exists() {
            panic!("the `mujoco` package at {} lacks {}: reinstall it ({hint})", dir.display(), need.display());
        }
    }
    // libclang for bindgen from the `libclang` PyPI package, when this Python has it. That package
    // has no compiler headers (stddef.h): the C compiler's, which the build needs anyway, stand in.
    let mut clang_args = Vec::new();
    if env::var_os("LIBCLANG_PATH").is_none() {
        let found = ask_python(
            "import importlib.util as u, os\n\
             s = u.find_spec('clang')\n\
             print(os.path.join(s.submodule_search_locations[0], 'native') if s else '')",
        );
        if let Some(native) =
            found.and_then(|l| l.into_iter().next()).filter(|d| Path::new(d).join("libclang.so").exists())
        {
            env::set_var("LIBCLANG_PATH", native);
            let cc = env::var("CC").unwrap_or_else(|_| "cc".into());
            let include = std::process::Command::new(&cc)
                .arg("-print-file-name=include")
                .output()
                .ok()
                .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_owned())
                .filter(|d| Path::new(d).join("stddef.h").exists())
                .unwrap_or_else(|| {
                    panic!("`{cc} -print-file-name=include` names no folder with stddef.h: install a C compiler (gcc)")
                });
            clang_args.push(format!("-isystem{include}"));
        }
    }
    (dir, clang_args)
}

fn main() {
    let wheel = env::var_os("CARGO_FEATURE_MUJOCO_WHEEL").is_some();
    let mut clang_args = Vec::new();
    let (include_dir, lib_dir) = if wheel {
        let (dir, args) = mujoco_wheel_dir();
        clang_args = args;
        (dir.join("include"), dir)
    } else if env::var_os("CARGO_FEATURE_MUJOCO3").is_some() {
        mujoco3_dirs()
    } else {
        (
            find_dir("MUJOCO_INCLUDE_DIR", INCLUDE_CANDIDATES, "mujoco/mujoco.h"),
            find_dir("MUJOCO_LIB_DIR", LIB_CANDIDATES, "libmujoco.so"),
        )
    };

    // The engine the headers are of must be the one the feature asks for: 2.x without
    // `mujoco3`, 3.x with it (the wrapper's code differs between them).
    let header_text = std::fs::read_to_string(include_dir.join("mujoco/mujoco.h")).unwrap_or_default();
    let version = header_text
        .lines()
        .find_map(|l| l.strip_prefix("#define mjVERSION_HEADER"))
        .and_then(|v| v.trim().parse::<u64>().ok())
        .unwrap_or(0);
    let want3 = env::var_os("CARGO_FEATURE_MUJOCO3").is_some();
    if want3 != (version >= 3_000_000) {
        panic!(
            "{} declares mjVERSION_HEADER {version}, but this build {}: {}",
            include_dir.join("mujoco/mujoco.h").display(),
            if want3 {
                "has the `mujoco3` feature (MuJoCo 3.x)"
            } else {
                "expects MuJoCo 2.2.2 (no `mujoco3` feature)"
            },
            if want3 { "point MUJOCO_DIR at MuJoCo 3 or run `make setup-mujoco3`" } else { SETUP_HINT }
        );
    }

    // Fatal errors that return (guard.c); its archive comes before libmujoco on the link line.
    println!("cargo:rerun-if-changed=guard.c");
    println!("cargo:rerun-if-changed=guard.h");
    cc::Build::new().file("guard.c").include(&include_dir).warnings(true).compile("bpguard");
    println!("cargo:rustc-link-search=native={}", lib_dir.display());
    if wheel {
        // The wheel has only the versioned file (wheels hold no symlinks): link it by that name.
        println!("cargo:rustc-link-lib=dylib:+verbatim=libmujoco.so.{MUJOCO3_VERSION}");
    } else {
        println!("cargo:rustc-link-lib=dylib=mujoco");
    }
    println!("cargo:include={}", include_dir.display());
    println!("cargo:lib_dir={}", lib_dir.display());
    println!("cargo:rerun-if-changed=wrapper.h");

    let header = include_dir.join("mujoco/mujoco.h");
    println!("cargo:rerun-if-changed={}", header.display());

    let bindings = bindgen::Builder::default()
        .header("wrapper.h")
        .clang_arg(format!("-I{}", include_dir.display()))
        .clang_args(&clang_args)
        .allowlist_function("mj.*")
        .allowlist_function("bp_.*")
        .allowlist_type("mj.*")
        .allowlist_var("mj.*")
        .rustified_enum("mjt.*")
        .derive_default(true)
        .layout_tests(false)
        .generate_comments(true)
        .generate()
        .unwrap_or_else(|e| {
            let hint = if wheel {
                format!(
                    "bindgen needs libclang: `pip install libclang==18.1.1` for {} (or set LIBCLANG_PATH)",
                    python()
                )
            } else {
                format!("libclang-dev is needed ({SETUP_HINT})")
            };
            panic!("bindgen failed on {}: {e}; {hint}", header.display())
        });

    let out = PathBuf::from(env::var("OUT_DIR").expect("cargo sets OUT_DIR")).join("bindings.rs");
    bindings.write_to_file(&out).unwrap_or_else(|e| panic!("cannot write {}: {e}", out.display()));
}
