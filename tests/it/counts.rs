//! Variable object counts: the number of copies drawn per episode stays in
//! its range (the curriculum's or a distribution's), absent copies touch
//! nothing and are zero in the observation (mask 0), a seed gives the same
//! episode in any vector engine, and malformed counts are clear errors.

use blockpuzzle::env::{registry, BlockEnv, EnvConfig, ObsMode, ACTION_DIM};
use blockpuzzle::policy::{Policy, RandomPolicy};
use blockpuzzle::task::Task;

fn env(id: &str, mode: ObsMode) -> BlockEnv {
    let mut config = EnvConfig::new(registry::task(id).unwrap());
    config.obs_mode = mode;
    BlockEnv::new(config).unwrap()
}

/// Number of greys present (BlocksChooseN-v0: blue, green, grey.0..grey.3).
fn greys(env: &BlockEnv) -> usize {
    let p = env.present();
    assert!(p[0] && p[1], "blue and green are always there");
    // The first n copies take part.
    let n = p[2..].iter().take_while(|&&x| x).count();
    assert!(p[2 + n..].iter().all(|&x| !x), "present copies form a prefix: {p:?}");
    n
}

#[test]
fn counts_stay_in_their_range_and_cover_it() {
    let mut e = env("BlocksChooseN-v0", ObsMode::Flat);
    for (distribution, lo, hi) in [(None, 0, 4), (Some("few"), 0, 2), (Some("many"), 3, 4), (Some("challenge"), 1, 4)] {
        e.set_distribution(distribution).unwrap();
        let mut seen = [0usize; 5];
        for seed in 0..150 {
            e.reset(Some(seed)).unwrap();
            seen[greys(&e)] += 1;
        }
        for (n, &k) in seen.iter().enumerate() {
            assert_eq!(k > 0, (lo..=hi).contains(&n), "{distribution:?}: {n} greys seen {k} times ({seen:?})");
        }
    }
}

#[test]
fn absent_objects_are_zero_rows_with_mask_zero_and_never_touch() {
    for mode in [ObsMode::Flat, ObsMode::Objects] {
        let mut e = env("BlocksChooseN-v0", mode);
        let spec = e.obs_spec();
        assert_eq!(spec.max_objects, 6);
        let mut policy = RandomPolicy::new(3);
        let mut checked_absent = 0;
        for seed in 0..12 {
            let (mut obs, info) = e.reset(Some(seed)).unwrap();
            let present = e.present().to_vec();
            let absent_objects: Vec<usize> = (0..e.objects().len()).filter(|&o| e.absent_objects()[o]).collect();
            assert_eq!(absent_objects.len(), present.iter().filter(|&&p| !p).count());
            let mut touching = info.touching;
            loop {
                for (k, row) in spec.objects(&obs).enumerate() {
                    if present[k] {
                        assert_eq!(ObsSpec::colour(row).iter().sum::<f32>(), 1.0, "slot {k} has its colour");
                    } else {
                        assert!(row.iter().all(|&v| v == 0.0), "absent slot {k}: {row:?}");
                        checked_absent += 1;
                    }
                }
                if let Some(mask) = spec.mask(&obs) {
                    let want: Vec<f32> = present.iter().map(|&p| if p { 1.0 } else { 0.0 }).collect();
                    assert_eq!(mask, &want[..]);
                }
                for (a, b) in &touching {
                    assert!(
                        !absent_objects.contains(a) && !absent_objects.contains(b),
                        "absent object in a contact {a}-{b}"
                    );
                }
                let s = e.step(&policy.act(&obs)).unwrap();
                touching = s.info.touching.clone();
                obs = s.obs;
                if s.terminated || s.truncated {
                    break;
                }
            }
        }
        assert!(checked_absent > 0, "some episode had an absent grey");
    }
}

use blockpuzzle::env::ObsSpec;

#[test]
fn the_same_seed_gives_the_same_episode() {
    let run = || {
        let mut e = env("BlocksChooseN-v0", ObsMode::Objects);
        let mut out = Vec::new();
        for seed in [5, 6, 5] {
            let (obs, _) = e.reset(Some(seed)).unwrap();
            out.push((e.present().to_vec(), obs));
        }
        out
    };
    let (a, b) = (run(), run());
    assert_eq!(a, b);
    assert_eq!(a[0], a[2], "seed 5 again after seed 6");
}

/// Environment `index`'s observations, rewards and flags over `steps` steps of a vector engine of
/// `n` BlocksChooseN-v0 environments (the `objects` observation) on `threads` threads.
fn vector_trajectory(n: usize, threads: usize, index: usize, steps: usize) -> Vec<f32> {
    let mut config = EnvConfig::new(registry::task("BlocksChooseN-v0").unwrap());
    config.obs_mode = ObsMode::Objects;
    crate::common::vector_trajectory(&config, (n, threads), index, steps, 40)
}

#[test]
fn a_vector_environment_is_the_same_whatever_the_count_and_threads() {
    // 60 steps cross an episode end (50 steps), so an autoreset draws new counts.
    let a = vector_trajectory(2, 1, 1, 60);
    assert_eq!(a, vector_trajectory(2, 2, 1, 60));
    assert_eq!(a, vector_trajectory(4, 3, 1, 60));
}

