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

/// What the crate is built from, when built from a git checkout: the commit of HEAD, with
/// `-dirty` when a file that goes into the build differs from it. The script runs again when
/// HEAD moves or one of those files changes (a folder is watched as a whole).
fn commit(manifest: &Path) -> Option<String> {
    let inputs = [
        "src",
        "tasks",
        "suites",
        "families",
        "models/scene.xml",
        "Cargo.toml",
        "Cargo.lock",
        "build.rs",
        "mujoco-sys",
    ];
    for input in inputs {
        println!("cargo:rerun-if-changed={input}");
    }
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
    args.extend(inputs);
    let dirty = !git(&args)?.is_empty();
    Some(if dirty { format!("{head}-dirty") } else { head })
}
