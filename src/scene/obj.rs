//! glint's own OBJ reader for the common case: positions (`v`) and faces (`f`) only, with
//! comments, groups (`o`, `g`), smoothing groups (`s`), normals and texture coordinates
//! (`vn`, `vt`, skipped) allowed. It parses in parallel, in chunks of whole lines, checks
//! as it parses (every error names its line), and gives the triangles in file order,
//! polygons fanned from their first vertex: exactly what tobj gives for such a file. A file
//! that names materials (`mtllib`, `usemtl`) or has other statements goes to tobj.

use rayon::prelude::*;

/// What [`parse`] found: the positions and triangles (untransformed) and the lines of faces
/// with fewer than three vertices (dropped, as tobj drops them).
#[derive(Debug)]
pub struct Parsed {
    /// The positions, in file order.
    pub vertices: Vec<[f32; 3]>,
    /// Triangles in file order, as indices into `vertices`.
    pub triangles: Vec<[u32; 3]>,
    /// 1-based lines of faces with fewer than three vertices.
    pub short_faces: Vec<usize>,
    /// The normals (`vn`), in file order, each finite and of nonzero length; read only when
    /// asked for (else empty).
    pub normals: Vec<[f32; 3]>,
    /// Per triangle, each corner's index into `normals`, or [`NO_NORMAL`] where the face
    /// gives none; empty when normals were not asked for.
    pub normal_ix: Vec<[u32; 3]>,
    /// Per triangle, (u, v) at each corner (v up); empty when the file has none (glint's
    /// OBJ reader never reads them: a textured OBJ goes to tobj).
    pub uvs: Vec<[[f32; 2]; 3]>,
}

/// `Parsed::normal_ix` of a corner without a `vn` index.
pub const NO_NORMAL: u32 = u32::MAX;

/// The longest line an OBJ or MTL file may have: 1 MiB. Real files have lines of tens of
/// bytes (a face of a few hundred corners is a few kilobytes); a longer one means the file
/// is not text (a binary file, or one endless run of the same byte), and reading on would
/// only cost time and memory before the same verdict.
pub const MAX_LINE_BYTES: usize = 1 << 20;

/// What is wrong with an OBJ or MTL text, at its own line (from 1). Each message starts
/// with "line N: ".
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum ObjError {
    /// A NUL byte: not a text file.
    #[error("line {line}: a NUL byte: this is not a text file")]
    Nul {
        /// The line of the first NUL.
        line: u32,
    },
    /// A line longer than 1 MiB (`MAX_LINE_BYTES`): not a text file.
    #[error(
        "line {line}: a line longer than {} MiB: this is not an OBJ or MTL text",
        MAX_LINE_BYTES >> 20
    )]
    LongLine {
        /// The long line.
        line: u32,
    },
    /// Text that cannot be an OBJ, where no more precise reason was found.
    #[error("line {line}: not an OBJ text")]
    NotText {
        /// Where it was noticed.
        line: u32,
    },
    /// Bytes that are not UTF-8 (an MTL).
    #[error("line {line}: not UTF-8")]
    NotUtf8 {
        /// The line of the first such byte.
        line: u32,
    },
    /// A `v` without three numbers.
    #[error("line {line}: a vertex (`v`) needs three numbers: {text:?}")]
    Vertex {
        /// The line.
        line: u32,
        /// The line's first 60 characters.
        text: String,
    },
    /// A `vn` without three finite numbers.
    #[error("line {line}: a normal (`vn`) needs three finite numbers: {text:?}")]
    Normal {
        /// The line.
        line: u32,
        /// The line's first 60 characters.
        text: String,
    },
    /// A `vn` of zero length.
    #[error("line {line}: a normal (`vn`) has zero length: {text:?}")]
    ZeroNormal {
        /// The line.
        line: u32,
        /// The line's first 60 characters.
        text: String,
    },
    /// A face corner whose position index is not an integer.
    #[error("line {line}: face vertex {word:?} is not an index")]
    FaceVertex {
        /// The line.
        line: u32,
        /// The corner as written (`v`, `v/t`, `v//n`, `v/t/n`).
        word: String,
    },
    /// A face corner whose normal index is not an integer.
    #[error("line {line}: face normal index in {word:?} is not an index")]
    FaceNormal {
        /// The line.
        line: u32,
        /// The corner as written.
        word: String,
    },
    /// A face's position index names no position defined before it.
    #[error(
        "line {line}: face vertex index {index} is out of range ({defined} vertices defined before it)"
    )]
    VertexIndex {
        /// The line.
        line: u32,
        /// The index as written (1-based, or negative: from the end).
        index: i64,
        /// The positions defined before the face.
        defined: i64,
    },
    /// A face's normal index names no normal defined before it.
    #[error(
        "line {line}: face normal index {index} is out of range ({defined} normals (`vn`) defined before it)"
    )]
    NormalIndex {
        /// The line.
        line: u32,
        /// The index as written.
        index: i64,
        /// The normals defined before the face.
        defined: i64,
    },
    /// A face corner whose texture index is not an integer (checked for files tobj reads).
    #[error("line {line}: face texture index in {word:?} is not an index")]
    FaceTexcoord {
        /// The line.
        line: u32,
        /// The corner as written.
        word: String,
    },
    /// A face's texture index names no texture coordinate (`vt`) defined before it
    /// (checked for files tobj reads: tobj 4 multiplies an index it has not checked, and
    /// one near 2^63 overflowed).
    #[error(
        "line {line}: face texture index {index} is out of range ({defined} texture coordinates (`vt`) defined before it)"
    )]
    TexcoordIndex {
        /// The line.
        line: u32,
        /// The index as written.
        index: i64,
        /// The texture coordinates defined before the face.
        defined: i64,
    },
    /// An MTL colour (`Ka`, `Kd`, `Ks`, `Ke`) with fewer than three values (tobj 4 panics
    /// on those).
    #[error("line {line}: a colour (Ka, Kd, Ks, Ke) needs three numbers")]
    ShortColour {
        /// The line.
        line: u32,
    },
}

