//! `.gz` meshes: inflated whole, or inflated and parsed in pieces at once.

use super::*;

/// A binary file's bytes, inflated where its name ends in `.gz`, at most `limit` of them
/// (unlike [`gunzip`], which refuses what no OBJ text holds).
pub(super) fn inflate(path: &Path, raw: Vec<u8>, limit: u64) -> Result<Vec<u8>, MeshError> {
    if path.extension().is_none_or(|e| e != "gz") {
        return Ok(raw);
    }
    use std::io::Read;
    let mut out = Vec::new();
    flate2::read::GzDecoder::new(&raw[..])
        .take(limit + 1)
        .read_to_end(&mut out)
        .map_err(MeshError::Gunzip)?;
    if out.len() as u64 > limit {
        return Err(MeshError::Unpacked { limit });
    }
    Ok(out)
}

/// The bytes of an OBJ file as read (`raw`), gunzipped (at most `limit` bytes) when the
/// name ends in `.gz`.
pub(super) fn gunzip(path: &Path, raw: Vec<u8>, limit: u64) -> Result<Vec<u8>, MeshError> {
    if path.extension().is_some_and(|e| e == "gz") {
        use std::io::Read;
        let mut out = Vec::new();
        let mut dec = flate2::read::GzDecoder::new(&raw[..]).take(limit + 1);
        // Inflated a block at a time and watched for what no OBJ has (a NUL byte, a line
        // longer than `obj::MAX_LINE_BYTES`), so that binary junk is refused after the
        // first megabyte of it, not after the whole input limit.
        let mut line_start = 0usize;
        loop {
            let old = out.len();
            out.resize(old + GUNZIP_BLOCK, 0);
            let n = dec.read(&mut out[old..]).map_err(MeshError::Gunzip)?;
            out.truncate(old + n);
            if n == 0 {
                break;
            }
            let new = &out[old..];
            let first_nl = new.iter().position(|&b| b == b'\n');
            let long = match first_nl {
                Some(k) => old + k - line_start > crate::scene::obj::MAX_LINE_BYTES,
                None => out.len() - line_start > crate::scene::obj::MAX_LINE_BYTES,
            };
            if long || new.contains(&0) {
                let why =
                    crate::scene::obj::junk(&out, false).unwrap_or(ObjError::NotText { line: 1 });
                return Err(MeshError::Obj(why));
            }
            if first_nl.is_some() {
                line_start = old + 1 + new.iter().rposition(|&b| b == b'\n').unwrap_or(0);
            }
        }
        if out.len() as u64 > limit {
            return Err(MeshError::Unpacked { limit });
        }
        return Ok(out);
    }
    Ok(raw)
}

/// What `obj::parse` returns.
pub(super) type ObjParse = Result<Option<Parsed>, ObjError>;

/// The bytes of text `gunzip_parse` inflates before it hands them to a parse.
pub(super) const GUNZIP_PIECE: usize = 2 << 20;

/// The bytes `gunzip` inflates at a time, at most a line's length
/// (`obj::MAX_LINE_BYTES`): a line that ends inside a block is no longer than the block.
pub(super) const GUNZIP_BLOCK: usize = 1 << 20;
const _: () = assert!(GUNZIP_BLOCK <= crate::scene::obj::MAX_LINE_BYTES);

