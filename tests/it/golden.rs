//! The environments stay bit-identical: digests of seeded episodes (random and
//! scripted policies, several levels and the challenge distribution; every
//! reset state, action, qpos, reward, flag and contact) must equal those
//! recorded in tests/golden.json for the engine of this build, so published
//! results and trained policies remain valid. The built-ins' 2.2.2 digests
//! were recorded before they became task files; the Python wheel checks the
//! 3.11.0 ones (python/tests/test_env.py).
//!
//! `BLOCKPUZZLE_PRINT_GOLDEN=1 cargo test --test it golden:: -- --nocapture`
//! prints the digests instead of checking them (only for a deliberate,
//! documented break).

use blockpuzzle::episode::rollout::episode_digest;

#[test]
fn environments_are_bit_identical_to_the_recorded_digests() {
    let engine = blockpuzzle::sim::mj::version();
    let golden: serde_json::Value =
        serde_json::from_str(include_str!("../golden.json")).expect("tests/golden.json is JSON");
    let cases = golden["cases"].as_array().expect("a list of cases");
    assert!(cases.len() >= 21, "the recorded cases are all there");
    let print = std::env::var_os("BLOCKPUZZLE_PRINT_GOLDEN").is_some();
    for case in cases {
        let id = case["env"].as_str().expect("env");
        let scripted = case["policy"].as_str() == Some("scripted");
        let level = case["level"].as_u64().expect("level") as usize;
        let challenge = case["challenge"].as_bool().expect("challenge");
        let seed = case["seed"].as_u64().expect("seed");
        let d = episode_digest(id, scripted, level, challenge, seed).expect("the case plays");
        if print {
            println!("{id} {} level {level} challenge {challenge} seed {seed}: {d}", case["policy"]);
            continue;
        }
        let want = case[engine.as_str()].as_str().unwrap_or_else(|| panic!("no digest recorded for MuJoCo {engine}"));
        assert_eq!(d, want, "episodes of {case} changed on MuJoCo {engine}");
    }
}
