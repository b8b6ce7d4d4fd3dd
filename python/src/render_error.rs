//! Rendering errors in Python: the core's messages ([`blockpuzzle::render::egl_message`]), which name
//! the system package that is missing in apt and dnf terms and say that no pip package provides it,
//! raised as `RuntimeError`, with `render()` named.

use blockpuzzle::render::RenderError;
use pyo3::exceptions::PyRuntimeError;
use pyo3::prelude::*;

/// A rendering error as a Python `RuntimeError`.
pub(crate) fn render_err(e: RenderError) -> PyErr {
    PyRuntimeError::new_err(format!("render(): {e}"))
}

/// The message `render()` raises when the EGL call `call` fails with `reason` (None: libEGL could
/// not be loaded): the message builder, for the tests (the failures need a machine without Mesa).
#[pyfunction]
#[pyo3(signature = (call, reason))]
pub(crate) fn _render_error_message(call: Option<&str>, reason: &str) -> String {
    format!("render(): {}", blockpuzzle::render::egl_message(call, reason))
}
