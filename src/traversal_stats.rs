//! Traversal statistics (`glint stats`): what each GPU lane does for a frame, counted on
//! the CPU mirror, which follows the shader's per-ray traversal step by step.
//!
//! Per ray kind (camera, shadow, reflected, refracted): how many rays, and per ray the
//! interior nodes visited, the leaves, the primitives tested, the deepest stack and the
//! bytes read (each node read, 32 bytes, at the root, at every step and for both children's
//! boxes at an interior node, and each primitive tested, 48 bytes a triangle and 32 a
//! sphere), as mean, p50, p99 and max. The warp spread is what a GPU warp waits for: the
//! frame is cut into the blocks of 8×4 pixels that 32 consecutive invocations of the
//! kernel trace (`pixel_of` in `shaders/trace.wgsl`), and for each block the most nodes
//! (interior and leaves) one pixel's rays of the kind visited is divided by the block's
//! mean; the figure is the mean of that ratio over the blocks where the kind was traced.
//! The counts are the ray tracer's (`--traversal ray`); the subgroup kernels traverse in
//! packets, which these figures do not describe.

use rayon::prelude::*;

use crate::buffers::{SceneBuffers, Specialisation};
use crate::cpu::count::{Counter, RayCount, RayKind};
use crate::cpu::trace::{Camera, Globals, trace_pixel};

/// A distribution over rays.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Summary {
    /// The mean.
    pub mean: f64,
    /// The median (the lower of the two middle values).
    pub p50: u64,
    /// The 99th percentile (nearest rank).
    pub p99: u64,
    /// The largest.
    pub max: u64,
}

impl Summary {
    fn of(mut v: Vec<u64>) -> Summary {
        if v.is_empty() {
            return Summary::default();
        }
        v.sort_unstable();
        let rank = |q: f64| v[((q * v.len() as f64).ceil() as usize).clamp(1, v.len()) - 1];
        Summary {
            mean: v.iter().map(|&x| x as f64).sum::<f64>() / v.len() as f64,
            p50: rank(0.5),
            p99: rank(0.99),
            max: v[v.len() - 1],
        }
    }
}

/// One ray kind's figures.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct KindStats {
    /// Rays of this kind.
    pub rays: u64,
    /// Interior nodes visited, per ray.
    pub nodes: Summary,
    /// Leaves visited, per ray.
    pub leaves: Summary,
    /// Primitives tested, per ray.
    pub prims: Summary,
    /// The deepest traversal stack, per ray.
    pub stack: Summary,
    /// Bytes of nodes and primitives read, per ray.
    pub bytes: Summary,
    /// The mean over 8×4 blocks of the block's most nodes for one pixel over its mean
    /// (1: every lane does the same work); 0 where no ray of the kind was traced.
    pub warp_spread: f64,
    /// The pixel (x, y) whose ray of this kind visited the most nodes (interior and
    /// leaves; the first such pixel in row order), where to look first.
    pub worst_pixel: Option<(u32, u32)>,
}

/// A frame's traversal statistics, by ray kind in [`RayKind::ALL`]'s order.
#[derive(Clone, Debug, PartialEq)]
pub struct TraversalStats {
    /// The frame's width.
    pub width: u32,
    /// The frame's height.
    pub height: u32,
    /// Each kind's figures.
    pub kinds: Vec<(RayKind, KindStats)>,
}

impl TraversalStats {
    /// One JSON object keyed by ray kind (`camera`, `shadow`, `reflected`, `refracted`),
    /// each holding `rays`, `nodes`, `leaves`, `prims`, `stack` and `bytes` (each with
    /// `mean`, `p50`, `p99`, `max`) and `warp_spread`.
    pub fn to_json(&self) -> String {
        let q = |s: &Summary| {
            format!(
                "{{\"mean\":{},\"p50\":{},\"p99\":{},\"max\":{}}}",
                s.mean, s.p50, s.p99, s.max
            )
        };
        let kinds: Vec<String> = self
            .kinds
            .iter()
            .map(|(k, s)| {
                format!(
                    "\"{}\":{{\"rays\":{},\"nodes\":{},\"leaves\":{},\"prims\":{},\"stack\":{},\"bytes\":{},\"warp_spread\":{},\"worst_pixel\":{}}}",
                    k.name(),
                    s.rays,
                    q(&s.nodes),
                    q(&s.leaves),
                    q(&s.prims),
                    q(&s.stack),
                    q(&s.bytes),
                    s.warp_spread,
                    s.worst_pixel
                        .map_or("null".to_string(), |(x, y)| format!("[{x},{y}]"))
                )
            })
            .collect();
        format!("{{{}}}", kinds.join(","))
    }
}

