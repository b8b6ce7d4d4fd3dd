//! Build script of the `blockpuzzle` crate.
//!
//! Records where this checkout keeps its scene files (`models/`) so that the
//! library finds them without configuration, and warns at build time when the
//! Fetch robot assets have not been fetched yet; records the git commit the
//! build was made from (results carry it: `crate::provenance`).

use std::path::Path;

fn main() {
    let manifest = std::env::var("CARGO_MANIFEST_DIR").expect("cargo sets CARGO_MANIFEST_DIR");
    let models = Path::new(&manifest).join("models");
    // A build for the Python wheel keeps no path of this checkout: it reads the Fetch assets of
    // the installed gymnasium-robotics (or $BLOCKPUZZLE_MODELS_DIR).
    let wheel = std::env::var_os("CARGO_FEATURE_MUJOCO_WHEEL").is_some();
    let default = if wheel { String::new() } else { models.display().to_string() };
    println!("cargo:rustc-env=BLOCKPUZZLE_DEFAULT_MODELS_DIR={default}");
    println!("cargo:rerun-if-changed=build.rs");
    // Built from a source package (the Python sdist has no .git): the commit its maker recorded.
    println!("cargo:rerun-if-env-changed=BLOCKPUZZLE_SOURCE_COMMIT");
    let commit = commit(Path::new(&manifest)).or_else(|| std::env::var("BLOCKPUZZLE_SOURCE_COMMIT").ok());
    println!("cargo:rustc-env=BLOCKPUZZLE_COMMIT={}", commit.unwrap_or_default());
    for input in INPUTS {
        println!("cargo:rerun-if-changed={input}");
    }
    let sources = sources_digest(Path::new(&manifest));
    println!("cargo:rustc-env=BLOCKPUZZLE_SOURCES={sources:016x}");
    println!("cargo:rustc-env=BLOCKPUZZLE_BUILD_ID={:016x}", build_id(sources));
    // `blockpuzzle` runs no training code (src/cli/halves.rs), yet the archives it links hold some
    // (a code unit that mixes both, libtch's C++ wrapper). Hidden from its dynamic symbol table,
    // their symbols are not kept for interposition, and the linker's garbage collection drops what
    // nothing reaches; with rust-lld (Rust's default linker on x86-64 Linux since 1.90), which
    // decides what a library is needed for after that collection, libtorch is then not loaded.
    println!("cargo:rustc-link-arg-bin=blockpuzzle=-Wl,--exclude-libs=ALL");
    // With the `mujoco3` feature, libmujoco.so.3.x lives in a folder of this checkout
    // (engines/, or MUJOCO_DIR): binaries and tests find it through an rpath.
    if let Some(lib) = std::env::var_os("DEP_MUJOCO_LIB_DIR") {
        if std::env::var_os("CARGO_FEATURE_MUJOCO3").is_some() && !wheel {
            println!("cargo:rustc-link-arg=-Wl,-rpath,{}", Path::new(&lib).display());
        }
    }
    let robot = models.join("gymnasium_robotics/fetch/robot.xml");
    if !robot.exists() && !wheel {
        println!(
            "cargo:warning=Fetch robot assets missing ({}); run `make setup` before running environments",
            robot.display()
        );
    }
}

/// The files and folders that go into the build. The script runs again when one of them changes (a
/// folder is watched as a whole), so what it records from them is never stale.
const INPUTS: [&str; 9] =
    ["src", "tasks", "suites", "families", "models/scene.xml", "Cargo.toml", "Cargo.lock", "build.rs", "mujoco-sys"];

/// A digest of every input's content (paths in order): equal for two builds only when they were
/// made from the same sources, whatever their features (the two engines' binaries of one checkout
/// share it, uncommitted changes included). Not a security measure: a check that builds belong
/// together.
fn sources_digest(manifest: &Path) -> u64 {
    use std::hash::Hasher;
    fn walk(path: &Path, out: &mut Vec<std::path::PathBuf>) {
        if path.is_dir() {
            let mut entries: Vec<_> =
                std::fs::read_dir(path).into_iter().flatten().flatten().map(|e| e.path()).collect();
            entries.sort();
            for entry in entries {
                // mujoco-sys's own build folder, if one was made there, is not an input.
                if entry.file_name().is_some_and(|n| n != "target") {
                    walk(&entry, out);
                }
            }
        } else if path.is_file() {
            out.push(path.to_path_buf());
        }
    }
    let mut files = Vec::new();
    for input in INPUTS {
        walk(&manifest.join(input), &mut files);
    }
    // SipHash with fixed keys: the same digest wherever the script runs (for one compiler).
    let mut h = std::hash::DefaultHasher::new();
    for file in files {
        h.write(file.strip_prefix(manifest).unwrap_or(&file).to_string_lossy().as_bytes());
        h.write(&std::fs::read(&file).unwrap_or_default());
    }
    h.finish()
}

/// What this build is, for the two halves of the command line (`blockpuzzle` hands the training
/// commands to `blockpuzzle-train`, src/cli/halves.rs): the sources' digest with the features and
/// profile, equal for two binaries only when they were built from the same sources in the same way.
fn build_id(sources: u64) -> u64 {
    use std::hash::Hasher;
    let mut h = std::hash::DefaultHasher::new();
    h.write_u64(sources);
    let mut how: Vec<String> =
        std::env::vars().filter(|(k, _)| k.starts_with("CARGO_FEATURE_")).map(|(k, _)| k).collect();
    how.sort();
    how.extend(["PROFILE", "OPT_LEVEL", "DEBUG", "TARGET"].iter().map(|k| std::env::var(k).unwrap_or_default()));
    h.write(how.join(" ").as_bytes());
    h.finish()
}

/// What the crate is built from, when built from a git checkout: the commit of HEAD, with
/// `-dirty` when a file that goes into the build differs from it. The script runs again when
/// HEAD moves or one of those files changes (a folder is watched as a whole).
fn commit(manifest: &Path) -> Option<String> {
    let git = |args: &[&str]| -> Option<String> {
        let out = std::process::Command::new("git").args(args).current_dir(manifest).output().ok()?;
        out.status.success().then(|| String::from_utf8_lossy(&out.stdout).trim().to_owned())
    };
    // Only the checkout this crate is the top of (a copy inside another repository is not one).
    let top = git(&["rev-parse", "--show-toplevel"])?;
    if Path::new(&top).canonicalize().ok()? != manifest.canonicalize().ok()? {
        return None;
    }
    // (A path that does not exist would make the script run at every build: watch those that do.)
    let reference = git(&["symbolic-ref", "-q", "HEAD"]).unwrap_or_default();
    for file in ["HEAD", "packed-refs", reference.as_str()] {
        let path = Path::new(&top).join(".git").join(file);
        if !file.is_empty() && path.is_file() {
            println!("cargo:rerun-if-changed={}", path.display());
        }
    }
    let head = git(&["rev-parse", "HEAD"])?;
    let mut args = vec!["status", "--porcelain", "--untracked-files=no", "--"];
    args.extend(INPUTS);
    let dirty = !git(&args)?.is_empty();
    Some(if dirty { format!("{head}-dirty") } else { head })
}
