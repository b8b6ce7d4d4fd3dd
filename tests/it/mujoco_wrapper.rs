//! The safe MuJoCo wrapper against the real library.

use blockpuzzle::sim::mj::{Data, MjError, Model, ObjType, Warning};
use std::path::Path;
use std::sync::Arc;

const PENDULUM: &str = r#"<mujoco>
  <option timestep="0.002"/>
  <worldbody>
    <geom name="floor" type="plane" size="1 1 0.1"/>
    <body name="ball" pos="0 0 0.5">
      <joint name="free" type="free"/>
      <geom name="ball" type="sphere" size="0.05" mass="1"/>
      <site name="centre"/>
    </body>
  </worldbody>
</mujoco>"#;

#[test]
fn loads_from_a_file_and_from_a_string() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("ball.xml");
    std::fs::write(&path, PENDULUM).unwrap();
    let a = Model::from_xml_file(&path).unwrap();
    let b = Model::from_xml_string(PENDULUM, &dir.path().join("virtual.xml")).unwrap();
    for m in [&a, &b] {
        assert_eq!((m.nq(), m.nv(), m.nbody(), m.ngeom(), m.nsite()), (7, 6, 2, 2, 1));
        assert_eq!(m.timestep(), 0.002);
    }
    assert!(!dir.path().join("virtual.xml").exists(), "the string model never touches the disk");
}

#[test]
fn name_lookups_return_results() {
    let m = Model::from_xml_string(PENDULUM, Path::new("/tmp/x.xml")).unwrap();
    assert_eq!(m.id(ObjType::Body, "ball").unwrap(), 1);
    assert_eq!(m.id(ObjType::Site, "centre").unwrap(), 0);
    assert_eq!(m.name(ObjType::Geom, 1).as_deref(), Some("ball"));
    assert_eq!(m.name(ObjType::Geom, 99), None);
    match m.id(ObjType::Joint, "nope") {
        Err(MjError::UnknownName { kind: "joint", name }) => assert_eq!(name, "nope"),
        other => panic!("{other:?}"),
    }
}

#[test]
fn bad_xml_carries_mujocos_message() {
    let err = Model::from_xml_string("<mujoco><worldbody><body><geom type=\"sphere\"", Path::new("/tmp/bad.xml"))
        .unwrap_err();
    match &err {
        MjError::Load { message, .. } => assert!(!message.is_empty(), "{err}"),
        other => panic!("{other:?}"),
    }
    let err = Model::from_xml_string(
        "<mujoco><worldbody><geom type=\"nosuchtype\"/></worldbody></mujoco>",
        Path::new("/tmp/bad.xml"),
    )
    .unwrap_err();
    assert!(err.to_string().to_lowercase().contains("type") || err.to_string().contains("invalid"), "{err}");
    let err = Model::from_xml_file(Path::new("/nonexistent/model.xml")).unwrap_err();
    assert!(matches!(err, MjError::MissingFile { .. }), "{err}");
}

#[test]
fn stepping_views_contacts_and_velocities() {
    let m = Arc::new(Model::from_xml_string(PENDULUM, Path::new("/tmp/x.xml")).unwrap());
    let mut d = Data::new(m.clone()).unwrap();
    d.forward().unwrap();
    assert_eq!(d.contacts().len(), 0);
    let z0 = d.site_xpos()[0][2];
    for _ in 0..100 {
        d.step().unwrap();
    }
    d.forward().unwrap();
    assert!(d.site_xpos()[0][2] < z0, "the ball falls");
    let v = d.object_velocity(ObjType::Site, 0, false).unwrap();
    assert!(v[5] < -0.5, "falling velocity {v:?}");
    assert!(d.object_velocity(ObjType::Site, 5, false).is_err());
    for _ in 0..1000 {
        d.step().unwrap();
    }
    d.forward().unwrap();
    let c = d.contacts();
    assert!(!c.is_empty(), "ball rests on the floor");
    let pair = (c[0].geom1().min(c[0].geom2()), c[0].geom1().max(c[0].geom2()));
    assert_eq!(pair, (0, 1));
    assert_eq!(d.warning_count(Warning::BadQacc), 0);
}

