//! Faces placed in the scene: parsed and `tobj` models, texture coordinates, checks.

use super::*;

/// `parsed`'s triangles placed by `xf`, of `material`. Each position is transformed once,
/// then the triangles gathered from them: the same numbers as transforming each
/// triangle's corners (`Transform::apply` is a pure function of the position).
pub(super) fn place_parsed(
    parsed: &Parsed,
    xf: &Transform,
    material: u32,
) -> Result<Vec<Triangle>, MeshError> {
    use rayon::prelude::*;
    let moved: Vec<[f32; 3]> = parsed.vertices.par_iter().map(|&p| xf.apply(p)).collect();
    // Gathered straight into place (an indexed collect: no partial lists to join, as
    // collecting `Result`s would make), the first face that fails `check_placed` noted on
    // the way. A position that is not finite is not finite once transformed either (inf·0
    // and NaN stay NaN), so checking the transformed corners finds every failing face.
    let first_bad = AtomicUsize::new(usize::MAX);
    let placed: Vec<Triangle> = parsed
        .triangles
        .par_iter()
        .enumerate()
        .map(|(f, ix)| {
            let vertices = ix.map(|k| moved[k as usize]);
            if vertices.iter().flatten().any(|x| !x.is_finite()) {
                first_bad.fetch_min(f, Ordering::Relaxed);
            }
            Triangle { vertices, material }
        })
        .collect();
    let f = first_bad.into_inner();
    if f != usize::MAX {
        let ix = parsed.triangles[f];
        let ps = ix.map(|k| parsed.vertices[k as usize]);
        // A corner is not finite, so `check_placed` says which way.
        if let Err(why) = check_placed(ps, ix.map(|k| moved[k as usize])) {
            return Err(MeshError::Face { face: f, why });
        }
    }
    Ok(placed)
}

/// tobj's objects placed by `xf` into `triangles`, each of its `material` (an error where
/// it has none); for each object, the range of its triangles and their texture coordinates
/// (none where it has no `vt`).
#[allow(clippy::type_complexity)]
pub(super) fn place_models(
    models: &[tobj::Model],
    material: impl Fn(&tobj::Model) -> Option<u32>,
    xf: &Transform,
    triangles: &mut Vec<Triangle>,
) -> Result<Vec<(std::ops::Range<usize>, Vec<[[f32; 2]; 3]>)>, MeshError> {
    let mut runs = Vec::new();
    for model in models {
        let start = triangles.len();
        let uvs = model_uvs(model)?;
        let mesh = &model.mesh;
        let object = || model.name.clone();
        let material = material(model).ok_or_else(|| MeshError::NoMaterial { object: object() })?;
        let n_vertices = mesh.positions.len() / 3;
        for (f, tri) in mesh.indices.chunks_exact(3).enumerate() {
            let mut ps = [[0.0f32; 3]; 3];
            for (slot, &ix) in ps.iter_mut().zip(tri) {
                let ix = ix as usize;
                if ix >= n_vertices {
                    return Err(MeshError::ObjectIndex {
                        object: object(),
                        face: f,
                        index: ix + 1,
                        vertices: n_vertices,
                    });
                }
                *slot = [
                    mesh.positions[3 * ix],
                    mesh.positions[3 * ix + 1],
                    mesh.positions[3 * ix + 2],
                ];
            }
            let vertices = place(xf, ps).map_err(|why| MeshError::ObjectFace {
                object: object(),
                face: f,
                why,
            })?;
            triangles.push(Triangle { vertices, material });
        }
        runs.push((start..triangles.len(), uvs));
    }
    Ok(runs)
}

/// A tobj object's texture coordinates, per triangle (none where it has none).
pub(super) fn model_uvs(model: &tobj::Model) -> Result<Vec<[[f32; 2]; 3]>, MeshError> {
    let mesh = &model.mesh;
    if mesh.texcoords.is_empty() || mesh.texcoord_indices.len() != mesh.indices.len() {
        return Ok(Vec::new());
    }
    let n = mesh.texcoords.len() / 2;
    mesh.texcoord_indices
        .chunks_exact(3)
        .enumerate()
        .map(|(f, tri)| {
            let mut uv = [[0.0f32; 2]; 3];
            for (slot, &ix) in uv.iter_mut().zip(tri) {
                let ix = ix as usize;
                if ix >= n {
                    return Err(MeshError::TexcoordIndex {
                        object: model.name.clone(),
                        face: f,
                        index: ix + 1,
                        texcoords: n,
                    });
                }
                *slot = [mesh.texcoords[2 * ix], mesh.texcoords[2 * ix + 1]];
                if !slot.iter().all(|x| x.is_finite()) {
                    return Err(MeshError::TexcoordValue {
                        object: model.name.clone(),
                        face: f,
                    });
                }
            }
            Ok(uv)
        })
        .collect()
}

/// The mesh entry's transform, its values checked.
pub(super) fn mesh_transform(
    v: &Validator<'_>,
    i: usize,
    m: &MeshFile,
) -> Result<Transform, SceneError> {
    for (name, s) in [
        ("scale", &m.scale),
        ("rotate", &m.rotate),
        ("translate", &m.translate),
    ] {
        if let Some(s) = s {
            v.finite3(s, &format!("meshes[{i}].{name}"))?;
        }
    }
    Ok(Transform::new(
        m.scale.as_ref().map(|s| *s.get_ref()).unwrap_or([1.0; 3]),
        m.rotate.as_ref().map(|s| *s.get_ref()).unwrap_or([0.0; 3]),
        m.translate
            .as_ref()
            .map(|s| *s.get_ref())
            .unwrap_or([0.0; 3]),
    ))
}

/// One triangle's file positions, checked finite, transformed, checked again.
pub(super) fn place(xf: &Transform, ps: [[f32; 3]; 3]) -> Result<[[f32; 3]; 3], FaceError> {
    check_placed(ps, ps.map(|p| xf.apply(p)))
}

/// `vs`, the transformed `ps`, when both are finite.
pub(super) fn check_placed(
    ps: [[f32; 3]; 3],
    vs: [[f32; 3]; 3],
) -> Result<[[f32; 3]; 3], FaceError> {
    if ps.iter().flatten().any(|x| !x.is_finite()) {
        return Err(FaceError::NotFinite);
    }
    if vs.iter().flatten().any(|x| !x.is_finite()) {
        return Err(FaceError::Overflow);
    }
    Ok(vs)
}
