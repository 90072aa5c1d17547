//! Reading a scene's files: the scene text and the files it names, regular files only,
//! within the input limit, and syntax errors named by line and table.

use super::*;

/// A scene file's text: a regular file within the input limit, in UTF-8 (else an error
/// naming the line where it stops being UTF-8).
pub(super) fn read_scene_text(path: &Path, limit: u64) -> Result<String, SceneError> {
    let bytes = read_limited(path, limit).map_err(|e| match e {
        ReadError::Io(error) => SceneError::Io {
            file: path.to_owned(),
            error,
        },
        other => SceneError::Syntax {
            file: path.to_owned(),
            line: 1,
            key: "(file)".into(),
            message: other.to_string(),
        },
    })?;
    String::from_utf8(bytes).map_err(|e| {
        let pos = e.utf8_error().valid_up_to();
        let text = String::from_utf8_lossy(e.as_bytes()).into_owned();
        SceneError::Syntax {
            file: path.to_owned(),
            line: line_of(&text, pos),
            key: "(file)".into(),
            message: format!("not UTF-8 at byte {pos}"),
        }
    })
}

pub(super) fn syntax_error(src: &str, path: &Path, e: &toml::de::Error) -> SceneError {
    let span = e.span().unwrap_or(0..0);
    let message = e.message().trim().to_string();
    // serde names the field in backticks ("unknown field `foo`", "missing field `bar`");
    // otherwise the key is the one assigned on the error's line, or the text under the span.
    let line = line_of(src, span.start);
    let line_key = src.lines().nth(line - 1).and_then(|l| {
        let (k, _) = l.split_once('=')?;
        let k = k.trim();
        (!k.is_empty() && !k.starts_with('[') && !k.starts_with('#')).then(|| k.to_string())
    });
    let key = message
        .split('`')
        .nth(1)
        .map(str::to_string)
        .or(line_key)
        .or_else(|| {
            let s = src.get(span.clone())?.trim();
            (!s.is_empty() && s.len() <= 40 && !s.contains('\n')).then(|| s.to_string())
        })
        .unwrap_or_else(|| "(document)".into());
    // The key's whole path: `camera.focal`, `lights[1].colour`, not `focal`.
    let key = match table_at(src, span.start) {
        Some(t)
            if !key.starts_with('(')
                && !key.contains(['.', '['])
                && t != key
                && !t.ends_with(&format!(".{key}"))
                && !t.starts_with(&format!("{key}[")) =>
        {
            format!("{t}.{key}")
        }
        _ => key,
    };
    SceneError::Syntax {
        file: path.to_owned(),
        line: line_of(src, span.start),
        key,
        message,
    }
}

/// The table that holds byte `offset` of a scene's text, as a key path (`camera`,
/// `lights[1]`, `materials.red`, `meshes[0].transform`); `None` at the top level. Read from
/// the table headers above the offset, line by line, as TOML defines them: `[[name]]`
/// appends to an array of tables, `[name]` opens a table, and a header below an array's
/// name extends its last element.
pub(super) fn table_at(src: &str, offset: usize) -> Option<String> {
    let is_path = |s: &str| {
        s.starts_with(|c: char| c.is_ascii_alphabetic() || c == '"' || c == '_')
            && s.chars()
                .all(|c| c.is_ascii_alphanumeric() || "_-.\" ".contains(c))
    };
    let mut counts: std::collections::HashMap<String, usize> = Default::default();
    let mut table = None;
    let mut start = 0;
    for line in src.split_inclusive('\n') {
        if start > offset {
            break;
        }
        start += line.len();
        let t = line.split('#').next().unwrap_or("").trim();
        let (name, array) = if let Some(n) = t.strip_prefix("[[").and_then(|r| r.strip_suffix("]]"))
        {
            (n.trim(), true)
        } else if let Some(n) = t.strip_prefix('[').and_then(|r| r.strip_suffix(']')) {
            (n.trim(), false)
        } else {
            continue;
        };
        if !is_path(name) {
            continue;
        }
        // Below an array of tables: `[a.b]` is `a[last].b`.
        let (head, rest) = name.split_once('.').unwrap_or((name, ""));
        let mut path = match counts.get(head) {
            Some(&n) if !rest.is_empty() => format!("{head}[{}].{rest}", n - 1),
            _ => name.to_string(),
        };
        if array {
            let n = counts.entry(name.to_string()).or_insert(0);
            path = format!("{path}[{n}]");
            *n += 1;
        }
        table = Some(path);
    }
    table
}

