//! Images: linear f32 RGB plus the hit distance per pixel, 8-bit output, and PNG files
//! written so that an interrupted render never leaves half an image.

use std::path::Path;

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
    #[error("{0}: unknown image extension: use .png")]
    Extension(std::path::PathBuf),
    /// The file system refused.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: std::path::PathBuf,
        /// The OS error.
        source: std::io::Error,
    },
    /// PNG encoding failed.
    #[error("{path}: {source}")]
    Encode {
        /// The file.
        path: std::path::PathBuf,
        /// The encoder's error.
        source: image::ImageError,
    },
}

/// One channel to 8 bits: clamp to [0, 1] (NaN is 0), scale by 255, round half up.
pub fn to_u8(x: f32) -> u8 {
    let c = if x > 0.0 {
        if x < 1.0 { x } else { 1.0 }
    } else {
        0.0
    };
    (c * 255.0 + 0.5) as u8
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

    /// The 8-bit RGB bytes, as written to the PNG.
    pub fn to_rgb8(&self) -> Vec<u8> {
        self.pixels
            .iter()
            .flat_map(|p| [to_u8(p[0]), to_u8(p[1]), to_u8(p[2])])
            .collect()
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
        check_extension(path)?;
        write_atomically(path, |tmp| {
            image::save_buffer_with_format(
                tmp,
                &self.to_rgb8(),
                self.width,
                self.height,
                image::ExtendedColorType::Rgb8,
                image::ImageFormat::Png,
            )
            .map_err(|source| ImageError::Encode {
                path: path.to_owned(),
                source,
            })
        })
    }
}

/// Fails unless `path` ends in `.png` (checked before rendering starts).
pub fn check_extension(path: &Path) -> Result<(), ImageError> {
    match path.extension().and_then(|e| e.to_str()) {
        Some(e) if e.eq_ignore_ascii_case("png") => Ok(()),
        _ => Err(ImageError::Extension(path.to_owned())),
    }
}

/// Runs `write` on a temporary path in `path`'s folder and renames the result to `path`;
/// on failure the temporary file is removed and `path` is untouched.
pub fn write_atomically(
    path: &Path,
    write: impl FnOnce(&Path) -> Result<(), ImageError>,
) -> Result<(), ImageError> {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let tmp = path.with_file_name(format!(".{name}.{}.tmp.png", std::process::id()));
    let result = write(&tmp).and_then(|()| {
        std::fs::rename(&tmp, path).map_err(|source| ImageError::Io {
            path: path.to_owned(),
            source,
        })
    });
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}
