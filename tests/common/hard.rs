//! The hard-case geometry shared by `tests/hard_cases.rs` (every tracer of glint's own) and
//! `tests/ray_query.rs` (the driver's): the triangle fan and its rays, the UV sphere, and
//! the leak and t-error counts against the exact oracle.
#![allow(dead_code)]

use glint::buffers::{HitOut, PRIM_NONE, RayIn, Triangle};
use glint::oracle;

use super::{Rng, tri};

pub const FAR: [f32; 3] = [148_376.0, 1234.0, -223_423.0];

pub fn add(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}
pub fn sub(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

pub fn ray(origin: [f32; 3], dir: [f32; 3]) -> RayIn {
    RayIn {
        origin,
        t_min: 0.0,
        dir,
        t_max: f32::MAX,
    }
}

/// Apex (0,0,1) and 8 ring vertices at radius 2 on z = 0, all moved by `offset`.
pub fn fan(offset: [f32; 3]) -> Vec<Triangle> {
    let apex = add([0.0, 0.0, 1.0], offset);
    let ring: Vec<[f32; 3]> = (0..8)
        .map(|k| {
            let a = k as f64 * std::f64::consts::TAU / 8.0;
            add(
                [(2.0 * a.cos()) as f32, (2.0 * a.sin()) as f32, 0.0],
                offset,
            )
        })
        .collect();
    (0..8)
        .map(|k| tri(apex, ring[k], ring[(k + 1) % 8]))
        .collect()
}

/// 10^5 rays at the apex and 10^5 at random points of the shared edges, from above.
///
/// The origins are steep enough (slope ≥ 0.94 against the fan's 0.5) that the fan seen
/// along the ray covers the apex all round: a ray that only grazes the apex at a silhouette
/// may be missed by any float test after rounding, and is no leak.
pub fn fan_rays(offset: [f32; 3], seed: u64) -> Vec<RayIn> {
    let mut rng = Rng::new(seed);
    let apex = add([0.0, 0.0, 1.0], offset);
    let mut rays = Vec::with_capacity(200_000);
    for k in 0..200_000 {
        let origin = add(
            [
                rng.range(-1.5, 1.5),
                rng.range(-1.5, 1.5),
                rng.range(3.0, 6.0),
            ],
            offset,
        );
        let target = if k < 100_000 {
            apex
        } else {
            let e = (rng.unit() * 8.0) as usize % 8;
            let a = e as f64 * std::f64::consts::TAU / 8.0;
            let s = 0.02 + 0.96 * rng.unit();
            let local = [
                (s * 2.0 * a.cos()) as f32,
                (s * 2.0 * a.sin()) as f32,
                (1.0 - s) as f32,
            ];
            add(local, offset)
        };
        rays.push(ray(origin, sub(target, origin)));
    }
    rays
}

/// Leaks: rays the oracle says hit the fan (some triangle, boundary included) that the
/// tracer says miss everything.
pub fn leaks(tris: &[Triangle], rays: &[RayIn], hits: &[HitOut]) -> usize {
    rays.iter()
        .zip(hits)
        .filter(|(r, h)| {
            h.prim == PRIM_NONE && tris.iter().any(|t| oracle::hit_triangle(r, t).is_some())
        })
        .count()
}

/// p50 and p99 of |t − t_oracle| / t_oracle over the rays both hit.
pub fn t_error(buf: &glint::buffers::SceneBuffers, rays: &[RayIn], hits: &[HitOut]) -> (f64, f64) {
    let mut errs: Vec<f64> = rays
        .iter()
        .zip(hits)
        .filter(|(_, h)| h.prim != PRIM_NONE)
        .filter_map(|(r, h)| oracle::closest_hit(buf, r).map(|(t, _)| ((h.t as f64 - t) / t).abs()))
        .collect();
    errs.sort_by(f64::total_cmp);
    let q = |p: f64| {
        errs.get(((errs.len() as f64 - 1.0) * p) as usize)
            .copied()
            .unwrap_or(0.0)
    };
    (q(0.5), q(0.99))
}

/// A UV sphere of `seg` segments around and `seg / 2` rings, radius `r`, at `c`.
pub fn uv_sphere(c: [f32; 3], r: f64, seg: usize) -> Vec<Triangle> {
    let rings = seg / 2;
    let p = |i: usize, j: usize| -> [f32; 3] {
        let th = std::f64::consts::PI * j as f64 / rings as f64;
        let ph = std::f64::consts::TAU * (i % seg) as f64 / seg as f64;
        let v = [
            r * th.sin() * ph.cos(),
            r * th.cos(),
            r * th.sin() * ph.sin(),
        ];
        add(v.map(|x| x as f32), c)
    };
    let mut out = Vec::new();
    for j in 0..rings {
        for i in 0..seg {
            let (a, b, cc, d) = (p(i, j), p(i + 1, j), p(i + 1, j + 1), p(i, j + 1));
            if j != 0 {
                out.push(tri(a, b, cc));
            }
            if j != rings - 1 {
                out.push(tri(a, cc, d));
            }
        }
    }
    out
}

/// `n` rays from random points within 0.5 of `c` (inside the UV sphere of radius 2 there)
/// in random directions: the closed-mesh tests' rays from inside.
pub fn rays_from_inside(c: [f32; 3], rng: &mut Rng, n: usize) -> Vec<RayIn> {
    (0..n)
        .map(|_| {
            let o = add(
                [
                    rng.range(-0.5, 0.5),
                    rng.range(-0.5, 0.5),
                    rng.range(-0.5, 0.5),
                ],
                c,
            );
            ray(
                o,
                [
                    rng.range(-1.0, 1.0),
                    rng.range(-1.0, 1.0),
                    rng.range(-1.0, 1.0),
                ],
            )
        })
        .collect()
}
