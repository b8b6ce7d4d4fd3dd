//! Property tests of the block placement over thousands of seeds (no MuJoCo).

use blockpuzzle::curriculum::{choose_radii, dist, is_valid, touch_radius, Layout, MIN_SEPARATION};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

const GRIP: [f64; 2] = [1.3419, 0.7491];
const SEEDS: u64 = 3000;
const EPS: f64 = 1e-9;

fn mid(a: [f64; 2], b: [f64; 2]) -> [f64; 2] {
    [(a[0] + b[0]) / 2.0, (a[1] + b[1]) / 2.0]
}

#[test]
fn levels_follow_the_paper() {
    assert_eq!(touch_radius(0), 0.08);
    assert!((touch_radius(2) - 0.13).abs() < EPS);
    assert_eq!(touch_radius(5), 0.20);
    assert_eq!(touch_radius(50), 0.20);
    assert_eq!(Layout::Touch.max_level(), 5);
    assert_eq!(Layout::Choose.max_level(), 10);
    let (r, rmin) = choose_radii(0);
    assert_eq!((r, rmin), (0.08, 0.20));
    let (r, rmin) = choose_radii(10);
    assert_eq!(r, 0.30);
    assert!(rmin.abs() < EPS);
    assert!((choose_radii(4).1 - 0.12).abs() < EPS);
}

#[test]
fn touch_placements_respect_every_constraint() {
    for level in 0..=5 {
        let r = touch_radius(level);
        for seed in 0..SEEDS {
            let mut rng = ChaCha8Rng::seed_from_u64(seed);
            let ps = Layout::Touch.sample(level, false, GRIP, 2, &mut rng).unwrap();
            assert!(is_valid(&ps), "level {level} seed {seed}: {ps:?}");
            assert!(dist(ps[0], GRIP) <= r + EPS);
            let d = dist(ps[0], ps[1]);
            assert!(d >= MIN_SEPARATION - EPS && d <= r + EPS, "level {level} seed {seed}: {d}");
        }
    }
}

#[test]
fn choose_placements_respect_every_constraint() {
    for level in 0..=10 {
        let (r, rmin) = choose_radii(level);
        for seed in 0..SEEDS / 2 {
            let mut rng = ChaCha8Rng::seed_from_u64(seed);
            let ps = Layout::Choose.sample(level, false, GRIP, 3, &mut rng).unwrap();
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
    for seed in 0..SEEDS {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let ps = Layout::Choose.sample(10, true, GRIP, 3, &mut rng).unwrap();
        assert!(is_valid(&ps), "seed {seed}: {ps:?}");
        let d = dist(ps[0], ps[1]);
        assert!((0.15 - EPS..=0.30 + EPS).contains(&d), "seed {seed}: blue-green {d}");
        assert!(dist(ps[2], mid(ps[0], ps[1])) <= 0.04 + EPS);
    }
}

#[test]
fn near_gripper_annulus() {
    let layout = Layout::NearGripper { min: 0.1, max: 0.15 };
    for seed in 0..SEEDS {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let ps = layout.sample(0, false, GRIP, 1, &mut rng).unwrap();
        let d = dist(ps[0], GRIP);
        assert!((0.1 - EPS..=0.15 + EPS).contains(&d) && is_valid(&ps), "seed {seed}: {d}");
    }
}

#[test]
fn placements_are_reproducible_and_vary() {
    let draw = |seed| Layout::Choose.sample(3, false, GRIP, 3, &mut ChaCha8Rng::seed_from_u64(seed)).unwrap();
    assert_eq!(draw(7), draw(7));
    assert_ne!(draw(7), draw(8));
}

#[test]
fn fixed_layout_checks_its_size() {
    let layout = Layout::Fixed(vec![[1.3, 0.7]]);
    assert!(layout.sample(0, false, GRIP, 2, &mut ChaCha8Rng::seed_from_u64(0)).is_err());
}
