//! Experiment: which geom pairs reach MuJoCo's narrow phase, counted with
//! mjcb_contactfilter (which then reimplements the default contype/conaffinity
//! filter). Usage: cargo run --release --example narrowphase_pairs [ENV_ID]
use blockpuzzle::env::make;
use blockpuzzle::mj::ObjType;
use blockpuzzle::policy::{Policy, RandomPolicy};
use std::collections::BTreeMap;
use std::sync::Mutex;
static PAIRS: Mutex<Option<BTreeMap<(i32, i32), u64>>> = Mutex::new(None);
unsafe extern "C" fn filt(m: *const mujoco_sys::mjModel, _d: *mut mujoco_sys::mjData, g1: i32, g2: i32) -> i32 {
    // SAFETY: MuJoCo passes its live model and valid geom ids.
    let m = unsafe { &*m };
    let (ct1, ca1, ct2, ca2) = unsafe { (*m.geom_contype.add(g1 as usize), *m.geom_conaffinity.add(g1 as usize), *m.geom_contype.add(g2 as usize), *m.geom_conaffinity.add(g2 as usize)) };
    let reject = (ct1 & ca2) == 0 && (ct2 & ca1) == 0;
    if !reject {
        *PAIRS.lock().unwrap().get_or_insert_with(BTreeMap::new).entry((g1.min(g2), g1.max(g2))).or_default() += 1;
    }
    reject as i32
}
fn main() {
    let id = std::env::args().nth(1).unwrap_or("BlocksTouch-v0".into());
    let mut env = make(&id).unwrap();
    // SAFETY: set once before any simulation, single-threaded experiment.
    unsafe { mujoco_sys::mjcb_contactfilter = Some(filt) };
    let mut p = RandomPolicy::new(0);
    let mut n = 0;
    for ep in 0..20 {
        let mut obs = env.reset(Some(ep)).unwrap().0;
        loop { let s = env.step(&p.act(&obs)).unwrap(); n += 21; obs = s.obs; if s.terminated || s.truncated { break; } }
    }
    let m = env.scene().model.clone();
    let gb = m.geom_bodyid().to_vec();
    let name = |g: i32| m.name(ObjType::Body, gb[g as usize] as usize).unwrap_or_default();
    let pairs = PAIRS.lock().unwrap().take().unwrap_or_default();
    let mut v: Vec<_> = pairs.into_iter().collect();
    v.sort_by_key(|x| std::cmp::Reverse(x.1));
    let total: u64 = v.iter().map(|x| x.1).sum();
    println!("{:.1} narrow-phase pairs per substep", total as f64 / n as f64);
    for ((a, b), c) in v.iter().take(40) { println!("{:>6.3}  {} - {}", *c as f64 / n as f64, name(*a), name(*b)); }
}
