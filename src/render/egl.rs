//! A headless OpenGL context through EGL: Mesa's surfaceless platform (a
//! software rasteriser; no display, no GPU, no `/dev/dri` needed), a context
//! created without a config (`EGL_KHR_no_config_context`: the surfaceless
//! display offers no configs) and made current without surfaces. MuJoCo then
//! renders into its own offscreen framebuffer.
//!
//! libEGL is loaded at run time, so a machine without it runs every other
//! command; only rendering fails, with [`RenderError::EglUnavailable`].

use super::RenderError;
use khronos_egl as egl;

/// `EGL_PLATFORM_SURFACELESS_MESA` (EGL_MESA_platform_surfaceless).
const PLATFORM_SURFACELESS_MESA: egl::Enum = 0x31DD;
/// Set to any value to act as if libEGL were missing (tests, or to check the
/// error path on a machine that has it).
pub const DISABLE_VAR: &str = "BLOCKPUZZLE_NO_EGL";

/// A current OpenGL context on this thread (on the process's surfaceless
/// EGL display). Released on drop.
pub struct GlContext {
    egl: &'static egl::DynamicInstance<egl::EGL1_5>,
    display: egl::Display,
    context: egl::Context,
}

fn call(what: &'static str) -> impl Fn(egl::Error) -> RenderError {
    move |e| RenderError::Egl { call: what, reason: e.to_string() }
}

/// libEGL, loaded once a process and never unloaded. Loading it for each context and letting the
/// last one's drop unload it unloads Mesa's driver and its LLVM with it; loading them again in the
/// same process then crashed llvmpipe (a segfault in libLLVM after a few dozen renderers made and
/// dropped one after another, as `blockpuzzle serve` does).
fn instance() -> Result<&'static egl::DynamicInstance<egl::EGL1_5>, RenderError> {
    static LOADED: std::sync::OnceLock<Result<egl::DynamicInstance<egl::EGL1_5>, String>> = std::sync::OnceLock::new();
    // SAFETY: loading libEGL runs its initialisers; it is the system's EGL loader (libglvnd or Mesa),
    // loaded once and kept for the process's life, and its functions are resolved by name against
    // the EGL 1.5 signatures khronos-egl declares.
    let loaded = LOADED
        .get_or_init(|| unsafe { egl::DynamicInstance::<egl::EGL1_5>::load_required() }.map_err(|e| e.to_string()));
    loaded.as_ref().map_err(|e| RenderError::EglUnavailable { reason: e.clone() })
}

impl GlContext {
    /// Creates the context and makes it current on the calling thread.
    ///
    /// # Errors
    /// [`RenderError::EglUnavailable`] when libEGL (or EGL 1.5) is missing or
    /// disabled by [`DISABLE_VAR`]; [`RenderError::Egl`] naming the EGL call
    /// that failed.
    pub fn new() -> Result<Self, RenderError> {
        switched_off()?;
        let egl = instance()?;
        // SAFETY: the surfaceless platform takes no native display (null) and
        // an attribute list holding only the terminator.
        let display =
            unsafe { egl.get_platform_display(PLATFORM_SURFACELESS_MESA, std::ptr::null_mut(), &[egl::ATTRIB_NONE]) }
                .map_err(call("eglGetPlatformDisplay(EGL_PLATFORM_SURFACELESS_MESA)"))?;
        egl.initialize(display).map_err(call("eglInitialize"))?;
        let made = (|| {
            egl.bind_api(egl::OPENGL_API).map_err(call("eglBindAPI(EGL_OPENGL_API)"))?;
            // SAFETY: EGL_NO_CONFIG_KHR is the null config handle.
            let no_config = unsafe { egl::Config::from_ptr(std::ptr::null_mut()) };
            let context = egl
                .create_context(display, no_config, None, &[egl::NONE])
                .map_err(call("eglCreateContext (EGL_KHR_no_config_context)"))?;
            if let Err(e) = egl.make_current(display, None, None, Some(context)) {
                let _ = egl.destroy_context(display, context);
                return Err(call("eglMakeCurrent")(e));
            }
            Ok(context)
        })();
        // The display is not terminated: EGL hands every caller in the
        // process the same display, and eglTerminate would pull it from
        // under renderers on other threads. It lives as long as the process.
        made.map(|context| Self { egl, display, context })
    }
}

/// [`RenderError::EglUnavailable`] while [`DISABLE_VAR`] is set.
fn switched_off() -> Result<(), RenderError> {
    match std::env::var_os(DISABLE_VAR) {
        Some(_) => Err(RenderError::EglUnavailable { reason: format!("disabled by {DISABLE_VAR}") }),
        None => Ok(()),
    }
}

thread_local! {
    /// The calling thread's context, made at its first renderer and kept until the thread ends.
    static THREAD_CONTEXT: std::cell::RefCell<Option<std::rc::Rc<GlContext>>> = const { std::cell::RefCell::new(None) };
}

/// The calling thread's OpenGL context, made current: one per thread, shared by every renderer the
/// thread makes. Making and destroying a context for each renderer made Mesa's llvmpipe crash in
/// libLLVM after some dozens of them on one thread (`blockpuzzle serve` renders every episode on
/// one thread), and compiled its shaders anew each time.
///
/// # Errors
/// As [`GlContext::new`], the first time on a thread.
pub fn thread_context() -> Result<std::rc::Rc<GlContext>, RenderError> {
    // Asked at every renderer, as when each made its own context: switching rendering off holds
    // for a thread that has rendered before.
    switched_off()?;
    THREAD_CONTEXT.with(|slot| {
        if let Some(gl) = slot.borrow().as_ref() {
            return Ok(std::rc::Rc::clone(gl));
        }
        let gl = std::rc::Rc::new(GlContext::new()?);
        *slot.borrow_mut() = Some(std::rc::Rc::clone(&gl));
        Ok(gl)
    })
}

impl Drop for GlContext {
    fn drop(&mut self) {
        let _ = self.egl.make_current(self.display, None, None, None);
        let _ = self.egl.destroy_context(self.display, self.context);
    }
}
