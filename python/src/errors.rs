//! glint's errors as Python exceptions: a scene error is a `glint.SceneError` (a
//! `ValueError`) with `file`, `line` and `key`; an I/O error an `OSError`; a cancelled
//! render `KeyboardInterrupt`; anything else a `glint.RenderError`.

use pyo3::exceptions::{PyKeyboardInterrupt, PyOSError, PyRuntimeError, PyValueError};
use pyo3::prelude::*;

pyo3::create_exception!(
    glint,
    SceneError,
    PyValueError,
    "A scene is invalid: the message names the file, the line and the key, as the command \
     line prints it; the attributes `file`, `line` and `key` hold them (`line` and `key` are \
     None where the error has none)."
);
pyo3::create_exception!(
    glint,
    RenderError,
    PyRuntimeError,
    "A render failed for a reason other than the scene or a file: no adapter, a device \
     error, a frame too large for memory."
);

/// A `SceneError` carrying `message`, `file`, `line` and `key`.
pub fn scene_error(
    py: Python<'_>,
    message: String,
    file: Option<String>,
    line: Option<usize>,
    key: Option<String>,
) -> PyErr {
    let err = SceneError::new_err(message);
    let value = err.value(py);
    // Setting attributes on a fresh exception instance cannot fail.
    let _ = value.setattr("file", file);
    let _ = value.setattr("line", line);
    let _ = value.setattr("key", key);
    err
}

/// A library scene error as a Python exception. `dict_source`: the scene came from a dict,
/// whose lines (those of the TOML it was written to) mean nothing to the caller, so the
/// message and `file` name `<dict>` and `line` is None.
pub fn from_scene_error(py: Python<'_>, e: &glint::scene::SceneError, dict_source: bool) -> PyErr {
    use glint::scene::SceneError as E;
    match e {
        E::Io { file, error } => os_error(file, error),
        E::Syntax { key, message, .. }
        | E::Invalid { key, message, .. }
        | E::Value { key, message, .. }
            if dict_source =>
        {
            scene_error(
                py,
                format!("<dict>: {key}: {message}"),
                Some("<dict>".into()),
                None,
                Some(key.clone()),
            )
        }
        E::Syntax { file, .. }
        | E::Invalid { file, .. }
        | E::Value { file, .. }
        | E::Set { file, .. }
        | E::Mesh { file, .. } => scene_error(
            py,
            e.to_string(),
            Some(file.display().to_string()),
            e.line(),
            e.key().map(str::to_string),
        ),
    }
}

/// A library render error as a Python exception.
pub fn from_render_error(py: Python<'_>, e: &glint::RenderError, dict_source: bool) -> PyErr {
    use glint::RenderError as E;
    match e {
        E::Scene(s) => from_scene_error(py, s, dict_source),
        E::Image(i) => image_error(i),
        E::Cancelled => PyKeyboardInterrupt::new_err("render cancelled"),
        E::Size(..) => PyValueError::new_err(e.to_string()),
        _ => RenderError::new_err(e.to_string()),
    }
}

/// An image error: an `OSError` where the file system refused, else a `ValueError` (an
/// unknown extension, a malformed file).
pub fn image_error(e: &glint::image::ImageError) -> PyErr {
    match e {
        glint::image::ImageError::Io { path, error } => os_error(path, error),
        _ => PyValueError::new_err(e.to_string()),
    }
}

/// An `OSError` as Python makes one (`OSError(errno, strerror, filename)`), so that it is
/// the subclass its errno names (`FileNotFoundError`, `PermissionError`, ...).
pub fn os_error(path: &std::path::Path, error: &std::io::Error) -> PyErr {
    match error.raw_os_error() {
        Some(code) => {
            // Rust's text ends in " (os error N)"; Python's strerror is the text alone.
            let text = error.to_string();
            let text = text.split(" (os error").next().unwrap_or(&text).to_string();
            PyOSError::new_err((code, text, path.display().to_string()))
        }
        None => PyOSError::new_err(format!("{}: {error}", path.display())),
    }
}

/// A panic's payload as a `glint.RenderError`: the interpreter lives on.
pub fn from_panic(payload: Box<dyn std::any::Any + Send>) -> PyErr {
    let what = payload
        .downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| payload.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "a panic".into());
    RenderError::new_err(format!("internal error in glint: {what}"))
}
