//! Build script of the `blockpuzzle` crate.
//!
//! Records where this checkout keeps its scene files (`models/`) so that the
//! library finds them without configuration, and warns at build time when the
//! Fetch robot assets have not been fetched yet.

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