impl ObjError {
    /// The line (from 1) of the file the error is at.
    pub fn line(&self) -> u32 {
        match *self {
            ObjError::Nul { line }
            | ObjError::LongLine { line }
            | ObjError::NotText { line }
            | ObjError::NotUtf8 { line }
            | ObjError::Vertex { line, .. }
            | ObjError::Normal { line, .. }
            | ObjError::ZeroNormal { line, .. }
            | ObjError::FaceVertex { line, .. }
            | ObjError::FaceNormal { line, .. }
            | ObjError::VertexIndex { line, .. }
            | ObjError::NormalIndex { line, .. }
            | ObjError::FaceTexcoord { line, .. }
            | ObjError::TexcoordIndex { line, .. }
            | ObjError::ShortColour { line } => line,
        }
    }

    fn line_mut(&mut self) -> &mut u32 {
        match self {
            ObjError::Nul { line }
            | ObjError::LongLine { line }
            | ObjError::NotText { line }
            | ObjError::NotUtf8 { line }
            | ObjError::Vertex { line, .. }
            | ObjError::Normal { line, .. }
            | ObjError::ZeroNormal { line, .. }
            | ObjError::FaceVertex { line, .. }
            | ObjError::FaceNormal { line, .. }
            | ObjError::VertexIndex { line, .. }
            | ObjError::NormalIndex { line, .. }
            | ObjError::FaceTexcoord { line, .. }
            | ObjError::TexcoordIndex { line, .. }
            | ObjError::ShortColour { line } => line,
        }
    }

    /// The error of a piece of text, moved to the whole file's lines: its line plus
    /// `before`, the lines that come before the piece.
    pub(super) fn after(mut self, before: u32) -> ObjError {
        *self.line_mut() += before;
        self
    }
}

/// The line (from 1) of byte `pos` of `bytes`.
fn line_at(bytes: &[u8], pos: usize) -> u32 {
    super::error::line_of_bytes(bytes, pos) as u32
}

