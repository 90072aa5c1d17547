//! The packet twin of `aov.rs`: the AOVs of a block's pixels, their centre rays traced
//! sixteen at a time (`camera_rays`, `closest_hit_packet`: the mirror's rays and hits, bit
//! for bit), each hit then described by the mirror's own `aov_of`.

use super::common::{Build, LANES};
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
    found: &PacketHits,
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

/// `trace_packet`'s colours and `aov_packet_body`'s records of the block at (i, j) from
/// one traversal: without antialiasing the colour's camera rays are the AOVs' centre rays,
/// so their hits are traced once. The colours are `trace_packet`'s in every bit. The
/// scene must take the packet shading (no antialiasing, textures or light kinds).
#[inline(always)]
pub(super) fn colour_aov_packet_body<B: Build>(
    b: B,
    g: &Globals<f32>,
    i: u32,
    j: u32,
) -> ([[f32; 4]; LANES], [AovOut; LANES]) {
    let half = 1.0f32 / (1.0 + 1.0);
    let (colours, rays, found, active) = sample_packet_hits::<B>(b, g, i, j, half, half);
    (colours, records(g, &rays, &found, active))
}
