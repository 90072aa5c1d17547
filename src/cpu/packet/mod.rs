//! The CPU's fast path for camera rays: sixteen rays (a 4×4 block of pixels) are traced
//! together. Through the BVH each node is fetched once for the sixteen and its two child
//! boxes are tested against all sixteen at once; without it (small scenes) each primitive
//! is tested against the sixteen at once. The lane loops below are written for LLVM to
//! vectorise, and `trace_packet` is compiled twice more: for AVX2 (a lane loop is two
//! eight-wide vectors) and AVX-512 (one sixteen-wide vector).
//!
//! Sixteen lanes, not eight: `docs/bench/cpu-packets.md`.
//!
//! This is not a mirror of a WGSL function: it is the mirror's faster twin, and it gives
//! the same image bit for bit. Lane by lane it does the mirror's operations in the
//! mirror's order: `camera_ray`, `make_shear`, `box_interval`, the three triangle tests,
//! `hit_sphere` and `shade` are written again as lane loops, op for op; the rest (a
//! non-integer `pow`, smooth shading's `shading_at`) calls the mirror's own functions one
//! lane at a time. Shadow rays go sixteen at a time as well, each lane from its own origin. Only the order
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

mod aov;
mod common;
mod prims;
mod shade;
mod trace;
mod whitted;

pub use aov::AovLanes;
pub use common::{LANES, Mask, PACKET_H, PACKET_W};
pub use trace::{NO_SLOT, PacketHits};

use crate::cpu::common::Globals;
use common::Portable;
#[cfg(target_arch = "x86_64")]
use common::{Avx2, Avx512};
use trace::trace_packet_body;

/// Which build of the packet tracer runs. Every build gives the same image, bit for bit:
/// floating-point results do not change with the instruction set (Rust never contracts
/// `a * b + c`), and `tests/packets.rs` renders with each build the CPU has.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Simd {
    /// The widest the CPU has: AVX-512 (one 16-lane vector a lane loop) where present,
    /// else AVX2 (two 8-lane vectors), else the baseline.
    Best,
    /// The AVX2 build, where the CPU has AVX2 (else the baseline).
    Avx2,
    /// The build for the target's baseline instruction set (SSE2 on x86-64), which a CPU
    /// without AVX2 runs: tests check it too.
    Baseline,
}

impl Simd {
    /// Every build, widest first.
    pub const ALL: [Simd; 3] = [Simd::Best, Simd::Avx2, Simd::Baseline];

    /// The instruction set this build runs on this CPU: `"avx512"`, `"avx2"` or
    /// `"baseline"`.
    pub fn name(self) -> &'static str {
        #[cfg(target_arch = "x86_64")]
        {
            if self == Simd::Best && has_avx512() {
                return "avx512";
            }
            if self != Simd::Baseline && std::arch::is_x86_feature_detected!("avx2") {
                return "avx2";
            }
        }
        "baseline"
    }
}

/// Whether the CPU has the AVX-512 subsets the AVX-512 build is compiled for.
#[cfg(target_arch = "x86_64")]
fn has_avx512() -> bool {
    std::arch::is_x86_feature_detected!("avx512f")
        && std::arch::is_x86_feature_detected!("avx512vl")
        && std::arch::is_x86_feature_detected!("avx512bw")
        && std::arch::is_x86_feature_detected!("avx512dq")
}

/// `trace_pixel` for the `PACKET_W` × `PACKET_H` block whose top-left pixel is (i, j),
/// lane `dy * PACKET_W + dx` for pixel (i + dx, j + dy); pixels outside the image are
/// left out. `simd` picks the build.
pub fn trace_packet(g: &Globals<f32>, i: u32, j: u32, simd: Simd) -> [[f32; 4]; LANES] {
    tracer(simd)(g, i, j)
}

/// The mirror's own `trace_pixel` for each pixel of the block, in a packet's lanes: what
/// the packet tracer is for scenes with directional or spot lights or with textures, which
/// only the mirror shades (so the packet path of every other scene is compiled as it was).
pub fn trace_packet_mirror(g: &Globals<f32>, i: u32, j: u32) -> [[f32; 4]; LANES] {
    let mut out = [[0.0f32; 4]; LANES];
    for (l, px) in out.iter_mut().enumerate() {
        let (x, y) = (
            i + (l % PACKET_W as usize) as u32,
            j + (l / PACKET_W as usize) as u32,
        );
        if x < g.cam.width && y < g.cam.height {
            *px = crate::cpu::trace::trace_pixel(g, x, y);
        }
    }
    out
}

/// The AOVs of a block's pixels, as [`trace_packet`]'s lanes ([`crate::cpu::aov::aov_pixel`]
/// of each): one build of [`aov_tracer`].
pub type AovFn = fn(&Globals<f32>, u32, u32) -> [crate::buffers::AovOut; LANES];

/// The AOV packet tracer's build `simd`, chosen once: the centre rays traced as
/// [`trace_packet`]'s, each hit described by the mirror's `aov_of` (the same records as
/// the mirror's `aov_pixel`, bit for bit).
pub fn aov_tracer(simd: Simd) -> AovFn {
    #[cfg(not(target_arch = "x86_64"))]
    let _ = simd;
    #[cfg(target_arch = "x86_64")]
    match simd.name() {
        // SAFETY: the token's detection said the CPU has AVX-512 F, VL, BW and DQ.
        "avx512" if Avx512::detect().is_some() => {
            return |g, i, j| unsafe { aov_packet_avx512(g, i, j) };
        }
        // SAFETY: the token's detection said the CPU has AVX2.
        "avx2" if Avx2::detect().is_some() => {
            return |g, i, j| unsafe { aov_packet_avx2(g, i, j) };
        }
        _ => {}
    }
    |g, i, j| aov::aov_packet_body(Portable, g, i, j)
}

