//! (A test binary of its own: it registers another assets folder for the whole process.)
//! The Fetch files can come from a folder registered at run time (the Python
//! package registers the installed gymnasium-robotics' `envs/assets`): the
//! scenes built from it are the checkout's, a changed or missing file is
//! refused naming it, and a refusal leaves the registration as it was.

use blockpuzzle::sim::scene::{self, SceneError, FETCH_FILES};
use std::path::Path;

fn copy_fetch_files(from: &Path, to: &Path) {
    for (rel, _) in FETCH_FILES {
        let dest = to.join(rel);
        std::fs::create_dir_all(dest.parent().expect("a parent")).expect("mkdir");
        std::fs::copy(from.join(rel), dest).expect("copy a Fetch file");
    }
}

fn first_observations() -> Vec<f32> {
    let mut env = blockpuzzle::make("BlocksChoose-v0").expect("BlocksChoose-v0");
    let (obs, _) = env.reset(Some(7)).expect("reset");
    let step = env.step(&[0.3, -0.2, 0.1, 0.0]).expect("step");
    obs.into_iter().chain(step.obs).collect()
}

#[test]
fn a_registered_assets_folder_builds_the_same_scenes_and_bad_copies_are_refused() {
    if std::env::var_os(scene::MODELS_DIR_VAR).is_some() {
        // The variable overrides any registered folder. Past the harness's capture: a green run says so.
        use std::io::Write;
        let _ =
            writeln!(std::io::stderr().lock(), "SKIPPED: the assets registration ({} is set)", scene::MODELS_DIR_VAR);
        return;
    }
    let checkout = scene::models_dir().expect("a checkout build knows its models/").join(scene::FETCH_ASSETS);
    let from_checkout = first_observations();
    assert_eq!(scene::assets().expect("assets").fetch_prefix, "gymnasium_robotics/");

    let copy = tempfile::tempdir().expect("temp dir");
    copy_fetch_files(&checkout, copy.path());
    scene::use_fetch_assets(copy.path()).expect("an exact copy of gymnasium-robotics' files");
    let found = scene::assets().expect("assets");
    assert_eq!((found.base.as_path(), found.fetch_prefix), (copy.path(), ""));
    assert_eq!(first_observations(), from_checkout, "the same scene from either folder");

    let bad = tempfile::tempdir().expect("temp dir");
    copy_fetch_files(&checkout, bad.path());
    let robot = bad.path().join("fetch/robot.xml");
    std::fs::write(&robot, std::fs::read_to_string(&robot).expect("read").replace("0.", "0.0")).expect("write");
    match scene::use_fetch_assets(bad.path()) {
        Err(e @ SceneError::AssetChecksum { .. }) => {
            let msg = e.to_string();
            assert!(
                msg.contains("robot.xml") && msg.contains("pip install --force-reinstall gymnasium-robotics==1.4.2"),
                "{msg}"
            );
        }
        other => panic!("a changed robot.xml was taken: {other:?}"),
    }
    std::fs::remove_file(bad.path().join("stls/fetch/gripper_link.stl")).expect("rm");
    assert!(matches!(
        scene::use_fetch_assets(bad.path()),
        Err(SceneError::AssetChecksum { .. } | SceneError::MissingAssets { .. })
    ));
    assert_eq!(scene::assets().expect("assets").base, copy.path(), "refusals leave the registration alone");
}
