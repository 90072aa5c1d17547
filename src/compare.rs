//! Metrics between two images of the same size.

use crate::image::{Image, to_u8};

/// How two images differ.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Diff {
    /// Pixels compared.
    pub pixels: usize,
    /// Pixels whose 8-bit colour differs in some channel.
    pub differing_pixels: usize,
    /// Pixels whose f32 colour differs in some bit (stricter than the 8-bit count).
    pub differing_bits: usize,
    /// Pixels that one image hit and the other missed.
    pub hit_miss: usize,
    /// Pixels that both images hit at distances that differ in some f32 bit.
    pub differing_t: usize,
    /// Largest channel difference, linear [0, 1] units.
    pub max_abs: f64,
    /// Root mean square channel difference.
    pub rms: f64,
    /// Mean channel difference.
    pub mean_abs: f64,
    /// Largest 8-bit channel difference.
    pub max_u8: u8,
}

/// When two images count as equal (`glint compare` and `glint diff --tolerance`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Tolerance {
    /// Every f32 bit of every colour, every hit/miss and every bit of every hit's t.
    Bits,
    /// The same 8-bit colour (what a PNG holds) and the same hit/miss.
    EightBit,
    /// No channel differs by more than this (linear units), and the same hit/miss.
    Abs(f64),
}

impl std::str::FromStr for Tolerance {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "bits" => Ok(Tolerance::Bits),
            "8bit" => Ok(Tolerance::EightBit),
            _ => match s.parse::<f64>() {
                Ok(x) if x.is_finite() && x >= 0.0 => Ok(Tolerance::Abs(x)),
                _ => Err(format!(
                    "{s:?}: expected bits, 8bit or a finite number >= 0 (the largest channel difference allowed)"
                )),
            },
        }
    }
}

impl std::fmt::Display for Tolerance {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Tolerance::Bits => f.write_str("every bit (colour, hit/miss, t)"),
            Tolerance::EightBit => f.write_str("8-bit colour and hit/miss"),
            Tolerance::Abs(x) => write!(f, "channels within {x:e} and hit/miss"),
        }
    }
}

impl Diff {
    /// Whether the two images are equal by `tolerance`'s criterion.
    pub fn within(&self, tolerance: Tolerance) -> bool {
        match tolerance {
            Tolerance::Bits => self.bit_exact(),
            Tolerance::EightBit => self.differing_pixels == 0 && self.hit_miss == 0,
            Tolerance::Abs(x) => self.max_abs <= x && self.hit_miss == 0,
        }
    }

    /// Whether the two images are the same in every f32 bit of every colour, in every
    /// hit/miss and in every bit of every hit distance: what lavapipe must give.
    pub fn bit_exact(&self) -> bool {
        self.differing_bits == 0 && self.hit_miss == 0 && self.differing_t == 0
    }
}

/// Compares `a` with `b` (their sizes must match).
pub fn diff(a: &Image, b: &Image) -> Diff {
    assert_eq!(
        (a.width, a.height),
        (b.width, b.height),
        "images of different sizes"
    );
    let mut d = Diff {
        pixels: a.pixels.len(),
        ..Diff::default()
    };
    let (mut sum, mut sum2) = (0.0f64, 0.0f64);
    for (p, q) in a.pixels.iter().zip(&b.pixels) {
        let mut off8 = false;
        let mut off_bits = false;
        for c in 0..3 {
            let e = (p[c] as f64 - q[c] as f64).abs();
            let e = if e.is_nan() { 1.0 } else { e };
            sum += e;
            sum2 += e * e;
            d.max_abs = d.max_abs.max(e);
            let (x, y) = (to_u8(p[c]), to_u8(q[c]));
            d.max_u8 = d.max_u8.max(x.abs_diff(y));
            off8 |= x != y;
            off_bits |= p[c].to_bits() != q[c].to_bits();
        }
        d.differing_pixels += off8 as usize;
        d.differing_bits += off_bits as usize;
        let (hit_p, hit_q) = (p[3] >= 0.0, q[3] >= 0.0);
        d.hit_miss += (hit_p != hit_q) as usize;
        d.differing_t += (hit_p && hit_q && p[3].to_bits() != q[3].to_bits()) as usize;
    }
    let n = (3 * d.pixels).max(1) as f64;
    d.mean_abs = sum / n;
    d.rms = (sum2 / n).sqrt();
    d
}

/// A picture of where `a` and `b` differ: black where equal in 8 bits, red where only the
/// colour differs (brighter for larger differences), white where hit and miss disagree.
pub fn diff_image(a: &Image, b: &Image) -> Image {
    let pixels = a
        .pixels
        .iter()
        .zip(&b.pixels)
        .map(|(p, q)| {
            if (p[3] >= 0.0) != (q[3] >= 0.0) {
                return [1.0, 1.0, 1.0, 0.0];
            }
            let m = (0..3)
                .map(|c| to_u8(p[c]).abs_diff(to_u8(q[c])))
                .max()
                .unwrap_or(0);
            if m == 0 {
                [0.0, 0.0, 0.0, 0.0]
            } else {
                [0.25 + 0.75 * (m as f32 / 255.0).sqrt(), 0.0, 0.0, 0.0]
            }
        })
        .collect();
    Image {
        width: a.width,
        height: a.height,
        pixels,
    }
}
