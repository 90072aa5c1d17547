//! Stanford PLY meshes (`.ply`, `.ply.gz`): ASCII and binary, little- and big-endian, read
//! into the OBJ reader's [`Parsed`], so that a PLY is placed, cached and shaded as an OBJ
//! of the same mesh is, and renders equal to it in every bit.
//!
//! - **Vertices**: the `vertex` element's `x`, `y`, `z` of any scalar type (a `double` is
//!   rounded to f32 once; an ASCII `float` is parsed straight to f32, as the OBJ reader
//!   parses its text). `u v` (or `s t`, `texture_u texture_v`) are the texture
//!   coordinates, v up, as OBJ's. `nx`, `ny`, `nz` are read for a smooth mesh: a zero normal is
//!   computed from the faces as a missing one is; one that is not finite is an error.
//! - **Faces**: the `face` element's list `vertex_indices` (or `vertex_index`), counts and
//!   indices of any integer type; polygons fanned from their first vertex, as OBJ's are.
//! - **Everything else** (other properties, other elements) is read
//!   past. Nothing is allocated from a count before the file is seen to hold that much.
//! - **Errors** name the header line, or the element and its index (from 0).

use super::obj::{NO_NORMAL, Normals, Parsed};

/// What is wrong with a PLY file.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum PlyError {
    /// The header is malformed or asks for what glint does not read.
    #[error("PLY header line {line}: {message}")]
    Header {
        /// The header's line, from 1.
        line: usize,
        /// What is wrong.
        message: String,
    },
    /// An element's data is wrong (or the file ends inside it).
    #[error("PLY element {element} {index}: {message}")]
    Element {
        /// The element's name (`vertex`, `face`, ...).
        element: String,
        /// The element's index, from 0.
        index: usize,
        /// What is wrong.
        message: String,
    },
}

/// The most bytes a header may have: real headers have a few hundred.
const MAX_HEADER_BYTES: usize = 64 << 10;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Format {
    Ascii,
    Little,
    Big,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    fn named(s: &str) -> Option<Scalar> {
        Some(match s {
            "char" | "int8" => Scalar::I8,
            "uchar" | "uint8" => Scalar::U8,
            "short" | "int16" => Scalar::I16,
            "ushort" | "uint16" => Scalar::U16,
            "int" | "int32" => Scalar::I32,
            "uint" | "uint32" => Scalar::U32,
            "float" | "float32" => Scalar::F32,
            "double" | "float64" => Scalar::F64,
            _ => return None,
        })
    }

    fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }

    fn is_integer(self) -> bool {
        !matches!(self, Scalar::F32 | Scalar::F64)
    }
}

/// What glint does with a property.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Use {
    /// A vertex's position (0..3), normal (3..6) or texture coordinate (6..8) component.
    Slot(usize),
    /// The face's corner list.
    Corners,
    /// Read past.
    Skip,
}

#[derive(Clone, Debug)]
enum Property {
    Scalar(Scalar, Use),
    List(Scalar, Scalar, Use),
}

#[derive(Clone, Debug)]
struct Element {
    name: String,
    count: usize,
    props: Vec<Property>,
    line: usize,
}

/// The header: the format, the elements, and where the data starts.
struct Header {
    format: Format,
    elements: Vec<Element>,
    body: usize,
}

fn header_error<T>(line: usize, message: impl Into<String>) -> Result<T, PlyError> {
    Err(PlyError::Header {
        line,
        message: message.into(),
    })
}

/// Whether `bytes` start as a PLY file does.
pub fn is_ply(bytes: &[u8]) -> bool {
    bytes.starts_with(b"ply\n") || bytes.starts_with(b"ply\r\n")
}

