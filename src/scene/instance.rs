//! Named meshes and `[[instances]]`: the checks of the file's entries and the instances'
//! maps (docs/scene-format.md, "Instances").

use super::format::{InstanceFile, MeshFile};
use super::mesh::Transform;
use super::*;

/// The most instances a scene may hold (file and bulk together): 2^24, 2 GiB of instance
/// records on the device, and the top level's node indices far inside u32.
pub const MAX_INSTANCES: usize = 1 << 24;

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
    if let Some(e) = entries.get(MAX_INSTANCES) {
        return v.err(
            e.span(),
            &format!("instances[{MAX_INSTANCES}]"),
            format!("more than {MAX_INSTANCES} instances"),
        );
    }
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
                if let Some(m) = &e.matrix {
                    return v.err(
                        m.span(),
                        &key("matrix"),
                        format!("`matrix` is the whole map: it takes no `{k}` beside it"),
                    );
                }
                *slot = v.finite3(s, &key(k))?;
            }
        }
        let [scale, rotate, translate] = parts;
        let made = match &e.matrix {
            Some(m) => maps_of_matrix(m.get_ref()).map_err(|why| (m.span(), "matrix", why)),
            None => maps(scale, rotate, translate).map_err(|why| {
                let span = e.scale.as_ref().map_or(e.mesh.span(), |s| s.span());
                (span, "scale", why)
            }),
        };
        let (to_world, to_object) = match made {
            Ok(m) => m,
            Err((span, k, why)) => return v.err(span, &key(k), why),
        };
        let material = match &e.material {
            None => None,
            Some(name) => {
                let k = v.material_index(names, name, &key("material"))?;
                if textured(uvs, &named[mesh].triangles) {
                    let why = InstancesError::Textured(named[mesh].name.clone());
                    return v.err(name.span(), &key("material"), why.to_string());
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

/// Whether some triangle of `triangles` (a named mesh's) has texture coordinates: its
/// texture follows its own material, which an instance's material then cannot replace.
fn textured(uvs: &[TextureCoords], triangles: &std::ops::Range<usize>) -> bool {
    uvs.iter()
        .any(|t| t.first < triangles.end && t.first + t.uvs.len() > triangles.start)
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

/// The maps of an object-to-world map given whole (rows `[m0, m1, m2, t]`, in f64): it
/// rounded to f32, and its inverse computed in f64 and rounded. An error where an entry is
/// not finite, the linear part is singular (its determinant 0 in f64), or a map does not
/// fit f32.
pub fn maps_of_matrix(m: &[[f64; 4]; 3]) -> Result<(Affine, Affine), String> {
    if !m.iter().flatten().all(|x| x.is_finite()) {
        return Err("every entry must be finite".into());
    }
    let linear = glam::DMat3::from_cols_array_2d(&[
        [m[0][0], m[1][0], m[2][0]],
        [m[0][1], m[1][1], m[2][1]],
        [m[0][2], m[1][2], m[2][2]],
    ]);
    let det = linear.determinant();
    if det == 0.0 || !det.is_finite() {
        return Err(format!(
            "the map is singular (determinant {det:e}): the instance would be flat, and has no inverse"
        ));
    }
    let inverse = linear.inverse();
    let t = glam::DVec3::new(m[0][3], m[1][3], m[2][3]);
    let back = -(inverse * t);
    let mut w = [[0.0f32; 4]; 3];
    let mut o = [[0.0f32; 4]; 3];
    for r in 0..3 {
        w[r] = m[r].map(|x| x as f32);
        let row = inverse.row(r);
        o[r] = [row.x as f32, row.y as f32, row.z as f32, back[r] as f32];
    }
    if !w.iter().chain(&o).flatten().all(|x| x.is_finite()) {
        return Err("the map or its inverse does not fit f32 (an entry too large)".into());
    }
    Ok((w, o))
}

impl Scene {
    /// Places the named mesh `mesh` once more for each object-to-world map of `to_world`
    /// (rows `[m0, m1, m2, t]`), with `material` (a name) replacing its own where given:
    /// `[[instances]]` in bulk, for a caller that has the maps as numbers (Python's
    /// `Scene.with_instances`). Nothing is added where any map or name is refused; the
    /// error names the map by its index.
    pub fn add_instances(
        &mut self,
        mesh: &str,
        to_world: &[[[f64; 4]; 3]],
        material: Option<&str>,
    ) -> Result<(), InstancesError> {
        let Some(k) = self.named.iter().position(|n| n.name == mesh) else {
            return Err(InstancesError::NoMesh {
                name: mesh.to_string(),
                named: self.named.iter().map(|n| n.name.clone()).collect(),
            });
        };
        let material = match material {
            None => None,
            Some(name) => {
                let Some(i) = self.materials.iter().position(|m| m.name == name) else {
                    return Err(InstancesError::NoMaterial(name.to_string()));
                };
                if textured(&self.uvs, &self.named[k].triangles) {
                    return Err(InstancesError::Textured(mesh.to_string()));
                }
                Some(i as u32)
            }
        };
        if self.instances.len() + to_world.len() > MAX_INSTANCES {
            return Err(InstancesError::TooMany {
                have: self.instances.len(),
                adding: to_world.len(),
            });
        }
        let mut added = Vec::with_capacity(to_world.len());
        for (index, m) in to_world.iter().enumerate() {
            let (w, o) = maps_of_matrix(m).map_err(|why| InstancesError::Map { index, why })?;
            added.push(Instance {
                mesh: k,
                to_world: w,
                to_object: o,
                material,
            });
        }
        self.instances.extend(added);
        Ok(())
    }
}

/// Why [`Scene::add_instances`] refused.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum InstancesError {
    /// No mesh has the name.
    #[error("no mesh is named {name:?} (named meshes: {})", if named.is_empty() { "none".to_string() } else { named.join(", ") })]
    NoMesh {
        /// The name asked for.
        name: String,
        /// The names there are.
        named: Vec<String>,
    },
    /// The material is not the scene's.
    #[error("no material is named {0:?}")]
    NoMaterial(String),
    /// The mesh is textured: a material cannot replace its own.
    #[error("mesh {0:?} is textured: an instance's material replaces only an untextured mesh's")]
    Textured(String),
    /// More than [`MAX_INSTANCES`] in all.
    #[error(
        "{have} instances and {adding} more exceed the most a scene holds, {}",
        MAX_INSTANCES
    )]
    TooMany {
        /// The scene's instances.
        have: usize,
        /// The maps given.
        adding: usize,
    },
    /// A map is refused.
    #[error("map {index}: {why}")]
    Map {
        /// Its index in the list.
        index: usize,
        /// Why.
        why: String,
    },
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
    fn a_matrix_and_its_inverse() {
        let m = [
            [0.0, -2.0, 0.0, 1.0],
            [2.0, 0.0, 0.0, -3.0],
            [0.0, 0.0, 0.5, 0.25],
        ];
        let (w, o) = maps_of_matrix(&m).unwrap();
        assert_eq!(w[1], [2.0, 0.0, 0.0, -3.0]);
        assert_eq!(o[0], [0.0, 0.5, 0.0, 1.5]);
        assert_eq!(o[1], [-0.5, 0.0, 0.0, 0.5]);
        assert_eq!(o[2], [0.0, 0.0, 2.0, -0.5]);
        let flat = [
            [1.0, 2.0, 3.0, 0.0],
            [2.0, 4.0, 6.0, 0.0],
            [0.0, 0.0, 1.0, 0.0],
        ];
        assert!(maps_of_matrix(&flat).unwrap_err().contains("singular"));
        let nan = [
            [f64::NAN, 0.0, 0.0, 0.0],
            [0.0, 1.0, 0.0, 0.0],
            [0.0, 0.0, 1.0, 0.0],
        ];
        assert!(maps_of_matrix(&nan).unwrap_err().contains("finite"));
        let big = [
            [1e300, 0.0, 0.0, 0.0],
            [0.0, 1.0, 0.0, 0.0],
            [0.0, 0.0, 1.0, 0.0],
        ];
        assert!(maps_of_matrix(&big).unwrap_err().contains("f32"));
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
