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
    /// The bytes of one row's pixels: 4 a channel a pixel.
    row_size: u64,
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

/// OpenEXR's pixel type of a 32-bit unsigned integer channel.
const UINT: i32 = 0;
/// OpenEXR's pixel type of a 32-bit float channel.
const FLOAT: i32 = 2;

/// The magic number, version, header and offset table of a `width`×`height` file whose
/// channels are `channels` (name and pixel type, in the file's order: sorted by name),
/// every one 4 bytes a pixel.
fn preamble(width: u32, height: u32, channels: &[(&str, i32)]) -> Vec<u8> {
    let mut out = vec![0x76, 0x2f, 0x31, 0x01, 2, 0, 0, 0];
    let mut chlist = Vec::new();
    for &(name, kind) in channels {
        chlist.extend_from_slice(name.as_bytes());
        chlist.push(0);
        chlist.extend_from_slice(&kind.to_le_bytes());
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
    let block = 8 + 4 * width as u64 * channels.len() as u64;
    let first = out.len() as u64 + 8 * height as u64;
    for y in 0..height as u64 {
        out.extend_from_slice(&(first + y * block).to_le_bytes());
    }
    out
}

impl ExrStream {
    /// Starts `path` (a `.exr`) for a `width`×`height` image of `[r, g, b, t]` pixels
    /// ([`ExrStream::write_rows`]). A row is at most 2^31 bytes (the block's size is an
    /// i32), far above glint's largest side.
    pub fn create(path: &Path, width: u32, height: u32) -> Result<ExrStream, ImageError> {
        ExrStream::create_channels(path, width, height, &CHANNELS.map(|(n, _)| (n, false)))
    }

    /// Starts `path` (a `.exr`) for a `width`×`height` image of `channels` (name, and
    /// whether it holds 32-bit unsigned integers rather than 32-bit floats), which must be
    /// sorted by name, as the file stores them; rows go in by [`ExrStream::write_row_with`].
    pub fn create_channels(
        path: &Path,
        width: u32,
        height: u32,
        channels: &[(&str, bool)],
    ) -> Result<ExrStream, ImageError> {
        if format_of(path)? != Format::Exr {
            return Err(ImageError::Extension(path.to_owned()));
        }
        debug_assert!(
            channels
                .windows(2)
                .all(|p| p[0].0.as_bytes() < p[1].0.as_bytes())
        );
        let target = write_target(path);
        let tmp = temp_path(&target, "tmp");
        set_pending(Some(tmp.clone()));
        let row_size = 4 * width as u64 * channels.len() as u64;
        let mut stream = ExrStream {
            path: path.to_owned(),
            target,
            tmp,
            writer: None,
            width,
            height,
            next_row: 0,
            row_size,
            row: Vec::with_capacity(8 + row_size as usize),
        };
        let kinds: Vec<(&str, i32)> = channels
            .iter()
            .map(|&(n, uint)| (n, if uint { UINT } else { FLOAT }))
            .collect();
        let file = std::fs::File::create(&stream.tmp).map_err(|e| stream.io(e))?;
        let mut w = BufWriter::with_capacity(1 << 20, file);
        w.write_all(&preamble(width, height, &kinds))
            .map_err(|e| stream.io(e))?;
        stream.writer = Some(w);
        Ok(stream)
    }

    /// Appends the next row: `put` appends each channel's `width` values, in the file's
    /// channel order, as little-endian bytes (4 a value).
    pub fn write_row_with(&mut self, put: impl FnOnce(&mut Vec<u8>)) -> Result<(), ImageError> {
        if self.next_row >= self.height {
            return Err(self.io(std::io::Error::other("more rows than the image holds")));
        }
        self.row.clear();
        self.row
            .extend_from_slice(&(self.next_row as i32).to_le_bytes());
        self.row
            .extend_from_slice(&(self.row_size as i32).to_le_bytes());
        put(&mut self.row);
        if self.row.len() as u64 != 8 + self.row_size {
            return Err(self.io(std::io::Error::other("a row of the wrong length")));
        }
        let writer = self.writer.as_mut().expect("not finished");
        if let Err(e) = writer.write_all(&self.row) {
            return Err(self.io(e));
        }
        self.next_row += 1;
        Ok(())
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
            self.write_row_with(|row| {
                for (_, c) in CHANNELS {
                    for p in line {
                        row.extend_from_slice(&p[c].to_le_bytes());
                    }
                }
            })?;
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

/// The values of one channel of [`write_channels`], one a pixel, row-major: owned, or
/// borrowed from a frame that holds them.
#[derive(Clone, Debug, PartialEq)]
pub enum ChannelData<'a> {
    /// 32-bit floats, stored exactly.
    F32(std::borrow::Cow<'a, [f32]>),
    /// 32-bit unsigned integers (OpenEXR's UINT), stored exactly.
    U32(std::borrow::Cow<'a, [u32]>),
}

impl ChannelData<'_> {
    fn len(&self) -> usize {
        match self {
            ChannelData::F32(v) => v.len(),
            ChannelData::U32(v) => v.len(),
        }
    }

    /// The little-endian bytes of pixels `range`.
    pub(crate) fn extend_row(&self, out: &mut Vec<u8>, range: std::ops::Range<usize>) {
        let words: &[u32] = match self {
            ChannelData::F32(v) => bytemuck::cast_slice(&v[range]),
            ChannelData::U32(v) => &v[range],
        };
        if cfg!(target_endian = "little") {
            out.extend_from_slice(bytemuck::cast_slice(words));
        } else {
            words.iter().for_each(|x| out.extend(x.to_le_bytes()));
        }
    }
}

/// Writes a `width`×`height` OpenEXR of any channels (single part, uncompressed
/// scanlines, every value exact), atomically: through a temporary file renamed over
/// `path`. The channels are stored sorted by name, as the format requires; each must hold
/// one value a pixel and the names must differ.
pub fn write_channels(
    path: &Path,
    width: u32,
    height: u32,
    channels: &[(String, ChannelData<'_>)],
) -> Result<(), ImageError> {
    if format_of(path)? != Format::Exr {
        return Err(ImageError::Extension(path.to_owned()));
    }
    let mut sorted: Vec<&(String, ChannelData<'_>)> = channels.iter().collect();
    sorted.sort_by(|a, b| a.0.as_bytes().cmp(b.0.as_bytes()));
    let pixels = width as usize * height as usize;
    let other = |m: String| ImageError::Io {
        path: path.to_owned(),
        error: std::io::Error::other(m),
    };
    for pair in sorted.windows(2) {
        if pair[0].0 == pair[1].0 {
            return Err(other(format!("two channels are named {:?}", pair[0].0)));
        }
    }
    if let Some((name, _)) = sorted.iter().find(|(_, d)| d.len() != pixels) {
        return Err(other(format!(
            "channel {name:?} does not hold one value a pixel"
        )));
    }
    let kinds: Vec<(&str, i32)> = sorted
        .iter()
        .map(|(n, d)| {
            let kind = match d {
                ChannelData::F32(_) => FLOAT,
                ChannelData::U32(_) => UINT,
            };
            (n.as_str(), kind)
        })
        .collect();
    super::write_atomically(path, |tmp| {
        let io = |error| ImageError::Io {
            path: path.to_owned(),
            error,
        };
        let file = std::fs::File::create(tmp).map_err(io)?;
        let mut w = BufWriter::with_capacity(1 << 20, file);
        w.write_all(&preamble(width, height, &kinds)).map_err(io)?;
        let w_px = width as usize;
        let size = (4 * w_px * sorted.len()) as i32;
        let mut row = Vec::with_capacity(8 + size as usize);
        for y in 0..height as usize {
            row.clear();
            row.extend_from_slice(&(y as i32).to_le_bytes());
            row.extend_from_slice(&size.to_le_bytes());
            for (_, d) in &sorted {
                d.extend_row(&mut row, y * w_px..(y + 1) * w_px);
            }
            w.write_all(&row).map_err(io)?;
        }
        let f = w.into_inner().map_err(|e| io(e.into_error()))?;
        f.sync_data().map_err(io)
    })
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
