//! Headless rendering (EGL + Mesa's software rasteriser): a known state
//! shows its blocks where the camera projects them, and the GIF and
//! filmstrip outputs decode with the expected frames and sizes.
//! The command-line tests need the `train` feature (the binary); the
//! renderer's own test runs wherever `render` is on (with either engine).
#![cfg(feature = "render")]

use blockpuzzle::env::{registry, BlockEnv, EnvConfig};
use blockpuzzle::render::{Renderer, View};
use image::Rgb;

const BLUE_AT: [f64; 2] = [1.30, 0.70];
const GREEN_AT: [f64; 2] = [1.40, 0.82];

fn blueish(p: &Rgb<u8>) -> bool {
    let [r, g, b] = p.0.map(i32::from);
    b > r + 40 && b > g + 20
}

fn greenish(p: &Rgb<u8>) -> bool {
    let [r, g, b] = p.0.map(i32::from);
    g > r + 40 && g > b + 40 && r < 80
}

/// No rule colour: the three channels within a few levels of each other.
fn grey(p: &Rgb<u8>) -> bool {
    let [r, g, b] = p.0.map(i32::from);
    r.max(g).max(b) - r.min(g).min(b) <= 12
}

#[test]
fn blocks_appear_where_the_camera_projects_them() {
    let spec = registry::task("BlocksTouch-v0").unwrap().spec.with_fixed_layout(&[BLUE_AT, GREEN_AT]).unwrap();
    let mut env = BlockEnv::new(EnvConfig::from_spec(spec).unwrap()).unwrap();
    env.reset(Some(0)).unwrap();
    let model = env.data().model().clone();
    // A closer camera than the default, so that each block covers many pixels.
    let view = View { width: 320, height: 240, distance: 1.2, ..View::default() };
    let mut r = Renderer::new(&model, &view).unwrap();
    let img = r.render(env.data_mut(), Some(("test", "0")));
    assert_eq!(img.dimensions(), (320, 240));
    let first = *img.get_pixel(0, 0);
    assert!(img.pixels().any(|p| *p != first), "the image is uniform");
    // Only rule objects wear rule colours: the backdrop above the horizon is grey (the Fetch files'
    // skybox is a light green, the goal's colour; models/scene.xml draws a grey one).
    for (x, y) in [(0, 0), (319, 0), (160, 0)] {
        assert!(grey(img.get_pixel(x, y)), "backdrop pixel ({x}, {y}) is {:?}", img.get_pixel(x, y));
    }
    let blocks = env.block_positions();
    for (pos, (is_colour, name)) in blocks.iter().zip([(blueish as fn(&Rgb<u8>) -> bool, "blue"), (greenish, "green")])
    {
        let (x, y) = r.project(*pos).expect("in front of the camera");
        assert!((0.0..320.0).contains(&x) && (0.0..240.0).contains(&y), "{name} projects off-frame: {x}, {y}");
        let p = img.get_pixel(x as u32, y as u32);
        assert!(is_colour(p), "{name} block centre at ({x:.0}, {y:.0}) has colour {p:?}");
    }
    // Somewhere else on the table: neither colour.
    let (x, y) = r.project([1.15, 0.95, 0.42]).unwrap();
    let p = img.get_pixel(x as u32, y as u32);
    assert!(!blueish(p) && !greenish(p), "table pixel {p:?}");
}

/// Through the command line (the binary needs the `train` feature).
#[cfg(feature = "train")]
mod cli {
    use super::*;
    use blockpuzzle::sim::rules::Colour;
    use image::AnimationDecoder;

    fn bp(args: &[&str], no_egl: bool) -> std::process::Output {
        let mut cmd = crate::common::blockpuzzle(args);
        if no_egl {
            cmd.env(blockpuzzle::render::egl::DISABLE_VAR, "1");
        } else {
            cmd.env_remove(blockpuzzle::render::egl::DISABLE_VAR);
        }
        cmd.output().unwrap()
    }