/// Why `bytes`, all or the start of an OBJ or MTL text, is not one: a NUL byte, or a line
/// longer than [`MAX_LINE_BYTES`] (where `whole`, the last line counts as ended), at its
/// line. `None` when neither is seen. One pass over the bytes, only to find the line of
/// what it found.
pub fn junk(bytes: &[u8], whole: bool) -> Option<ObjError> {
    if bytes.contains(&0) {
        let at = bytes.iter().position(|&b| b == 0).unwrap_or(0);
        return Some(ObjError::Nul {
            line: line_at(bytes, at),
        });
    }
    let mut start = 0;
    for end in bytes
        .iter()
        .enumerate()
        .filter(|&(_, &b)| b == b'\n')
        .map(|(k, _)| k)
        .chain(whole.then_some(bytes.len()))
    {
        if end - start > MAX_LINE_BYTES {
            return Some(ObjError::LongLine {
                line: line_at(bytes, start),
            });
        }
        start = end + 1;
    }
    if !whole && bytes.len().saturating_sub(start) > MAX_LINE_BYTES {
        return Some(ObjError::LongLine {
            line: line_at(bytes, start),
        });
    }
    None
}

/// Whether a reader takes the normals (`vn` and the faces' third indices): only a smooth
/// mesh needs them, and only then are they checked.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Normals {
    /// Skip them, as a flat mesh does.
    Skip,
    /// Read and check them.
    Read,
}

/// One triangle of a chunk: raw position indices, the positions the chunk defined before
/// it and its line within the chunk (32 bytes: a mesh's faces are the reader's largest
/// working set).
type RawFace = ([i64; 3], u32, u32);

/// A triangle's raw normal indices (0: none) and the normals the chunk defined before it;
/// kept only when normals are read.
type RawNormals = ([i64; 3], u32);

/// How far back a chunk's face corners reach for one kind of item (`vt`, or `vn` where
/// normals are skipped), for a file tobj reads: a corner's index `i` needs `|i|` items
/// defined before its face (1-based, or from the end), of which the chunk itself defined
/// `local`; `need = |i| - local` is what the text before the chunk must have defined. Kept
/// are the corners whose need beats every earlier one in the chunk: the first corner whose
/// need the text before cannot meet is among them. Entries: (need, line, index, local).
#[derive(Default)]
struct Reach(Vec<(i64, u32, i64, u32)>);

impl Reach {
    fn push(&mut self, index: i64, local: u32, line: u32) {
        // Index 0 (and i64::MIN, whose magnitude is no i64) is out of range whatever came
        // before.
        let need = match index.checked_abs() {
            Some(m) if m > 0 => m - local as i64,
            _ => i64::MAX,
        };
        if self.0.last().is_none_or(|&(n, ..)| need > n) {
            self.0.push((need, line, index, local));
        }
    }

    /// The first corner out of range where the text before the chunk defined `before`
    /// items: (line within the chunk, index, items defined before its face).
    fn first_out(&self, before: i64) -> Option<(u32, i64, i64)> {
        self.0
            .iter()
            .find(|&&(need, ..)| need > before)
            .map(|&(_, line, index, local)| (line, index, before + local as i64))
    }
}

/// A chunk's result: its vertices (and normals), and its triangles.
#[derive(Default)]
struct Chunk {
    vertices: Vec<[f32; 3]>,
    normals: Vec<[f32; 3]>,
    faces: Vec<RawFace>,
    /// Per face, when normals are read.
    face_normals: Vec<RawNormals>,
    short_faces: Vec<u32>,
    lines: u32,
    /// For a file tobj reads: the `vt` lines, and the `vn` lines where normals are skipped.
    texcoords: u32,
    skipped_normals: u32,
    /// For a file tobj reads: how far its faces' texture indices reach, and their normal
    /// indices where normals are skipped.
    reach_t: Reach,
    reach_n: Reach,
}

/// Parses `text`: `Ok(None)` when it needs tobj (materials or statements this reader does
/// not know), `Err` at its line for a malformed position, normal or face.
pub fn parse(text: &str, normals: Normals) -> Result<Option<Parsed>, ObjError> {
    parse_with(text, true, normals)
}

/// Checks an OBJ that tobj will read (one with materials or other statements): the same
/// errors, with their lines, as [`parse`] gives, for positions, normals and faces;
/// statements this reader does not know are skipped. Returns what [`parse`] would, its
/// triangles in tobj's order (file order, polygons fanned from their first vertex), and
/// with `short_faces` the lines of faces with fewer than three vertices, which tobj drops
/// in silence.
pub fn check(text: &str, normals: Normals) -> Result<Parsed, ObjError> {
    Ok(parse_with(text, false, normals)?.expect("a lenient parse always finishes"))
}