fn header(bytes: &[u8], normals: Normals) -> Result<Header, PlyError> {
    if !is_ply(bytes) {
        return header_error(1, "not a PLY file (it does not start with `ply`)");
    }
    let mut format = None;
    let mut elements: Vec<Element> = Vec::new();
    let mut pos = 0;
    let mut line_no = 0;
    loop {
        let rest = &bytes[pos..];
        let Some(nl) = rest.iter().position(|&b| b == b'\n') else {
            return header_error(line_no + 1, "the file ends before `end_header`");
        };
        line_no += 1;
        if pos + nl > MAX_HEADER_BYTES {
            return header_error(
                line_no,
                format!("no `end_header` in the first {MAX_HEADER_BYTES} bytes"),
            );
        }
        let raw = &rest[..nl];
        pos += nl + 1;
        let Ok(line) = std::str::from_utf8(raw) else {
            return header_error(line_no, "not text");
        };
        let words: Vec<&str> = line.split_ascii_whitespace().collect();
        match words.as_slice() {
            ["ply"] if line_no == 1 => {}
            [] | ["comment", ..] | ["obj_info", ..] => {}
            ["format", f, version] => {
                if *version != "1.0" {
                    return header_error(
                        line_no,
                        format!("format version {version}: glint reads 1.0"),
                    );
                }
                format = Some(match *f {
                    "ascii" => Format::Ascii,
                    "binary_little_endian" => Format::Little,
                    "binary_big_endian" => Format::Big,
                    other => return header_error(line_no, format!("unknown format {other:?}")),
                });
            }
            ["element", name, count] => {
                let Ok(count) = count.parse::<usize>() else {
                    return header_error(
                        line_no,
                        format!("element {name}: count {count:?} is not a number"),
                    );
                };
                elements.push(Element {
                    name: name.to_string(),
                    count,
                    props: Vec::new(),
                    line: line_no,
                });
            }
            ["property", "list", count, item, name] => {
                let Some(e) = elements.last_mut() else {
                    return header_error(line_no, "a property before any element");
                };
                let (Some(c), Some(i)) = (Scalar::named(count), Scalar::named(item)) else {
                    return header_error(line_no, format!("unknown type in {line:?}"));
                };
                let corners =
                    e.name == "face" && (*name == "vertex_indices" || *name == "vertex_index");
                if corners && !(c.is_integer() && i.is_integer()) {
                    return header_error(
                        line_no,
                        format!("{name}: counts and indices must be integers"),
                    );
                }
                if !c.is_integer() {
                    return header_error(
                        line_no,
                        format!("{name}: a list's count must be an integer type"),
                    );
                }
                e.props.push(Property::List(
                    c,
                    i,
                    if corners { Use::Corners } else { Use::Skip },
                ));
            }
            ["property", ty, name] => {
                let Some(e) = elements.last_mut() else {
                    return header_error(line_no, "a property before any element");
                };
                let Some(t) = Scalar::named(ty) else {
                    return header_error(line_no, format!("unknown type {ty:?}"));
                };
                let slot = match (e.name.as_str(), *name) {
                    ("vertex", "x") => Use::Slot(0),
                    ("vertex", "y") => Use::Slot(1),
                    ("vertex", "z") => Use::Slot(2),
                    ("vertex", "nx") if normals == Normals::Read => Use::Slot(3),
                    ("vertex", "ny") if normals == Normals::Read => Use::Slot(4),
                    ("vertex", "nz") if normals == Normals::Read => Use::Slot(5),
                    ("vertex", "u" | "s" | "texture_u" | "texture_s") => Use::Slot(6),
                    ("vertex", "v" | "t" | "texture_v" | "texture_t") => Use::Slot(7),
                    _ => Use::Skip,
                };
                e.props.push(Property::Scalar(t, slot));
            }
            ["end_header"] => break,
            _ => return header_error(line_no, format!("cannot read {:?}", trunc(line))),
        }
    }
    let Some(format) = format else {
        return header_error(line_no, "no `format` line");
    };
    let Some(v) = elements.iter().find(|e| e.name == "vertex") else {
        return header_error(line_no, "no `vertex` element");
    };
    for (k, axis) in ["x", "y", "z"].iter().enumerate() {
        if !v
            .props
            .iter()
            .any(|p| matches!(p, Property::Scalar(_, Use::Slot(s)) if *s == k))
        {
            return header_error(
                v.line,
                format!("the vertex element has no `{axis}` property"),
            );
        }
    }
    let Some(f) = elements.iter().find(|e| e.name == "face") else {
        return header_error(line_no, "no `face` element");
    };
    if !f
        .props
        .iter()
        .any(|p| matches!(p, Property::List(_, _, Use::Corners)))
    {
        return header_error(f.line, "the face element has no `vertex_indices` list");
    }
    Ok(Header {
        format,
        elements,
        body: pos,
    })
}

fn trunc(s: &str) -> &str {
    match s.char_indices().nth(60) {
        Some((k, _)) => &s[..k],
        None => s,
    }
}

/// A value as read: an integer, or a float (an ASCII float of type `float` parsed straight
/// to f32).
#[derive(Clone, Copy)]
enum Value {
    Int(i64),
    F32(f32),
    F64(f64),
}

impl Value {
    fn as_f32(self) -> f32 {
        match self {
            Value::Int(i) => i as f32,
            Value::F32(x) => x,
            Value::F64(x) => x as f32,
        }
    }
}