#[test]
fn a_red_floor_does_not_fail_an_absent_blue() {
    // Two of three blues may be absent, parked on the red floor: the rules never hear of them.
    let text = r#"
version = 1
id = "ParkedBlue-v0"
[floor]
colour = "red"
[[objects]]
name = "green"
colour = "green"
start = { around = "gripper", distance = [0.1, 0.15] }
[[objects]]
name = "blue"
colour = "blue"
count = [1, 3]
start = { around = "green", distance = [0.1, 0.2] }
"#;
    let mut e = BlockEnv::new(EnvConfig::new(Task::from_toml(text, None).unwrap())).unwrap();
    let mut absent_seen = false;
    for seed in 0..20 {
        e.reset(Some(seed)).unwrap();
        absent_seen |= e.present().iter().any(|&p| !p);
        for _ in 0..5 {
            let s = e.step(&[0.0; ACTION_DIM]).unwrap();
            assert!(!s.info.is_failure && !s.terminated, "seed {seed}: {:?}", s.info);
        }
    }
    assert!(absent_seen);
}

fn task_error(text: &str) -> String {
    Task::from_toml(text, None).unwrap_err().to_string()
}

const HEAD: &str = "version = 1\nid = \"T-v0\"\n[[objects]]\nname = \"blue\"\ncolour = \"blue\"\n";

#[test]
fn malformed_counts_are_clear_errors() {
    let green = |extra: &str| format!("{HEAD}[[objects]]\nname = \"green\"\ncolour = \"green\"\n{extra}");
    let e = task_error(&green("count = [3, 1]\n"));
    assert!(e.contains("count = [3, 1]") && e.contains("min ≤ max"), "{e}");
    let e = task_error(&green("count = [0, 0]\n"));
    assert!(e.contains("1 ≤ max"), "{e}");
    // With no green in some episodes, the task would have nothing to succeed with.
    let e = task_error(&green("count = [0, 2]\n"));
    assert!(e.contains("fewest objects") && e.contains("green"), "{e}");
    // An object placed relative to one that may be absent.
    let text = format!(
        "{}[[objects]]\nname = \"grey\"\ncolour = \"grey\"\ncount = [0, 2]\n[[objects]]\nname = \"late\"\ncolour = \"grey\"\nstart = {{ around = \"grey.1\" }}\n",
        green("")
    );
    let e = task_error(&text);
    assert!(e.contains("\"late\"") && e.contains("\"grey.1\"") && e.contains("absent in some episodes"), "{e}");
    // A copy that is always there may anchor another.
    let ok = text.replace("count = [0, 2]", "count = [2, 3]");
    Task::from_toml(&ok, None).unwrap();
    // Distribution counts: an entry without a count, and a range beyond the scene's copies.
    let grey = format!("{}[[objects]]\nname = \"grey\"\ncolour = \"grey\"\ncount = [0, 2]\n", green(""));
    let e = task_error(&format!("{grey}[distributions.d]\ncounts = {{ green = [1, 1] }}\n"));
    assert!(e.contains("\"green\"") && e.contains("not an object entry with a count"), "{e}");
    let e = task_error(&format!("{grey}[distributions.d]\ncounts = {{ grey = [1, 3] }}\n"));
    assert!(e.contains("counts.grey = [1, 3]") && e.contains("[0, 2]"), "{e}");
    // Shuffling an object that may be absent.
    let e = task_error(&format!("shuffle = [[\"blue\", \"grey.1\"]]\n{grey}"));
    assert!(e.contains("shuffle") && e.contains("absent"), "{e}");
    // A count field that is not a pair of counts.
    let e = task_error(&green("count = 2\n"));
    assert!(e.contains("count") || e.contains("invalid type"), "{e}");
}

#[test]
fn tasks_without_counts_draw_nothing_for_them() {
    // The built-in tasks keep their episodes (tests/it/golden.rs pins them); here: no slot is ever absent.
    for id in registry::ids().into_iter().filter(|id| *id != "BlocksChooseN-v0") {
        let task = registry::task(id).unwrap();
        if !task.count_groups().is_empty() {
            continue;
        }
        let mut e = BlockEnv::new(EnvConfig::new(task)).unwrap();
        e.reset(Some(1)).unwrap();
        assert!(e.present().iter().all(|&p| p), "{id}");
    }
}

#[cfg(feature = "train")]
#[test]
fn the_grey_blind_view_drops_absent_greys_too() {
    use blockpuzzle::policy::actor::without_grey;
    let mut e = env("BlocksChooseN-v0", ObsMode::Flat);
    for seed in 0..10 {
        let (obs, _) = e.reset(Some(seed)).unwrap();
        // Whatever the number of greys: robot, blue, green (the BlocksTouch-v0 observation).
        let v = without_grey(&obs);
        assert_eq!(v.len(), blockpuzzle::env::obs_dim(2), "seed {seed}");
        assert_eq!(&v[..], &obs[..blockpuzzle::env::obs_dim(2)]);
    }
}
