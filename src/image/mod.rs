//! Images: linear f32 RGB plus the hit distance per pixel, 8-bit output, and PNG files
//! written so that an interrupted render never leaves half an image.

mod exr;

pub use crate::shared::encoding::{Encoding, SRGB_THRESHOLDS, UnknownEncoding, to_u8_srgb};
pub use exr::{ChannelData, ExrStream, write_channels};

use std::path::{Path, PathBuf};

/// A rendered frame: per pixel `[r, g, b, t]`, colours linear in [0, 1], `t` the hit
/// distance of the primary ray or −1 for a miss. Row-major, top row first.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// `width * height` pixels.
    pub pixels: Vec<[f32; 4]>,
}

/// Why an image could not be written.
#[derive(Debug, thiserror::Error)]
pub enum ImageError {
    /// The extension is not one glint writes.
    #[error("{0}: unknown image extension: use .png or .exr")]
    Extension(std::path::PathBuf),
    /// A file could not be decoded, or is not what glint reads.
    #[error("{path}: {message}")]
    Decode {
        /// The file.
        path: std::path::PathBuf,
        /// What is wrong.
        message: String,
    },
    /// The file system refused.
    #[error("{path}: {error}")]
    Io {
        /// The file.
        path: std::path::PathBuf,
        /// The OS error.
        error: std::io::Error,
    },
    /// PNG encoding failed.
    #[error("{path}: {error}")]
    Encode {
        /// The file.
        path: std::path::PathBuf,
        /// The encoder's error.
        error: image::ImageError,
    },
}

/// One channel to 8 bits (the shader's `to_u8`, glint's one quantisation).
pub use crate::shared::real::to_u8;

/// The 8-bit RGB bytes of `[r, g, b, t]` pixels (`to_u8` of each channel), in parallel.
fn rgb8(pixels: &[[f32; 4]]) -> Vec<u8> {
    rgb_bytes(pixels, |p| [to_u8(p[0]), to_u8(p[1]), to_u8(p[2])])
}

/// The 8-bit RGB bytes of `[r, g, b, t]` pixels encoded as `encoding` says.
fn encoded(pixels: &[[f32; 4]], encoding: Encoding) -> Vec<u8> {
    match encoding {
        Encoding::Linear => rgb8(pixels),
        Encoding::Srgb => rgb_bytes(pixels, |p| {
            [to_u8_srgb(p[0]), to_u8_srgb(p[1]), to_u8_srgb(p[2])]
        }),
    }
}

/// Three bytes a pixel, `rgb` of each, written in parallel chunks into one buffer.
fn rgb_bytes<P: Sync>(pixels: &[P], rgb: impl Fn(&P) -> [u8; 3] + Sync) -> Vec<u8> {
    use rayon::prelude::*;
    const CHUNK: usize = 4096;
    let mut bytes = vec![0u8; pixels.len() * 3];
    bytes
        .par_chunks_mut(3 * CHUNK)
        .zip(pixels.par_chunks(CHUNK))
        .for_each(|(out, px)| {
            for (o, p) in out.chunks_exact_mut(3).zip(px) {
                o.copy_from_slice(&rgb(p));
            }
        });
    bytes
}

impl Image {
    /// A `width`×`height` image filled with `fill`.
    pub fn new(width: u32, height: u32, fill: [f32; 4]) -> Self {
        Image {
            width,
            height,
            pixels: vec![fill; width as usize * height as usize],
        }
    }

    /// Makes this a `width`×`height` image to be drawn over: the pixel buffer is kept when
    /// it already holds that many pixels (their values are left as they were, for the
    /// caller to overwrite), else replaced by a zeroed one.
    pub fn reshape(&mut self, width: u32, height: u32) {
        let n = width as usize * height as usize;
        if self.pixels.len() != n {
            self.pixels = vec![[0.0; 4]; n];
        }
        self.width = width;
        self.height = height;
    }

    /// The 8-bit RGB bytes, as written to a linear PNG.
    pub fn to_rgb8(&self) -> Vec<u8> {
        rgb8(&self.pixels)
    }

    /// The 8-bit RGB bytes, as written to a PNG encoded as `encoding` says.
    pub fn to_rgb8_encoded(&self, encoding: Encoding) -> Vec<u8> {
        encoded(&self.pixels, encoding)
    }