/// How a scene reads the files it names (meshes and their MTLs): the bytes, or why not.
pub type ReadFile<'a> = dyn Fn(&Path) -> Result<Vec<u8>, ReadError> + 'a;

/// [`ReadFile`] from the file system: regular files only, at most the default input limit
/// ([`LoadOptions`]).
pub fn read_from_disk(path: &Path) -> Result<Vec<u8>, ReadError> {
    read_from_disk_limited(path, LoadOptions::default().max_input_bytes)
}

/// [`read_from_disk`] with at most `limit` bytes.
pub fn read_from_disk_limited(path: &Path, limit: u64) -> Result<Vec<u8>, ReadError> {
    read_limited(path, limit)
}

/// A [`ReadFile`] that reads only files whose real path (symbolic links followed) lies
/// below `root`, which must itself be canonical; at most the default input limit.
pub fn confined_reader(root: PathBuf) -> impl Fn(&Path) -> Result<Vec<u8>, ReadError> {
    confined_reader_limited(root, LoadOptions::default().max_input_bytes)
}

/// [`confined_reader`] with at most `limit` bytes a file.
pub fn confined_reader_limited(
    root: PathBuf,
    limit: u64,
) -> impl Fn(&Path) -> Result<Vec<u8>, ReadError> {
    move |path: &Path| {
        let real = std::fs::canonicalize(path).map_err(ReadError::Io)?;
        if !real.starts_with(&root) {
            return Err(ReadError::Outside {
                path: real,
                root: root.clone(),
            });
        }
        read_from_disk_limited(&real, limit)
    }
}

/// The default of [`LoadOptions::max_input_bytes`], MiB: 2 GiB, twice the largest mesh
/// glint is meant for (an OBJ of about 15 million triangles).
pub const DEFAULT_MAX_INPUT_MIB: u64 = 2048;

/// Why an input file was not read.
#[derive(Debug, thiserror::Error)]
pub enum ReadError {
    /// The OS refused.
    #[error("cannot read: {0}")]
    Io(std::io::Error),
    /// A FIFO, a device, a socket or a folder: glint reads regular files only (a named pipe
    /// would block forever, a device never ends).
    #[error("not a regular file (it is {0}): glint reads only regular files")]
    NotRegular(&'static str),
    /// Longer than the limit.
    #[error(
        "larger than the input limit of {} MiB (set GLINT_MAX_INPUT_MIB to raise it)",
        .0 >> 20
    )]
    TooLarge(u64),
    /// In confined mode ([`LoadOptions::confine`]), a file whose real path is not below the
    /// scene's folder.
    #[error("{path} is outside the scene's folder {root} (--confine)")]
    Outside {
        /// The file's real path (symbolic links followed).
        path: PathBuf,
        /// The scene's folder, canonical.
        root: PathBuf,
    },
    /// Any other reason a [`ReadFile`] gives, printed as it is (a reader that serves files
    /// from memory has reasons of its own).
    #[error("{0}")]
    Other(String),
}

pub(super) fn kind_of(t: std::fs::FileType) -> &'static str {
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if t.is_fifo() {
            return "a named pipe";
        }
        if t.is_char_device() || t.is_block_device() {
            return "a device";
        }
        if t.is_socket() {
            return "a socket";
        }
    }
    if t.is_dir() { "a folder" } else { "not a file" }
}

/// Reads a regular file of at most `limit` bytes. The type is checked before the file is
/// opened (opening a named pipe blocks) and again on the open file.
pub fn read_limited(path: &Path, limit: u64) -> Result<Vec<u8>, ReadError> {
    use std::io::Read;
    let meta = std::fs::metadata(path).map_err(ReadError::Io)?;
    if !meta.is_file() {
        return Err(ReadError::NotRegular(kind_of(meta.file_type())));
    }
    let mut opts = std::fs::OpenOptions::new();
    opts.read(true);
    #[cfg(target_os = "linux")]
    {
        use std::os::unix::fs::OpenOptionsExt;
        opts.custom_flags(0o4000); // O_NONBLOCK: a FIFO swapped in after the check does not block
    }
    let file = opts.open(path).map_err(ReadError::Io)?;
    let meta = file.metadata().map_err(ReadError::Io)?;
    if !meta.is_file() {
        return Err(ReadError::NotRegular(kind_of(meta.file_type())));
    }
    if meta.len() > limit {
        return Err(ReadError::TooLarge(limit));
    }
    let mut out = Vec::with_capacity(meta.len() as usize);
    file.take(limit + 1)
        .read_to_end(&mut out)
        .map_err(ReadError::Io)?;
    if out.len() as u64 > limit {
        return Err(ReadError::TooLarge(limit));
    }
    Ok(out)
}
