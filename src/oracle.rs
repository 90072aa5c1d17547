//! The oracle for hit or miss: exact orientation predicates (Shewchuk's, from the `robust`
//! crate) for triangles, and an interval test for spheres ([`sphere_line_hit`]: f64 with a
//! proven bound on its rounding, answering "unsure" inside the bound). It decides what a
//! ray of f32 inputs really hits, so that the tracers' leaks and false hits can be counted.
//! [`hit_sphere`] is not an oracle: it is the tracers' own formula in f64, for distances.
//!
//! Assumption: `origin + dir` is exact in f64 (true when their exponents differ by less than
//! 29, which every test ray satisfies); the hit point of a ray is then on the line through
//! two exactly known points.

use robust::{Coord, Coord3D, orient2d, orient3d};

use crate::buffers::{RayIn, SceneBuffers, Sphere, TRIANGLE_BIT, Triangle};

fn c3(p: [f64; 3]) -> Coord3D<f64> {
    Coord3D {
        x: p[0],
        y: p[1],
        z: p[2],
    }
}

fn widen(p: [f32; 3]) -> [f64; 3] {
    p.map(f64::from)
}

/// Whether a triangle has exactly zero area (each coordinate projection is degenerate).
pub fn triangle_is_degenerate(tri: &Triangle) -> bool {
    let (a, b, c) = (widen(tri.a), widen(tri.b), widen(tri.c));
    let proj = |i: usize, j: usize| {
        orient2d(
            Coord { x: a[i], y: a[j] },
            Coord { x: b[i], y: b[j] },
            Coord { x: c[i], y: c[j] },
        )
    };
    proj(0, 1) == 0.0 && proj(1, 2) == 0.0 && proj(2, 0) == 0.0
}

/// The exact answer to "does the ray hit the closed triangle at some t in (t_min, t_max)":
/// `Some(t)` (t in f64, approximate; hit or miss exact), or `None`. A ray in the
/// triangle's plane and a degenerate triangle never hit, as in every tracer.
pub fn hit_triangle(ray: &RayIn, tri: &Triangle) -> Option<f64> {
    if triangle_is_degenerate(tri) {
        return None;
    }
    let o = widen(ray.origin);
    let d = widen(ray.dir);
    let p = [o[0] + d[0], o[1] + d[1], o[2] + d[2]];
    let (a, b, c) = (c3(widen(tri.a)), c3(widen(tri.b)), c3(widen(tri.c)));
    let (co, cp) = (c3(o), c3(p));
    // The line crosses the closed triangle iff the three edge orientations agree in sign.
    let s = [
        orient3d(co, cp, a, b),
        orient3d(co, cp, b, c),
        orient3d(co, cp, c, a),
    ];
    let pos = s.iter().any(|&x| x > 0.0);
    let neg = s.iter().any(|&x| x < 0.0);
    if pos && neg || (!pos && !neg) {
        return None; // outside, or the line lies in the plane
    }
    // Where along the line: t = side(o) / (side(o) − side(p)).
    let so = orient3d(a, b, c, co);
    let sp = orient3d(a, b, c, cp);
    if so == sp {
        return None; // parallel (cannot happen when the line crosses, kept for safety)
    }
    let t = so / (so - sp);
    (t > ray.t_min as f64 && t < ray.t_max as f64).then_some(t)
}

/// Whether the line through `ray` meets the closed ball of `s`, decided exactly: `Some(hit)`
/// when the answer is certain, `None` when the line passes within the rounding bound of the
/// tangent.
///
/// The test is r²·|d|² − |f × d|² ≥ 0 with f = origin − centre (the squared distance from
/// the centre to the line, times |d|²). Every input is an f32, exact in f64; each of the
/// about ten roundings on the way has relative error at most u = 2^-53, and every term is
/// at most (|f|² + r²)·|d|² in size, so the computed value is within
/// 32·u·(|f|² + r²)·|d|² of the true one (a bound about 3× the worst case, 2^-48 relative).
/// Assumes no overflow or underflow in f64 (|coordinates| within 1e±60).
pub fn sphere_line_hit(ray: &RayIn, s: &Sphere) -> Option<bool> {
    let o = widen(ray.origin);
    let d = widen(ray.dir);
    let c = widen(s.center);
    let r = s.radius as f64;
    let f = [o[0] - c[0], o[1] - c[1], o[2] - c[2]];
    let x = [
        f[1] * d[2] - f[2] * d[1],
        f[2] * d[0] - f[0] * d[2],
        f[0] * d[1] - f[1] * d[0],
    ];
    let d2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
    let f2 = f[0] * f[0] + f[1] * f[1] + f[2] * f[2];
    let value = r * r * d2 - (x[0] * x[0] + x[1] * x[1] + x[2] * x[2]);
    let bound = 32.0 * f64::EPSILON / 2.0 * (f2 + r * r) * d2;
    if value > bound {
        Some(true)
    } else if value < -bound {
        Some(false)
    } else {
        None
    }
}