impl std::fmt::Display for TraversalStats {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        writeln!(
            f,
            "{:<10} {:>9}  {:>22}  {:>22}  {:>22}  {:>14}  {:>26}  {:>6}  worst pixel",
            "rays",
            "count",
            "nodes mean/p50/p99/max",
            "leaves",
            "prims",
            "stack p50/max",
            "bytes mean/p50/p99/max",
            "warp"
        )?;
        for (k, s) in &self.kinds {
            let q = |s: &Summary| format!("{:.1}/{}/{}/{}", s.mean, s.p50, s.p99, s.max);
            writeln!(
                f,
                "{:<10} {:>9}  {:>22}  {:>22}  {:>22}  {:>14}  {:>26}  {:>6.2}  {}",
                k.name(),
                s.rays,
                q(&s.nodes),
                q(&s.leaves),
                q(&s.prims),
                format!("{}/{}", s.stack.p50, s.stack.max),
                q(&s.bytes),
                s.warp_spread,
                s.worst_pixel
                    .map_or("-".to_string(), |(x, y)| format!("{x},{y}"))
            )?;
        }
        Ok(())
    }
}

/// The traversal statistics of the frame `buf` describes (its size, camera and samples),
/// under the specialisation `spec` (the shader's for the scene:
/// [`Specialisation::for_scene`]). Every pixel is traced by the f32 mirror with a counter
/// ([`crate::cpu::count`]); the image is not kept.
pub fn traversal_stats(buf: &SceneBuffers, spec: Specialisation) -> TraversalStats {
    let (w, h) = (buf.params.width, buf.params.height);
    // Per row: per pixel, its rays in order.
    let rows: Vec<Vec<Vec<(RayKind, RayCount)>>> = (0..h)
        .into_par_iter()
        .map(|j| {
            let g = Globals {
                cam: Camera::from_params(&buf.params),
                buf,
                spec,
                count: Counter::new(),
            };
            (0..w)
                .map(|i| {
                    trace_pixel(&g, i, j);
                    g.count.take()
                })
                .collect()
        })
        .collect();
    let kinds = RayKind::ALL
        .iter()
        .map(|&kind| (kind, kind_stats(&rows, kind, w, h)))
        .collect();
    TraversalStats {
        width: w,
        height: h,
        kinds,
    }
}

fn kind_stats(rows: &[Vec<Vec<(RayKind, RayCount)>>], kind: RayKind, w: u32, h: u32) -> KindStats {
    let rays: Vec<&RayCount> = rows
        .iter()
        .flatten()
        .flatten()
        .filter(|(k, _)| *k == kind)
        .map(|(_, c)| c)
        .collect();
    let field = |f: fn(&RayCount) -> u64| Summary::of(rays.iter().map(|c| f(c)).collect());
    // Nodes (interior and leaves) per pixel for this kind.
    let per_pixel = |i: u32, j: u32| -> u64 {
        rows[j as usize][i as usize]
            .iter()
            .filter(|(k, _)| *k == kind)
            .map(|(_, c)| (c.interior + c.leaves) as u64)
            .sum()
    };
    let traced = |i: u32, j: u32| rows[j as usize][i as usize].iter().any(|(k, _)| *k == kind);
    let mut ratios = Vec::new();
    for by in (0..h).step_by(4) {
        for bx in (0..w).step_by(8) {
            let lanes: Vec<(u32, u32)> = (by..(by + 4).min(h))
                .flat_map(|j| (bx..(bx + 8).min(w)).map(move |i| (i, j)))
                .collect();
            if !lanes.iter().any(|&(i, j)| traced(i, j)) {
                continue;
            }
            let work: Vec<u64> = lanes.iter().map(|&(i, j)| per_pixel(i, j)).collect();
            let mean = work.iter().sum::<u64>() as f64 / work.len() as f64;
            if mean > 0.0 {
                ratios.push(*work.iter().max().unwrap_or(&0) as f64 / mean);
            }
        }
    }
    let mut worst: Option<((u32, u32), u32)> = None;
    for (j, row) in rows.iter().enumerate() {
        for (i, px) in row.iter().enumerate() {
            for (_, c) in px.iter().filter(|(k, _)| *k == kind) {
                if worst.is_none_or(|(_, n)| c.interior + c.leaves > n) {
                    worst = Some(((i as u32, j as u32), c.interior + c.leaves));
                }
            }
        }
    }
    KindStats {
        worst_pixel: worst.map(|(p, _)| p),
        rays: rays.len() as u64,
        nodes: field(|c| c.interior as u64),
        leaves: field(|c| c.leaves as u64),
        prims: field(|c| c.prims as u64),
        stack: field(|c| c.stack as u64),
        bytes: field(|c| c.bytes),
        warp_spread: if ratios.is_empty() {
            0.0
        } else {
            ratios.iter().sum::<f64>() / ratios.len() as f64
        },
    }
}