#[test]
fn copy_restores_state_exactly() {
    let m = Arc::new(Model::from_xml_string(PENDULUM, Path::new("/tmp/x.xml")).unwrap());
    let mut d = Data::new(m.clone()).unwrap();
    d.qvel_mut()[0] = 0.3;
    let snapshot = d.try_clone().unwrap();
    let run = |d: &mut Data| {
        for _ in 0..300 {
            d.step().unwrap();
        }
        d.qpos().to_vec()
    };
    let a = run(&mut d);
    d.copy_from(&snapshot).unwrap();
    assert_eq!(run(&mut d), a);
    let other = Arc::new(Model::from_xml_string(PENDULUM, Path::new("/tmp/y.xml")).unwrap());
    let foreign = Data::new(other).unwrap();
    assert!(matches!(d.copy_from(&foreign), Err(MjError::ModelMismatch)));
}

#[test]
fn nan_state_raises_warning_counters() {
    let m = Arc::new(Model::from_xml_string(PENDULUM, Path::new("/tmp/x.xml")).unwrap());
    let mut d = Data::new(m).unwrap();
    blockpuzzle::sim::mj::install_handlers();
    d.qvel_mut()[2] = f64::NAN;
    d.step().unwrap();
    assert!(d.warning_count(Warning::BadQvel) > 0);
}

#[test]
fn version_is_the_engine_built_for() {
    let want = if cfg!(feature = "mujoco3") { "3.11.0" } else { "2.2.2" };
    assert_eq!(blockpuzzle::sim::mj::version(), want);
    assert_eq!(blockpuzzle::sim::mj::header_version(), want);
}

/// A fatal MuJoCo error (here: its stack is too small once the ball touches
/// the floor) makes the call return an error with MuJoCo's message instead of
/// ending the process; a model that fails to compile leaves the handlers in
/// place; the process goes on simulating; another thread's errors are its own.
#[test]
fn fatal_mujoco_errors_return_instead_of_ending_the_process() {
    // 2.2.2 sizes the stack in mjtNums (`nstack`), 3.x its arena in bytes (`memory`).
    let sized = |small: bool| {
        let size = match (cfg!(feature = "mujoco3"), small) {
            (false, true) => "nstack=\"50\"",
            (false, false) => "nstack=\"100\"",
            (true, true) => "memory=\"100\"",
            (true, false) => "memory=\"4K\"",
        };
        PENDULUM.replace("<option timestep=\"0.002\"/>", &format!("<option timestep=\"0.002\"/><size {size}/>"))
    };
    let overflow = |e: &str| e.to_lowercase().contains("stack overflow");
    // Too small even to compile: a load error (and our handlers are back afterwards).
    let err = Model::from_xml_string(&sized(true), Path::new("/tmp/x.xml")).unwrap_err();
    assert!(overflow(&err.to_string()), "{err}");
    let m = Arc::new(Model::from_xml_string(&sized(false), Path::new("/tmp/x.xml")).unwrap());
    let mut d = Data::new(m).unwrap();
    let err = (0..1000).find_map(|_| d.step().err()).expect("the stack overflows once the ball lands");
    assert!(matches!(err, MjError::Fatal { .. }), "{err}");
    assert!(overflow(&err.to_string()), "{err}");
    assert!(d.reset().is_ok(), "reset works on the failed state");
    let again = std::thread::spawn(move || (0..1000).find_map(|_| d.step().err()).map(|e| e.to_string()));
    assert!(again.join().unwrap().is_some_and(|e| overflow(&e)));
    // The process is alive and simulates normally.
    let m = Arc::new(Model::from_xml_string(PENDULUM, Path::new("/tmp/x.xml")).unwrap());
    let mut ok = Data::new(m).unwrap();
    for _ in 0..2000 {
        ok.step().unwrap();
    }
}