    fn text(o: &std::process::Output) -> String {
        format!("{}{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr))
    }

    #[test]
    fn gif_and_filmstrip_decode_with_the_expected_frames() {
        let dir = tempfile::tempdir().unwrap();
        let path = |f: &str| dir.path().join(f).to_str().unwrap().to_owned();
        let (traj, gif, strip) = (path("r.jsonl"), path("r.gif"), path("strip.png"));
        let o = bp(
            &[
                "rollout",
                "--env",
                "GripperTouch-v0",
                "--policy",
                "scripted",
                "--episodes",
                "1",
                "--out",
                &traj,
                "--render",
                &gif,
                "--width",
                "64",
                "--height",
                "48",
            ],
            false,
        );
        assert!(o.status.success(), "{}", text(&o));
        let steps = blockpuzzle::episode::rollout::read_dump(std::path::Path::new(&traj)).unwrap()[0].steps.len();
        let decoder = image::codecs::gif::GifDecoder::new(std::fs::File::open(&gif).unwrap()).unwrap();
        let frames = decoder.into_frames().collect_frames().unwrap();
        assert_eq!(frames.len(), steps + 1, "reset state + one frame per step");
        assert!(frames.iter().all(|f| f.buffer().dimensions() == (64, 48)));

        let o = bp(
            &["render", "--traj", &traj, "--filmstrip", "3", "--width", "40", "--height", "30", "--out", &strip],
            false,
        );
        assert!(o.status.success(), "{}", text(&o));
        assert_eq!(image::open(&strip).unwrap().to_rgb8().dimensions(), (3 * 40, 30));

        // --max-frames: a GIF of that many evenly spaced frames; --no-caption: frames without the
        // caption's dark box in the top-left corner.
        let (short, bare) = (path("short.gif"), path("bare.gif"));
        let frames_of = |gif: &str| {
            let decoder = image::codecs::gif::GifDecoder::new(std::fs::File::open(gif).unwrap()).unwrap();
            decoder.into_frames().collect_frames().unwrap()
        };
        let o = bp(
            &["render", "--traj", &traj, "--max-frames", "3", "--width", "64", "--height", "48", "--out", &short],
            false,
        );
        assert!(o.status.success(), "{}", text(&o));
        let captioned = frames_of(&short);
        assert_eq!(captioned.len(), 3.min(steps + 1), "at most --max-frames frames");
        let args = ["render", "--traj", &traj, "--max-frames", "3", "--width", "64", "--height", "48", "--no-caption"];
        let o = bp(&args.iter().copied().chain(["--out", &bare]).collect::<Vec<_>>(), false);
        assert!(o.status.success(), "{}", text(&o));
        // The caption's box is dark: without it the top-left quarter is brighter.
        let luma = |f: &image::Frame| -> u64 {
            let img = f.buffer();
            let (w, h) = img.dimensions();
            let quarter = img.enumerate_pixels().filter(|(x, y, _)| *x < w / 2 && *y < h / 2);
            quarter.map(|(_, _, p)| u64::from(p[0]) + u64::from(p[1]) + u64::from(p[2])).sum()
        };
        let (b, c) = (luma(&frames_of(&bare)[0]), luma(&captioned[0]));
        assert!(b > c + c / 10, "the caption's box darkens the corner: {b} without, {c} with");
        let o =
            bp(&["render", "--traj", &traj, "--max-frames", "3", "--filmstrip", "2", "--out", &path("x.png")], false);
        assert!(!o.status.success() && text(&o).contains("--max-frames N keeps N frames of a GIF"), "{}", text(&o));

        let o = bp(&["render", "--traj", &traj, "--episode", "5", "--out", &path("x.gif")], false);
        assert!(!o.status.success() && text(&o).contains("holds 1 episodes"), "{}", text(&o));
        let o = bp(&["render", "--traj", &traj, "--out", &path("x.png")], false);
        assert!(!o.status.success() && text(&o).contains("--filmstrip"), "{}", text(&o));
        let o = bp(&["render", "--traj", &traj, "--out", &path("x.gif"), "--fps", "0"], false);
        assert!(
            !o.status.success() && text(&o).contains("'0' for '--fps") && text(&o).contains("1 to 100"),
            "{}",
            text(&o)
        );
        let o = bp(&["render", "--traj", &traj, "--out", &path("x.mp4")], false);
        assert!(!o.status.success() && text(&o).contains(".mp4 is not written here"), "{}", text(&o));
        assert!(!std::path::Path::new(&path("x.mp4")).exists(), "nothing written");

        // A zoo policy plays one seeded episode and renders it, as its dump would.
        let policy_strip = path("policy.png");
        let o = bp(
            &[
                "render",
                "--policy",
                "ReachAvoid-v0-ddpg",
                "--seed",
                "5",
                "--filmstrip",
                "2",
                "--width",
                "40",
                "--height",
                "30",
                "--out",
                &policy_strip,
            ],
            false,
        );
        assert!(o.status.success() && text(&o).contains("seed 5 ("), "{}", text(&o));
        assert_eq!(image::open(&policy_strip).unwrap().to_rgb8().dimensions(), (2 * 40, 30));
        let o = bp(&["render", "--out", &path("y.gif")], false);
        assert!(!o.status.success() && text(&o).contains("--traj"), "{}", text(&o));
    }

    #[test]
    fn without_egl_rendering_fails_clearly_and_the_rest_works() {
        let dir = tempfile::tempdir().unwrap();
        let traj = dir.path().join("r.jsonl");
        let traj = traj.to_str().unwrap();
        let o = bp(
            &["rollout", "--env", "GripperTouch-v0", "--policy", "scripted", "--episodes", "1", "--out", traj],
            true,
        );
        assert!(o.status.success(), "{}", text(&o));
        let gif = dir.path().join("r.gif");
        let o = bp(&["render", "--traj", traj, "--out", gif.to_str().unwrap()], true);
        assert!(!o.status.success());
        let t = text(&o);
        assert!(t.contains("switched off by the environment variable BLOCKPUZZLE_NO_EGL; unset it"), "{t}");
        assert!(!gif.exists(), "nothing written");
        assert!(bp(&["envs"], true).status.success());
    }

    /// A dump whose objects are not what its task deals at its seed (blue marked absent beside a
    /// "success") is refused as edited, before anything is drawn (issue 60); the dump as recorded
    /// renders, a shuffled task's colours and a count task's absent blocks included.
    #[test]
    fn a_dump_with_edited_objects_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        for env in ["BlocksTouch-v0", "BlocksChooseShuffled-v0", "BlocksChooseN-v0"] {
            let traj = dir.path().join(format!("{env}.jsonl"));
            let traj = traj.to_str().unwrap();
            let args =
                ["rollout", "--env", env, "--policy", "scripted", "--episodes", "3", "--seed", "4", "--out", traj];
            let o = bp(&args, false);
            assert!(o.status.success(), "{}", text(&o));
            let strip = dir.path().join(format!("{env}.png"));
            let args =
                ["render", "--traj", traj, "--episode", "2", "--filmstrip", "2", "--width", "32", "--height", "24"];
            let o = bp(&[&args[..], &["--out", strip.to_str().unwrap()]].concat(), false);
            assert!(o.status.success(), "{env}: {}", text(&o));
        }
        let traj = dir.path().join("BlocksTouch-v0.jsonl");
        let mut ep: serde_json::Value =
            serde_json::from_str(std::fs::read_to_string(&traj).unwrap().lines().next().unwrap()).unwrap();
        let blue = ep["objects"].as_array().unwrap().iter().position(|o| o["colour"] == "blue").unwrap();
        ep["objects"][blue]["absent"] = true.into();
        ep["success"] = true.into();
        let edited = dir.path().join("edited.jsonl");
        std::fs::write(&edited, format!("{ep}\n")).unwrap();
        let gif = dir.path().join("e.gif");
        let o = bp(&["render", "--traj", edited.to_str().unwrap(), "--out", gif.to_str().unwrap()], false);
        let t = text(&o);
        assert!(
            !o.status.success() && t.contains("as absent") && t.contains("deals it blue") && t.contains("edited"),
            "{t}"
        );
        assert!(!gif.exists());
    }

