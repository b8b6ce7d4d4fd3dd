//! Headless rendering with MuJoCo's own renderer (`mjv_updateScene`,
//! `mjr_render`, `mjr_readPixels`) in an offscreen OpenGL context made
//! through EGL ([`egl`]): frames of an environment's state, and GIF, PNG
//! folder and filmstrip outputs ([`output`]).

pub mod egl;
pub mod output;
pub mod replay;

use crate::mj::{Data, Model};
use image::RgbImage;
use mujoco_sys as sys;
use std::ffi::CString;
use thiserror::Error;

/// Rendering errors.
#[derive(Debug, Error)]
pub enum RenderError {
    /// No usable libEGL (or rendering switched off).
    #[error(
        "headless rendering needs EGL, which is not available ({reason}); install libegl1, libegl-mesa0 and \
         libgl1-mesa-dri (make setup). Everything else works without it"
    )]
    EglUnavailable {
        /// What went wrong.
        reason: String,
    },
    /// An EGL call failed.
    #[error("{call} failed: {reason}")]
    Egl {
        /// The call.
        call: &'static str,
        /// EGL's error.
        reason: String,
    },
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
}

impl Default for View {
    /// 480 × 480, the Fetch tasks' viewer camera: the table from the front-side.
    fn default() -> Self {
        Self { width: 480, height: 480, lookat: [1.3, 0.75, 0.55], distance: 2.5, azimuth: 132.0, elevation: -14.0 }
    }
}

/// MuJoCo's scene and render context in a headless OpenGL context.
/// Not `Send`: the OpenGL context is current on the thread that made it.
pub struct Renderer {
    scene: Box<sys::mjvScene>,
    context: Box<sys::mjrContext>,
    camera: sys::mjvCamera,
    option: sys::mjvOption,
    view: View,
    /// Colours drawn instead of the model's, by geom id.
    recolour: Vec<(usize, [f32; 4])>,
    // Declared last: dropped after the MuJoCo objects that use it.
    _gl: egl::GlContext,
}

/// Most geoms MuJoCo's scene holds.
const MAX_GEOMS: i32 = 2000;

impl Renderer {
    /// A renderer for `model` with the camera and size of `view`.
    ///
    /// # Errors
    /// No EGL, an EGL failure, a frame larger than the model's offscreen buffer.
    pub fn new(model: &Model, view: &View) -> Result<Self, RenderError> {
        if view.width == 0 || view.height == 0 {
            return Err(RenderError::Empty { width: view.width, height: view.height });
        }
        let gl = egl::GlContext::new()?;
        let m = model.as_ptr();
        // SAFETY: `m` is a live compiled model.
        let (max_width, max_height) =
            unsafe { ((*m).vis.global.offwidth as usize, (*m).vis.global.offheight as usize) };
        if view.width > max_width || view.height > max_height {
            return Err(RenderError::TooLarge { width: view.width, height: view.height, max_width, max_height });
        }
        let mut scene = Box::<sys::mjvScene>::default();
        let mut context = Box::<sys::mjrContext>::default();
        let mut camera = sys::mjvCamera::default();
        let mut option = sys::mjvOption::default();
        // SAFETY: the structs are owned and writable; the OpenGL context made
        // above is current on this thread, as mjr_makeContext requires; the
        // scene and context are freed in Drop before the OpenGL context.
        unsafe {
            sys::mjv_defaultCamera(&mut camera);
            sys::mjv_defaultOption(&mut option);
            sys::mjv_defaultScene(scene.as_mut());
            sys::mjr_defaultContext(context.as_mut());
            sys::mjv_makeScene(m, scene.as_mut(), MAX_GEOMS);
            sys::mjr_makeContext(m, context.as_mut(), sys::mjtFontScale::mjFONTSCALE_150 as i32);
            sys::mjr_setBuffer(sys::mjtFramebuffer::mjFB_OFFSCREEN as i32, context.as_mut());
        }
        camera.type_ = sys::mjtCamera::mjCAMERA_FREE as i32;
        camera.lookat = view.lookat;
        camera.distance = view.distance;
        camera.azimuth = view.azimuth;
        camera.elevation = view.elevation;
        Ok(Self { scene, context, camera, option, view: view.clone(), recolour: Vec::new(), _gl: gl })
    }

