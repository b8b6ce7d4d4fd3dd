//! The set network as a policy: on real `objects` observations its
//! action does not depend on the order of the object rows nor on padded rows,
//! it plays observations with more slots exactly as with fewer, and it
//! round-trips through the zoo (format 3) acting identically.
#![cfg(feature = "train")]

use blockpuzzle::benchmark::saved::SavedPolicy;
use blockpuzzle::benchmark::zoo::{self, ExportInfo};
use blockpuzzle::env::{registry, BlockEnv, EnvConfig, ObsMode, ObsSpec};
use blockpuzzle::learn::agents::arch::{Arch, NetConfig, NetKind, Pooling};
use blockpuzzle::learn::agents::ddpg::{Ddpg, DdpgConfig};
use blockpuzzle::learn::agents::shared::SharedConfig;
use blockpuzzle::policy::actor::AnyPolicy;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

fn objects_env(id: &str) -> BlockEnv {
    BlockEnv::new(EnvConfig { obs_mode: ObsMode::Objects, ..EnvConfig::new(registry::task(id).unwrap()) }).unwrap()
}

/// A set DDPG agent on `id`'s `objects` observation, its normaliser fitted to some reset observations.
fn set_agent(id: &str, pooling: Pooling, seed: u64) -> (Ddpg, Vec<Vec<f32>>) {
    let mut env = objects_env(id);
    env.set_level(env.max_level()).unwrap();
    let net = NetConfig { net: NetKind::Set, set_pooling: pooling, ..NetConfig::default() };
    let arch = Arch::of(&env.obs_spec(), &net).unwrap();
    let shared = SharedConfig { hidden: 32, layers: 2, ..SharedConfig::default() };
    let mut agent = Ddpg::build(arch, 4, shared, DdpgConfig::default(), &mut ChaCha8Rng::seed_from_u64(seed));
    let obs: Vec<Vec<f32>> = (0..20).map(|s| env.reset(Some(s)).unwrap().0.to_vec()).collect();
    agent.norm.update(&obs.concat());
    (agent, obs)
}

/// `obs` (laid out as `spec`) with its object slots in the order `perm`.
fn permuted(spec: &ObsSpec, obs: &[f32], perm: &[usize]) -> Vec<f32> {
    let (r, f, m) = (spec.robot_dim(), spec.object_dim(), spec.max_objects);
    let mut y = obs[..r].to_vec();
    for &k in perm {
        y.extend_from_slice(&obs[r + k * f..r + (k + 1) * f]);
    }
    y.extend(perm.iter().map(|&k| obs[r + m * f + k]));
    y
}

/// `obs` with `extra` more slots holding junk rows and mask 0.
fn padded(spec: &ObsSpec, obs: &[f32], extra: usize) -> Vec<f32> {
    let (r, f, m) = (spec.robot_dim(), spec.object_dim(), spec.max_objects);
    let mut y = obs[..r + m * f].to_vec();
    y.extend(std::iter::repeat(3.25).take(extra * f));
    y.extend_from_slice(&obs[r + m * f..]);
    y.extend(std::iter::repeat(0.0).take(extra));
    y
}

#[test]
fn a_set_policy_ignores_row_order_and_padding_on_real_observations() {
    for pooling in [Pooling::MeanMax, Pooling::Attention, Pooling::Colour] {
        let (agent, observations) = set_agent("BlocksChooseN-v0", pooling, 1);
        let policy = AnyPolicy::Deterministic(agent.policy());
        let spec = objects_env("BlocksChooseN-v0").obs_spec();
        let bigger = policy.with_slots(spec.max_objects + 3);
        let mut moved = 0;
        for obs in &observations {
            let a = policy.act(obs);
            for perm in [[5, 4, 3, 2, 1, 0], [1, 0, 2, 3, 4, 5], [2, 5, 0, 4, 1, 3]] {
                let b = policy.act(&permuted(&spec, obs, &perm));
                assert!(a.iter().zip(&b).all(|(x, y)| (x - y).abs() < 1e-5), "{pooling:?} {perm:?}: {a:?} vs {b:?}");
            }
            // Three more slots, all absent (junk rows): exactly the same action.
            assert_eq!(bigger.act(&padded(&spec, obs, 3)), a, "{pooling:?}");
            // A present row does change the action: the network reads the rows.
            let mut other = obs.clone();
            other[spec.robot_dim()] += 0.5;
            moved += usize::from(policy.act(&other) != a);
        }
        assert!(moved > 0, "{pooling:?}: the first row's position changed nothing");
    }
}

#[test]
fn a_set_policy_round_trips_through_the_zoo() {
    let dir = tempfile::tempdir().unwrap();
    for (k, pooling) in [Pooling::MeanMax, Pooling::Attention, Pooling::Colour].into_iter().enumerate() {
        let (agent, observations) = set_agent("BlocksChoose-v0", pooling, 2);
        let task = registry::task("BlocksChoose-v0").unwrap();
        let saved = SavedPolicy {
            env_id: "BlocksChoose-v0".into(),
            task: Some(task.source),
            tasks: Vec::new(),
            stream: None,
            epoch: 3,
            env_steps: Some(1000),
            finals_success: 0.0,
            algo: Some(blockpuzzle::benchmark::saved::Trainer::Td3),
            obs_mode: None,
            fixtures: None,
            policy: AnyPolicy::Deterministic(agent.policy()),
            critic: Some(agent.critic.to_plain()),
            blend: None,
            started_from: None,
            solver: None,
        };
        let info = ExportInfo {
            name: format!("set-{k}"),
            description: "a test entry".into(),
            keep_critic: true,
            ..ExportInfo::default()
        };
        let path = zoo::export(dir.path(), &saved, &info).unwrap();
        let (meta, loaded) = zoo::load(&path).unwrap();
        assert_eq!(meta.format, zoo::FORMAT);
        assert_eq!(meta.actor.set, saved.policy.net().set);
        assert_eq!(meta.actor.sizes[0], observations[0].len(), "the observation's length");
        assert_eq!(loaded.obs_mode(), ObsMode::Objects);
        for obs in &observations {
            assert_eq!(loaded.policy.act(obs), saved.policy.act(obs));
            let mut sa = obs.clone();
            sa.extend([0.1, -0.2, 0.3, 0.9]);
            assert_eq!(loaded.critic.as_ref().unwrap().forward(&sa), saved.critic.as_ref().unwrap().forward(&sa));
        }
        // The probes were taken on the `objects` observation.
        assert_eq!(meta.probes[0].obs.len(), observations[0].len());
    }
}
