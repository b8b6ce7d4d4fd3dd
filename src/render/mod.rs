//! Layer 8, render (the `render` feature): headless rendering.
//!
//! | module | what |
//! |---|---|
//! | [`egl`] | a headless OpenGL context through EGL (software, no display) |
//! | [`output`] | frames written as an animated GIF, a folder of PNGs or a filmstrip |
//! | [`replay`] | frames of a recorded episode, its stored states put back |
//!
//! Headless rendering with MuJoCo's own renderer (`mjv_updateScene`,
//! `mjr_render`, `mjr_readPixels`) in an offscreen OpenGL context made
//! through EGL ([`egl`]): frames of an environment's state, and GIF, PNG
//! folder and filmstrip outputs ([`output`]).

pub mod egl;
pub mod output;
pub mod replay;

use crate::sim::mj::render::{FreeCamera, Visual};
use crate::sim::mj::{Data, Model};
use image::RgbImage;
use std::ffi::CString;
use thiserror::Error;

/// The camera's distance from the point it looks at, metres (`--distance`).
pub const CAMERA_DISTANCE_M: (f64, f64) = (0.1, 50.0);
/// The camera's elevation, degrees (`--elevation`).
pub const CAMERA_ELEVATION_DEG: (f64, f64) = (-90.0, 90.0);

/// Every package headless rendering uses, on Debian and Ubuntu.
const APT_ALL: &str = "apt-get install libegl1 libegl-mesa0 libgl1-mesa-dri";
/// The same on Fedora and RHEL.
const DNF_ALL: &str = "dnf install libglvnd-egl mesa-libEGL mesa-dri-drivers";

/// The message of a failed EGL step, as a user of the command line or the Python package can act
/// on it: what failed (EGL's own words kept), the system package that most likely lacks, the
/// install lines for apt and dnf, and that no pip package provides them. `call` is the EGL call
/// that failed (None: libEGL itself could not be loaded, or rendering is switched off).
pub fn egl_message(call: Option<&str>, reason: &str) -> String {
    use egl::DISABLE_VAR;
    if call.is_none() && reason.contains(DISABLE_VAR) {
        return format!(
            "headless rendering is switched off by the environment variable {DISABLE_VAR}; unset it (`unset \
             {DISABLE_VAR}` in the shell, `del os.environ[\"{DISABLE_VAR}\"]` in Python before the first render)"
        );
    }
    // What failed, and the package that most likely lacks, for each step EGL takes.
    let (what, missing) = match call {
        None => ("the EGL library libEGL.so.1 could not be loaded", "libegl1 (libEGL.so.1, the EGL loader)"),
        Some(c) if c.starts_with("eglGetPlatformDisplay") => (
            "libEGL.so.1 loaded, but no EGL vendor offers Mesa's surfaceless platform",
            "libegl-mesa0 (Mesa's EGL vendor, libEGL_mesa.so.0)",
        ),
        Some(c) if c.starts_with("eglInitialize") => (
            "Mesa's EGL could not start a renderer",
            "libgl1-mesa-dri (Mesa's DRI drivers, with the software rasteriser)",
        ),
        Some(_) => (
            "Mesa's EGL could not make an OpenGL context",
            "libgl1-mesa-dri or libegl-mesa0 (a Mesa with EGL_KHR_no_config_context)",
        ),
    };
    let failed = match call {
        None => reason.to_owned(),
        Some(c) => format!("{c} failed: {reason}"),
    };
    format!(
        "headless rendering needs EGL with Mesa, and {what} ({failed}); the missing package is most likely {missing}. \
         Install the three (as root): `{APT_ALL}` on Debian or Ubuntu, `{DNF_ALL}` on Fedora or RHEL; they are system \
         libraries, which no pip package provides. Everything but rendering works without them"
    )
}

/// Rendering errors.
#[derive(Debug, Error)]
pub enum RenderError {
    /// No usable libEGL (or rendering switched off).
    #[error("{}", egl_message(None, reason))]
    EglUnavailable {
        /// What went wrong.
        reason: String,
    },
    /// An EGL call failed.
    #[error("{}", egl_message(Some(call), reason))]
    Egl {
        /// The call.
        call: &'static str,
        /// EGL's error.
        reason: String,
    },
    /// A camera that would show nothing or the inside of the scene.
    #[error("{0}")]
    Camera(String),
    /// Requested frame larger than the model's offscreen buffer.
    #[error("a {width} x {height} frame does not fit MuJoCo's {max_width} x {max_height} offscreen buffer")]
    TooLarge {
        /// Requested width.
        width: usize,
        /// Requested height.
        height: usize,
        /// Buffer width.
        max_width: usize,
        /// Buffer height.
        max_height: usize,
    },
    /// Width or height zero.
    #[error("frame size must be at least 1 x 1, got {width} x {height}")]
    Empty {
        /// Requested width.
        width: usize,
        /// Requested height.
        height: usize,
    },
}