    /// Draws every geom of the rule objects in its object's colour (`colours`
    /// in rule-object order: the episode's, which move between episodes when
    /// the task shuffles roles): the blocks always, the gripper, table and
    /// floor when they are not grey (the Fetch gripper's geoms carry their own
    /// grey, which would hide a material).
    ///
    /// # Errors
    /// A scene without the BlockPuzzle materials.
    pub fn colour_objects(
        &mut self,
        scene: &crate::scene::Scene,
        colours: &[crate::rules::Colour],
    ) -> Result<(), crate::mj::MjError> {
        self.recolour.clear();
        for (g, &o) in scene.geom_object.iter().enumerate() {
            let Some(&c) = usize::try_from(o).ok().and_then(|o| colours.get(o)) else { continue };
            let block = o as usize >= crate::scene::FIRST_BLOCK_OBJECT && Some(o as usize) != scene.floor_object;
            if block || c != crate::rules::Colour::Grey {
                self.recolour.push((g, scene.rgba(c)?));
            }
        }
        Ok(())
    }

    /// The frame size and camera.
    pub fn view(&self) -> &View {
        &self.view
    }

    fn viewport(&self) -> sys::mjrRect {
        sys::mjrRect { left: 0, bottom: 0, width: self.view.width as i32, height: self.view.height as i32 }
    }

    /// Renders the state in `data` (its kinematics must be current), with
    /// an optional caption in the top-left corner (`left` column and
    /// `right` column, lines separated by `\n`).
    pub fn render(&mut self, data: &mut Data, caption: Option<(&str, &str)>) -> RgbImage {
        let (w, h) = (self.view.width, self.view.height);
        let viewport = self.viewport();
        let text = caption.map(|(a, b)| {
            (
                CString::new(a.replace('\0', "")).unwrap_or_default(),
                CString::new(b.replace('\0', "")).unwrap_or_default(),
            )
        });
        let mut rgb = vec![0u8; 3 * w * h];
        let m = data.model().as_ptr();
        // SAFETY: model and data belong together (Data holds its Model); the
        // scene and context were made for a model of this kind on this
        // thread's current OpenGL context; `scene.geoms` holds `ngeom`
        // initialised geoms after mjv_updateScene; `rgb` holds width × height × 3
        // bytes, what mjr_readPixels writes for `viewport`; no depth buffer.
        unsafe {
            sys::mjv_updateScene(
                m,
                data.as_mut_ptr(),
                &self.option,
                std::ptr::null(),
                &mut self.camera,
                sys::mjtCatBit::mjCAT_ALL as i32,
                self.scene.as_mut(),
            );
            for i in 0..self.scene.ngeom.max(0) as usize {
                let g = &mut *self.scene.geoms.add(i);
                if g.objtype == sys::mjtObj::mjOBJ_GEOM as i32 {
                    if let Some((_, rgba)) = self.recolour.iter().find(|(id, _)| *id as i32 == g.objid) {
                        g.rgba = *rgba;
                    }
                }
            }
            sys::mjr_render(viewport, self.scene.as_mut(), self.context.as_ref());
            if let Some((a, b)) = &text {
                sys::mjr_overlay(
                    sys::mjtFont::mjFONT_NORMAL as i32,
                    sys::mjtGridPos::mjGRID_TOPLEFT as i32,
                    viewport,
                    a.as_ptr(),
                    b.as_ptr(),
                    self.context.as_ref(),
                );
            }
            sys::mjr_readPixels(rgb.as_mut_ptr(), std::ptr::null_mut(), viewport, self.context.as_ref());
        }
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
        let cam = &self.scene.camera[0];
        let f = cam.forward.map(f64::from);
        let up = cam.up.map(f64::from);
        let right = [f[1] * up[2] - f[2] * up[1], f[2] * up[0] - f[0] * up[2], f[0] * up[1] - f[1] * up[0]];
        let v = [p[0] - cam.pos[0] as f64, p[1] - cam.pos[1] as f64, p[2] - cam.pos[2] as f64];
        let dot = |a: [f64; 3]| a[0] * v[0] + a[1] * v[1] + a[2] * v[2];
        let (x, y, z) = (dot(right), dot(up), dot(f));
        if z <= 0.0 {
            return None;
        }
        // mjr_render's frustum: glFrustum(center ± halfwidth, bottom, top, near),
        // halfwidth matching the viewport's aspect ratio.
        let (near, bottom, top) = (cam.frustum_near as f64, cam.frustum_bottom as f64, cam.frustum_top as f64);
        let aspect = self.view.width as f64 / self.view.height as f64;
        let half = 0.5 * aspect * (top - bottom);
        let (xn, yn) = (x / z * near, y / z * near);
        let col = (xn - (cam.frustum_center as f64 - half)) / (2.0 * half) * self.view.width as f64;
        let row_from_bottom = (yn - bottom) / (top - bottom) * self.view.height as f64;
        Some((col, self.view.height as f64 - row_from_bottom))
    }
}

impl Drop for Renderer {
    fn drop(&mut self) {
        // SAFETY: made in `new` and freed once; the OpenGL context (`_gl`)
        // is dropped after this and is still current.
        unsafe {
            sys::mjr_freeContext(self.context.as_mut());
            sys::mjv_freeScene(self.scene.as_mut());
        }
    }
}
