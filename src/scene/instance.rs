//! Named meshes and `[[instances]]`: the checks of the file's entries and the instances'
//! maps (docs/scene-format.md, "Instances").

use super::format::{InstanceFile, MeshFile};
use super::mesh::Transform;
use super::*;

/// Mesh entry `i`'s name and visibility, its triangles being `triangles`: `None` where it
/// has no name. A second mesh of the same name, or `hidden` without a name, is an error.
pub(super) fn named_mesh(
    v: &Validator<'_>,
    i: usize,
    m: &MeshFile,
    triangles: std::ops::Range<usize>,
    named: &[NamedMesh],
) -> Result<Option<NamedMesh>, SceneError> {
    let hidden = m.hidden.as_ref().is_some_and(|h| *h.get_ref());
    let Some(name) = &m.name else {
        return match &m.hidden {
            Some(h) if hidden => v.err(
                h.span(),
                &format!("meshes[{i}].hidden"),
                "a hidden mesh needs a name, for [[instances]] to place it by".into(),
            ),
            _ => Ok(None),
        };
    };
    let key = format!("meshes[{i}].name");
    if name.get_ref().is_empty() {
        return v.err(name.span(), &key, "a mesh's name is not empty".into());
    }
    if named.iter().any(|n| n.name == *name.get_ref()) {
        return v.err(
            name.span(),
            &key,
            format!("a second mesh named {:?}: names are unique", name.get_ref()),
        );
    }
    Ok(Some(NamedMesh {
        name: name.get_ref().clone(),
        triangles,
        hidden,
    }))
}

/// The `[[instances]]` entries, checked: each names a mesh of `named`, its scale has no
/// zero component and both of its maps are finite in f32, and its material (if any) is
/// one of `names` and replaces no textured material (a triangle's texture follows its own
/// material: `uvs` says which triangles have coordinates).
pub(super) fn instances(
    v: &Validator<'_>,
    entries: &[Spanned<InstanceFile>],
    named: &[NamedMesh],
    names: &[String],
    uvs: &[TextureCoords],
) -> Result<Vec<Instance>, SceneError> {
    let mut out = Vec::with_capacity(entries.len());
    for (i, e) in entries.iter().enumerate() {
        let e = e.get_ref();
        let key = |k: &str| format!("instances[{i}].{k}");
        let Some(mesh) = named.iter().position(|n| n.name == *e.mesh.get_ref()) else {
            let known: Vec<&str> = named.iter().map(|n| n.name.as_str()).collect();
            let message = if known.is_empty() {
                format!(
                    "no mesh is named {:?}: give a [[meshes]] entry `name = {:?}`",
                    e.mesh.get_ref(),
                    e.mesh.get_ref()
                )
            } else {
                format!(
                    "no mesh is named {:?} (named meshes: {})",
                    e.mesh.get_ref(),
                    known.join(", ")
                )
            };
            return v.err(e.mesh.span(), &key("mesh"), message);
        };
        let mut parts = [[1.0f32; 3], [0.0; 3], [0.0; 3]];
        for (slot, (k, s)) in parts.iter_mut().zip([
            ("scale", &e.scale),
            ("rotate", &e.rotate),
            ("translate", &e.translate),
        ]) {
            if let Some(s) = s {
                *slot = v.finite3(s, &key(k))?;
            }
        }
        let [scale, rotate, translate] = parts;
        let (to_world, to_object) = match maps(scale, rotate, translate) {
            Ok(m) => m,
            Err(why) => {
                let span = e.scale.as_ref().map_or(e.mesh.span(), |s| s.span());
                return v.err(span, &key("scale"), why);
            }
        };
        let material = match &e.material {
            None => None,
            Some(name) => {
                let k = v.material_index(names, name, &key("material"))?;
                let range = &named[mesh].triangles;
                let textured = uvs
                    .iter()
                    .any(|t| t.first < range.end && t.first + t.uvs.len() > range.start);
                if textured {
                    return v.err(
                        name.span(),
                        &key("material"),
                        format!(
                            "mesh {:?} is textured: an instance's material replaces only an untextured mesh's",
                            named[mesh].name
                        ),
                    );
                }
                Some(k)
            }
        };
        out.push(Instance {
            mesh,
            to_world,
            to_object,
            material,
        });
    }
    Ok(out)
}

