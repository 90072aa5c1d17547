//! The f32-safe range of each primitive test, worked out from the tracers' arithmetic, and
//! the warnings for a scene that leaves it. Inside the range no intermediate of the test
//! overflows or underflows f32; outside it a primitive may silently vanish (an infinite or
//! zero determinant reads as a miss), so glint says so, naming the primitive. Nothing here
//! changes an image.
//!
//! Notation: E is a triangle's longest edge, D the largest distance from one of its points
//! (or a sphere's centre) to a ray origin that can reach it: the eye, and with shadows on,
//! each light (shadow rays run between surface points and lights); r a sphere's radius.
//! f32 overflows above 3.4e38 and loses precision below 1.2e-38 (subnormals); each bound
//! keeps a factor of about 30 to spare for the sums of three terms.
//!
//! | test | largest intermediates | range |
//! |---|---|---|
//! | naive | `dot(cr, cr)` and `d00 * d11`, both ~E⁴ | 1e-9 ≤ E ≤ 1e9 |
//! | Möller–Trumbore | `dot(e2, q)` ~ E²·D; `det` ~ E²·\|d\| | E²·D ≤ 1e37, E ≥ 1e-18 |
//! | watertight | `t_scaled` = U·Az + V·Bz + W·Cz ~ D³ | D ≤ 1e12 |
//! | sphere | `disc` ~ D²·\|d\|², `r * r` | D ≤ 1e18, 1e-18 ≤ r ≤ 1e18 |

use rayon::prelude::*;

use super::{Scene, TriangleAlgorithm};

/// Naive test: the longest edge it handles (`dot(cr, cr)` ~ E⁴ ≤ 1e36).
pub const NAIVE_MAX_EDGE: f64 = 1e9;
/// Naive test: the shortest edge it handles (E⁴ ≥ 1e-36, above the subnormals).
pub const NAIVE_MIN_EDGE: f64 = 1e-9;
/// Möller–Trumbore: the largest E²·D (`dot(e2, q)`).
pub const MT_MAX_E2D: f64 = 1e37;
/// Möller–Trumbore: the shortest edge (`det` ~ E² above the subnormals).
pub const MT_MIN_EDGE: f64 = 1e-18;
/// Watertight: the largest distance from a ray origin (`t_scaled` ~ D³ ≤ 1e36).
pub const WATERTIGHT_MAX_DIST: f64 = 1e12;
/// Spheres: the largest distance from a ray origin (`disc` ~ D²).
pub const SPHERE_MAX_DIST: f64 = 1e18;
/// Spheres: the smallest radius (`r * r` above the subnormals).
pub const SPHERE_MIN_RADIUS: f64 = 1e-18;
/// Spheres: the largest radius (`r * r` finite).
pub const SPHERE_MAX_RADIUS: f64 = 1e18;

fn dist(a: [f32; 3], b: [f32; 3]) -> f64 {
    (0..3)
        .map(|k| (a[k] as f64 - b[k] as f64).powi(2))
        .sum::<f64>()
        .sqrt()
}

impl Scene {
    /// The ray origins whose rays reach primitives: the eye, and each light with shadows.
    fn origins(&self) -> Vec<[f32; 3]> {
        let mut o = vec![self.camera.eye];
        if self.shadows {
            o.extend(self.lights.iter().map(|l| l.position));
        }
        o
    }

    /// Warnings for every primitive outside the f32-safe range of `algo` (triangles) or of
    /// the sphere test, each naming the scene file, the line and key (or the mesh file) and
    /// the bound. Groups of primitives from one source give one warning with a count.
    pub fn range_warnings(&self, algo: TriangleAlgorithm) -> Vec<String> {
        let origins = self.origins();
        let far = |p: [f32; 3]| origins.iter().map(|&o| dist(p, o)).fold(0.0, f64::max);
        let mut out = Vec::new();
        for (k, s) in self.spheres.iter().enumerate() {
            let d = far(s.center);
            let r = s.radius as f64;
            let why = if d > SPHERE_MAX_DIST {
                Some(format!("{d:.1e} from a ray origin (> {SPHERE_MAX_DIST:e})"))
            } else if r < SPHERE_MIN_RADIUS {
                Some(format!("radius {r:.1e} < {SPHERE_MIN_RADIUS:e}"))
            } else if r > SPHERE_MAX_RADIUS {
                Some(format!("radius {r:.1e} > {SPHERE_MAX_RADIUS:e}"))
            } else {
                None
            };
            if let Some(why) = why {
                let src = self.sphere_sources.get(k).map_or("", String::as_str);
                out.push(format!(
                    "{src}: outside the f32-safe range of the sphere test ({why}): it may not be drawn \
                     (render with --backend cpu-f64 to see it)"
                ));
            }
        }
        // Why triangle `v` is outside the range, if it is (a string only then).
        let why = |v: [[f32; 3]; 3]| -> Option<String> {
            let e = (0..3)
                .map(|i| dist(v[i], v[(i + 1) % 3]))
                .fold(0.0, f64::max);
            let d = v.iter().map(|&p| far(p)).fold(0.0, f64::max);
            match algo {
                TriangleAlgorithm::Naive if e > NAIVE_MAX_EDGE => {
                    Some(format!("an edge of {e:.1e} > {NAIVE_MAX_EDGE:e}"))
                }
                TriangleAlgorithm::Naive if e > 0.0 && e < NAIVE_MIN_EDGE => {
                    Some(format!("an edge of {e:.1e} < {NAIVE_MIN_EDGE:e}"))
                }
                TriangleAlgorithm::MollerTrumbore if e * e * d > MT_MAX_E2D => Some(format!(
                    "edge² × distance {:.1e} > {MT_MAX_E2D:e}",
                    e * e * d
                )),
                TriangleAlgorithm::MollerTrumbore if e > 0.0 && e < MT_MIN_EDGE => {
                    Some(format!("an edge of {e:.1e} < {MT_MIN_EDGE:e}"))
                }
                TriangleAlgorithm::Watertight if d > WATERTIGHT_MAX_DIST => Some(format!(
                    "{d:.1e} from a ray origin > {WATERTIGHT_MAX_DIST:e}"
                )),
                _ => None,
            }
        };
        for (g, (first, src)) in self.triangle_sources.iter().enumerate() {
            let end = self
                .triangle_sources
                .get(g + 1)
                .map_or(self.triangles.len(), |n| n.0);
            // Each group's triangles in parallel: how many are outside, and the first.
            let (bad, first_bad) = self.triangles[*first..end]
                .par_iter()
                .enumerate()
                .filter(|(_, t)| why(t.vertices).is_some())
                .map(|(k, _)| (1usize, k))
                .reduce(|| (0, usize::MAX), |a, b| (a.0 + b.0, a.1.min(b.1)));
            if bad > 0 {
                let t = &self.triangles[first + first_bad];
                let example = format!(
                    "triangle {first_bad} of it: {}",
                    why(t.vertices).unwrap_or_default()
                );
                out.push(format!(
                    "{src}: {bad} triangle(s) outside the f32-safe range of the {algo} test \
                     ({example}): they may not be drawn (render with --backend cpu-f64 to see them)"
                ));
            }
        }
        out
    }
}
