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
//! helpers), `prims.rs` (the lane triangle test and one primitive against the packet),
//! `trace.rs` (camera rays, box test, searches), `shade.rs` (shading), `instance.rs` (the
//! two-level searches of scenes with instances) and `whitted.rs`, each the twin of the
//! mirror's file of the same stem; this file picks the build (`trace_packet`).

mod aov;
mod common;
mod instance;
mod prims;
mod shade;
mod trace;
mod whitted;

pub use aov::AovLanes;
pub use common::{LANES, Mask, PACKET_H, PACKET_W};
pub use trace::NO_SLOT;

use crate::cpu::common::Globals;
#[cfg(target_arch = "x86_64")]
use common::{Avx2, Avx512};
use common::{Portable, Two};
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
    tracer(simd, g.spec.instances)(g, i, j)
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

/// The colours and AOVs of a block's pixels from one traversal: one build of
/// [`colour_aov_tracer`].
pub type ColourAovFn = fn(&Globals<f32>, u32, u32) -> ([[f32; 4]; LANES], AovLanes);

/// A packet tracer: [`trace_packet`] of one build.
pub type PacketFn = fn(&Globals<f32>, u32, u32) -> [[f32; 4]; LANES];

/// The builds of one packet function `$body(build, g, i, j)`: `$pick::<TWO>(simd)` chooses
/// one for the CPU; `$avx2` and `$avx512` are the body compiled for those instruction
/// sets, `$avx2_two` and `$avx512_two` the same for scenes with instances (the two-level
/// search, `common::Two`). Each is a function of its own, so that the one-level builds are
/// compiled as they would be without the two levels.
macro_rules! builds {
    ($pick:ident, $avx2:ident, $avx2_two:ident, $avx512:ident, $avx512_two:ident,
     $body:path, $out:ty, $fnty:ty) => {
        fn $pick<const TWO: bool>(simd: Simd) -> $fnty {
            #[cfg(not(target_arch = "x86_64"))]
            let _ = simd;
            #[cfg(target_arch = "x86_64")]
            match simd.name() {
                // SAFETY: the token's detection said the CPU has AVX-512 F, VL, BW and DQ.
                "avx512" if Avx512::detect().is_some() => {
                    if TWO {
                        return |g, i, j| unsafe { $avx512_two(g, i, j) };
                    }
                    return |g, i, j| unsafe { $avx512(g, i, j) };
                }
                // SAFETY: the token's detection said the CPU has AVX2.
                "avx2" if Avx2::detect().is_some() => {
                    if TWO {
                        return |g, i, j| unsafe { $avx2_two(g, i, j) };
                    }
                    return |g, i, j| unsafe { $avx2(g, i, j) };
                }
                _ => {}
            }
            if TWO {
                return |g, i, j| $body(Two(Portable), g, i, j);
            }
            |g, i, j| $body(Portable, g, i, j)
        }

        /// The body compiled for AVX2: a lane loop is two eight-wide vectors.
        #[cfg(target_arch = "x86_64")]
        #[target_feature(enable = "avx2")]
        unsafe fn $avx2(g: &Globals<f32>, i: u32, j: u32) -> $out {
            // SAFETY: this function is compiled for AVX2 and runs only where the CPU has it.
            $body(unsafe { Avx2::new_unchecked() }, g, i, j)
        }

        /// The AVX2 body for scenes with instances.
        #[cfg(target_arch = "x86_64")]
        #[target_feature(enable = "avx2")]
        unsafe fn $avx2_two(g: &Globals<f32>, i: u32, j: u32) -> $out {
            // SAFETY: as for the one-level build.
            $body(Two(unsafe { Avx2::new_unchecked() }), g, i, j)
        }

        /// The body compiled for AVX-512: a lane loop is one sixteen-wide vector, and lane
        /// masks are mask registers.
        #[cfg(target_arch = "x86_64")]
        #[target_feature(enable = "avx2,avx512f,avx512vl,avx512bw,avx512dq")]
        unsafe fn $avx512(g: &Globals<f32>, i: u32, j: u32) -> $out {
            // SAFETY: this function is compiled for AVX-512 F and runs only where the CPU
            // has it.
            $body(unsafe { Avx512::new_unchecked() }, g, i, j)
        }

        /// The AVX-512 body for scenes with instances.
        #[cfg(target_arch = "x86_64")]
        #[target_feature(enable = "avx2,avx512f,avx512vl,avx512bw,avx512dq")]
        unsafe fn $avx512_two(g: &Globals<f32>, i: u32, j: u32) -> $out {
            // SAFETY: as for the one-level build.
            $body(Two(unsafe { Avx512::new_unchecked() }), g, i, j)
        }
    };
}

builds!(
    pick_tracer,
    trace_packet_avx2,
    trace_packet_avx2_two,
    trace_packet_avx512,
    trace_packet_avx512_two,
    trace_packet_body,
    [[f32; 4]; LANES],
    PacketFn
);
builds!(
    pick_aov,
    aov_packet_avx2,
    aov_packet_avx2_two,
    aov_packet_avx512,
    aov_packet_avx512_two,
    aov::aov_packet_body,
    [crate::buffers::AovOut; LANES],
    AovFn
);
builds!(
    pick_colour_aov,
    colour_aov_avx2,
    colour_aov_avx2_two,
    colour_aov_avx512,
    colour_aov_avx512_two,
    aov::colour_aov_packet_body,
    ([[f32; 4]; LANES], AovLanes),
    ColourAovFn
);

/// [`trace_packet`]'s build `simd`, chosen once (the CPU's features are asked here, not at
/// every packet), for a scene with instances (the two-level search) or without.
pub fn tracer(simd: Simd, instances: bool) -> PacketFn {
    if instances {
        pick_tracer::<true>(simd)
    } else {
        pick_tracer::<false>(simd)
    }
}

/// The AOV packet tracer's build `simd`, chosen once: the centre rays traced as
/// [`trace_packet`]'s, each hit described by the mirror's `aov_of` (the same records as
/// the mirror's `aov_pixel`, bit for bit), for a scene with instances or without.
pub fn aov_tracer(simd: Simd, instances: bool) -> AovFn {
    if instances {
        pick_aov::<true>(simd)
    } else {
        pick_aov::<false>(simd)
    }
}

/// [`trace_packet`] and [`aov_tracer`]'s packet at once, the hits of the camera rays
/// traced once (build `simd`), for a scene with instances or without. For scenes that
/// [`trace_packet`] shades itself: without antialiasing, textures or directional and spot
/// lights.
pub fn colour_aov_tracer(simd: Simd, instances: bool) -> ColourAovFn {
    if instances {
        pick_colour_aov::<true>(simd)
    } else {
        pick_colour_aov::<false>(simd)
    }
}
