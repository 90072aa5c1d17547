//! An OBJ's positions and faces as a binary little-endian PLY, every coordinate parsed to
//! f32 as glint's OBJ reader parses it, so that the two files give the same triangles:
//! `cargo run --release --example obj_to_ply -- scenes/meshes/dragon_full.obj.gz dragon.ply`
//! (`scenes/fetch-meshes.sh` makes the dragon's PLY this way).

use std::io::{BufWriter, Read, Write};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [src, dst] = args.as_slice() else {
        return Err("usage: obj_to_ply IN.obj[.gz] OUT.ply".into());
    };
    let raw = std::fs::read(src)?;
    let text = if src.ends_with(".gz") {
        let mut s = String::new();
        flate2::read::GzDecoder::new(&raw[..]).read_to_string(&mut s)?;
        s
    } else {
        String::from_utf8(raw)?
    };
    let mut vertices: Vec<[f32; 3]> = Vec::new();
    let mut faces: Vec<Vec<i32>> = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let mut w = line.split_whitespace();
        match w.next() {
            Some("v") => {
                let mut p = [0.0f32; 3];
                for c in &mut p {
                    *c = w
                        .next()
                        .ok_or(format!("line {}: short v", n + 1))?
                        .parse()?;
                }
                vertices.push(p);
            }
            Some("f") => {
                let mut f = Vec::new();
                for c in w {
                    let i: i64 = c.split('/').next().unwrap_or("").parse()?;
                    let k = if i < 0 {
                        vertices.len() as i64 + i
                    } else {
                        i - 1
                    };
                    f.push(i32::try_from(k)?);
                }
                if f.len() >= 3 {
                    faces.push(f);
                }
            }
            _ => {}
        }
    }
    let mut out = BufWriter::new(std::fs::File::create(dst)?);
    write!(
        out,
        "ply\nformat binary_little_endian 1.0\ncomment from {src} by glint's obj_to_ply\nelement vertex {}\nproperty float x\nproperty float y\nproperty float z\nelement face {}\nproperty list uchar int vertex_indices\nend_header\n",
        vertices.len(),
        faces.len()
    )?;
    for p in &vertices {
        for c in p {
            out.write_all(&c.to_le_bytes())?;
        }
    }
    for f in &faces {
        out.write_all(&[u8::try_from(f.len())?])?;
        for k in f {
            out.write_all(&k.to_le_bytes())?;
        }
    }
    out.flush()?;
    println!("{dst}: {} vertices, {} faces", vertices.len(), faces.len());
    Ok(())
}