/// The nearest root of the sphere in (t_min, t_max) in f64, or `None`: the tracers' own
/// formula (Ray Tracing Gems ch. 7) evaluated in f64. Good for distances; for hit or miss
/// near the silhouette use [`sphere_line_hit`], which is exact.
pub fn hit_sphere(ray: &RayIn, s: &Sphere) -> Option<f64> {
    let o = widen(ray.origin);
    let d = widen(ray.dir);
    let c = widen(s.center);
    let r = s.radius as f64;
    let f = [o[0] - c[0], o[1] - c[1], o[2] - c[2]];
    let a = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
    let b = -(f[0] * d[0] + f[1] * d[1] + f[2] * d[2]);
    let perp = [
        f[0] + d[0] * (b / a),
        f[1] + d[1] * (b / a),
        f[2] + d[2] * (b / a),
    ];
    let disc = a * (r * r - (perp[0] * perp[0] + perp[1] * perp[1] + perp[2] * perp[2]));
    if disc.is_nan() || disc < 0.0 {
        return None;
    }
    let q = b + b.signum() * disc.sqrt();
    let cc = f[0] * f[0] + f[1] * f[1] + f[2] * f[2] - r * r;
    let (t0, t1) = (cc / q, q / a);
    let (near, far) = if t0 < t1 { (t0, t1) } else { (t1, t0) };
    let inside = |t: f64| t > ray.t_min as f64 && t < ray.t_max as f64;
    if inside(near) {
        Some(near)
    } else if inside(far) {
        Some(far)
    } else {
        None
    }
}

/// The nearest hit over the whole scene: `(t, prim)` with `TRIANGLE_BIT` on triangles.
pub fn closest_hit(buf: &SceneBuffers, ray: &RayIn) -> Option<(f64, u32)> {
    let mut best: Option<(f64, u32)> = None;
    let mut consider = |t: Option<f64>, prim: u32| {
        if let Some(t) = t
            && best.is_none_or(|(bt, _)| t < bt)
        {
            best = Some((t, prim));
        }
    };
    for (k, s) in buf.spheres.iter().enumerate() {
        consider(hit_sphere(ray, s), k as u32);
    }
    for (k, tri) in buf.triangles.iter().enumerate() {
        consider(hit_triangle(ray, tri), k as u32 | TRIANGLE_BIT);
    }
    best
}

/// A unit icosphere as OBJ text: the icosahedron, each triangle split in four `k` times,
/// every new vertex pushed out onto the sphere (shared, so the mesh is closed), positions
/// rounded to f32 and written so that they read back exactly; faces wound outward. For
/// measuring smooth against flat shading against the analytic sphere.
pub fn icosphere_obj(k: u32) -> String {
    use std::collections::HashMap;
    let t = (1.0 + 5f64.sqrt()) / 2.0;
    let mut v: Vec<[f64; 3]> = [
        [-1.0, t, 0.0],
        [1.0, t, 0.0],
        [-1.0, -t, 0.0],
        [1.0, -t, 0.0],
        [0.0, -1.0, t],
        [0.0, 1.0, t],
        [0.0, -1.0, -t],
        [0.0, 1.0, -t],
        [t, 0.0, -1.0],
        [t, 0.0, 1.0],
        [-t, 0.0, -1.0],
        [-t, 0.0, 1.0],
    ]
    .to_vec();
    let unit = |p: [f64; 3]| {
        let l = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
        [p[0] / l, p[1] / l, p[2] / l]
    };
    for p in v.iter_mut() {
        *p = unit(*p);
    }
    let mut f: Vec<[usize; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..k {
        let mut mid: HashMap<(usize, usize), usize> = HashMap::new();
        let mut next = Vec::with_capacity(f.len() * 4);
        for [a, b, c] in f {
            let mut m = |i: usize, j: usize| {
                *mid.entry((i.min(j), i.max(j))).or_insert_with(|| {
                    let (p, q) = (v[i], v[j]);
                    v.push(unit([
                        (p[0] + q[0]) / 2.0,
                        (p[1] + q[1]) / 2.0,
                        (p[2] + q[2]) / 2.0,
                    ]));
                    v.len() - 1
                })
            };
            let (ab, bc, ca) = (m(a, b), m(b, c), m(c, a));
            next.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        f = next;
    }
    let mut s = format!("# unit icosphere, {k} subdivisions, {} faces\n", f.len());
    for p in &v {
        s += &format!("v {} {} {}\n", p[0] as f32, p[1] as f32, p[2] as f32);
    }
    for [a, b, c] in &f {
        s += &format!("f {} {} {}\n", a + 1, b + 1, c + 1);
    }
    s
}