/// [`parse`]; with `strict` false, unknown statements are skipped instead of handing the
/// file to tobj.
fn parse_with(text: &str, strict: bool, normals: Normals) -> Result<Option<Parsed>, ObjError> {
    let bytes = text.as_bytes();
    let pieces = rayon::current_num_threads().max(1) * 4;
    let mut cuts = vec![0usize];
    for k in 1..pieces {
        let last = *cuts.last().expect("cuts starts with 0");
        let from = (bytes.len() * k / pieces).max(last);
        let next = bytes[from..]
            .iter()
            .position(|&b| b == b'\n')
            .map_or(bytes.len(), |p| from + p + 1);
        if next > last && next < bytes.len() {
            cuts.push(next);
        }
    }
    cuts.push(bytes.len());
    let chunks: Vec<Result<Option<Chunk>, ObjError>> = cuts
        .par_windows(2)
        .map(|w| parse_chunk(&text[w[0]..w[1]], strict, normals))
        .collect();
    join(chunks, normals)
}

/// One piece of an OBJ's text, whole lines, parsed as [`parse`] parses it: pieces given to
/// [`join_pieces`] in file order give what [`parse`] gives for their text joined, wherever
/// the file was cut (at line ends). This lets a file be parsed as it arrives (a gunzip).
pub struct Piece(Result<Option<Chunk>, ObjError>);

/// Parses one piece of whole lines (its last line may lack its `\n` only at the file's end).
pub fn parse_piece(text: &str, normals: Normals) -> Piece {
    Piece(parse_chunk(text, true, normals))
}

/// [`parse`]'s result for the text of `pieces` (in file order) joined.
pub fn join_pieces(pieces: Vec<Piece>, normals: Normals) -> Result<Option<Parsed>, ObjError> {
    join(pieces.into_iter().map(|p| p.0).collect(), normals)
}

