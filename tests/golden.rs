//! The built-in environments stay bit-identical: digests of seeded episodes
//! (random and scripted policies, several levels and the challenge
//! distribution), recorded before the built-ins became task files, must not
//! change. They cover every reset state, action, qpos, reward and flag, so
//! published results and trained policies remain valid.
//!
//! `BLOCKPUZZLE_PRINT_GOLDEN=1 cargo test --test golden -- --nocapture`
//! prints the digests instead of checking them (only for a deliberate,
//! documented break).

use blockpuzzle::env::registry;
use blockpuzzle::policy::{Policy, RandomPolicy, ScriptedPolicy};
use blockpuzzle::rollout::{run_episode, EpisodeRecord};
use sha2::{Digest, Sha256};

/// (env id, policy, level, challenge, first seed); three episodes each.
const CASES: &[(&str, &str, usize, bool, u64)] = &[
    ("BlocksTouch-v0", "random", 0, false, 0),
    ("BlocksTouch-v0", "random", 5, false, 10),
    ("BlocksTouch-v0", "scripted", 0, false, 20),
    ("BlocksTouch-v0", "scripted", 2, false, 30),
    ("BlocksTouch-v0", "scripted", 5, false, 40),
    ("BlocksChoose-v0", "random", 3, false, 50),
    ("BlocksChoose-v0", "random", 10, true, 60),
    ("BlocksChoose-v0", "scripted", 0, false, 70),
    ("BlocksChoose-v0", "scripted", 5, false, 80),
    ("BlocksChoose-v0", "scripted", 10, false, 90),
    ("BlocksChoose-v0", "scripted", 10, true, 100),
    ("GripperTouch-v0", "random", 0, false, 110),
    ("GripperTouch-v0", "scripted", 0, false, 120),
];

/// Recorded at commit bb154a3, before the built-ins became task files.
const GOLDEN: &[&str] = &[
    "b481516c8754462f43a536194c2cc6410dc643aee01e8b858eb84fd6fe351766",
    "852af3041a9ed49d9c8f22c56a0f4ee853c1d6adacd1daab6da7d747592abf65",
    "0268089034247403c01c99eb6878b60ae0c474a995ff908167a1e3d0f0be65b1",
    "dda20156c63ccaace55ae708798a6aa71c324ef399ec7e1a58603adeeeb7e406",
    "493c40f2a6732bd8e00bc47cf7413f1cb18687a79d4ad40440a9b6a4eb0aefbf",
    "3e1450729483a11945340b0830a648cc310a11b04ae129f9e0ab0e6159c7783a",
    "369166ce903e4c5f8455bb6cfbd7b7c178d4742fdab82aa839fd6c4a04f5addb",
    "4ebd48044d204b2daad351f9304fd5c471a9425169b664d14c44d59698568ed2",
    "39c84b0e0062e42a093ffd8fe0ee9d6771f4d50369fd72884c1a387e3474987c",
    "7a176b07d081b8c7c8f285afaa540a242dc52748bf344b1d4c6980e10992b859",
    "4fc7a0fe302e93e84075aa3b605c280ab23e9bb830815174093500ab8221d242",
    "ca2f8b1a5eeb1da28c96b68a4bc9dcc51ca6951722bf0a213fba164681796082",
    "9da5e7c5c1b80fde8f0873f1a17cfd1af63e5d958c194eb9a9251928ae001608",
];

fn absorb(h: &mut Sha256, ep: &EpisodeRecord) {
    let f64s = |h: &mut Sha256, v: &[f64]| v.iter().for_each(|x| h.update(x.to_bits().to_le_bytes()));
    f64s(h, &ep.initial.qpos);
    for s in &ep.steps {
        s.action.iter().for_each(|a| h.update(a.to_bits().to_le_bytes()));
        f64s(h, &s.state.qpos);
        h.update(s.reward.to_bits().to_le_bytes());
        h.update([s.terminated as u8, s.truncated as u8, s.is_success as u8, s.is_failure as u8, s.unstable as u8]);
        for &(a, b) in &s.touching {
            h.update([a as u8, b as u8]);
        }
    }
}

/// The tasks added as task files, recorded when they were added: they pin the
/// draw order of the `on`, `towards`, `angle` and `yaw` samplers, the shuffle,
/// the settling at reset and the gripper action.
const NEW_CASES: &[(&str, &str, usize, bool, u64)] = &[
    ("BlocksChooseShuffled-v0", "scripted", 10, false, 200),
    ("BlocksChooseShuffled-v0", "random", 3, true, 210),
    ("ReachAvoid-v0", "scripted", 5, false, 220),
    ("ReachAvoid-v0", "random", 2, false, 230),
    ("ToppleTower-v0", "scripted", 3, false, 240),
    ("ToppleTower-v0", "random", 0, false, 250),
    ("BlocksStack-v0", "scripted", 4, false, 260),
    ("BlocksStack-v0", "random", 1, false, 270),
];

const NEW_GOLDEN: &[&str] = &[
    "6112c80f1072d3025d1616a82f1eff6baff2be634cca39350689675a557ba1e4",
    "6ea200eecf90d4faa784c0a7871abd1f5a8c927383d3014c5690f84015799aad",
    "4e5751272fc6f368ced96d3e6c3f9941cf238dadc934e044c7cf0066406e298a",
    "9fa62554f12d417ec829c2d7dd55c0534afe67bb25bbcee6d1ab0f36b9b90101",
    "6120d50130339c70024225f714a3fffddee65faf46eb55822de674e0da1617ee",
    "ca5f6994374c715bae5bedd37b3a9039d9ba14c0f403989246146b9d63634cbb",
    "ba7c165de8eef8cb9c6d210e12889e7dabf7b10688caaffbb253c564d3f40d7a",
    "1b627df8da36b403f961d4f3cab9008b913fa6241720f23b10db93ed23912dca",
];

fn digest(&(id, policy, level, challenge, seed): &(&str, &str, usize, bool, u64)) -> String {
    let mut env = registry::make(id).unwrap();
    env.set_level(level).unwrap();
    env.set_challenge(challenge).unwrap();
    let colours = |e: &blockpuzzle::BlockEnv| e.block_colours().iter().map(|c| *c as u8).collect::<Vec<u8>>();
    let mut policy: Box<dyn Policy> = match policy {
        "random" => Box::new(RandomPolicy::new(seed)),
        _ => Box::new(ScriptedPolicy::for_env(env.config())),
    };
    let mut h = Sha256::new();
    for k in 0..3 {
        let ep = run_episode(&mut env, policy.as_mut(), seed + k).unwrap();
        absorb(&mut h, &ep);
        if !env.config().task.spec.shuffle.is_empty() {
            h.update(colours(&env));
        }
    }
    h.finalize().iter().map(|b| format!("{b:02x}")).collect()
}

fn check(cases: &[(&str, &str, usize, bool, u64)], golden: &[&str]) {
    let digests: Vec<String> = cases.iter().map(digest).collect();
    if std::env::var_os("BLOCKPUZZLE_PRINT_GOLDEN").is_some() {
        for d in &digests {
            println!("    \"{d}\",");
        }
        return;
    }
    assert_eq!(digests.len(), golden.len(), "one recorded digest per case");
    for ((case, d), g) in cases.iter().zip(&digests).zip(golden) {
        assert_eq!(d, g, "episodes of {case:?} changed");
    }
}

#[test]
fn builtin_environments_are_bit_identical_to_the_recorded_digests() {
    check(CASES, GOLDEN);
}

#[test]
fn new_tasks_are_bit_identical_to_their_recorded_digests() {
    check(NEW_CASES, NEW_GOLDEN);
}
