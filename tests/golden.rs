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
#[cfg(not(feature = "mujoco3"))]
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

/// The same cases on MuJoCo 3.11.0 (the `mujoco3` feature), recorded when that
/// engine was added: another engine, other trajectories, each as reproducible.
#[cfg(feature = "mujoco3")]
const GOLDEN: &[&str] = &[
    "92bb762b86e5cbca84b16ab32df313a31ef999338437be46a5832ad6f3a73033",
    "e2fc3ab2ff1af6c4a8d8ae5e838919caee10b28624fd316051f32c8c1f627eae",
    "98df2056f915c2be7139826e0de3b8f610b6c872f37d6f111234c3c115288448",
    "6e5b0a4bf6d533e1715a5fdb8dc8b46fca5d17e3e3eb43b0dc8372974558dded",
    "075752a86e25fb56d0b1041c06ddf729a67f807a1324fd5a2bf89d81ad8ed908",
    "2ef844d3478e285b315bf3c3e624914f5324eaa00d7a6802d2ce41fd8c295479",
    "44cf87e68e4554e22f868a04171c7eaf5b14eaf130264ced05dd977a5d94abb9",
    "b93b057beecaee06ced94e824db3ac0c592d3de34f71be8cd7b5bb17372753fc",
    "a76dc1a588caa0d26ad732337ccd8acdd3aea3edb222e4e48a8846fc6486a4e4",
    "8952a368d7e662a75837d27ac7605d7595083cf866a9a54776b5e05660ede405",
    "6444d786f8fc1ca6170003f34425d16b7b06c9533d0a03be5634c837796c07ac",
    "b139c601ad6da57842d2f4ab128c1d50cb771ad1df55ba0e6a0154c057fa8d3c",
    "28d2c31fd3c3d603071de171c1a40fa03da513b445201645899d4f2fc7bb1f5a",
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

#[cfg(not(feature = "mujoco3"))]
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

#[cfg(feature = "mujoco3")]
const NEW_GOLDEN: &[&str] = &[
    "577995fc20a6bb46c1b37ce7d03fee278a268e045ecd25e37b9d2070bdf1b4d4",
    "89247ab4a51d4033cf1b18f9224c8bb84158e0a6eb090b7149625f17663d25a3",
    "6dd48df3f1000af3bfef2b2d2dae59345dec871696bb30ff4df2225427054303",
    "66cb74a1b3c0967ced9e63d1b8eb48693da7dd72b7c7b2c82d8c6d7251720aa3",
    "deaabda3273ff4ba42151135710b50edd63ee30582c158e33096c6483a64264e",
    "4f8a90d5d2d5ad62211b3f7922cf8f98a3e729750632cbd31613d4f7f3320db4",
    "c901ebf0d3fcd92883b87b98be5e2d0a192f170ab5ee81b6d78bd4511578dea7",
    "da1fa35b93b276061b1609103284510ce2e03375085dde3d62a2ca5ba26e5c0a",
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