/// The chunks of a text (whole lines each, in file order) joined into what [`parse`] gives.
fn join(
    chunks: Vec<Result<Option<Chunk>, ObjError>>,
    normals: Normals,
) -> Result<Option<Parsed>, ObjError> {
    // Line and vertex offsets of each chunk; the first error in file order wins.
    let mut done = Vec::with_capacity(chunks.len());
    let (mut line0, mut v0, mut n0) = (0u32, 0usize, 0usize);
    // The first texture (or skipped normal) index out of range, for a file tobj reads.
    let (mut t0, mut m0, mut reach_error) = (0i64, 0i64, None::<ObjError>);
    for c in chunks {
        match c {
            Ok(Some(c)) => {
                if reach_error.is_none() {
                    let t = c.reach_t.first_out(t0).map(|(line, index, defined)| {
                        ObjError::TexcoordIndex {
                            line: line0 + line,
                            index,
                            defined,
                        }
                    });
                    let n = c.reach_n.first_out(m0).map(|(line, index, defined)| {
                        ObjError::NormalIndex {
                            line: line0 + line,
                            index,
                            defined,
                        }
                    });
                    reach_error = match (t, n) {
                        (Some(t), Some(n)) => Some(if n.line() < t.line() { n } else { t }),
                        (t, n) => t.or(n),
                    };
                }
                let offsets = (line0, v0, n0);
                line0 += c.lines;
                v0 += c.vertices.len();
                n0 += c.normals.len();
                t0 += c.texcoords as i64;
                m0 += c.skipped_normals as i64;
                done.push((c, offsets));
            }
            Ok(None) => return Ok(None),
            Err(e) => return Err(e.after(line0)),
        }
    }
    let vertices: Vec<[f32; 3]> = done
        .iter()
        .flat_map(|(c, _)| c.vertices.iter().copied())
        .collect();
    let all_normals: Vec<[f32; 3]> = done
        .iter()
        .flat_map(|(c, _)| c.normals.iter().copied())
        .collect();
    // An OBJ index (1-based, or negative: relative to the end) among `defined` items.
    let index = |i: i64, defined: i64| -> Option<u32> {
        let k = if i > 0 { i - 1 } else { defined + i };
        (i != 0 && k >= 0 && k < defined).then_some(k as u32)
    };
    let resolve = |(ix, before, line): &RawFace, (l0, v0, _): (u32, usize, usize)| {
        let defined = v0 as i64 + *before as i64;
        let mut out = [0u32; 3];
        for (slot, &i) in out.iter_mut().zip(ix) {
            *slot = index(i, defined).ok_or(ObjError::VertexIndex {
                line: l0 + line,
                index: i,
                defined,
            })?;
        }
        Ok(out)
    };
    let resolve_normals =
        |(nix, nbefore): &RawNormals, line: u32, (l0, _, n0): (u32, usize, usize)| {
            let n_defined = n0 as i64 + *nbefore as i64;
            let mut nout = [NO_NORMAL; 3];
            for (slot, &i) in nout.iter_mut().zip(nix) {
                if i != 0 {
                    *slot = index(i, n_defined).ok_or(ObjError::NormalIndex {
                        line: l0 + line,
                        index: i,
                        defined: n_defined,
                    })?;
                }
            }
            Ok(nout)
        };
    // Each chunk resolves its faces straight into its own stretch of the result, in
    // parallel: no per-chunk vectors to join afterwards. The first error in file order wins.
    let total: usize = done.iter().map(|(c, _)| c.faces.len()).sum();
    let mut triangles = vec![[0u32; 3]; total];
    let mut normal_ix = if normals == Normals::Read {
        vec![[NO_NORMAL; 3]; total]
    } else {
        Vec::new()
    };
    {
        let mut tri_rest = &mut triangles[..];
        let mut nrm_rest = &mut normal_ix[..];
        let mut jobs = Vec::with_capacity(done.len());
        for (c, off) in &done {
            let (t, rest) = std::mem::take(&mut tri_rest).split_at_mut(c.faces.len());
            tri_rest = rest;
            let n = if normals == Normals::Read {
                let (n, rest) = std::mem::take(&mut nrm_rest).split_at_mut(c.faces.len());
                nrm_rest = rest;
                n
            } else {
                &mut []
            };
            jobs.push((c, *off, t, n));
        }
        let errors: Vec<Option<ObjError>> = jobs
            .into_par_iter()
            .map(|(c, off, t, n)| {
                // Face by face, its positions before its normals, as errors are ordered.
                for (k, f) in c.faces.iter().enumerate() {
                    t[k] = resolve(f, off).map_err(Some)?;
                    if let (Some(slot), Some(raw)) = (n.get_mut(k), c.face_normals.get(k)) {
                        *slot = resolve_normals(raw, f.2, off).map_err(Some)?;
                    }
                }
                Ok::<(), Option<ObjError>>(())
            })
            .map(|r| r.err().flatten())
            .collect();
        // The first error in file order (a position's or normal's before a texture's on
        // one line).
        let first = errors.into_iter().flatten().next();
        match (first, reach_error) {
            (Some(e), Some(r)) => return Err(if r.line() < e.line() { r } else { e }),
            (Some(e), None) | (None, Some(e)) => return Err(e),
            (None, None) => {}
        }
    }
    let short_faces = done
        .iter()
        .flat_map(|(c, (l0, _, _))| c.short_faces.iter().map(move |l| (l0 + l) as usize))
        .collect();
    Ok(Some(Parsed {
        vertices,
        triangles,
        short_faces,
        normals: all_normals,
        normal_ix,
        uvs: Vec::new(),
    }))
}

/// The lines of `text`, split at every `\n` (as `text.split('\n')`, a last empty piece
/// included), by a byte loop: OBJ lines are short, and `str::split`'s `memchr` set-up per
/// line was 9 % of a whole render of the dragon.
fn lines(text: &str) -> impl Iterator<Item = &str> {
    let mut rest = Some(text);
    std::iter::from_fn(move || {
        let t = rest?;
        match t.bytes().position(|b| b == b'\n') {
            Some(k) => {
                rest = Some(&t[k + 1..]);
                Some(&t[..k])
            }
            None => {
                rest = None;
                Some(t)
            }
        }
    })
}

