//! With the `mujoco3` feature the extension module links MuJoCo 3 from a
//! folder of the checkout (engines/, or MUJOCO_DIR): give it an rpath there.
fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    if std::env::var_os("CARGO_FEATURE_MUJOCO3").is_some() {
        if let Some(lib) = std::env::var_os("DEP_MUJOCO_LIB_DIR") {
            println!("cargo:rustc-link-arg=-Wl,-rpath,{}", std::path::Path::new(&lib).display());
        }
    }
}
