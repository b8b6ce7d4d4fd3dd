//! The extension module links `libmujoco.so.3.11.0` of the `mujoco` PyPI
//! package (mujoco-sys's `mujoco-wheel` feature). Installed, the module sits in
//! `site-packages/blockpuzzle/` and the library in `site-packages/mujoco/`: an
//! rpath `$ORIGIN/../mujoco` finds it there, whatever the folder.
fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    println!("cargo:rustc-link-arg=-Wl,-rpath,$ORIGIN/../mujoco");
}