/// One chunk of whole lines. Lines are counted from 1 within the chunk.
fn parse_chunk(text: &str, strict: bool, normals: Normals) -> Result<Option<Chunk>, ObjError> {
    if text.as_bytes().contains(&0) {
        return Err(junk(text.as_bytes(), true).unwrap_or(ObjError::Nul { line: 1 }));
    }
    let mut c = Chunk::default();
    let mut face: Vec<i64> = Vec::with_capacity(8);
    let mut face_n: Vec<i64> = Vec::with_capacity(8);
    for line in lines(text) {
        c.lines += 1;
        if line.len() > MAX_LINE_BYTES {
            return Err(ObjError::LongLine { line: c.lines });
        }
        let mut words = line.split_ascii_whitespace();
        let Some(kw) = words.next() else { continue };
        match kw {
            "v" => {
                let mut p = [0.0f32; 3];
                for slot in p.iter_mut() {
                    match words.next().map(str::parse::<f32>) {
                        Some(Ok(x)) => *slot = x,
                        _ => {
                            return Err(ObjError::Vertex {
                                line: c.lines,
                                text: trunc(line).to_string(),
                            });
                        }
                    }
                }
                c.vertices.push(p);
            }
            "vn" if normals == Normals::Read => {
                let mut n = [0.0f32; 3];
                for slot in n.iter_mut() {
                    match words.next().map(str::parse::<f32>) {
                        Some(Ok(x)) if x.is_finite() => *slot = x,
                        _ => {
                            return Err(ObjError::Normal {
                                line: c.lines,
                                text: trunc(line).to_string(),
                            });
                        }
                    }
                }
                let len2 = n.iter().map(|&x| x as f64 * x as f64).sum::<f64>();
                if len2 <= 0.0 {
                    return Err(ObjError::ZeroNormal {
                        line: c.lines,
                        text: trunc(line).to_string(),
                    });
                }
                c.normals.push(n);
            }
            "f" => {
                face.clear();
                face_n.clear();
                for w in words {
                    // `v`, `v/t`, `v//n` or `v/t/n`: the index before the first slash. Found
                    // by a byte loop (most words have no slash; `split('/')` cost more).
                    let slash = w.bytes().position(|b| b == b'/');
                    let first = &w[..slash.unwrap_or(w.len())];
                    let ix: i64 = first.parse().map_err(|_| ObjError::FaceVertex {
                        line: c.lines,
                        word: w.to_string(),
                    })?;
                    face.push(ix);
                    if !strict && slash.is_some() {
                        // For tobj: the texture index, and the normal index where normals
                        // are skipped (tobj reads them anyway), each in range.
                        let local = c.texcoords;
                        let mut parts = slash.map_or("", |k| &w[k + 1..]).split('/');
                        if let Some(t) = parts.next().filter(|t| !t.is_empty()) {
                            let t: i64 = t.parse().map_err(|_| ObjError::FaceTexcoord {
                                line: c.lines,
                                word: w.to_string(),
                            })?;
                            c.reach_t.push(t, local, c.lines);
                        }
                        if normals == Normals::Skip
                            && let Some(n) = parts.next().filter(|n| !n.is_empty())
                        {
                            let n: i64 = n.parse().map_err(|_| ObjError::FaceNormal {
                                line: c.lines,
                                word: w.to_string(),
                            })?;
                            c.reach_n.push(n, c.skipped_normals, c.lines);
                        }
                    }
                    if normals == Normals::Read {
                        // The third part, after the texture index.
                        let n = match slash.and_then(|k| w[k + 1..].split('/').nth(1)) {
                            None | Some("") => 0,
                            Some(n) => n.parse().map_err(|_| ObjError::FaceNormal {
                                line: c.lines,
                                word: w.to_string(),
                            })?,
                        };
                        face_n.push(n);
                    }
                }
                if face.len() < 3 {
                    c.short_faces.push(c.lines);
                    continue;
                }
                let before = c.vertices.len() as u32;
                let n_before = c.normals.len() as u32;
                let nix = |k: usize| face_n.get(k).copied().unwrap_or(0);
                for k in 2..face.len() {
                    c.faces
                        .push(([face[0], face[k - 1], face[k]], before, c.lines));
                    if normals == Normals::Read {
                        c.face_normals
                            .push(([nix(0), nix(k - 1), nix(k)], n_before));
                    }
                }
            }
            "vt" => c.texcoords += 1,
            "vn" => c.skipped_normals += 1,
            "o" | "g" | "s" => {}
            k if k.starts_with('#') => {}
            _ if strict => return Ok(None),
            _ => {}
        }
    }
    // The chunk ends in '\n' (but the last), so split gives one empty line too many.
    if text.ends_with('\n') {
        c.lines -= 1;
    }
    Ok(Some(c))
}

