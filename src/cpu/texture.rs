//! The CPU mirror of `shaders/texture.wgsl`: image textures, filtered by the bilinear
//! lookup written out (pbrt-v4's `Image::Bilerp`) from the same linear f32 texels the
//! shader reads, so both tracers agree bit for bit (see the WGSL header for why not the
//! GPU's sampler, and why spheres stay untextured).

// `!(x > 0)` is not `x <= 0` for NaN; the shader writes it so, on purpose, and so does its mirror.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use super::common::{Globals, Hit, flush3};
use super::count::Count;
use super::prims::is_triangle;
use crate::buffers::{Material, NO_TEXTURE, NO_UVS, TRIANGLE_BIT, Texture};
use crate::shared::real::{Real, V3};

/// WGSL `Albedo`: the reflectances a hit is shaded with.
#[derive(Clone, Copy, Debug)]
pub struct Albedo<R> {
    /// Ambient reflectance, textured where the material says.
    pub ka: V3<R>,
    /// Diffuse reflectance, textured where the material says.
    pub kd: V3<R>,
}

/// WGSL `wrap01`: `u` wrapped into [0, 1] (repeat); 0 for NaN and ±inf.
#[inline]
pub fn wrap01<R: Real>(u: R) -> R {
    let f = u - u.floor();
    if f >= R::ZERO && f <= R::ONE {
        f
    } else {
        R::ZERO
    }
}

/// WGSL `texel`: texel (x, y) of `tex` (row y from the bottom), wrapped into the image.
#[inline]
pub fn texel<R: Real, C: Count>(g: &Globals<R, C>, tex: &Texture, x: i32, y: i32) -> V3<R> {
    let w = tex.width as i32;
    let h = tex.height as i32;
    let xw = if x < 0 {
        x + w
    } else if x >= w {
        x - w
    } else {
        x
    };
    let yw = if y < 0 {
        y + h
    } else if y >= h {
        y - h
    } else {
        y
    };
    let k = (tex.offset + 3 * (yw as u32 * tex.width + xw as u32)) as usize;
    let t = &g.buf.texels;
    V3::new(
        R::from_f32(f32::from_bits(t[k])),
        R::from_f32(f32::from_bits(t[k + 1])),
        R::from_f32(f32::from_bits(t[k + 2])),
    )
}

/// WGSL `texture_place`: texture `id`'s place, the four words at 4 × `id` in `texels`.
#[inline]
pub fn texture_place<R: Real, C: Count>(g: &Globals<R, C>, id: u32) -> Texture {
    let k = 4 * id as usize;
    let t = &g.buf.texels;
    Texture {
        offset: t[k],
        width: t[k + 1],
        height: t[k + 2],
        _pad0: 0,
    }
}

/// WGSL `texture_colour`: texture `id` at `uv` (v up), bilinear between the four texel
/// centres around it, wrapping around the edges.
pub fn texture_colour<R: Real, C: Count>(g: &Globals<R, C>, id: u32, uv: [R; 2]) -> V3<R> {
    let tex = &texture_place(g, id);
    let half = R::ONE / (R::ONE + R::ONE);
    let x = wrap01(uv[0]) * R::from_u32(tex.width) - half;
    let y = wrap01(uv[1]) * R::from_u32(tex.height) - half;
    let xf = x.floor();
    let yf = y.floor();
    let dx = x - xf;
    let dy = y - yf;
    let xi = xf.to_i32();
    let yi = yf.to_i32();
    let c00 = texel(g, tex, xi, yi) * ((R::ONE - dx) * (R::ONE - dy));
    let c10 = texel(g, tex, xi + 1, yi) * (dx * (R::ONE - dy));
    let c01 = texel(g, tex, xi, yi + 1) * ((R::ONE - dx) * dy);
    let c11 = texel(g, tex, xi + 1, yi + 1) * (dx * dy);
    c00 + c10 + c01 + c11
}

/// WGSL `albedo`: kd times the colour of the hit triangle's `map_kd` at its (u, v), ka
/// times its `map_ka`'s (each product flushed as `shade`'s terms are); `m`'s own for
/// spheres and untextured triangles.
pub fn albedo<R: Real, C: Count>(g: &Globals<R, C>, hit: &Hit<R>, m: &Material) -> Albedo<R> {
    let mut out = Albedo {
        ka: V3::from_f32(m.ka),
        kd: V3::from_f32(m.kd),
    };
    if !g.spec.textures || !is_triangle(g, hit.prim) {
        return out;
    }
    let tri = &g.buf.triangles[(hit.prim & !TRIANGLE_BIT) as usize];
    if tri.uvs == NO_UVS {
        return out;
    }
    let r = &g.buf.uvs[tri.uvs as usize];
    let w = R::ONE - hit.u - hit.v;
    let c = |k: usize| {
        R::from_f32(r.uv_a[k]) * w + R::from_f32(r.uv_b[k]) * hit.u + R::from_f32(r.uv_c[k]) * hit.v
    };
    let uv = [c(0), c(1)];
    let mut kd_colour = V3::new(R::ONE, R::ONE, R::ONE);
    if r.map_kd != NO_TEXTURE {
        kd_colour = texture_colour(g, r.map_kd, uv);
        out.kd = flush3(V3::from_f32(m.kd) * kd_colour);
    }
    if r.map_ka != NO_TEXTURE {
        if r.map_ka == r.map_kd {
            out.ka = flush3(V3::from_f32(m.ka) * kd_colour);
        } else {
            out.ka = flush3(V3::from_f32(m.ka) * texture_colour(g, r.map_ka, uv));
        }
    }
    out
}