    /// Whether some pixel's colour differs from another's (a blank image has one colour).
    pub fn is_blank(&self) -> bool {
        let rgb = self.to_rgb8();
        rgb.chunks_exact(3).all(|c| c == &rgb[..3])
    }

    /// How many pixels the primary ray hit.
    pub fn hit_count(&self) -> usize {
        self.pixels.iter().filter(|p| p[3] >= 0.0).count()
    }

    /// Writes a PNG: to a temporary file beside `path`, then renamed over it.
    pub fn save_png(&self, path: &Path) -> Result<(), ImageError> {
        self.save_png_encoded(path, Encoding::Linear)
    }

    /// [`Image::save_png`] with the bytes encoded as `encoding` says.
    pub fn save_png_encoded(&self, path: &Path, encoding: Encoding) -> Result<(), ImageError> {
        let mut s = PngStream::create_encoded(path, self.width, self.height, encoding)?;
        s.write_rows(&self.pixels)?;
        s.finish()
    }
}

/// The PNG compression glint writes with: png's `Fast` (fdeflate, tuned for PNG). On the
/// seed scenes it encodes several times faster than the `image` crate's default
/// (`Balanced`) for files a little larger; a render's PNG is a result to look at, and time
/// to image is what the user waits for.
pub const PNG_COMPRESSION: png::Compression = png::Compression::Fast;

/// A PNG written band by band, so a frame never has to be whole in memory: rows go to a
/// temporary file beside the output (removed on failure, on drop and on SIGINT/SIGTERM,
/// see [`remove_pending_temp`]), renamed over the output by [`PngStream::finish`].
pub struct PngStream {
    path: PathBuf,
    target: PathBuf,
    tmp: PathBuf,
    writer: Option<png::StreamWriter<'static, std::io::BufWriter<std::fs::File>>>,
    rows_left: u32,
    width: u32,
    encoding: Encoding,
}

impl PngStream {
    /// Starts `path` (a `.png`) for a `width`×`height` RGB image.
    pub fn create(path: &Path, width: u32, height: u32) -> Result<PngStream, ImageError> {
        PngStream::create_encoded(path, width, height, Encoding::Linear)
    }

    /// [`PngStream::create`] for bytes encoded as `encoding` says (an sRGB PNG carries the
    /// `sRGB` chunk).
    pub fn create_encoded(
        path: &Path,
        width: u32,
        height: u32,
        encoding: Encoding,
    ) -> Result<PngStream, ImageError> {
        if format_of(path)? != Format::Png {
            return Err(ImageError::Extension(path.to_owned()));
        }
        let target = write_target(path);
        let tmp = temp_path(&target, "tmp");
        let io = |error| ImageError::Io {
            path: path.to_owned(),
            error,
        };
        let enc = |e: png::EncodingError| ImageError::Encode {
            path: path.to_owned(),
            error: image::ImageError::IoError(std::io::Error::other(e)),
        };
        set_pending(Some(tmp.clone()));
        let file = std::fs::File::create(&tmp).map_err(io)?;
        let mut e = png::Encoder::new(std::io::BufWriter::new(file), width, height);
        e.set_color(png::ColorType::Rgb);
        e.set_depth(png::BitDepth::Eight);
        e.set_compression(PNG_COMPRESSION);
        if encoding == Encoding::Srgb {
            e.set_source_srgb(png::SrgbRenderingIntent::Perceptual);
        }
        let writer = e
            .write_header()
            .and_then(|w| w.into_stream_writer())
            .map_err(enc)?;
        Ok(PngStream {
            path: path.to_owned(),
            target,
            tmp,
            writer: Some(writer),
            rows_left: height,
            width,
            encoding,
        })
    }

    /// Appends whole rows (`[r, g, b, t]` pixels, as [`Image::pixels`]), top to bottom.
    pub fn write_rows(&mut self, pixels: &[[f32; 4]]) -> Result<(), ImageError> {
        let bytes = encoded(pixels, self.encoding);
        self.write_bytes(&bytes, pixels.len())
    }

    /// How the bytes encode the linear image.
    pub fn encoding(&self) -> Encoding {
        self.encoding
    }

    /// Appends the RGB `bytes` of `pixels` pixels (whole rows).
    fn write_bytes(&mut self, bytes: &[u8], pixels: usize) -> Result<(), ImageError> {
        use std::io::Write;
        let rows = (pixels / self.width.max(1) as usize) as u32;
        let w = self.writer.as_mut().expect("not finished");
        w.write_all(bytes).map_err(|error| ImageError::Io {
            path: self.path.clone(),
            error,
        })?;
        self.rows_left = self.rows_left.saturating_sub(rows);
        Ok(())
    }