/// At most the first 60 characters of `s`, for error messages.
pub(super) fn trunc(s: &str) -> &str {
    match s.char_indices().nth(60) {
        Some((k, _)) => &s[..k],
        None => s,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// tobj's triangles for `text` (positions only, triangulated), in its order.
    fn tobj_triangles(text: &str) -> Vec<[[f32; 3]; 3]> {
        let opts = tobj::LoadOptions {
            triangulate: true,
            single_index: false,
            ignore_points: true,
            ignore_lines: true,
        };
        let (models, _) = tobj::load_obj_buf(&mut text.as_bytes(), &opts, |_| {
            Err(tobj::LoadError::OpenFileFailed)
        })
        .unwrap();
        let mut out = Vec::new();
        for m in &models {
            let p = &m.mesh.positions;
            for t in m.mesh.indices.chunks_exact(3) {
                out.push([0, 1, 2].map(|k| {
                    let i = t[k] as usize;
                    [p[3 * i], p[3 * i + 1], p[3 * i + 2]]
                }));
            }
        }
        out
    }

    fn same_as_tobj(text: &str) {
        let p = parse(text, Normals::Skip)
            .unwrap()
            .expect("the fast path takes it");
        let ours: Vec<[[f32; 3]; 3]> = p
            .triangles
            .iter()
            .map(|t| t.map(|i| p.vertices[i as usize]))
            .collect();
        assert_eq!(ours, tobj_triangles(text));
    }

    #[test]
    fn real_meshes_give_tobjs_triangles() {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/meshes");
        let mut n = 0;
        for e in std::fs::read_dir(dir).unwrap() {
            let p = e.unwrap().path();
            if p.extension().is_some_and(|x| x == "obj") {
                same_as_tobj(&std::fs::read_to_string(&p).unwrap());
                n += 1;
            }
        }
        assert!(n >= 3, "no meshes found");
    }

    #[test]
    fn polygons_groups_normals_negative_indices_and_crlf() {
        same_as_tobj(
            "# a quad, a pentagon, groups, normals\r\nv 0 0 0\r\nv 1 0 0\r\nv 1 1 0\r\nv 0 1 0\r\n\
             vn 0 0 1\r\no a\r\nf 1//1 2//1 3//1 4//1\r\ng b\r\ns 1\r\nv 0.5 2 0\r\n\
             f -5 -4 -3 -1 -2\r\nvt 0 0\r\nf 1/1 2/1 3/1\r\n",
        );
    }

    #[test]
    fn what_it_does_not_take_goes_to_tobj_and_errors_name_lines() {
        assert!(
            parse("mtllib a.mtl\nv 0 0 0\n", Normals::Skip)
                .unwrap()
                .is_none()
        );
        assert!(
            parse("v 0 0 0\nusemtl x\n", Normals::Skip)
                .unwrap()
                .is_none()
        );
        let e = parse("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n", Normals::Skip)
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("line 4: face vertex index 4 is out of range"),
            "{e}"
        );
        let e = parse("v 0 0 0\nv 1 nope 0\n", Normals::Skip)
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("line 2: a vertex"), "{e}");
        // What tobj reads is checked the same way, its other statements skipped.
        let e = check(
            "mtllib a.mtl\nv 0 0 0\nv 1 0 0\nusemtl x\nv 0 1 0\nf 1 2 5\n",
            Normals::Skip,
        )
        .unwrap_err()
        .to_string();
        assert!(
            e.starts_with("line 6: face vertex index 5 is out of range"),
            "{e}"
        );
        assert_eq!(
            check("mtllib a.mtl\nv 0 0 0\nv 1 0 0\nf 1 2\n", Normals::Skip)
                .unwrap()
                .short_faces,
            vec![4]
        );
        let p = parse("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2\nf 1 2 3\n", Normals::Skip)
            .unwrap()
            .unwrap();
        assert_eq!((p.triangles.len(), p.short_faces), (1, vec![4]));
    }

    #[test]
    fn normals_are_read_checked_and_indexed_per_corner() {
        let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nvn 0 0 1\nvn 0 0.6 0.8\n\
                    f 1//1 2//2 3//1 4//2\nf 1 2 3\nf 1/1/-1 2/1/1 3/1/2\n";
        let p = parse(text, Normals::Read).unwrap().unwrap();
        assert_eq!(p.normals, vec![[0.0, 0.0, 1.0], [0.0, 0.6, 0.8]]);
        assert_eq!(
            p.normal_ix,
            vec![[0, 1, 0], [0, 0, 1], [NO_NORMAL; 3], [1, 0, 1]]
        );
        assert!(
            parse(text, Normals::Skip)
                .unwrap()
                .unwrap()
                .normals
                .is_empty()
        );
        let e = parse("v 0 0 0\nvn 0 0 0\n", Normals::Read)
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("line 2: a normal (`vn`) has zero length"),
            "{e}"
        );
        let e = parse("v 0 0 0\nvn 0 nan 1\n", Normals::Read)
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("line 2: a normal (`vn`) needs three finite"),
            "{e}"
        );
        let e = parse(
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//1 3//2\n",
            Normals::Read,
        )
        .unwrap_err()
        .to_string();
        assert!(
            e.starts_with("line 5: face normal index 2 is out of range (1 normals"),
            "{e}"
        );
        // A flat mesh's normals are not looked at: today's files keep loading.
        assert!(parse("v 0 0 0\nvn 0 0 0\n", Normals::Skip).is_ok());
    }

    #[test]
    fn errors_are_typed_with_their_line_and_print_as_before() {
        let e = parse("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 -4\n", Normals::Skip).unwrap_err();
        assert_eq!(
            e,
            ObjError::VertexIndex {
                line: 4,
                index: -4,
                defined: 3
            }
        );
        assert_eq!(e.line(), 4);
        assert_eq!(
            e.to_string(),
            "line 4: face vertex index -4 is out of range (3 vertices defined before it)"
        );
        // The twin: one index less is in range, and the file is read.
        assert!(parse("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 -3\n", Normals::Skip).is_ok());
        let e = parse("v 0 0 0\nf 1 2 x/1\n", Normals::Skip).unwrap_err();
        assert_eq!(e.to_string(), "line 2: face vertex \"x/1\" is not an index");
        assert_eq!(e.clone().after(10).line(), 12);
        let nul = junk(b"v 0 0 0\nv 1\0 0 0\n", true).unwrap();
        assert_eq!(nul, ObjError::Nul { line: 2 });
        assert_eq!(
            nul.to_string(),
            "line 2: a NUL byte: this is not a text file"
        );
        assert_eq!(
            junk(b"v 0 0 0\nv 1 0 0\n", true),
            None,
            "the twin: text is no junk"
        );
        let long = "#".repeat(MAX_LINE_BYTES + 1);
        let e = junk(format!("v 0 0 0\n{long}").as_bytes(), true).unwrap();
        assert_eq!(
            e.to_string(),
            "line 2: a line longer than 1 MiB: this is not an OBJ or MTL text"
        );
        assert_eq!(
            junk(&long.as_bytes()[1..], true),
            None,
            "one byte less is a line"
        );
    }

    #[test]
    fn line_numbers_hold_across_chunks() {
        // Enough lines for every chunk; the bad face is near the end.
        let mut s = String::new();
        for k in 0..20_000 {
            s += &format!("v {k} 0 0\nv {k} 1 0\nv {k} 0 1\nf -3 -2 -1\n");
        }
        s += "f 1 2 999999\n";
        let e = parse(&s, Normals::Skip).unwrap_err().to_string();
        assert!(e.starts_with("line 80001: "), "{e}");
        let ok = &s[..s.len() - "f 1 2 999999\n".len()];
        same_as_tobj(ok);
    }
}