/// The data after the header, read value by value.
enum Body<'b> {
    Binary {
        bytes: &'b [u8],
        pos: usize,
        big: bool,
    },
    Ascii {
        words: AsciiWords<'b>,
    },
}

/// The whitespace-separated words of ASCII data.
struct AsciiWords<'b> {
    bytes: &'b [u8],
    pos: usize,
}

impl<'b> Iterator for AsciiWords<'b> {
    type Item = &'b [u8];
    fn next(&mut self) -> Option<&'b [u8]> {
        let b = self.bytes;
        while self.pos < b.len() && b[self.pos].is_ascii_whitespace() {
            self.pos += 1;
        }
        let start = self.pos;
        while self.pos < b.len() && !b[self.pos].is_ascii_whitespace() {
            self.pos += 1;
        }
        (self.pos > start).then(|| &b[start..self.pos])
    }
}

impl Body<'_> {
    /// The next value of type `t`; `Err` says why not (the file's end, or a bad word).
    fn value(&mut self, t: Scalar) -> Result<Value, String> {
        match self {
            Body::Binary { bytes, pos, big } => {
                let n = t.size();
                let Some(b) = bytes.get(*pos..*pos + n) else {
                    return Err("the file ends here".into());
                };
                *pos += n;
                let mut a = [0u8; 8];
                a[..n].copy_from_slice(b);
                if *big {
                    a[..n].reverse();
                }
                Ok(match t {
                    Scalar::I8 => Value::Int(a[0] as i8 as i64),
                    Scalar::U8 => Value::Int(a[0] as i64),
                    Scalar::I16 => Value::Int(i16::from_le_bytes([a[0], a[1]]) as i64),
                    Scalar::U16 => Value::Int(u16::from_le_bytes([a[0], a[1]]) as i64),
                    Scalar::I32 => Value::Int(i32::from_le_bytes([a[0], a[1], a[2], a[3]]) as i64),
                    Scalar::U32 => Value::Int(u32::from_le_bytes([a[0], a[1], a[2], a[3]]) as i64),
                    Scalar::F32 => Value::F32(f32::from_le_bytes([a[0], a[1], a[2], a[3]])),
                    Scalar::F64 => Value::F64(f64::from_le_bytes(a)),
                })
            }
            Body::Ascii { words } => {
                let Some(w) = words.next() else {
                    return Err("the file ends here".into());
                };
                let s = std::str::from_utf8(w).map_err(|_| "a value is not text".to_string())?;
                let bad = || format!("{:?} is not a {t:?} value", trunc(s));
                Ok(match t {
                    Scalar::F32 => Value::F32(s.parse().map_err(|_| bad())?),
                    Scalar::F64 => Value::F64(s.parse().map_err(|_| bad())?),
                    _ => {
                        let i: i64 = s.parse().map_err(|_| bad())?;
                        let (lo, hi) = match t {
                            Scalar::I8 => (i8::MIN as i64, i8::MAX as i64),
                            Scalar::U8 => (0, u8::MAX as i64),
                            Scalar::I16 => (i16::MIN as i64, i16::MAX as i64),
                            Scalar::U16 => (0, u16::MAX as i64),
                            Scalar::I32 => (i32::MIN as i64, i32::MAX as i64),
                            _ => (0, u32::MAX as i64),
                        };
                        if !(lo..=hi).contains(&i) {
                            return Err(bad());
                        }
                        Value::Int(i)
                    }
                })
            }
        }
    }

    /// The bytes left (binary), or an upper bound on the values left (ASCII: each takes at
    /// least a character and a separator).
    fn room(&self) -> usize {
        match self {
            Body::Binary { bytes, pos, .. } => bytes.len() - pos,
            Body::Ascii { words } => (words.bytes.len() - words.pos).div_ceil(2),
        }
    }
}

