//! Image textures as a scene holds them: a PNG or JPEG (8 or 16 bits a channel, grey or
//! colour, alpha ignored) decoded with `image`, its sRGB values made linear once, here, in
//! f64 and rounded to f32, and its rows stored bottom first, so that the lookup's v runs
//! up as OBJ's does. Both tracers read these texels; neither converts anything.
//!
//! Memory is bounded: a scene's textures hold at most [`TEXEL_BUDGET`] texels (96 MiB as
//! the GPU's buffer holds them). A texture too large for that is downscaled by halving
//! (each texel the mean of a 2×2 block, in linear light), the largest first, until the
//! scene's fit, with a warning naming the file and both sizes.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use super::ReadError;

/// The most texels a scene's textures may hold together: 2^23, 96 MiB of linear RGB f32,
/// inside the 128 MiB that every WebGPU and Vulkan device lets one storage binding hold.
pub const TEXEL_BUDGET: usize = 1 << 23;

/// The largest image side decoded (a file claiming more is refused before decoding).
pub const MAX_SIDE: u32 = 1 << 15;

/// A decoded texture.
#[derive(Clone, Debug, PartialEq)]
pub struct Texture {
    /// The file it was read from.
    pub path: PathBuf,
    /// Texels a row.
    pub width: u32,
    /// Rows.
    pub height: u32,
    /// Linear RGB, three f32 a texel, rows from the bottom (v = 0) up.
    pub texels: Vec<f32>,
    /// The file's own size, before any downscale to the budget.
    pub decoded: (u32, u32),
}

/// What is wrong with a texture file.
#[derive(Debug, thiserror::Error)]
pub enum TextureError {
    /// The file could not be read.
    #[error("{0}")]
    Read(ReadError),
    /// The file is not an image `image` can decode (or is larger than it may decode).
    #[error("cannot decode: {0}")]
    Decode(String),
    /// The image's samples are not 8- or 16-bit integers.
    #[error("{0} images are not supported as textures: give an 8- or 16-bit PNG or JPEG")]
    Format(String),
}

/// The linear value of an sRGB-encoded one in [0, 1] (IEC 61966-2-1), in f64.
pub fn srgb_to_linear(c: f64) -> f64 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// `srgb_to_linear` of every code of a `bits`-bit channel, rounded to f32.
fn linear_table(bits: u32) -> Vec<f32> {
    let max = ((1u32 << bits) - 1) as f64;
    (0..1u32 << bits)
        .map(|k| srgb_to_linear(k as f64 / max) as f32)
        .collect()
}

/// The texture in `bytes` (read from `path`), converted to linear light.
pub fn decode(path: &Path, bytes: &[u8]) -> Result<Texture, TextureError> {
    let mut reader = image::ImageReader::new(std::io::Cursor::new(bytes))
        .with_guessed_format()
        .map_err(|e| TextureError::Decode(e.to_string()))?;
    let mut limits = image::Limits::default();
    limits.max_image_width = Some(MAX_SIDE);
    limits.max_image_height = Some(MAX_SIDE);
    reader.limits(limits);
    let img = reader
        .decode()
        .map_err(|e| TextureError::Decode(e.to_string()))?;
    use image::ColorType as C;
    let (width, height) = (img.width(), img.height());
    let s = shrink_for(width, height);
    let (w, h, texels) = match img.color() {
        C::L8 | C::La8 | C::Rgb8 | C::Rgba8 => {
            let table = linear_table(8);
            let rgb = img.into_rgb8().into_raw();
            linear_rows(&rgb, width, height, s, |c| table[c as usize])
        }
        C::L16 | C::La16 | C::Rgb16 | C::Rgba16 => {
            let table = linear_table(16);
            let rgb = img.into_rgb16().into_raw();
            linear_rows(&rgb, width, height, s, |c| table[c as usize])
        }
        other => return Err(TextureError::Format(format!("{other:?}"))),
    };
    Ok(Texture {
        path: path.to_owned(),
        width: w,
        height: h,
        texels,
        decoded: (width, height),
    })
}

/// Interleaved RGB samples of a `width`×`height` image stored top row first, made linear
/// by `linear`, rows reversed (bottom first), and shrunk by `s` (a power of two): each
/// texel the mean, in f64, of the `s`×`s` block it covers (clamped at the edges), so that
/// a texture over the budget never exists at full size in f32. With `s` = 1 each texel is
/// `linear` of its sample exactly.
fn linear_rows<T: Copy>(
    samples: &[T],
    width: u32,
    height: u32,
    s: u32,
    linear: impl Fn(T) -> f32,
) -> (u32, u32, Vec<f32>) {
    let (w, h) = ((width / s).max(1), (height / s).max(1));
    let mut out = Vec::with_capacity(3 * w as usize * h as usize);
    let mut sum = vec![0.0f64; 3 * w as usize];
    for y in 0..h {
        sum.iter_mut().for_each(|v| *v = 0.0);
        for dy in 0..s {
            let row_up = (y * s + dy).min(height - 1);
            let src = (height - 1 - row_up) as usize * 3 * width as usize;
            for x in 0..w {
                for dx in 0..s {
                    let col = (x * s + dx).min(width - 1) as usize;
                    for c in 0..3 {
                        sum[3 * x as usize + c] += linear(samples[src + 3 * col + c]) as f64;
                    }
                }
            }
        }
        let n = (s * s) as f64;
        out.extend(sum.iter().map(|&v| (v / n) as f32));
    }
    (w, h, out)
}