/// Gunzips `raw` and parses the OBJ with glint's reader at once: pieces of about `piece`
/// bytes of whole lines are parsed in parallel (`obj::parse_piece`) while the rest is
/// inflated, then joined in file order (`obj::join_pieces`), which gives what `obj::parse`
/// gives for the whole text. Returns the text's bytes and the parse, or `None` where this
/// does not apply and the caller reads the file the ordinary way, which then reports
/// whatever is wrong as it always has: the gzip trailer's size (ISIZE) is 0, above the
/// input limit, or not the size inflated (a multi-member or damaged file); the inflate
/// fails; a piece is not UTF-8; the text starts with a byte-order mark.
/// Stages: "gunzip" is the time spent inflating, "OBJ parse" the wait after it.
pub(super) fn gunzip_parse(
    raw: &[u8],
    normals: Normals,
    piece: usize,
    limit: u64,
    stages: &crate::stages::Stages,
) -> Option<(Vec<u8>, ObjParse)> {
    use std::io::Read;
    use std::sync::Mutex;
    let t0 = web_time::Instant::now();
    let isize_bytes: [u8; 4] = raw.get(raw.len().checked_sub(4)?..)?.try_into().ok()?;
    let size = u32::from_le_bytes(isize_bytes) as usize;
    if size == 0 || size as u64 > limit {
        return None;
    }
    let mut buf = vec![0u8; size];
    let mut inflating = std::time::Duration::ZERO;
    let mut ok = true;
    let mut junk = None;
    let pieces: Mutex<Vec<(usize, Option<crate::scene::obj::Piece>)>> = Mutex::new(Vec::new());
    rayon::scope(|s| {
        let mut dec = flate2::read::GzDecoder::new(raw);
        let mut rest: &mut [u8] = &mut buf[..];
        // Bytes at the head of `rest` inflated but not yet handed out.
        let mut filled = 0usize;
        // The pieces handed out, to number the line of a junk error.
        let mut handed: Vec<&[u8]> = Vec::new();
        for index in 0.. {
            let t = web_time::Instant::now();
            let mut want = (filled + piece).min(rest.len());
            let mut cut = None;
            // Bytes of `rest` already searched for a line end (each byte once: a long line
            // read on is not searched again from its start).
            let mut searched = 0usize;
            while cut.is_none() {
                while filled < want {
                    match dec.read(&mut rest[filled..want]) {
                        Ok(0) => break,
                        Ok(n) => filled += n,
                        Err(_) => {
                            ok = false;
                            break;
                        }
                    }
                }
                if !ok {
                    break;
                }
                if filled < want || filled == rest.len() {
                    // The end of the stream, or of the buffer: all that is left.
                    cut = Some(filled);
                } else if let Some(nl) = rest[searched..filled].iter().rposition(|&b| b == b'\n') {
                    cut = Some(searched + nl + 1);
                } else if filled > crate::scene::obj::MAX_LINE_BYTES
                    || rest[searched..filled].contains(&0)
                {
                    // No line end in more than a line's length, or a NUL: not an OBJ text.
                    let before: usize = handed
                        .iter()
                        .map(|h| crate::scene::error::line_of_bytes(h, h.len()) - 1)
                        .sum();
                    let why = crate::scene::obj::junk(&rest[..filled], false)
                        .unwrap_or(ObjError::NotText { line: 1 });
                    junk = Some(why.after(before as u32));
                    break;
                } else {
                    searched = filled;
                    want = (want + piece).min(rest.len()); // one long line: read on
                }
            }
            if junk.is_some() {
                break;
            }
            let at_end = filled < want || filled == rest.len();
            if at_end && ok {
                // The stream must end where ISIZE said.
                ok = filled == rest.len() && matches!(dec.read(&mut [0u8; 1]), Ok(0));
            }
            inflating += t.elapsed();
            let Some(cut) = cut.filter(|_| ok) else { break };
            let (head, tail) = std::mem::take(&mut rest).split_at_mut(cut);
            rest = tail;
            filled -= cut;
            let head: &[u8] = head;
            handed.push(head);
            if index == 0 && head.starts_with(b"\xEF\xBB\xBF") {
                ok = false;
                break;
            }
            let pieces = &pieces;
            s.spawn(move |_| {
                let parsed = std::str::from_utf8(head)
                    .ok()
                    .map(|text| crate::scene::obj::parse_piece(text, normals));
                if let Ok(mut p) = pieces.lock() {
                    p.push((index, parsed));
                }
            });
            if at_end {
                break;
            }
        }
    });
    stages.record("gunzip", inflating);
    if let Some(why) = junk {
        return Some((Vec::new(), Err(why)));
    }
    let mut pieces = pieces.into_inner().ok()?;
    if !ok {
        return None;
    }
    pieces.sort_by_key(|(index, _)| *index);
    let pieces: Option<Vec<crate::scene::obj::Piece>> =
        pieces.into_iter().map(|(_, p)| p).collect();
    let parsed = crate::scene::obj::join_pieces(pieces?, normals);
    stages.record("OBJ parse", t0.elapsed().saturating_sub(inflating));
    Some((buf, parsed))
}