    /// Each EGL step's failure names the system package that most likely lacks, the apt and dnf lines,
    /// and that pip has none (issue 60); EGL's own words are kept.
    #[test]
    fn each_egl_failure_names_the_package_to_install() {
        use blockpuzzle::render::RenderError;
        let cases = [
            (None, "libEGL.so.1: cannot open shared object file", "libegl1"),
            (
                Some("eglGetPlatformDisplay(EGL_PLATFORM_SURFACELESS_MESA)"),
                "One or more argument values",
                "libegl-mesa0",
            ),
            (Some("eglInitialize"), "EGL is not initialized", "libgl1-mesa-dri"),
            (Some("eglCreateContext"), "Bad match", "libgl1-mesa-dri"),
        ];
        for (call, reason, missing) in cases {
            let e = match call {
                None => RenderError::EglUnavailable { reason: reason.into() },
                Some(call) => RenderError::Egl { call, reason: reason.into() },
            };
            let t = e.to_string();
            assert!(t.contains(&format!("the missing package is most likely {missing}")), "{t}");
            assert!(
                t.contains("apt-get install libegl1 libegl-mesa0 libgl1-mesa-dri") && t.contains("dnf install"),
                "{t}"
            );
            assert!(t.contains("no pip package provides") && t.contains(reason) && !t.contains("make setup"), "{t}");
        }
    }

