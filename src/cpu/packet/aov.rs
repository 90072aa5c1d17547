//! The packet twin of `aov.rs`: the AOVs of a block's pixels, their centre rays traced
//! sixteen at a time (`camera_rays`, `closest_hit_packet`: the mirror's rays and hits, bit
//! for bit), each hit then described by the mirror's own `aov_of`; or, beside the colour,
//! by what the packet shading found of it (`colour_aov_packet_body`).

// Lane loops index several arrays in step, `for l in 0..LANES`, the form LLVM vectorises.
#![allow(clippy::needless_range_loop)]

use super::common::{Build, InstLanes, LANES};
use super::shade::HitLanes;
use super::trace::{PacketHits, camera_rays, closest_hit_packet, sample_packet_hits};
use crate::buffers::{AovOut, PRIM_NONE};
use crate::cpu::aov::{MISS, aov_of};
use crate::cpu::common::{Globals, Ray};

/// `aov_pixel` for the block whose top-left pixel is (i, j), lane `dy * PACKET_W + dx`
/// for pixel (i + dx, j + dy); lanes outside the image hold `MISS`.
#[inline(always)]
pub(super) fn aov_packet_body<B: Build>(b: B, g: &Globals<f32>, i: u32, j: u32) -> [AovOut; LANES] {
    let half = 1.0f32 / (1.0 + 1.0);
    let (rays, dir, active) = camera_rays(g, i, j, half, half);
    let found = closest_hit_packet::<B>(b, g, &rays, &dir, active, 0.0, f32::MAX);
    records(g, &rays, &found, active)
}

/// Each lane's `aov_of`, `MISS` where it missed or lies outside the image (`active`).
#[inline(always)]
fn records(
    g: &Globals<f32>,
    rays: &[Ray<f32>; LANES],
    found: &PacketHits<impl InstLanes>,
    active: super::common::Mask,
) -> [AovOut; LANES] {
    let mut out = [MISS; LANES];
    for l in 0..LANES {
        if active & (1 << l) != 0 && found.prim[l] != PRIM_NONE {
            out[l] = aov_of(g, rays[l], &found.hit(l));
        }
    }
    out
}

/// A packet's AOV records as lane arrays (lane `dy * PACKET_W + dx` for pixel
/// (i + dx, j + dy)): lane l's fields are `AovOut`'s, [`AovLanes::record`] puts them
/// together.
#[derive(Clone, Copy)]
pub struct AovLanes {
    /// `AovOut::t` of each lane.
    pub t: [f32; LANES],
    /// `AovOut::depth` of each lane.
    pub depth: [f32; LANES],
    /// `AovOut::position`, component by component.
    pub position: [[f32; LANES]; 3],
    /// `AovOut::geo_normal`, component by component.
    pub geo_normal: [[f32; LANES]; 3],
    /// `AovOut::normal`, component by component.
    pub normal: [[f32; LANES]; 3],
    /// `AovOut::albedo`, component by component.
    pub albedo: [[f32; LANES]; 3],
    /// `AovOut::prim` of each lane.
    pub prim: [u32; LANES],
    /// `AovOut::material` of each lane.
    pub material: [u32; LANES],
}

impl AovLanes {
    /// Lane l's record.
    #[inline(always)]
    pub fn record(&self, l: usize) -> AovOut {
        let v = |a: &[[f32; LANES]; 3]| [a[0][l], a[1][l], a[2][l]];
        AovOut {
            position: v(&self.position),
            t: self.t[l],
            geo_normal: v(&self.geo_normal),
            depth: self.depth[l],
            normal: v(&self.normal),
            prim: self.prim[l],
            albedo: v(&self.albedo),
            material: self.material[l],
        }
    }
}

/// `trace_packet`'s colours and `aov_packet_body`'s records of the block at (i, j) from
/// one traversal: without antialiasing the colour's camera rays are the AOVs' centre rays,
/// so their hits are traced once, and the shading's own point, normals and material
/// (`HitLanes`) are `aov_of`'s (its operations, in its order: the point, the normal
/// turned to face the ray, `shading_at`; then the depth t·(dir·forward) and kd, there
/// being no texture). The colours are `trace_packet`'s in every bit, the records
/// `aov_pixel`'s. The scene must take the packet shading (no antialiasing, textures or
/// light kinds).
#[inline(always)]
pub(super) fn colour_aov_packet_body<B: Build>(
    b: B,
    g: &Globals<f32>,
    i: u32,
    j: u32,
) -> ([[f32; 4]; LANES], AovLanes) {
    let half = 1.0f32 / (1.0 + 1.0);
    let mut facts = HitLanes {
        p: [[0.0; LANES]; 3],
        n: [[0.0; LANES]; 3],
        ns: [[0.0; LANES]; 3],
        material: [0; LANES],
    };
    let (colours, rays, found, active) =
        sample_packet_hits::<B, _>(b, g, i, j, half, half, &mut facts);
    let mut hit = [false; LANES];
    for l in 0..LANES {
        hit[l] = (active >> l) & 1 != 0 && found.prim[l] != PRIM_NONE;
    }
    let f = g.cam.forward;
    // Every lane starts as `MISS`; a lane that hit takes its own values.
    let splat = |v: [f32; 3]| [[v[0]; LANES], [v[1]; LANES], [v[2]; LANES]];
    let mut out = AovLanes {
        t: [MISS.t; LANES],
        depth: [MISS.depth; LANES],
        position: splat(MISS.position),
        geo_normal: splat(MISS.geo_normal),
        normal: splat(MISS.normal),
        albedo: splat(MISS.albedo),
        prim: [MISS.prim; LANES],
        material: [MISS.material; LANES],
    };
    for l in 0..LANES {
        let t = found.t[l];
        let d = rays[l].dir;
        let depth = t * (d.x * f.x + d.y * f.y + d.z * f.z);
        out.t[l] = if hit[l] { t } else { out.t[l] };
        out.depth[l] = if hit[l] { depth } else { out.depth[l] };
        out.prim[l] = if hit[l] { found.prim[l] } else { out.prim[l] };
        out.material[l] = if hit[l] {
            facts.material[l]
        } else {
            out.material[l]
        };
        for k in 0..3 {
            out.position[k][l] = if hit[l] {
                facts.p[k][l]
            } else {
                out.position[k][l]
            };
            out.geo_normal[k][l] = if hit[l] {
                facts.n[k][l]
            } else {
                out.geo_normal[k][l]
            };
            out.normal[k][l] = if hit[l] {
                facts.ns[k][l]
            } else {
                out.normal[k][l]
            };
        }
    }
    // kd, gathered only where a lane hit (elsewhere the material is not an index).
    for l in 0..LANES {
        if hit[l] {
            let kd = g.buf.materials[facts.material[l] as usize].kd;
            for k in 0..3 {
                out.albedo[k][l] = kd[k];
            }
        }
    }
    (colours, out)
}
