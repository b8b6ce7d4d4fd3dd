//! Which body pairs touch, and which only have overlapping bounding spheres
//! (so MuJoCo runs a narrow-phase test on them for nothing), over random
//! rollouts. The collision filter in src/sim/scene/filter.rs was chosen from this.
//! Usage: cargo run --release --example collision_pairs [ENV_ID]
use blockpuzzle::sim::mj::ObjType;
use rand::{Rng, SeedableRng};
use std::collections::BTreeMap;
fn main() {
    let id = std::env::args().nth(1).unwrap_or("BlocksChoose-v0".into());
    let mut config = blockpuzzle::env::registry::config(&id).unwrap();
    config.collision_filter = false; // see every pair
    let mut env = blockpuzzle::BlockEnv::new(config).unwrap();
    let m = env.scene().model.clone();
    let bname = |b: usize| m.name(ObjType::Body, b).unwrap_or(format!("body{b}"));
    let gb = m.geom_bodyid().to_vec();
    let ng = m.ngeom();
    let mut contacts: BTreeMap<(String, String), usize> = BTreeMap::new();
    let mut spheres: BTreeMap<(String, String), usize> = BTreeMap::new();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(0);
    let mut nsub = 0;
    for ep in 0..40 {
        env.reset(Some(ep)).unwrap();
        loop {
            let a: Vec<f32> = (0..4).map(|_| rng.gen_range(-1.0..1.0)).collect();
            let s = env.step(&a).unwrap();
            nsub += 1;
            let d = env.data();
            for c in d.contacts() {
                let (a, b) = (bname(gb[c.geom1()] as usize), bname(gb[c.geom2()] as usize));
                *contacts.entry((a.clone().min(b.clone()), a.max(b))).or_default() += 1;
            }
            let xp = d.geom_xpos();
            let rb = m.geom_rbound();
            let ct = m.geom_contype();
            let ca = m.geom_conaffinity();
            for i in 0..ng {
                for j in i + 1..ng {
                    if gb[i] == gb[j] {
                        continue;
                    }
                    if (ct[i] & ca[j]) == 0 && (ct[j] & ca[i]) == 0 {
                        continue;
                    }
                    let dd: f64 = (0..3).map(|k| (xp[i][k] - xp[j][k]).powi(2)).sum::<f64>().sqrt();
                    if rb[i] > 0.0 && rb[j] > 0.0 && dd < rb[i] + rb[j] + 0.002 {
                        let (a, b) = (bname(gb[i] as usize), bname(gb[j] as usize));
                        *spheres.entry((a.clone().min(b.clone()), a.max(b))).or_default() += 1;
                    }
                }
            }
            if s.terminated || s.truncated {
                break;
            }
        }
    }
    println!("steps {nsub}\nCONTACTS:");
    for (k, v) in &contacts {
        println!("  {k:?} {v}");
    }
    println!("SPHERE OVERLAPS:");
    for (k, v) in &spheres {
        println!("  {k:?} {v} {}", if contacts.contains_key(k) { "(contact)" } else { "" });
    }
    let parents = m.body_parentid();
    println!("parents: {:?}", (0..m.nbody()).map(|b| (bname(b), bname(parents[b] as usize))).collect::<Vec<_>>());
}
