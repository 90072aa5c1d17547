//! An OpenEXR file written row by row: uncompressed scanlines, whose block offsets are known
//! before any pixel is, so the header, the offset table and then each row go to the file as
//! they come and a frame never has to be whole in memory (a 16384×16384 frame is 4 GiB of
//! f32 pixels).
//!
//! The layout (OpenEXR's "Reading and Writing Image Files" and file-layout documents):
//! magic `76 2f 31 01`, version 2 with no flags (single-part scanline), the header's
//! attributes (`name\0type\0size value`, ended by a zero byte), one u64 offset per
//! scanline block, then each block: `y: i32`, `size: i32`, and the row of each channel in
//! the header's (alphabetical) order, A, B, G, R, as little-endian f32. A is the hit
//! distance t (−1 for a miss), as in every EXR glint writes.

use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

use super::{Format, ImageError, format_of, set_pending, temp_path, write_target};

/// The channels in the order the file stores them, and the index of each in a
/// `[r, g, b, t]` pixel.
const CHANNELS: [(&str, usize); 4] = [("A", 3), ("B", 2), ("G", 1), ("R", 0)];

/// An EXR written row by row through a temporary file beside the output (removed on
/// failure, on drop and on SIGINT/SIGTERM), renamed over the output by
/// [`ExrStream::finish`]. Pixels are stored exactly (32-bit float, no compression).
pub struct ExrStream {
    path: PathBuf,
    target: PathBuf,
    tmp: PathBuf,
    writer: Option<BufWriter<std::fs::File>>,
    width: u32,
    height: u32,
    next_row: u32,
    row: Vec<u8>,
}

/// One attribute of the header.
fn attribute(out: &mut Vec<u8>, name: &str, kind: &str, value: &[u8]) {
    out.extend_from_slice(name.as_bytes());
    out.push(0);
    out.extend_from_slice(kind.as_bytes());
    out.push(0);
    out.extend_from_slice(&(value.len() as i32).to_le_bytes());
    out.extend_from_slice(value);
}

/// The magic number, version, header and offset table of a `width`×`height` file.
fn preamble(width: u32, height: u32) -> Vec<u8> {
    let mut out = vec![0x76, 0x2f, 0x31, 0x01, 2, 0, 0, 0];
    let mut chlist = Vec::new();
    for (name, _) in CHANNELS {
        chlist.extend_from_slice(name.as_bytes());
        chlist.push(0);
        chlist.extend_from_slice(&2i32.to_le_bytes()); // FLOAT
        chlist.extend_from_slice(&[0, 0, 0, 0]); // pLinear, reserved
        chlist.extend_from_slice(&1i32.to_le_bytes()); // xSampling
        chlist.extend_from_slice(&1i32.to_le_bytes()); // ySampling
    }
    chlist.push(0);
    let window: Vec<u8> = [0, 0, width as i32 - 1, height as i32 - 1]
        .iter()
        .flat_map(|v| v.to_le_bytes())
        .collect();
    attribute(&mut out, "channels", "chlist", &chlist);
    attribute(&mut out, "compression", "compression", &[0]); // NO_COMPRESSION
    attribute(&mut out, "dataWindow", "box2i", &window);
    attribute(&mut out, "displayWindow", "box2i", &window);
    attribute(&mut out, "lineOrder", "lineOrder", &[0]); // INCREASING_Y
    attribute(&mut out, "pixelAspectRatio", "float", &1f32.to_le_bytes());
    attribute(&mut out, "screenWindowCenter", "v2f", &[0; 8]);
    attribute(&mut out, "screenWindowWidth", "float", &1f32.to_le_bytes());
    out.push(0);
    let block = 8 + row_bytes(width);
    let first = out.len() as u64 + 8 * height as u64;
    for y in 0..height as u64 {
        out.extend_from_slice(&(first + y * block).to_le_bytes());
    }
    out
}

/// The pixel bytes of one row: four channels of `width` f32.
fn row_bytes(width: u32) -> u64 {
    16 * width as u64
}