/// Frame size and the free camera.
#[derive(Debug, Clone, PartialEq)]
pub struct View {
    /// Frame width in pixels.
    pub width: usize,
    /// Frame height in pixels.
    pub height: usize,
    /// Point the camera looks at.
    pub lookat: [f64; 3],
    /// Distance from `lookat`.
    pub distance: f64,
    /// Azimuth in degrees.
    pub azimuth: f64,
    /// Elevation in degrees (negative: looking down).
    pub elevation: f64,
    /// Whether a replayed episode's frames carry its caption (task, step, outcome) in a corner.
    pub caption: bool,
}

impl View {
    /// Whether the camera shows the scene: a finite distance from 0.1 to 50 m
    /// (closer puts it inside the objects, farther makes the scene a few
    /// pixels), an elevation from −90° to 90° (beyond, it turns upside down),
    /// a finite azimuth and point to look at.
    ///
    /// # Errors
    /// The first value out of range, naming the flag and the range.
    pub fn check(&self) -> Result<(), String> {
        let (d, e) = (CAMERA_DISTANCE_M, CAMERA_ELEVATION_DEG);
        if !crate::support::limits::within(self.distance, d) {
            return Err(format!(
                "--distance {}: the camera's distance is {} to {} m (closer puts it inside the objects, farther \
                 shrinks the scene to a few pixels)",
                self.distance, d.0, d.1
            ));
        }
        if !crate::support::limits::within(self.elevation, e) {
            return Err(format!(
                "--elevation {}: the camera's elevation is {}° to {}° (negative looks down)",
                self.elevation, e.0, e.1
            ));
        }
        if !self.azimuth.is_finite() {
            return Err(format!(
                "--azimuth {}: give the camera's azimuth in degrees (any finite number)",
                self.azimuth
            ));
        }
        if self.lookat.iter().any(|v| !v.is_finite()) {
            return Err(format!("the camera's point to look at {:?} is not finite", self.lookat));
        }
        Ok(())
    }
}

impl Default for View {
    /// 480 × 480, the Fetch tasks' viewer camera: the table from the front-side, with captions.
    fn default() -> Self {
        Self {
            width: 480,
            height: 480,
            lookat: [1.3, 0.75, 0.55],
            distance: 2.5,
            azimuth: 132.0,
            elevation: -14.0,
            caption: true,
        }
    }
}

/// MuJoCo's scene and render context in a headless OpenGL context.
/// Not `Send`: the OpenGL context is current on the thread that made it.
pub struct Renderer {
    visual: Visual,
    view: View,
    /// Colours drawn instead of the model's, by geom id.
    recolour: Vec<(usize, [f32; 4])>,
    // Declared last: dropped after the MuJoCo objects that use it.
    _gl: std::rc::Rc<egl::GlContext>,
}

impl Renderer {
    /// A renderer for `model` with the camera and size of `view`.
    ///
    /// # Errors
    /// No EGL, an EGL failure, a frame larger than the model's offscreen buffer.
    pub fn new(model: &Model, view: &View) -> Result<Self, RenderError> {
        if view.width == 0 || view.height == 0 {
            return Err(RenderError::Empty { width: view.width, height: view.height });
        }
        view.check().map_err(RenderError::Camera)?;
        let gl = egl::thread_context()?;
        let (max_width, max_height) = model.offscreen_size();
        if view.width > max_width || view.height > max_height {
            return Err(RenderError::TooLarge { width: view.width, height: view.height, max_width, max_height });
        }
        let camera = FreeCamera {
            lookat: view.lookat,
            distance: view.distance,
            azimuth: view.azimuth,
            elevation: view.elevation,
        };
        // SAFETY: `gl` is this thread's one context, current on it since it was made (nothing
        // here makes another current); the struct holds a reference to it declared after `visual`,
        // so it stays alive until `visual` is dropped.
        let visual = unsafe { Visual::new(model, &camera) };
        Ok(Self { visual, view: view.clone(), recolour: Vec::new(), _gl: gl })
    }