/// A hidden mesh that no instance places draws nothing: an error at its `hidden` key.
pub(super) fn check_hidden_placed(
    v: &Validator<'_>,
    meshes: &[Spanned<MeshFile>],
    named: &[NamedMesh],
    instances: &[Instance],
) -> Result<(), SceneError> {
    for (i, m) in meshes.iter().enumerate() {
        let m = m.get_ref();
        let (Some(name), Some(h)) = (&m.name, &m.hidden) else {
            continue;
        };
        let Some(k) = named.iter().position(|n| n.name == *name.get_ref()) else {
            continue;
        };
        if named[k].hidden && !instances.iter().any(|x| x.mesh == k) {
            return v.err(
                h.span(),
                &format!("meshes[{i}].hidden"),
                format!(
                    "mesh {:?} is hidden and no [[instances]] entry places it: it would draw nothing",
                    name.get_ref()
                ),
            );
        }
    }
    Ok(())
}

/// `to_world` = T·R·S and `to_object` = S⁻¹·Rᵀ·T⁻¹ (rotation as a mesh entry's: x, then
/// y, then z), in f64, each rounded to f32 once. An error where a scale component is 0
/// (no inverse) or a map does not fit f32.
pub(super) fn maps(
    scale: [f32; 3],
    rotate: [f32; 3],
    translate: [f32; 3],
) -> Result<(Affine, Affine), String> {
    if scale.contains(&0.0) {
        return Err(format!(
            "{scale:?} has a zero component: the instance would be flat, and has no inverse"
        ));
    }
    let xf = Transform::new(scale, rotate, translate);
    let linear = xf.rot * glam::DMat3::from_diagonal(xf.scale);
    let inverse = glam::DMat3::from_diagonal(xf.scale.recip()) * xf.rot.transpose();
    let back = -(inverse * xf.translate);
    let rows = |m: glam::DMat3, t: glam::DVec3| -> Option<Affine> {
        let mut a = [[0.0f32; 4]; 3];
        for (r, row) in a.iter_mut().enumerate() {
            let m = m.row(r);
            *row = [m.x as f32, m.y as f32, m.z as f32, t[r] as f32];
            if !row.iter().all(|x| x.is_finite()) {
                return None;
            }
        }
        Some(a)
    };
    match (rows(linear, xf.translate), rows(inverse, back)) {
        (Some(w), Some(o)) => Ok((w, o)),
        _ => Err(format!(
            "{scale:?} makes a map that f32 cannot hold (a component too large or too small)"
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_maps_are_inverse() {
        let (w, o) = maps([2.0, -0.5, 3.0], [30.0, 45.0, -60.0], [1.0, 2.0, -3.0]).unwrap();
        let apply = |m: &Affine, p: [f64; 3]| -> [f64; 3] {
            [0, 1, 2].map(|r| {
                m[r][0] as f64 * p[0]
                    + m[r][1] as f64 * p[1]
                    + m[r][2] as f64 * p[2]
                    + m[r][3] as f64
            })
        };
        let p = [0.3, -1.7, 2.2];
        let q = apply(&o, apply(&w, p));
        for k in 0..3 {
            assert!((q[k] - p[k]).abs() < 1e-5, "{q:?} is not {p:?}");
        }
    }

    #[test]
    fn no_transform_is_the_identity_in_every_bit() {
        assert_eq!(
            maps([1.0; 3], [0.0; 3], [0.0; 3]).unwrap(),
            (IDENTITY, IDENTITY)
        );
    }

    #[test]
    fn a_zero_scale_has_no_inverse() {
        assert!(
            maps([1.0, 0.0, 1.0], [0.0; 3], [0.0; 3])
                .unwrap_err()
                .contains("zero")
        );
        assert!(maps([1e-30, 1.0, 1.0], [0.0; 3], [0.0; 3]).is_ok());
        assert!(
            maps([1e-39, 1.0, 1.0], [0.0; 3], [0.0; 3])
                .unwrap_err()
                .contains("f32")
        );
    }
}
