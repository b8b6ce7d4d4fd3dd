//! Each rule scenario in simulation, with blocks placed by hand.

use blockpuzzle::env::{BlockEnv, EnvConfig, EnvError};
use blockpuzzle::sim::rules::{ContactState, Verdict};
use blockpuzzle::task::spec::TaskSpec;
use blockpuzzle::Colour::{self, *};

const FAR: [f64; 2] = [1.12, 1.02];
// 4.9 cm apart: the 5 cm cubes overlap by 1 mm, so MuJoCo reports a contact
const A: [f64; 2] = [1.30, 0.60];
const A_TOUCH: [f64; 2] = [1.349, 0.60];

fn spec(blocks: Vec<Colour>, positions: Vec<[f64; 2]>) -> TaskSpec {
    TaskSpec::fixed("Test-v0", &blocks, &positions).unwrap()
}

fn env(blocks: Vec<Colour>, positions: Vec<[f64; 2]>) -> BlockEnv {
    BlockEnv::new(EnvConfig::from_spec(spec(blocks, positions)).unwrap()).unwrap()
}

/// A fixed-layout task with the gripper and table in these colours.
fn coloured(gripper: Colour, table: Colour, blocks: Vec<Colour>, positions: Vec<[f64; 2]>) -> BlockEnv {
    let mut s = spec(blocks, positions);
    s.robot.gripper = gripper;
    s.table.colour = table;
    BlockEnv::new(EnvConfig::from_spec(s).unwrap()).unwrap()
}

#[test]
fn blue_placed_touching_green_succeeds_on_the_first_step() {
    let mut e = env(vec![Blue, Green], vec![A, A_TOUCH]);
    let (_, info) = e.reset(Some(0)).unwrap();
    assert!(info.touching.contains(&(2, 3)), "{:?}", info.touching);
    assert!(!info.is_success, "success is only declared by a step");
    let s = e.step(&[0.0; 4]).unwrap();
    assert!(s.terminated && !s.truncated && s.info.is_success && !s.info.is_failure);
    assert_eq!(s.reward, 0.0);
    assert_eq!(e.verdict(), Some(Verdict::Success));
    assert_eq!(e.contact_matrix().get(2, 3), ContactState::TouchingNow);
}

#[test]
fn red_touching_blue_at_reset_is_rejected() {
    let mut e = env(vec![Blue, Green, Red], vec![A, FAR, A_TOUCH]);
    match e.reset(Some(0)) {
        Err(EnvError::InitialViolation { red, blue }) => {
            assert_eq!((red.as_str(), blue.as_str()), ("block2", "block0"))
        }
        other => panic!("{other:?}"),
    }
    let mut red_table = coloured(Grey, Red, vec![Blue, Green], vec![A, FAR]);
    let err = red_table.reset(Some(0)).unwrap_err();
    assert!(err.to_string().contains("table") && err.to_string().contains("block0"), "{err}");
}

#[test]
fn blue_gripper_on_red_block_fails_with_the_remaining_steps_as_penalty() {
    let mut e = coloured(Blue, Grey, vec![Red, Green], vec![[1.342, 0.749], FAR]);
    e.reset(Some(0)).unwrap();
    let mut t = 0;
    loop {
        let s = e.step(&[0.0, 0.0, -1.0, 0.0]).unwrap();
        t += 1;
        if s.terminated {
            assert!(s.info.is_failure && !s.info.is_success);
            assert_eq!(s.reward, -((50 - t + 1) as f32), "failure at step {t}");
            assert!(s.info.touching.contains(&(0, 2)), "{:?}", s.info.touching);
            break;
        }
        assert_eq!(s.reward, -1.0);
        assert!(t < 20, "the gripper never reached the red block");
    }
}

#[test]
fn blue_gripper_on_red_table_fails() {
    let mut e = coloured(Blue, Red, vec![Green], vec![FAR]);
    e.reset(Some(0)).unwrap();
    let outcome = (0..20).find_map(|_| {
        let s = e.step(&[0.0, 0.0, -1.0, 0.0]).unwrap();
        s.terminated.then_some(s.info.is_failure)
    });
    assert_eq!(outcome, Some(true));
}

#[test]
fn grey_and_red_green_contacts_are_neutral() {
    // grey touching blue, and red touching green: nothing happens
    let mut e = env(vec![Blue, Green, Grey, Red], vec![A, FAR, A_TOUCH, [FAR[0] + 0.049, FAR[1]]]);
    let (_, info) = e.reset(Some(0)).unwrap();
    assert!(info.touching.contains(&(2, 4)) && info.touching.contains(&(3, 5)), "{:?}", info.touching);
    for _ in 0..3 {
        let s = e.step(&[0.0, 0.0, 0.5, 0.0]).unwrap();
        assert!(!s.terminated && !s.info.is_success && !s.info.is_failure);
        assert_eq!(s.reward, -1.0);
    }
    assert_eq!(e.contact_matrix().get(2, 4), ContactState::TouchingNow);
    assert_eq!(e.contact_matrix().get(2, 3), ContactState::NeverTouched);
}

#[test]
fn blue_gripper_reaching_green_block_succeeds() {
    let mut e = blockpuzzle::make("GripperTouch-v0").unwrap();
    let mut policy = blockpuzzle::policy::ScriptedPolicy::for_env(e.config());
    use blockpuzzle::policy::Policy;
    let (mut obs, _) = e.reset(Some(11)).unwrap();
    for _ in 0..50 {
        let s = e.step(&policy.act(&obs)).unwrap();
        if s.terminated {
            assert!(s.info.is_success && s.info.touching.contains(&(0, 2)));
            return;
        }
        obs = s.obs;
    }
    panic!("the gripper never touched the green block");
}