    /// Draws every geom of the rule objects in its object's colour (`colours`
    /// in rule-object order: the episode's, which move between episodes when
    /// the task shuffles roles): the blocks always, the gripper, table and
    /// floor when they are not grey (the Fetch gripper's geoms carry their own
    /// grey, which would hide a material). Objects `absent` marks (indexed
    /// like `colours`; shorter: the rest present) are not drawn.
    ///
    /// # Errors
    /// A scene without the BlockPuzzle materials.
    pub fn colour_objects(
        &mut self,
        scene: &crate::sim::scene::Scene,
        colours: &[crate::sim::rules::Colour],
        absent: &[bool],
    ) -> Result<(), crate::sim::mj::MjError> {
        self.recolour.clear();
        for (g, &o) in scene.geom_object.iter().enumerate() {
            let Some(&c) = usize::try_from(o).ok().and_then(|o| colours.get(o)) else { continue };
            if absent.get(o as usize).copied().unwrap_or(false) {
                self.recolour.push((g, [0.0; 4]));
                continue;
            }
            let block = o as usize >= crate::sim::scene::FIRST_BLOCK_OBJECT && Some(o as usize) != scene.floor_object;
            if block || c != crate::sim::rules::Colour::Grey {
                self.recolour.push((g, scene.rgba(c)?));
            }
        }
        Ok(())
    }

    /// [`Renderer::colour_objects`] with `env`'s objects as its episode shows them: their colours
    /// (which move between episodes where a task shuffles roles) and the objects absent from it.
    ///
    /// # Errors
    /// A scene without the BlockPuzzle materials.
    pub fn colour_env(&mut self, env: &crate::env::BlockEnv) -> Result<(), crate::sim::mj::MjError> {
        let colours: Vec<_> = env.objects().iter().map(|o| o.colour).collect();
        self.colour_objects(env.scene(), &colours, &env.absent_objects())
    }

    /// The frame size and camera.
    pub fn view(&self) -> &View {
        &self.view
    }

    /// Renders the state in `data` (its kinematics must be current), with
    /// an optional caption in the top-left corner (`left` column and
    /// `right` column, lines separated by `\n`).
    pub fn render(&mut self, data: &mut Data, caption: Option<(&str, &str)>) -> RgbImage {
        let (w, h) = (self.view.width, self.view.height);
        let text = caption.map(|(a, b)| {
            (
                CString::new(a.replace('\0', "")).unwrap_or_default(),
                CString::new(b.replace('\0', "")).unwrap_or_default(),
            )
        });
        let mut rgb = vec![0u8; 3 * w * h];
        let caption = text.as_ref().map(|(a, b)| (a.as_c_str(), b.as_c_str()));
        self.visual.render(data, (w, h), &self.recolour, caption, &mut rgb);
        // OpenGL rows run bottom-up; images top-down.
        let mut flipped = Vec::with_capacity(rgb.len());
        for row in rgb.chunks_exact(3 * w).rev() {
            flipped.extend_from_slice(row);
        }
        RgbImage::from_raw(w as u32, h as u32, flipped).unwrap_or_else(|| RgbImage::new(w as u32, h as u32))
    }

    /// Pixel (column from the left, row from the top) where the world point
    /// `p` appears in the last rendered frame; None behind the camera.
    pub fn project(&self, p: [f64; 3]) -> Option<(f64, f64)> {
        let cam = self.visual.camera_frame();
        let (f, up) = (cam.forward, cam.up);
        let right = [f[1] * up[2] - f[2] * up[1], f[2] * up[0] - f[0] * up[2], f[0] * up[1] - f[1] * up[0]];
        let v = [p[0] - cam.pos[0], p[1] - cam.pos[1], p[2] - cam.pos[2]];
        let dot = |a: [f64; 3]| a[0] * v[0] + a[1] * v[1] + a[2] * v[2];
        let (x, y, z) = (dot(right), dot(up), dot(f));
        if z <= 0.0 {
            return None;
        }
        // mjr_render's frustum: glFrustum(center ± halfwidth, bottom, top, near),
        // halfwidth matching the viewport's aspect ratio.
        let (near, bottom, top) = (cam.frustum_near, cam.frustum_bottom, cam.frustum_top);
        let aspect = self.view.width as f64 / self.view.height as f64;
        let half = 0.5 * aspect * (top - bottom);
        let (xn, yn) = (x / z * near, y / z * near);
        let col = (xn - (cam.frustum_center - half)) / (2.0 * half) * self.view.width as f64;
        let row_from_bottom = (yn - bottom) / (top - bottom) * self.view.height as f64;
        Some((col, self.view.height as f64 - row_from_bottom))
    }
}