    /// Appends whole rows of packed pixels (`pack_rgba8`: red in the lowest byte), top to
    /// bottom: the lean frame's readback, written as it came.
    /// Only for a linear PNG: packed bytes are linear already.
    pub fn write_rgba8_rows(&mut self, pixels: &[u32]) -> Result<(), ImageError> {
        assert_eq!(
            self.encoding,
            Encoding::Linear,
            "packed rows are linear bytes: an sRGB PNG takes f32 rows"
        );
        let bytes = rgb_bytes(pixels, |p| {
            let [r, g, b, _] = p.to_le_bytes();
            [r, g, b]
        });
        self.write_bytes(&bytes, pixels.len())
    }

    /// Ends the PNG (every row must have been written) and renames it over the output.
    pub fn finish(mut self) -> Result<(), ImageError> {
        let path = self.path.clone();
        let enc = |e: png::EncodingError| ImageError::Encode {
            path: path.clone(),
            error: image::ImageError::IoError(std::io::Error::other(e)),
        };
        if self.rows_left != 0 {
            return Err(ImageError::Io {
                path: path.clone(),
                error: std::io::Error::other(format!("{} rows were never written", self.rows_left)),
            });
        }
        let w = self.writer.take().expect("not finished");
        w.finish().map_err(enc)?;
        std::fs::rename(&self.tmp, &self.target).map_err(|error| ImageError::Io {
            path: path.clone(),
            error,
        })?;
        set_pending(None);
        Ok(())
    }
}

impl Drop for PngStream {
    fn drop(&mut self) {
        if self.writer.is_some() {
            self.writer = None;
            let _ = std::fs::remove_file(&self.tmp);
            set_pending(None);
        }
    }
}

/// The file formats glint writes and reads.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    /// 8-bit RGB PNG (what is looked at).
    Png,
    /// OpenEXR, 32-bit float RGBA with the hit distance t in A (−1 for a miss): the f32
    /// image exactly, for checking a render made elsewhere bit for bit.
    Exr,
}

/// The format `path`'s extension names, or an error (checked before rendering starts).
pub fn format_of(path: &Path) -> Result<Format, ImageError> {
    match path.extension().and_then(|e| e.to_str()) {
        Some(e) if e.eq_ignore_ascii_case("png") => Ok(Format::Png),
        Some(e) if e.eq_ignore_ascii_case("exr") => Ok(Format::Exr),
        _ => Err(ImageError::Extension(path.to_owned())),
    }
}

/// Fails unless `path` ends in `.png` or `.exr` (checked before rendering starts).
pub fn check_extension(path: &Path) -> Result<(), ImageError> {
    format_of(path).map(|_| ())
}

impl Image {
    /// Writes the f32 image to an OpenEXR file exactly (RGBA 32-bit float, A = t), through
    /// a temporary file renamed over `path`.
    pub fn save_exr(&self, path: &Path) -> Result<(), ImageError> {
        let flat: Vec<f32> = self.pixels.iter().flatten().copied().collect();
        write_atomically(path, |tmp| {
            image::save_buffer_with_format(
                tmp,
                bytemuck::cast_slice(&flat),
                self.width,
                self.height,
                image::ExtendedColorType::Rgba32F,
                image::ImageFormat::OpenExr,
            )
            .map_err(|error| ImageError::Encode {
                path: path.to_owned(),
                error,
            })
        })
    }

    /// Writes PNG or EXR as the extension says.
    pub fn save(&self, path: &Path) -> Result<(), ImageError> {
        match format_of(path)? {
            Format::Png => self.save_png(path),
            Format::Exr => self.save_exr(path),
        }
    }

    /// Reads an image glint wrote: an EXR exactly (t from A), a PNG as 8-bit colours
    /// divided by 255 with t = 0 for every pixel (a PNG has no hit distances). At most the
    /// default input limit is read ([`crate::scene::LoadOptions`]).
    pub fn load(path: &Path) -> Result<Image, ImageError> {
        Image::load_limited(path, crate::scene::LoadOptions::default().max_input_bytes)
    }