/// Reads a PLY file's bytes: its vertices and triangles (and, for a smooth mesh, its
/// normals) in file order, polygons fanned from their first vertex.
pub fn parse(bytes: &[u8], normals: Normals) -> Result<Parsed, PlyError> {
    let h = header(bytes, normals)?;
    let data = &bytes[h.body..];
    let mut body = match h.format {
        Format::Ascii => Body::Ascii {
            words: AsciiWords {
                bytes: data,
                pos: 0,
            },
        },
        f => Body::Binary {
            bytes: data,
            pos: 0,
            big: f == Format::Big,
        },
    };
    let n_vertices = h
        .elements
        .iter()
        .find(|e| e.name == "vertex")
        .map_or(0, |e| e.count);
    let mut out = Parsed {
        vertices: Vec::new(),
        triangles: Vec::new(),
        short_faces: Vec::new(),
        normals: Vec::new(),
        normal_ix: Vec::new(),
        uvs: Vec::new(),
    };
    let mut has_normals = false;
    let mut has_uvs = false;
    let mut texcoords: Vec<[f32; 2]> = Vec::new();
    let mut corners: Vec<u32> = Vec::new();
    for e in &h.elements {
        let err = |index: usize, message: String| PlyError::Element {
            element: e.name.clone(),
            index,
            message,
        };
        // The least each instance takes, to refuse a count the file cannot hold before
        // reserving anything for it.
        let least = match h.format {
            Format::Ascii => e.props.len(),
            _ => e
                .props
                .iter()
                .map(|p| match p {
                    Property::Scalar(t, _) => t.size(),
                    Property::List(c, _, _) => c.size(),
                })
                .sum(),
        };
        if least > 0 && e.count > body.room() / least.max(1) + 1 {
            return Err(err(
                0,
                format!(
                    "the header says {} of them; the file cannot hold that many",
                    e.count
                ),
            ));
        }
        let is_vertex = e.name == "vertex";
        let is_face = e.name == "face";
        if is_vertex {
            out.vertices.reserve(e.count);
            has_normals = normals == Normals::Read
                && e.props
                    .iter()
                    .any(|p| matches!(p, Property::Scalar(_, Use::Slot(3..=5))));
            if has_normals {
                out.normals.reserve(e.count);
            }
            has_uvs = e
                .props
                .iter()
                .any(|p| matches!(p, Property::Scalar(_, Use::Slot(6..=7))));
            if has_uvs {
                texcoords.reserve(e.count);
            }
        }
        if is_face {
            out.triangles.reserve(e.count);
        }
        for index in 0..e.count {
            let mut slots = [0.0f32; 8];
            corners.clear();
            for p in &e.props {
                match *p {
                    Property::Scalar(t, u) => {
                        let v = body.value(t).map_err(|m| err(index, m))?;
                        if let Use::Slot(s) = u {
                            slots[s] = v.as_f32();
                        }
                    }
                    Property::List(c, t, u) => {
                        let n = match body.value(c).map_err(|m| err(index, m))? {
                            Value::Int(n) if n >= 0 => n as usize,
                            _ => return Err(err(index, "a list's count is negative".into())),
                        };
                        if n > body.room() {
                            return Err(err(
                                index,
                                format!("a list of {n} values runs past the file's end"),
                            ));
                        }
                        for _ in 0..n {
                            let v = body.value(t).map_err(|m| err(index, m))?;
                            if u == Use::Corners {
                                let Value::Int(k) = v else {
                                    unreachable!("indices are integers")
                                };
                                if k < 0 || k as usize >= n_vertices {
                                    return Err(err(
                                        index,
                                        format!(
                                            "vertex index {k} is out of range (the file has {n_vertices} vertices)"
                                        ),
                                    ));
                                }
                                corners.push(k as u32);
                            }
                        }
                    }
                }
            }
            if is_vertex {
                out.vertices.push([slots[0], slots[1], slots[2]]);
                if has_normals {
                    let n = [slots[3], slots[4], slots[5]];
                    if n.iter().any(|x| !x.is_finite()) {
                        return Err(err(index, format!("the normal {n:?} is not finite")));
                    }
                    out.normals.push(n);
                }
                if has_uvs {
                    let uv = [slots[6], slots[7]];
                    if uv.iter().any(|x| !x.is_finite()) {
                        return Err(err(
                            index,
                            format!("the texture coordinate {uv:?} is not finite"),
                        ));
                    }
                    texcoords.push(uv);
                }
            }
            if is_face {
                if corners.len() < 3 {
                    return Err(err(
                        index,
                        format!("{} vertices: a face needs at least 3", corners.len()),
                    ));
                }
                for k in 1..corners.len() - 1 {
                    out.triangles.push([corners[0], corners[k], corners[k + 1]]);
                }
            }
        }
    }
    if has_uvs {
        out.uvs = out
            .triangles
            .iter()
            .map(|t| t.map(|k| texcoords[k as usize]))
            .collect();
    }
    if normals == Normals::Read {
        out.normal_ix = out
            .triangles
            .iter()
            .map(|t| {
                t.map(|k| {
                    let zero = !has_normals || out.normals[k as usize].iter().all(|&x| x == 0.0);
                    if zero { NO_NORMAL } else { k }
                })
            })
            .collect();
    }
    Ok(out)
}