/// The AOV packet compiled for AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn aov_packet_avx2(g: &Globals<f32>, i: u32, j: u32) -> [crate::buffers::AovOut; LANES] {
    // SAFETY: this function is compiled for AVX2 and runs only where the CPU has it.
    aov::aov_packet_body(unsafe { Avx2::new_unchecked() }, g, i, j)
}

/// The AOV packet compiled for AVX-512.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,avx512f,avx512vl,avx512bw,avx512dq")]
unsafe fn aov_packet_avx512(g: &Globals<f32>, i: u32, j: u32) -> [crate::buffers::AovOut; LANES] {
    // SAFETY: this function is compiled for AVX-512 F and runs only where the CPU has it.
    aov::aov_packet_body(unsafe { Avx512::new_unchecked() }, g, i, j)
}

/// The colours and AOVs of a block's pixels from one traversal: one build of
/// [`colour_aov_tracer`].
pub type ColourAovFn = fn(&Globals<f32>, u32, u32) -> ([[f32; 4]; LANES], AovLanes);

/// [`trace_packet`] and [`aov_tracer`]'s packet at once, the hits of the camera rays
/// traced once (build `simd`). For scenes that [`trace_packet`] shades itself: without
/// antialiasing, textures or directional and spot lights.
pub fn colour_aov_tracer(simd: Simd) -> ColourAovFn {
    #[cfg(not(target_arch = "x86_64"))]
    let _ = simd;
    #[cfg(target_arch = "x86_64")]
    match simd.name() {
        // SAFETY: the token's detection said the CPU has AVX-512 F, VL, BW and DQ.
        "avx512" if Avx512::detect().is_some() => {
            return |g, i, j| unsafe { colour_aov_avx512(g, i, j) };
        }
        // SAFETY: the token's detection said the CPU has AVX2.
        "avx2" if Avx2::detect().is_some() => {
            return |g, i, j| unsafe { colour_aov_avx2(g, i, j) };
        }
        _ => {}
    }
    |g, i, j| aov::colour_aov_packet_body(Portable, g, i, j)
}

/// The colour and AOV packet compiled for AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn colour_aov_avx2(g: &Globals<f32>, i: u32, j: u32) -> ([[f32; 4]; LANES], AovLanes) {
    // SAFETY: this function is compiled for AVX2 and runs only where the CPU has it.
    aov::colour_aov_packet_body(unsafe { Avx2::new_unchecked() }, g, i, j)
}

/// The colour and AOV packet compiled for AVX-512.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,avx512f,avx512vl,avx512bw,avx512dq")]
unsafe fn colour_aov_avx512(g: &Globals<f32>, i: u32, j: u32) -> ([[f32; 4]; LANES], AovLanes) {
    // SAFETY: this function is compiled for AVX-512 F and runs only where the CPU has it.
    aov::colour_aov_packet_body(unsafe { Avx512::new_unchecked() }, g, i, j)
}

/// A packet tracer: [`trace_packet`] of one build.
pub type PacketFn = fn(&Globals<f32>, u32, u32) -> [[f32; 4]; LANES];

/// [`trace_packet`]'s build `simd`, chosen once (the CPU's features are asked here, not at
/// every packet).
pub fn tracer(simd: Simd) -> PacketFn {
    #[cfg(not(target_arch = "x86_64"))]
    let _ = simd;
    #[cfg(target_arch = "x86_64")]
    match simd.name() {
        // SAFETY: the token's detection said the CPU has AVX-512 F, VL, BW and DQ.
        "avx512" if Avx512::detect().is_some() => {
            return |g, i, j| unsafe { trace_packet_avx512(g, i, j) };
        }
        // SAFETY: the token's detection said the CPU has AVX2.
        "avx2" if Avx2::detect().is_some() => {
            return |g, i, j| unsafe { trace_packet_avx2(g, i, j) };
        }
        _ => {}
    }
    |g, i, j| trace_packet_body(Portable, g, i, j)
}

/// `trace_packet` compiled for AVX2: a lane loop is two eight-wide vectors.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn trace_packet_avx2(g: &Globals<f32>, i: u32, j: u32) -> [[f32; 4]; LANES] {
    // SAFETY: this function is compiled for AVX2 and runs only where the CPU has it.
    trace_packet_body(unsafe { Avx2::new_unchecked() }, g, i, j)
}

/// `trace_packet` compiled for AVX-512: a lane loop is one sixteen-wide vector, and lane
/// masks are mask registers.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,avx512f,avx512vl,avx512bw,avx512dq")]
unsafe fn trace_packet_avx512(g: &Globals<f32>, i: u32, j: u32) -> [[f32; 4]; LANES] {
    // SAFETY: this function is compiled for AVX-512 F and runs only where the CPU has it.
    trace_packet_body(unsafe { Avx512::new_unchecked() }, g, i, j)
}
