//! Build script of the `blockpuzzle` crate.
//!
//! Records where this checkout keeps its scene files (`models/`) so that the
//! library finds them without configuration, and warns at build time when the
//! Fetch robot assets have not been fetched yet.

use std::path::Path;

fn main() {
    let manifest = std::env::var("CARGO_MANIFEST_DIR").expect("cargo sets CARGO_MANIFEST_DIR");
    let models = Path::new(&manifest).join("models");
    println!("cargo:rustc-env=BLOCKPUZZLE_DEFAULT_MODELS_DIR={}", models.display());
    println!("cargo:rerun-if-changed=build.rs");
    // With the `mujoco3` feature, libmujoco.so.3.x lives in a folder of this checkout
    // (engines/, or MUJOCO_DIR): binaries and tests find it through an rpath.
    if let Some(lib) = std::env::var_os("DEP_MUJOCO_LIB_DIR") {
        if std::env::var_os("CARGO_FEATURE_MUJOCO3").is_some() {
            println!("cargo:rustc-link-arg=-Wl,-rpath,{}", Path::new(&lib).display());
        }
    }
    let robot = models.join("gymnasium_robotics/fetch/robot.xml");
    if !robot.exists() {
        println!(
            "cargo:warning=Fetch robot assets missing ({}); run `make setup` before running environments",
            robot.display()
        );
    }
}
