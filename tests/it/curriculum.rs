//! Property tests of the built-in tasks' layouts over thousands of seeds
//! (the task sampler alone, no MuJoCo): the curricula of the paper.

use blockpuzzle::env::registry;
use blockpuzzle::task::sampler::Placed;
use blockpuzzle::task::Task;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

const GRIP: [f64; 2] = [1.3419, 0.7491];
const SEEDS: u64 = 3000;
const EPS: f64 = 1e-9;
const TABLE_CENTER: [f64; 2] = [1.3, 0.75];
const TABLE_HALF: [f64; 2] = [0.25, 0.35];

fn dist(a: [f64; 2], b: [f64; 2]) -> f64 {
    (a[0] - b[0]).hypot(a[1] - b[1])
}

fn mid(a: [f64; 2], b: [f64; 2]) -> [f64; 2] {
    [(a[0] + b[0]) / 2.0, (a[1] + b[1]) / 2.0]
}

/// On the table with a block's margin and centres at least 7.5 cm apart.
fn is_valid(ps: &[[f64; 2]]) -> bool {
    ps.iter().all(|p| (0..2).all(|k| (p[k] - TABLE_CENTER[k]).abs() <= TABLE_HALF[k] - 0.025))
        && ps.iter().enumerate().all(|(i, a)| ps[i + 1..].iter().all(|b| dist(*a, *b) >= 0.075))
}

fn param(task: &Task, level: usize, name: &str) -> f64 {
    task.params(level, None).into_iter().find(|(n, _)| n == name).unwrap().1
}

fn draw(task: &Task, level: usize, distribution: Option<usize>, seed: u64) -> Vec<[f64; 2]> {
    let ps: Vec<Option<Placed>> = task.sample(level, distribution, GRIP, &mut ChaCha8Rng::seed_from_u64(seed)).unwrap();
    // These tasks have no counts: every object is placed.
    let ps: Vec<Placed> = ps.into_iter().map(|p| p.expect("no absent objects")).collect();
    assert!(ps.iter().all(|p| p.z.is_none() && p.yaw.is_none()), "built-in blocks rest on the table unturned");
    ps.iter().map(|p| p.xy).collect()
}

#[test]
fn levels_follow_the_paper() {
    let touch = registry::task("BlocksTouch-v0").unwrap();
    let choose = registry::task("BlocksChoose-v0").unwrap();
    assert_eq!(param(&touch, 0, "R"), 0.08);
    assert!((param(&touch, 2, "R") - 0.13).abs() < EPS);
    assert_eq!(param(&touch, 5, "R"), 0.20);
    assert_eq!(param(&touch, 50, "R"), 0.20, "levels beyond the maximum are clamped");
    assert_eq!(touch.max_level(), 5);
    assert_eq!(choose.max_level(), 10);
    assert_eq!((param(&choose, 0, "R"), param(&choose, 0, "R_min")), (0.08, 0.20));
    assert_eq!(param(&choose, 10, "R"), 0.30);
    assert!(param(&choose, 10, "R_min").abs() < EPS);
    assert!((param(&choose, 4, "R_min") - 0.12).abs() < EPS);
    assert_eq!(touch.spec.curriculum.success_threshold, 0.7);
    assert_eq!(choose.distribution_names(), vec!["challenge"]);
}

#[test]
fn touch_placements_respect_every_constraint() {
    let task = registry::task("BlocksTouch-v0").unwrap();
    for level in 0..=5 {
        let r = param(&task, level, "R");
        for seed in 0..SEEDS {
            let ps = draw(&task, level, None, seed);
            assert!(is_valid(&ps), "level {level} seed {seed}: {ps:?}");
            assert!(dist(ps[0], GRIP) <= r + EPS);
            let d = dist(ps[0], ps[1]);
            assert!(d >= 0.075 - EPS && d <= r + EPS, "level {level} seed {seed}: {d}");
        }
    }
}

#[test]
fn choose_placements_respect_every_constraint() {
    let task = registry::task("BlocksChoose-v0").unwrap();
    for level in 0..=10 {
        let (r, rmin) = (param(&task, level, "R"), param(&task, level, "R_min"));
        for seed in 0..SEEDS / 2 {
            let ps = draw(&task, level, None, seed);
            assert!(is_valid(&ps), "level {level} seed {seed}: {ps:?}");
            assert!(dist(ps[0], GRIP) <= r + EPS);
            assert!(dist(ps[0], ps[1]) <= r + EPS);
            let g = dist(ps[2], mid(ps[0], ps[1]));
            assert!(g >= rmin - EPS && g <= 0.30 + EPS, "level {level} seed {seed}: grey at {g}");
        }
    }
}

#[test]
fn challenge_placements_respect_every_constraint() {
    let task = registry::task("BlocksChoose-v0").unwrap();
    let challenge = task.distribution("challenge");
    for seed in 0..SEEDS {
        let ps = draw(&task, 0, challenge, seed);
        assert!(is_valid(&ps), "seed {seed}: {ps:?}");
        let d = dist(ps[0], ps[1]);
        assert!((0.15 - EPS..=0.30 + EPS).contains(&d), "seed {seed}: blue-green {d}");
        assert!(dist(ps[2], mid(ps[0], ps[1])) <= 0.04 + EPS);
    }
}

#[test]
fn near_gripper_annulus() {
    let task = registry::task("GripperTouch-v0").unwrap();
    for seed in 0..SEEDS {
        let ps = draw(&task, 0, None, seed);
        let d = dist(ps[0], GRIP);
        assert!((0.1 - EPS..=0.15 + EPS).contains(&d) && is_valid(&ps), "seed {seed}: {d}");
    }
}

#[test]
fn placements_are_reproducible_and_vary() {
    let task = registry::task("BlocksChoose-v0").unwrap();
    assert_eq!(draw(&task, 3, None, 7), draw(&task, 3, None, 7));
    assert_ne!(draw(&task, 3, None, 7), draw(&task, 3, None, 8));
}
