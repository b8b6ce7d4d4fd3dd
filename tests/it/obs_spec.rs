//! The observation spec: the flat layout every id has by default, and the
//! object-centric layout (robot | object rows | mask) selected per
//! environment; readers take offsets from the spec.

use blockpuzzle::env::{registry, BlockEnv, EnvConfig, ObsMode, ObsSpec, BLOCK_OBS, ROBOT_OBS};
use blockpuzzle::policy::{Policy, ScriptedPolicy};

fn env(id: &str, mode: ObsMode) -> BlockEnv {
    let task = registry::task(id).unwrap();
    BlockEnv::new(EnvConfig { obs_mode: mode, ..EnvConfig::new(task) }).unwrap()
}

#[test]
fn the_spec_describes_each_layout() {
    let flat = ObsSpec::flat(3);
    assert_eq!(flat.dim(), ROBOT_OBS + 3 * BLOCK_OBS);
    assert_eq!(flat.names().len(), flat.dim());
    assert_eq!(flat.names()[ROBOT_OBS + BLOCK_OBS], "object1/pos.x");
    assert_eq!(flat.names().last().unwrap(), "object2/colour.grey");
    let objects = ObsSpec::new(ObsMode::Objects, 3);
    assert_eq!(objects.object_dim(), BLOCK_OBS + 3);
    assert_eq!(objects.dim(), ROBOT_OBS + 3 * (BLOCK_OBS + 3) + 3);
    assert_eq!(objects.names().len(), objects.dim());
    assert_eq!(objects.names()[ROBOT_OBS + BLOCK_OBS], "object0/size.x");
    assert_eq!(objects.names().last().unwrap(), "mask/2");
    assert_eq!("objects".parse::<ObsMode>(), Ok(ObsMode::Objects));
    let err = "set".parse::<ObsMode>().unwrap_err();
    assert!(err.contains("\"flat\" or \"objects\""), "{err}");
    // Every mode: its name parses back, and its spec's names, dimension and mask agree.
    for mode in ObsMode::ALL {
        assert_eq!(mode.name().parse::<ObsMode>(), Ok(mode));
        assert_eq!(mode.to_string(), mode.name());
        let spec = ObsSpec::new(mode, 2);
        assert_eq!(spec.names().len(), spec.dim(), "{mode}");
        assert_eq!(spec.object_dim(), BLOCK_OBS + mode.extra_object_features().len(), "{mode}");
        let obs = vec![1.0; spec.dim()];
        assert_eq!(spec.mask(&obs).map(<[f32]>::len), mode.has_mask().then_some(spec.rows()), "{mode}");
        assert_eq!(spec.rows(), 2 + mode.fixtures().len(), "{mode}");
        assert_eq!(spec.objects(&obs).count(), 2, "{mode}");
    }
}

/// The objects mode holds the flat observation's robot features and
/// object rows, each row extended by the object's half extents, and the
/// mask (every slot present while counts are fixed), step for step; the
/// flat mode is what every id had (its golden digests are tests/it/golden.rs).
#[test]
fn objects_mode_is_the_flat_observation_with_sizes_and_a_mask() {
    let (mut flat, mut objects) = (env("BlocksChoose-v0", ObsMode::Flat), env("BlocksChoose-v0", ObsMode::Objects));
    let spec = objects.obs_spec();
    assert_eq!((spec.mode, spec.max_objects), (ObsMode::Objects, 3));
    assert_eq!(objects.observation_space().low.len(), spec.dim());
    assert_eq!(objects.observation_space().high[spec.dim() - 1], 1.0);
    assert_eq!(flat.observation_space().low.len(), flat.obs_spec().dim());
    let (mut a, _) = flat.reset(Some(5)).unwrap();
    let (mut b, _) = objects.reset(Some(5)).unwrap();
    let mut policy = ScriptedPolicy::for_env(objects.config());
    let mut flat_policy = ScriptedPolicy::for_env(flat.config());
    for _ in 0..30 {
        assert_eq!(b.len(), spec.dim());
        assert_eq!(spec.robot(&b), &a[..ROBOT_OBS]);
        let flat_rows = ObsSpec::flat(3);
        for (row, flat_row) in spec.objects(&b).zip(flat_rows.objects(&a)) {
            assert_eq!(&row[..BLOCK_OBS], flat_row);
            assert_eq!(&row[BLOCK_OBS..], &[0.025f32; 3], "the default half extents");
            assert_eq!(ObsSpec::colour(row), ObsSpec::colour(flat_row));
        }
        assert_eq!(spec.mask(&b), Some(&[1.0f32, 1.0, 1.0][..]));
        assert_eq!(spec.objects(&b).count(), 3);
        // The scripted controller reads the blocks through the spec: the same action in either layout.
        let (act, flat_act) = (policy.act(&b), flat_policy.act(&a));
        assert_eq!(act, flat_act);
        let (sa, sb) = (flat.step(&flat_act).unwrap(), objects.step(&act).unwrap());
        assert_eq!((sa.reward, sa.terminated, sa.truncated), (sb.reward, sb.terminated, sb.truncated));
        if sa.terminated || sa.truncated {
            break;
        }
        (a, b) = (sa.obs, sb.obs);
    }
}

#[test]
fn keep_objects_drops_rows_and_keeps_the_robot() {
    let spec = ObsSpec::flat(3);
    let obs: Vec<f32> = (0..spec.dim()).map(|i| i as f32).collect();
    let kept = spec.keep_objects(&obs, |row| row[0] as usize != ROBOT_OBS + BLOCK_OBS);
    assert_eq!(kept.len(), ROBOT_OBS + 2 * BLOCK_OBS);
    assert_eq!(&kept[..ROBOT_OBS + BLOCK_OBS], &obs[..ROBOT_OBS + BLOCK_OBS]);
    assert_eq!(&kept[ROBOT_OBS + BLOCK_OBS..], &obs[ROBOT_OBS + 2 * BLOCK_OBS..]);
}
