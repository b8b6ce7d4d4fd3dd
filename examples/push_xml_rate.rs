//! MuJoCo 2.2.2's mj_step rate on gymnasium-robotics' own FetchPush model
//! (push.xml), driven like FetchPush-v4 with random actions. Compares the
//! physics engine on the same model as the Python benchmark.
//! Usage: cargo run --release --example push_xml_rate -- PATH/TO/push.xml
use blockpuzzle::sim::mj::{Data, Model, ObjType, EQ_WELD};
use rand::{Rng, SeedableRng};
use std::sync::Arc;
fn main() -> anyhow::Result<()> {
    let path = std::env::args().nth(1).ok_or_else(|| anyhow::anyhow!("usage: push_xml_rate PUSH_XML"))?;
    let mut m = Model::from_xml_file(std::path::Path::new(&path))?;
    let welds: Vec<usize> = m.eq_type().iter().enumerate().filter(|(_, &t)| t == EQ_WELD).map(|(i, _)| i).collect();
    for i in welds {
        m.eq_data_mut()[i][..7].copy_from_slice(&[0., 0., 0., 0., 0., 0., 1.]);
    }
    let m = Arc::new(m);
    let mut d = Data::new(m.clone())?;
    for (k, v) in [0.405, 0.48, 0.0].iter().enumerate() {
        let j = m.id(ObjType::Joint, &format!("robot0:slide{k}"))?;
        d.qpos_mut()[m.jnt_qposadr()[j] as usize] = *v;
    }
    let j = m.id(ObjType::Joint, "object0:joint")?;
    let a = m.jnt_qposadr()[j] as usize;
    d.qpos_mut()[a..a + 7].copy_from_slice(&[1.25, 0.53, 0.4, 1., 0., 0., 0.]);
    d.forward()?;
    let grip = m.id(ObjType::Site, "robot0:grip")?;
    let g = d.site_xpos()[grip];
    d.mocap_pos_mut()[0] = [g[0] - 0.498, g[1] + 0.005, g[2] - 0.431];
    d.mocap_quat_mut()[0] = [1., 0., 1., 0.];
    for _ in 0..200 {
        d.step()?;
    }
    let gl = m.id(ObjType::Body, "robot0:gripper_link")?;
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(0);
    let init = d.try_clone()?;
    let (mut phys, mut n) = (0.0, 0);
    let t0 = std::time::Instant::now();
    for ep in 0..60 {
        d.copy_from(&init)?;
        let x = 1.342 + rng.gen_range(-0.15..0.15);
        let y = 0.749 + rng.gen_range(-0.15..0.15);
        d.qpos_mut()[a] = x;
        d.qpos_mut()[a + 1] = y;
        d.forward()?;
        let _ = ep;
        for _ in 0..50 {
            let (p, q) = (d.xpos()[gl], d.xquat()[gl]);
            let act: Vec<f64> = (0..3).map(|_| rng.gen_range(-1.0..1.0) * 0.05).collect();
            d.mocap_pos_mut()[0] = [p[0] + act[0], p[1] + act[1], p[2] + act[2]];
            d.mocap_quat_mut()[0] = [q[0] + 1., q[1], q[2] + 1., q[3]];
            let t = std::time::Instant::now();
            for _ in 0..20 {
                d.step()?;
            }
            phys += t.elapsed().as_secs_f64();
            n += 20;
            d.forward()?;
        }
    }
    println!(
        "MuJoCo {} on {}: mj_step/s {:.0} (loop {:.2}s)",
        blockpuzzle::sim::mj::version(),
        path,
        n as f64 / phys,
        t0.elapsed().as_secs_f64()
    );
    Ok(())
}
