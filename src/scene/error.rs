//! Scene errors: every one names the file, the line and the key.

use std::path::PathBuf;

/// Why a scene could not be loaded.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// The scene file (or a mesh it names) could not be read.
    #[error("{file}: cannot read: {error}")]
    Io {
        /// The file.
        file: PathBuf,
        /// The OS error (in the message, so not also a `source`: printed once).
        error: std::io::Error,
    },
    /// The TOML is malformed, or a key is unknown, missing or of the wrong type.
    #[error("{file}:{line}: {key}: {message}")]
    Syntax {
        /// The file.
        file: PathBuf,
        /// 1-based line.
        line: usize,
        /// The key at fault, as well as it can be told.
        key: String,
        /// What the parser said.
        message: String,
    },
    /// A value is out of its domain (NaN, a negative radius, an unknown material, ...).
    #[error("{file}:{line}: {key}: {message}")]
    Invalid {
        /// The file.
        file: PathBuf,
        /// 1-based line.
        line: usize,
        /// The key at fault, with its table (`spheres[2].radius`).
        key: String,
        /// What is wrong and what is allowed.
        message: String,
    },
    /// A value of a scene built or edited in memory is out of its domain
    /// ([`super::Scene::validate`]): the same key and message as [`SceneError::Invalid`]
    /// for a file, without a line.
    #[error("{file}: {key}: {message}")]
    Value {
        /// The scene's path ([`super::Scene::path`]).
        file: PathBuf,
        /// The key at fault, with its table (`spheres[2].radius`).
        key: String,
        /// What is wrong and what is allowed.
        message: String,
    },
    /// A `--set` setting cannot be made ([`super::set`]).
    #[error("{file}: {error}")]
    Set {
        /// The scene file.
        file: PathBuf,
        /// The setting and what is wrong with it.
        error: super::set::SetError,
    },
    /// A mesh file is bad.
    #[error("{file}:{line}: {key}: mesh {mesh}: {error}")]
    Mesh {
        /// The scene file.
        file: PathBuf,
        /// The line of the `[[meshes]]` entry's `file` key.
        line: usize,
        /// `meshes[i].file`.
        key: String,
        /// The OBJ file.
        mesh: PathBuf,
        /// What is wrong with it (or with its MTL), in the file's own terms: its line where
        /// it has one. In the message, so not also a `source`: printed once. Boxed, so that
        /// every `Result` of the loader stays small.
        error: Box<super::MeshError>,
    },
}

impl SceneError {
    /// The 1-based line the error points at, when it has one.
    pub fn line(&self) -> Option<usize> {
        match self {
            SceneError::Io { .. } | SceneError::Value { .. } | SceneError::Set { .. } => None,
            SceneError::Syntax { line, .. }
            | SceneError::Invalid { line, .. }
            | SceneError::Mesh { line, .. } => Some(*line),
        }
    }

    /// The key the error names, when it has one.
    pub fn key(&self) -> Option<&str> {
        match self {
            SceneError::Io { .. } | SceneError::Set { .. } => None,
            SceneError::Syntax { key, .. }
            | SceneError::Invalid { key, .. }
            | SceneError::Value { key, .. }
            | SceneError::Mesh { key, .. } => Some(key),
        }
    }
}

impl SceneError {
    /// This error of a scene read with `--set` settings, told in the file's terms: its line
    /// the file's own, and, where a setting wrote the value at fault, the setting named.
    pub(super) fn through_settings(mut self, applied: &super::set::Applied) -> SceneError {
        match &mut self {
            SceneError::Syntax {
                line, key, message, ..
            }
            | SceneError::Invalid {
                line, key, message, ..
            } => {
                if let Some(arg) = applied.setting_for(*line, key) {
                    message.push_str(&format!(" (set by --set {arg})"));
                }
                *line = applied.file_line(*line);
            }
            SceneError::Mesh { line, .. } => *line = applied.file_line(*line),
            SceneError::Io { .. } | SceneError::Value { .. } | SceneError::Set { .. } => {}
        }
        self
    }
}

/// The 1-based line of byte offset `pos` in `src`.
pub fn line_of(src: &str, pos: usize) -> usize {
    line_of_bytes(src.as_bytes(), pos)
}

/// [`line_of`] for bytes that need not be UTF-8 (a mesh or MTL being refused).
pub fn line_of_bytes(bytes: &[u8], pos: usize) -> usize {
    bytes[..pos.min(bytes.len())]
        .iter()
        .filter(|&&b| b == b'\n')
        .count()
        + 1
}
