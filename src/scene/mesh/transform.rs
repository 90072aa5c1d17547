//! A mesh entry's placement (scale, rotate, translate) and its vertex normals.

use super::*;

/// The affine map of a mesh entry, in f64 with glam: scale, then rotate (x, then y, then
/// z: Rz·Ry·Rx), then translate, rounded to f32 once at the end. Host-side geometry: both
/// tracers read the same transformed f32 vertices, so its rounding is shared by
/// construction (glam's `DMat3 * DVec3` sums each row left to right, without FMA).
pub(in crate::scene) struct Transform {
    pub(in crate::scene) scale: glam::DVec3,
    pub(in crate::scene) rot: glam::DMat3,
    pub(in crate::scene) translate: glam::DVec3,
}

impl Transform {
    pub(in crate::scene) fn new(
        scale: [f32; 3],
        rotate_deg: [f32; 3],
        translate: [f32; 3],
    ) -> Self {
        let [ax, ay, az] = rotate_deg.map(|d| (d as f64).to_radians());
        let v = |a: [f32; 3]| glam::DVec3::new(a[0] as f64, a[1] as f64, a[2] as f64);
        Transform {
            scale: v(scale),
            rot: glam::DMat3::from_rotation_z(az)
                * glam::DMat3::from_rotation_y(ay)
                * glam::DMat3::from_rotation_x(ax),
            translate: v(translate),
        }
    }

    pub(super) fn apply(&self, p: [f32; 3]) -> [f32; 3] {
        let p = glam::DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64);
        (self.rot * (p * self.scale) + self.translate)
            .as_vec3()
            .to_array()
    }

    /// A normal carried along: by the inverse transpose of the linear part, (R·S)⁻ᵀ =
    /// R·S⁻¹, then normalised, in f64, rounded to f32 once. None when it is not finite
    /// and nonzero (a zero scale component).
    pub(super) fn apply_normal(&self, n: [f32; 3]) -> Option<[f32; 3]> {
        let n = glam::DVec3::new(n[0] as f64, n[1] as f64, n[2] as f64);
        let m = self.rot * (n / self.scale);
        let len = m.length();
        if !(len > 0.0 && len.is_finite()) {
            return None;
        }
        Some((m / len).as_vec3().to_array())
    }
}

/// The area-weighted vertex normals of `triangles` (Gouraud's): each triangle adds its
/// normal scaled by its area (the unnormalised cross product), in f64, unnormalised; zero
/// where no triangle with area touches. Why area and not angle (Thürmer and Wüthrich):
/// scanned meshes hold folded slivers, and a sliver whose angle at a vertex is near 180°
/// carries a full π of angle weight with the tilted normal of its fold, while its area is
/// nearly nothing. With angle weights the dragon showed dark specks where such vertices
/// bent the normals of every triangle around them by 30–40°; area weights remove them
/// (and on a regular mesh such as the icosphere the two agree closely).
pub(super) fn area_weighted(vertices: &[[f32; 3]], triangles: &[[u32; 3]]) -> Vec<glam::DVec3> {
    let mut acc = vec![glam::DVec3::ZERO; vertices.len()];
    let v = |k: u32| {
        let p = vertices[k as usize];
        glam::DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64)
    };
    for t in triangles {
        let [p0, p1, p2] = t.map(v);
        let n = (p1 - p0).cross(p2 - p0);
        if !n.is_finite() {
            continue;
        }
        for &k in t {
            acc[k as usize] += n;
        }
    }
    acc
}

/// The unit normal at each corner of each of `parsed`'s triangles, in world space: the
/// OBJ's `vn` where the face names one, else the area-weighted vertex normal (the
/// triangle's own normal where that is zero), each rounded to f32 as a file would hold
/// it, then carried by the transform. A mesh without `vn` thus gets exactly the normals of
/// the same mesh with its computed normals written out as `vn`.
pub(super) fn corner_normals(
    parsed: &Parsed,
    xf: &Transform,
) -> Result<Vec<[[f32; 3]; 3]>, MeshError> {
    use rayon::prelude::*;
    let needs_computed = parsed.normal_ix.iter().flatten().any(|&k| k == NO_NORMAL);
    let acc = if needs_computed {
        area_weighted(&parsed.vertices, &parsed.triangles)
    } else {
        Vec::new()
    };
    let unit_f32 = |n: glam::DVec3| -> Option<[f32; 3]> {
        let len = n.length();
        (len > 0.0 && len.is_finite()).then(|| (n / len).as_vec3().to_array())
    };
    parsed
        .triangles
        .par_iter()
        .zip(&parsed.normal_ix)
        .enumerate()
        .map(|(f, (tri, nix))| {
            let mut out = [[0.0f32; 3]; 3];
            for c in 0..3 {
                let object = if nix[c] != NO_NORMAL {
                    parsed.normals[nix[c] as usize]
                } else {
                    let [p0, p1, p2] = tri.map(|k| {
                        let p = parsed.vertices[k as usize];
                        glam::DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64)
                    });
                    unit_f32(acc[tri[c] as usize])
                        .or_else(|| unit_f32((p1 - p0).cross(p2 - p0)))
                        .unwrap_or([0.0, 0.0, 1.0]) // zero area: never hit
                };
                out[c] = xf.apply_normal(object).ok_or(MeshError::Face {
                    face: f,
                    why: FaceError::NormalLost,
                })?;
            }
            Ok(out)
        })
        .collect()
}