impl ExrStream {
    /// Starts `path` (a `.exr`) for a `width`×`height` image. A row is at most 2^31 bytes
    /// (the block's size is an i32), far above glint's largest side.
    pub fn create(path: &Path, width: u32, height: u32) -> Result<ExrStream, ImageError> {
        if format_of(path)? != Format::Exr {
            return Err(ImageError::Extension(path.to_owned()));
        }
        let target = write_target(path);
        let tmp = temp_path(&target, "tmp");
        set_pending(Some(tmp.clone()));
        let mut stream = ExrStream {
            path: path.to_owned(),
            target,
            tmp,
            writer: None,
            width,
            height,
            next_row: 0,
            row: Vec::with_capacity(8 + row_bytes(width) as usize),
        };
        let file = std::fs::File::create(&stream.tmp).map_err(|e| stream.io(e))?;
        let mut w = BufWriter::with_capacity(1 << 20, file);
        w.write_all(&preamble(width, height))
            .map_err(|e| stream.io(e))?;
        stream.writer = Some(w);
        Ok(stream)
    }

    fn io(&self, error: std::io::Error) -> ImageError {
        ImageError::Io {
            path: self.path.clone(),
            error,
        }
    }

    /// Appends whole rows (`[r, g, b, t]` pixels, as [`super::Image::pixels`]), top to
    /// bottom.
    pub fn write_rows(&mut self, pixels: &[[f32; 4]]) -> Result<(), ImageError> {
        let w = self.width.max(1) as usize;
        for line in pixels.chunks(w) {
            if self.next_row >= self.height || line.len() != w {
                return Err(self.io(std::io::Error::other("more pixels than the image holds")));
            }
            self.row.clear();
            self.row
                .extend_from_slice(&(self.next_row as i32).to_le_bytes());
            self.row
                .extend_from_slice(&(row_bytes(self.width) as i32).to_le_bytes());
            for (_, c) in CHANNELS {
                for p in line {
                    self.row.extend_from_slice(&p[c].to_le_bytes());
                }
            }
            let writer = self.writer.as_mut().expect("not finished");
            if let Err(e) = writer.write_all(&self.row) {
                return Err(self.io(e));
            }
            self.next_row += 1;
        }
        Ok(())
    }

    /// Ends the file (every row must have been written) and renames it over the output.
    pub fn finish(mut self) -> Result<(), ImageError> {
        if self.next_row != self.height {
            let left = self.height - self.next_row;
            return Err(self.io(std::io::Error::other(format!(
                "{left} rows were never written"
            ))));
        }
        let w = self.writer.take().expect("not finished");
        let done = w
            .into_inner()
            .map_err(|e| e.into_error())
            .and_then(|f| f.sync_data().map(|_| f))
            .and_then(|_| std::fs::rename(&self.tmp, &self.target));
        if let Err(e) = done {
            let _ = std::fs::remove_file(&self.tmp);
            return Err(self.io(e));
        }
        set_pending(None);
        Ok(())
    }
}

impl Drop for ExrStream {
    fn drop(&mut self) {
        if self.writer.is_some() {
            self.writer = None;
            let _ = std::fs::remove_file(&self.tmp);
            set_pending(None);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::ExrStream;
    use crate::image::Image;

    fn frame(w: u32, h: u32) -> Image {
        let pixels = (0..w * h)
            .map(|k| {
                let x = k as f32;
                [
                    x * 0.1,
                    f32::MIN_POSITIVE / 3.0,
                    -x,
                    if k % 3 == 0 { -1.0 } else { x },
                ]
            })
            .collect();
        Image {
            width: w,
            height: h,
            pixels,
        }
    }

    /// A file streamed in uneven bands reads back (through the `exr` crate) equal in every
    /// bit, subnormals and −1 included; the twin: a file missing its last row is refused
    /// at `finish` and leaves no file behind.
    #[test]
    fn streamed_exr_reads_back_bit_for_bit() {
        let dir = std::env::temp_dir().join(format!("glint-exr-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("a.exr");
        let img = frame(7, 5);
        let mut s = ExrStream::create(&path, 7, 5).unwrap();
        s.write_rows(&img.pixels[..14]).unwrap();
        s.write_rows(&img.pixels[14..]).unwrap();
        s.finish().unwrap();
        let back = Image::load(&path).unwrap();
        assert_eq!((back.width, back.height), (7, 5));
        let bits =
            |i: &Image| -> Vec<u32> { i.pixels.iter().flatten().map(|v| v.to_bits()).collect() };
        assert_eq!(bits(&back), bits(&img));

        let short = dir.join("b.exr");
        let mut s = ExrStream::create(&short, 7, 5).unwrap();
        s.write_rows(&img.pixels[..28]).unwrap();
        let e = s.finish().unwrap_err();
        assert!(e.to_string().contains("1 rows were never written"), "{e}");
        assert!(!short.exists());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
