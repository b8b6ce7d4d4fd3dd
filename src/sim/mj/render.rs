//! MuJoCo's own renderer (`mjv_*` abstract scene, `mjr_*` OpenGL context):
//! the engine half of headless rendering. The OpenGL context it draws into
//! is made elsewhere (`crate::render::egl`).

use super::{Data, Model};
use mujoco_sys as sys;
use std::ffi::CStr;

/// Most geoms the abstract scene holds.
const MAX_GEOMS: i32 = 2000;

/// A free camera looking at a point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FreeCamera {
    /// Point the camera looks at.
    pub lookat: [f64; 3],
    /// Distance from `lookat`.
    pub distance: f64,
    /// Azimuth in degrees.
    pub azimuth: f64,
    /// Elevation in degrees (negative: looking down).
    pub elevation: f64,
}

/// Where the last rendered frame's camera was (`mjvGLCamera`): position,
/// axes and OpenGL frustum, enough to project world points to pixels.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CameraFrame {
    pub pos: [f64; 3],
    pub forward: [f64; 3],
    pub up: [f64; 3],
    pub frustum_center: f64,
    pub frustum_near: f64,
    pub frustum_bottom: f64,
    pub frustum_top: f64,
}

/// MuJoCo's abstract scene and OpenGL render context for one model, drawing
/// offscreen. Not `Send`: the OpenGL context is current on one thread.
pub struct Visual {
    scene: Box<sys::mjvScene>,
    context: Box<sys::mjrContext>,
    camera: sys::mjvCamera,
    option: sys::mjvOption,
    /// Keeps the raw pointers from making this `Send`.
    _thread_bound: std::marker::PhantomData<*const ()>,
}

impl Model {
    /// The offscreen buffer's width and height (`vis.global.offwidth/offheight`).
    pub fn offscreen_size(&self) -> (usize, usize) {
        // SAFETY: `as_ptr` is a live compiled model.
        let g = unsafe { (*self.as_ptr()).vis.global };
        (g.offwidth.max(0) as usize, g.offheight.max(0) as usize)
    }
}

impl Visual {
    /// The scene and render context for `model`, seen from `camera`.
    ///
    /// # Safety
    /// An OpenGL context must be current on this thread, stay current for as
    /// long as the `Visual` lives, and be destroyed only after it is dropped.
    pub unsafe fn new(model: &Model, camera: &FreeCamera) -> Self {
        let mut scene = Box::<sys::mjvScene>::default();
        let mut context = Box::<sys::mjrContext>::default();
        let mut cam = sys::mjvCamera::default();
        let mut option = sys::mjvOption::default();
        // SAFETY: the structs are owned and writable; the caller guarantees a
        // current OpenGL context, as mjr_makeContext requires; the scene and
        // context are freed in Drop, before that context goes.
        unsafe {
            sys::mjv_defaultCamera(&mut cam);
            sys::mjv_defaultOption(&mut option);
            sys::mjv_defaultScene(scene.as_mut());
            sys::mjr_defaultContext(context.as_mut());
            sys::mjv_makeScene(model.as_ptr(), scene.as_mut(), MAX_GEOMS);
            sys::mjr_makeContext(model.as_ptr(), context.as_mut(), sys::mjtFontScale::mjFONTSCALE_150 as i32);
            sys::mjr_setBuffer(sys::mjtFramebuffer::mjFB_OFFSCREEN as i32, context.as_mut());
        }
        cam.type_ = sys::mjtCamera::mjCAMERA_FREE as i32;
        cam.lookat = camera.lookat;
        cam.distance = camera.distance;
        cam.azimuth = camera.azimuth;
        cam.elevation = camera.elevation;
        Self { scene, context, camera: cam, option, _thread_bound: std::marker::PhantomData }
    }

    /// Draws the state in `data` (its kinematics current) into a `width` ×
    /// `height` viewport, geoms listed in `recolour` (geom id, RGBA) in those
    /// colours (alpha 0: not drawn), with an optional caption (left and right columns) in the
    /// top-left corner, and reads the pixels back into `rgb` (bottom row first,
    /// `3 · width · height` bytes; a shorter buffer is left untouched).
    pub fn render(
        &mut self,
        data: &mut Data,
        (width, height): (usize, usize),
        recolour: &[(usize, [f32; 4])],
        caption: Option<(&CStr, &CStr)>,
        rgb: &mut [u8],
    ) {
        if rgb.len() < 3 * width * height {
            return;
        }
        let viewport = sys::mjrRect { left: 0, bottom: 0, width: width as i32, height: height as i32 };
        let m = data.model().as_ptr();
        // SAFETY: model and data belong together (Data holds its Model); the
        // scene and context were made for a model of this kind on this
        // thread's current OpenGL context (`new`'s contract); `scene.geoms`
        // holds `ngeom` initialised geoms after mjv_updateScene; `rgb` holds at
        // least width × height × 3 bytes, what mjr_readPixels writes for
        // `viewport`; no depth buffer.
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
            // Recolour; a colour of alpha 0 leaves the geom out (the scene's
            // list is compacted in place, keeping the order of the rest).
            let mut kept = 0;
            for i in 0..self.scene.ngeom.max(0) as usize {
                let g = &mut *self.scene.geoms.add(i);
                if g.objtype == sys::mjtObj::mjOBJ_GEOM as i32 {
                    if let Some((_, rgba)) = recolour.iter().find(|(id, _)| *id as i32 == g.objid) {
                        if rgba[3] == 0.0 {
                            continue;
                        }
                        g.rgba = *rgba;
                    }
                }
                if kept != i {
                    *self.scene.geoms.add(kept) = *self.scene.geoms.add(i);
                }
                kept += 1;
            }
            self.scene.ngeom = kept as i32;
            sys::mjr_render(viewport, self.scene.as_mut(), self.context.as_ref());
            if let Some((a, b)) = caption {
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
    }

    /// The camera of the last rendered frame.
    pub fn camera_frame(&self) -> CameraFrame {
        let c = &self.scene.camera[0];
        CameraFrame {
            pos: c.pos.map(f64::from),
            forward: c.forward.map(f64::from),
            up: c.up.map(f64::from),
            frustum_center: c.frustum_center as f64,
            frustum_near: c.frustum_near as f64,
            frustum_bottom: c.frustum_bottom as f64,
            frustum_top: c.frustum_top as f64,
        }
    }
}

impl Drop for Visual {
    fn drop(&mut self) {
        // SAFETY: made in `new` and freed once; `new`'s contract keeps the
        // OpenGL context current until after this.
        unsafe {
            sys::mjr_freeContext(self.context.as_mut());
            sys::mjv_freeScene(self.scene.as_mut());
        }
    }
}
