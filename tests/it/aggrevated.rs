//! AggreVaTeD's expert view: a BlocksChoose observation with the grey block
//! removed is, field by field, the BlocksTouch observation of the same
//! blue and green blocks.
#![cfg(feature = "train")]

use blockpuzzle::env::{registry, BlockEnv, EnvConfig, BLOCK_OBS, ROBOT_OBS};
use blockpuzzle::policy::actor::{obs_dim_without_grey, without_grey};

const BLUE: [f64; 2] = [1.30, 0.70];
const GREEN: [f64; 2] = [1.40, 0.82];
const GREY_FAR: [f64; 2] = [1.15, 0.95];

fn env(id: &str, positions: Vec<[f64; 2]>) -> BlockEnv {
    let spec = registry::task(id).unwrap().spec.with_fixed_layout(&positions).unwrap();
    BlockEnv::new(EnvConfig::from_spec(spec).unwrap()).unwrap()
}

#[test]
fn grey_removed_view_matches_the_blocks_touch_layout() {
    let mut touch = env("BlocksTouch-v0", vec![BLUE, GREEN]);
    let mut choose = env("BlocksChoose-v0", vec![BLUE, GREEN, GREY_FAR]);
    let (mut a, _) = touch.reset(Some(0)).unwrap();
    let (mut b, _) = choose.reset(Some(0)).unwrap();
    assert_eq!(b.len(), ROBOT_OBS + 3 * BLOCK_OBS);
    assert_eq!(a.len(), ROBOT_OBS + 2 * BLOCK_OBS);
    assert_eq!(obs_dim_without_grey(&choose.config().blocks()), a.len());
    // The grey block's own features are what was cut: its one-hot says grey.
    assert_eq!(&b[b.len() - 4..], &[0.0, 0.0, 0.0, 1.0]);
    // At reset and while the arm moves (away from the grey block), the views
    // are equal field by field up to the solver's rounding (the extra body
    // changes MuJoCo's constraint system in the last bits: ~1e-16 here).
    let field = |i: usize| -> String {
        if i < ROBOT_OBS {
            format!("robot[{i}]")
        } else {
            format!("block {} feature {}", (i - ROBOT_OBS) / BLOCK_OBS, (i - ROBOT_OBS) % BLOCK_OBS)
        }
    };
    for t in 0..16 {
        if t > 0 {
            let act = [0.6, 0.4, -0.5, if t % 2 == 0 { 1.0 } else { -1.0 }];
            a = touch.step(&act).unwrap().obs;
            b = choose.step(&act).unwrap().obs;
        }
        let v = without_grey(&b);
        assert_eq!(v.len(), a.len());
        for (i, (x, y)) in v.iter().zip(&a).enumerate() {
            assert!((x - y).abs() < 1e-5, "step {t}, {}: {x} vs {y}", field(i));
            // The one-hot colours (last 4 of each block) are exact.
            if i >= ROBOT_OBS && (i - ROBOT_OBS) % BLOCK_OBS >= BLOCK_OBS - 4 {
                assert_eq!(x, y, "{}", field(i));
            }
        }
    }
}