    #[test]
    fn task_check_renders_one_reset_state_per_level_and_a_shuffled_episode_in_its_colours() {
        let dir = tempfile::tempdir().unwrap();
        let strip = dir.path().join("resets.png");
        let o = bp(
            &[
                "task",
                "check",
                "ToppleTower-v0",
                "--samples",
                "2",
                "--render",
                strip.to_str().unwrap(),
                "--width",
                "64",
                "--height",
                "48",
            ],
            false,
        );
        assert!(o.status.success(), "{}", text(&o));
        let img = image::open(&strip).unwrap();
        assert_eq!((img.width(), img.height()), (4 * 64, 48), "levels 0-3, one frame each");

        // A shuffled episode replays with the episode's colours, not the task file's: find a
        // seed that deals the green role to slot 0 (blue in the file) where the camera sees it.
        let view = View { width: 320, height: 240, distance: 1.2, ..View::default() };
        let mut env = registry::make("BlocksChooseShuffled-v0").unwrap();
        env.set_level(env.max_level()).unwrap();
        let model = env.data().model().clone();
        let mut probe = Renderer::new(&model, &view).unwrap();
        let found = (0..200).find_map(|seed| {
            env.reset(Some(seed)).unwrap();
            if env.block_colours()[0] != Colour::Green {
                return None;
            }
            let file_colours = probe.render(env.data_mut(), None);
            let (x, y) = probe.project(env.block_positions()[0])?;
            blueish(file_colours.get_pixel(x as u32, y as u32)).then_some((seed, x as u32, y as u32))
        });
        let (seed, x, y) = found.expect("a seed with slot 0 green and in view");
        let traj = dir.path().join("s.jsonl");
        let args = format!("rollout --env BlocksChooseShuffled-v0 --policy random --episodes 1 --seed {seed} --out");
        let o = bp(&args.split(' ').chain([traj.to_str().unwrap()]).collect::<Vec<_>>(), false);
        assert!(o.status.success(), "{}", text(&o));
        let ep = &blockpuzzle::episode::rollout::read_dump(&traj).unwrap()[0];
        assert_eq!(ep.objects[2].colour, Colour::Green);
        let (frames, _) = blockpuzzle::render::replay::episode_frames(ep, &view).unwrap();
        let px = frames[0].get_pixel(x, y);
        assert!(greenish(px), "slot 0 drawn green, as dealt this episode: {px:?}");

        // A dump of a task file renders after the file is gone (from the copy in the dump).
        let file = dir.path().join("gone.toml");
        let source = blockpuzzle::env::registry::REGISTRY.iter().find(|r| r.id == "GripperTouch-v0").unwrap().toml;
        std::fs::write(&file, source.replace("GripperTouch-v0", "Gone-v0")).unwrap();
        let traj = dir.path().join("gone.jsonl");
        let o = bp(
            &["rollout", "--env", file.to_str().unwrap(), "--episodes", "1", "--out", traj.to_str().unwrap()],
            false,
        );
        assert!(o.status.success(), "{}", text(&o));
        std::fs::remove_file(&file).unwrap();
        let gif = dir.path().join("gone.gif");
        let o = bp(
            &[
                "render",
                "--traj",
                traj.to_str().unwrap(),
                "--out",
                gif.to_str().unwrap(),
                "--width",
                "64",
                "--height",
                "48",
            ],
            false,
        );
        assert!(o.status.success() && gif.exists(), "{}", text(&o));
    }
}
