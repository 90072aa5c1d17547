//! The CPU's fast path for camera rays: eight rays (a 4×2 block of pixels) are traced
//! together. Through the BVH each node is fetched once for the eight and its two child
//! boxes are tested against all eight at once; without it (small scenes) each primitive
//! is tested against the eight at once. The lane loops below are written for LLVM to
//! vectorise, and `trace_packet` is compiled a second time for AVX2.
//!
//! This is not a mirror of a WGSL function: it is the mirror's faster twin, and it gives
//! the same image bit for bit. Lane by lane it does the mirror's operations in the
//! mirror's order: `camera_ray`, `make_shear`, `box_interval`, the watertight test and
//! `shade` are written again as lane loops, op for op; everything else (the other
//! triangle tests, spheres, `pow`) calls the mirror's own functions one lane at a time.
//! Shadow rays go eight at a time as well, each lane from its own origin. Only the order
//! in which BVH leaves are reached differs, and `closest_hit_bvh`'s result does not
//! depend on that order: it is the hit with the smallest t and, of equal t, the lowest
//! primitive id (what `closest_hit_all` keeps), because every box test is conservative
//! for any bound past the nearest hit. `occluded_bvh`'s answer does not depend on it
//! either: each lane reaches exactly the leaves its own traversal would.
//! `tests/packets.rs` checks the two images against each other, bit for bit.
//!
//! The packet code is split as the mirror is: `common.rs` (the packet, its rays and lane
//! helpers), `prims.rs` (the lane triangle test and one primitive against the packet) and
//! `trace.rs` (camera rays, box test, searches, shading), each the twin of the mirror's
//! file of the same stem; this file picks the build (`trace_packet`).

mod common;
mod prims;
mod trace;

pub use common::{LANES, Mask, PACKET_H, PACKET_W};
pub use trace::{NO_SLOT, PacketHits, camera_rays, closest_hit_packet};

use crate::cpu::common::Globals;
use trace::trace_packet_body;

/// Which build of the packet tracer runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Simd {
    /// The widest the CPU has (AVX2 on x86-64 when present).
    Best,
    /// The build for the target's baseline instruction set (SSE2 on x86-64), which a CPU
    /// without AVX2 runs: tests check it too.
    Baseline,
}

/// `trace_pixel` for the `PACKET_W` × `PACKET_H` block whose top-left pixel is (i, j),
/// lane `dy * PACKET_W + dx` for pixel (i + dx, j + dy); pixels outside the image are
/// left out.
/// `simd` picks the build: [`Simd::Best`] is AVX2 where the CPU has it.
pub fn trace_packet(g: &Globals<f32>, i: u32, j: u32, simd: Simd) -> [[f32; 4]; LANES] {
    #[cfg(not(target_arch = "x86_64"))]
    let _ = simd;
    #[cfg(target_arch = "x86_64")]
    if simd == Simd::Best && std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU has AVX2, checked just above.
        return unsafe { trace_packet_avx2(g, i, j) };
    }
    trace_packet_body(g, i, j)
}

/// `trace_packet` compiled for AVX2: the lane loops become eight-wide. Floating-point
/// results do not change with the instruction set (Rust never contracts `a * b + c`).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn trace_packet_avx2(g: &Globals<f32>, i: u32, j: u32) -> [[f32; 4]; LANES] {
    trace_packet_body(g, i, j)
}