/// The power of two that a `width`×`height` texture is shrunk by to fit [`TEXEL_BUDGET`]
/// alone (1 when it fits).
fn shrink_for(width: u32, height: u32) -> u32 {
    let mut s = 1;
    while ((width / s).max(1) as usize) * ((height / s).max(1) as usize) > TEXEL_BUDGET {
        s *= 2;
    }
    s
}

/// `t` at half its size (each side halved, rounding down, at least 1): each texel the
/// mean of the 2×2 block it covers (clamped at an odd edge), in f64, rounded once.
pub fn halve(t: &Texture) -> Texture {
    let (w, h) = ((t.width / 2).max(1), (t.height / 2).max(1));
    let at = |x: u32, y: u32, c: usize| {
        let (x, y) = (x.min(t.width - 1), y.min(t.height - 1));
        t.texels[3 * (y as usize * t.width as usize + x as usize) + c] as f64
    };
    let mut texels = Vec::with_capacity(3 * w as usize * h as usize);
    for y in 0..h {
        for x in 0..w {
            for c in 0..3 {
                let sum = at(2 * x, 2 * y, c)
                    + at(2 * x + 1, 2 * y, c)
                    + at(2 * x, 2 * y + 1, c)
                    + at(2 * x + 1, 2 * y + 1, c);
                texels.push((sum / 4.0) as f32);
            }
        }
    }
    Texture {
        path: t.path.clone(),
        width: w,
        height: h,
        texels,
        decoded: t.decoded,
    }
}

/// A scene's textures as they are read: each file decoded once, however many materials
/// name it.
#[derive(Debug, Default)]
pub struct TextureSet {
    /// The textures, in the order first named.
    pub textures: Vec<Texture>,
    by_path: HashMap<PathBuf, u32>,
}

impl TextureSet {
    /// The index of the texture at `path`, read with `read` and decoded on first use.
    /// Decoding is timed into `stages` as "texture decode".
    pub fn add(
        &mut self,
        path: &Path,
        read: &super::ReadFile<'_>,
        stages: &crate::stages::Stages,
    ) -> Result<u32, TextureError> {
        if let Some(&k) = self.by_path.get(path) {
            return Ok(k);
        }
        let bytes = read(path).map_err(TextureError::Read)?;
        self.add_bytes(path, &bytes, stages)
    }

    /// The index of the texture encoded in `bytes`, known as `path` (a file, or an image
    /// inside a glTF: `file#imageK`), decoded on first use.
    /// Decoding is timed into `stages` as "texture decode".
    pub fn add_bytes(
        &mut self,
        path: &Path,
        bytes: &[u8],
        stages: &crate::stages::Stages,
    ) -> Result<u32, TextureError> {
        if let Some(&k) = self.by_path.get(path) {
            return Ok(k);
        }
        let t = stages.time("texture decode", || decode(path, bytes))?;
        let k = self.textures.len() as u32;
        self.textures.push(t);
        self.by_path.insert(path.to_owned(), k);
        Ok(k)
    }

    /// The textures, each too large for [`TEXEL_BUDGET`] halved (the largest first) until
    /// all fit; a warning for each one halved.
    pub fn into_fitted(mut self) -> (Vec<Texture>, Vec<String>) {
        let total = |ts: &[Texture]| {
            ts.iter()
                .map(|t| t.width as usize * t.height as usize)
                .sum::<usize>()
        };
        while total(&self.textures) > TEXEL_BUDGET {
            let Some(k) = (0..self.textures.len())
                .filter(|&k| self.textures[k].width * self.textures[k].height > 1)
                .max_by_key(|&k| {
                    self.textures[k].width as usize * self.textures[k].height as usize
                })
            else {
                break;
            };
            self.textures[k] = halve(&self.textures[k]);
        }
        let warnings = self
            .textures
            .iter()
            .filter(|t| (t.width, t.height) != t.decoded)
            .map(|t| {
                let (w, h) = t.decoded;
                format!(
                    "{}: {w}×{h} texels downscaled to {}×{} to fit the scene's texture budget of {} texels",
                    t.path.display(),
                    t.width,
                    t.height,
                    TEXEL_BUDGET
                )
            })
            .collect();
        (self.textures, warnings)
    }
}
