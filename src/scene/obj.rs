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
}

/// A chunk's result: its vertices, and each triangle's raw indices with the number of
/// vertices the chunk had defined before it and its line within the chunk.
#[derive(Default)]
struct Chunk {
    vertices: Vec<[f32; 3]>,
    faces: Vec<([i64; 3], u32, u32)>,
    short_faces: Vec<u32>,
    lines: u32,
}

/// Parses `text`: `Ok(None)` when it needs tobj (materials or statements this reader does
/// not know), `Err` with the line for a malformed position or face.
pub fn parse(text: &str) -> Result<Option<Parsed>, String> {
    parse_with(text, true)
}

/// Checks an OBJ that tobj will read (one with materials or other statements): the same
/// errors, with their lines, as [`parse`] gives, for positions and faces; statements this
/// reader does not know are skipped. Returns the lines of faces with fewer than three
/// vertices, which tobj drops in silence.
pub fn check(text: &str) -> Result<Vec<usize>, String> {
    Ok(parse_with(text, false)?.map_or_else(Vec::new, |p| p.short_faces))
}

/// [`parse`]; with `strict` false, unknown statements are skipped instead of handing the
/// file to tobj.
fn parse_with(text: &str, strict: bool) -> Result<Option<Parsed>, String> {
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
    let chunks: Vec<Result<Option<Chunk>, (u32, String)>> = cuts
        .par_windows(2)
        .map(|w| parse_chunk(&text[w[0]..w[1]], strict))
        .collect();
    // Line and vertex offsets of each chunk; the first error in file order wins.
    let mut done = Vec::with_capacity(chunks.len());
    let (mut line0, mut v0) = (0u32, 0usize);
    for c in chunks {
        match c {
            Ok(Some(c)) => {
                let offsets = (line0, v0);
                line0 += c.lines;
                v0 += c.vertices.len();
                done.push((c, offsets));
            }
            Ok(None) => return Ok(None),
            Err((line, e)) => return Err(format!("line {}: {e}", line0 + line)),
        }
    }
    let vertices: Vec<[f32; 3]> = done
        .iter()
        .flat_map(|(c, _)| c.vertices.iter().copied())
        .collect();
    let resolve = |(ix, before, line): &([i64; 3], u32, u32), (l0, v0): (u32, usize)| {
        let defined = v0 as i64 + *before as i64;
        let mut out = [0u32; 3];
        for (slot, &i) in out.iter_mut().zip(ix) {
            let k = if i > 0 { i - 1 } else { defined + i };
            if i == 0 || k < 0 || k >= defined {
                return Err(format!(
                    "line {}: face vertex index {i} is out of range ({defined} vertices defined before it)",
                    l0 + line
                ));
            }
            *slot = k as u32;
        }
        Ok(out)
    };
    let triangles = done
        .par_iter()
        .map(|(c, off)| {
            c.faces
                .iter()
                .map(|f| resolve(f, *off))
                .collect::<Result<Vec<_>, String>>()
        })
        .collect::<Result<Vec<Vec<_>>, String>>()?
        .concat();
    let short_faces = done
        .iter()
        .flat_map(|(c, (l0, _))| c.short_faces.iter().map(move |l| (l0 + l) as usize))
        .collect();
    Ok(Some(Parsed {
        vertices,
        triangles,
        short_faces,
    }))
}

/// One chunk of whole lines. Lines are counted from 1 within the chunk.
fn parse_chunk(text: &str, strict: bool) -> Result<Option<Chunk>, (u32, String)> {
    let mut c = Chunk::default();
    let mut face: Vec<i64> = Vec::with_capacity(8);
    for line in text.split('\n') {
        c.lines += 1;
        let mut words = line.split_ascii_whitespace();
        let Some(kw) = words.next() else { continue };
        match kw {
            "v" => {
                let mut p = [0.0f32; 3];
                for slot in p.iter_mut() {
                    match words.next().map(str::parse::<f32>) {
                        Some(Ok(x)) => *slot = x,
                        _ => {
                            return Err((
                                c.lines,
                                format!("a vertex (`v`) needs three numbers: {:?}", trunc(line)),
                            ));
                        }
                    }
                }
                c.vertices.push(p);
            }
            "f" => {
                face.clear();
                for w in words {
                    let first = w.split('/').next().unwrap_or("");
                    let ix: i64 = first
                        .parse()
                        .map_err(|_| (c.lines, format!("face vertex {w:?} is not an index")))?;
                    face.push(ix);
                }
                if face.len() < 3 {
                    c.short_faces.push(c.lines);
                    continue;
                }
                let before = c.vertices.len() as u32;
                for k in 2..face.len() {
                    c.faces
                        .push(([face[0], face[k - 1], face[k]], before, c.lines));
                }
            }
            "vn" | "vt" | "o" | "g" | "s" => {}
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
        let p = parse(text).unwrap().expect("the fast path takes it");
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
        assert!(parse("mtllib a.mtl\nv 0 0 0\n").unwrap().is_none());
        assert!(parse("v 0 0 0\nusemtl x\n").unwrap().is_none());
        let e = parse("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n").unwrap_err();
        assert!(
            e.starts_with("line 4: face vertex index 4 is out of range"),
            "{e}"
        );
        let e = parse("v 0 0 0\nv 1 nope 0\n").unwrap_err();
        assert!(e.starts_with("line 2: a vertex"), "{e}");
        // What tobj reads is checked the same way, its other statements skipped.
        let e = check("mtllib a.mtl\nv 0 0 0\nv 1 0 0\nusemtl x\nv 0 1 0\nf 1 2 5\n").unwrap_err();
        assert!(
            e.starts_with("line 6: face vertex index 5 is out of range"),
            "{e}"
        );
        assert_eq!(
            check("mtllib a.mtl\nv 0 0 0\nv 1 0 0\nf 1 2\n").unwrap(),
            vec![4]
        );
        let p = parse("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2\nf 1 2 3\n")
            .unwrap()
            .unwrap();
        assert_eq!((p.triangles.len(), p.short_faces), (1, vec![4]));
    }

    #[test]
    fn line_numbers_hold_across_chunks() {
        // Enough lines for every chunk; the bad face is near the end.
        let mut s = String::new();
        for k in 0..20_000 {
            s += &format!("v {k} 0 0\nv {k} 1 0\nv {k} 0 1\nf -3 -2 -1\n");
        }
        s += "f 1 2 999999\n";
        let e = parse(&s).unwrap_err();
        assert!(e.starts_with("line 80001: "), "{e}");
        let ok = &s[..s.len() - "f 1 2 999999\n".len()];
        same_as_tobj(ok);
    }
}