    /// [`Image::load`] reading at most `limit` bytes.
    pub fn load_limited(path: &Path, limit: u64) -> Result<Image, ImageError> {
        let format = format_of(path)?;
        let bytes = crate::scene::read_limited(path, limit).map_err(|e| ImageError::Decode {
            path: path.to_owned(),
            message: e.to_string(),
        })?;
        let decode = |message: String| ImageError::Decode {
            path: path.to_owned(),
            message,
        };
        let img = image::load_from_memory_with_format(
            &bytes,
            match format {
                Format::Png => image::ImageFormat::Png,
                Format::Exr => image::ImageFormat::OpenExr,
            },
        )
        .map_err(|e| decode(e.to_string()))?;
        let (width, height) = (img.width(), img.height());
        let pixels = match format {
            Format::Exr => img.into_rgba32f().pixels().map(|p| p.0).collect(),
            Format::Png => img
                .into_rgb8()
                .pixels()
                .map(|p| {
                    [
                        p.0[0] as f32 / 255.0,
                        p.0[1] as f32 / 255.0,
                        p.0[2] as f32 / 255.0,
                        0.0,
                    ]
                })
                .collect(),
        };
        Ok(Image {
            width,
            height,
            pixels,
        })
    }
}

/// The temporary file being written now, if any: removed by [`remove_pending_temp`] (the
/// command line calls it on SIGINT and SIGTERM).
static PENDING_TEMP: std::sync::Mutex<Option<PathBuf>> = std::sync::Mutex::new(None);

/// Records `tmp` as the temporary file being written now (`None`: none is).
pub(crate) fn set_pending(tmp: Option<PathBuf>) {
    if let Ok(mut g) = PENDING_TEMP.lock() {
        *g = tmp;
    }
}

/// Removes the temporary file that [`write_atomically`] is writing, if any. Safe to call
/// from a signal-handling thread; the finished output file is never touched.
pub fn remove_pending_temp() {
    if let Ok(mut g) = PENDING_TEMP.lock()
        && let Some(p) = g.take()
    {
        let _ = std::fs::remove_file(p);
    }
}

/// Where writing to `path` really writes: the final target of a chain of symbolic links
/// (glint writes through a link and leaves the link in place), else `path` itself.
pub fn write_target(path: &Path) -> PathBuf {
    let mut p = path.to_owned();
    for _ in 0..40 {
        match std::fs::read_link(&p) {
            Ok(t) => p = p.parent().unwrap_or(Path::new(".")).join(t),
            Err(_) => break,
        }
    }
    p
}

/// The temporary name beside `target`: `.NAME.PID.KIND`, with NAME shortened so the whole
/// stays within the 255-byte file name limit of common file systems.
pub(crate) fn temp_path(target: &Path, kind: &str) -> PathBuf {
    let name = target
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let suffix = format!(".{}.{kind}", std::process::id());
    let mut keep = name.len().min(255 - 1 - suffix.len());
    while !name.is_char_boundary(keep) {
        keep -= 1;
    }
    target.with_file_name(format!(".{}{suffix}", &name[..keep]))
}

/// Checks, before any work, that `path` can be written: its folder exists and a file can
/// be created there (the temporary file is created and removed at once).
pub fn check_writable(path: &Path) -> Result<(), ImageError> {
    check_extension(path)?;
    let target = write_target(path);
    if target.is_dir() {
        return Err(ImageError::Io {
            path: path.to_owned(),
            error: std::io::Error::other("is a folder"),
        });
    }
    let probe = temp_path(&target, "probe");
    std::fs::File::create(&probe).map_err(|error| ImageError::Io {
        path: path.to_owned(),
        error,
    })?;
    let _ = std::fs::remove_file(&probe);
    Ok(())
}

/// Runs `write` on a temporary path in `path`'s folder and renames the result to `path`;
/// on failure the temporary file is removed and `path` is untouched. When `path` is a
/// symbolic link, the file it points to is replaced and the link kept.
pub fn write_atomically(
    path: &Path,
    write: impl FnOnce(&Path) -> Result<(), ImageError>,
) -> Result<(), ImageError> {
    let target = write_target(path);
    let tmp = temp_path(&target, "tmp");
    set_pending(Some(tmp.clone()));
    let result = write(&tmp).and_then(|()| {
        std::fs::rename(&tmp, &target).map_err(|error| ImageError::Io {
            path: path.to_owned(),
            error,
        })
    });
    set_pending(None);
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}
