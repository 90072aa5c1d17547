//! glTF 2.0 meshes (`.gltf` with external or embedded buffers, `.glb`), read with the
//! `gltf` crate into the OBJ reader's [`Parsed`], with a material per triangle.
//!
//! - **What is drawn:** every primitive of mode TRIANGLES of every node of the default scene
//!   (else the first), node transforms composed from the root down. Other modes, skins
//!   (the rest pose is drawn) and morph targets (the base shape is drawn) are left out with
//!   one warning each, never in silence.
//! - **Exact where it can be:** a node whose composed transform is the identity keeps its
//!   positions' bits, so a `.glb` of a mesh gives the OBJ's triangles; any other transform
//!   is applied in f64 and rounded once. Normals go through the inverse transpose, in f64.
//! - **Indices** of any width; a primitive without indices is a list of triangles in
//!   vertex order. An index past its primitive's vertices is an error naming the mesh and
//!   the primitive.
//! - **Materials:** `baseColorFactor` gives kd and ka (a diffuse material); a primitive
//!   without one takes glTF's default, white. Textures are not modelled: a material with a
//!   `baseColorTexture` gets a warning and its factor only.
//! - **Buffers** are read through the scene's reader, relative to the file, with its limits
//!   and confinement; `data:` URIs are decoded.

use std::path::Path;

use glam::{DMat3, DMat4, DVec3};

use super::ReadError;
use super::obj::{NO_NORMAL, Normals, Parsed};

/// What is wrong with a glTF file.
#[derive(Debug, thiserror::Error)]
pub enum GltfError {
    /// The `gltf` crate refused the file (JSON, GLB container, or its validation).
    #[error("glTF: {0}")]
    Document(gltf::Error),
    /// A buffer could not be read.
    #[error("glTF buffer {index} ({uri}): {error}")]
    Buffer {
        /// The buffer's index.
        index: usize,
        /// Its URI (`data:` URIs shortened).
        uri: String,
        /// Why.
        error: ReadError,
    },
    /// A buffer is malformed or shorter than it says.
    #[error("glTF buffer {index}: {message}")]
    BufferData {
        /// The buffer's index.
        index: usize,
        /// What is wrong.
        message: String,
    },
    /// A primitive is malformed.
    #[error("glTF mesh {mesh} primitive {primitive}: {message}")]
    Primitive {
        /// The mesh's index.
        mesh: usize,
        /// The primitive's index within the mesh.
        primitive: usize,
        /// What is wrong.
        message: String,
    },
    /// A material's base colour is out of the scene's colour domain.
    #[error("glTF material {index} ({name:?}): baseColorFactor {message}")]
    Material {
        /// The material's index.
        index: usize,
        /// Its name (or `materialK`).
        name: String,
        /// What is wrong, as for a scene colour.
        message: String,
    },
    /// No scene to draw.
    #[error("glTF: the file has no scene")]
    NoScene,
}

/// A glTF file's triangles, their materials and what was left out.
pub struct GltfMesh {
    /// Positions, triangles and (for a smooth mesh) normals, in the file's order: nodes
    /// depth-first, then primitives.
    pub parsed: Parsed,
    /// Per material of the file (then glTF's default, white, last): its name and base
    /// colour.
    pub materials: Vec<(String, [f32; 3])>,
    /// Per triangle, its index into `materials`.
    pub triangle_material: Vec<u32>,
    /// Whether the file's buffers are all inside it (a `.glb`, or `data:` URIs): then its
    /// bytes say everything, and it may be cached by them.
    pub self_contained: bool,
    /// One line per thing left out.
    pub warnings: Vec<String>,
}

/// Reads the glTF at `path` (its bytes `bytes`), its external buffers through `read`.
pub fn read(
    bytes: &[u8],
    path: &Path,
    read: &super::ReadFile<'_>,
    normals: Normals,
) -> Result<GltfMesh, GltfError> {
    let g = gltf::Gltf::from_slice(bytes).map_err(GltfError::Document)?;
    let folder = path.parent().unwrap_or(Path::new("."));
    let mut self_contained = true;
    let mut buffers: Vec<Vec<u8>> = Vec::new();
    for b in g.document.buffers() {
        let index = b.index();
        let data = match b.source() {
            gltf::buffer::Source::Bin => g.blob.clone().ok_or_else(|| GltfError::BufferData {
                index,
                message: "refers to the GLB's binary chunk, which the file does not have".into(),
            })?,
            gltf::buffer::Source::Uri(uri) => match uri.strip_prefix("data:") {
                Some(rest) => {
                    let (_, b64) =
                        rest.split_once(";base64,")
                            .ok_or_else(|| GltfError::BufferData {
                                index,
                                message: "a data: URI that is not base64".into(),
                            })?;
                    use base64::Engine as _;
                    base64::engine::general_purpose::STANDARD
                        .decode(b64)
                        .map_err(|e| GltfError::BufferData {
                            index,
                            message: format!("bad base64: {e}"),
                        })?
                }
                None => {
                    self_contained = false;
                    read(&folder.join(uri)).map_err(|error| GltfError::Buffer {
                        index,
                        uri: uri.to_string(),
                        error,
                    })?
                }
            },
        };
        if data.len() < b.length() {
            return Err(GltfError::BufferData {
                index,
                message: format!("holds {} bytes where it says {}", data.len(), b.length()),
            });
        }
        buffers.push(data);
    }

    let mut materials: Vec<(String, [f32; 3])> = Vec::new();
    let mut textured = 0;
    for (k, m) in g.document.materials().enumerate() {
        let pbr = m.pbr_metallic_roughness();
        let c = pbr.base_color_factor();
        if pbr.base_color_texture().is_some() {
            textured += 1;
        }
        let name = m
            .name()
            .map_or_else(|| format!("material{k}"), str::to_string);
        materials.push((name, [c[0], c[1], c[2]]));
    }
    let default_material = materials.len() as u32;
    materials.push(("default".into(), [1.0; 3]));

    let scene = g
        .document
        .default_scene()
        .or_else(|| g.document.scenes().next())
        .ok_or(GltfError::NoScene)?;
    let mut out = GltfMesh {
        parsed: Parsed {
            vertices: Vec::new(),
            triangles: Vec::new(),
            short_faces: Vec::new(),
            normals: Vec::new(),
            normal_ix: Vec::new(),
        },
        materials,
        triangle_material: Vec::new(),
        self_contained,
        warnings: Vec::new(),
    };
    let mut left = LeftOut::default();
    let mut stack: Vec<(gltf::Node<'_>, DMat4)> =
        scene.nodes().map(|n| (n, DMat4::IDENTITY)).collect();
    stack.reverse();
    while let Some((node, parent)) = stack.pop() {
        let m = parent
            * DMat4::from_cols_array_2d(&node.transform().matrix().map(|c| c.map(f64::from)));
        if node.skin().is_some() {
            left.skins += 1;
        }
        if let Some(mesh) = node.mesh() {
            add_mesh(
                &mesh,
                &m,
                &buffers,
                normals,
                default_material,
                &mut out,
                &mut left,
            )?;
        }
        let children: Vec<_> = node.children().collect();
        for c in children.into_iter().rev() {
            stack.push((c, m));
        }
    }
    if left.modes > 0 {
        out.warnings.push(format!(
            "{} primitive(s) not of mode TRIANGLES (points, lines, strips, fans) left out",
            left.modes
        ));
    }
    if left.skins > 0 {
        out.warnings.push(format!(
            "{} skinned node(s) drawn in their rest pose",
            left.skins
        ));
    }
    if left.morphs > 0 {
        out.warnings.push(format!(
            "{} primitive(s) with morph targets drawn in their base shape",
            left.morphs
        ));
    }
    if textured > 0 {
        out.warnings.push(format!(
            "{textured} material(s) with a base colour texture: textures are not modelled, the base colour factor is used"
        ));
    }
    Ok(out)
}

#[derive(Default)]
struct LeftOut {
    modes: usize,
    skins: usize,
    morphs: usize,
}

/// One mesh's primitives, placed by `m`, appended to `out`.
fn add_mesh(
    mesh: &gltf::Mesh<'_>,
    m: &DMat4,
    buffers: &[Vec<u8>],
    normals: Normals,
    default_material: u32,
    out: &mut GltfMesh,
    left: &mut LeftOut,
) -> Result<(), GltfError> {
    let identity = *m == DMat4::IDENTITY;
    let normal_m: DMat3 = DMat3::from_mat4(*m).inverse().transpose();
    for (pi, prim) in mesh.primitives().enumerate() {
        let err = |message: String| GltfError::Primitive {
            mesh: mesh.index(),
            primitive: pi,
            message,
        };
        if prim.mode() != gltf::mesh::Mode::Triangles {
            left.modes += 1;
            continue;
        }
        if prim.morph_targets().len() > 0 {
            left.morphs += 1;
        }
        let reader = prim.reader(|b| buffers.get(b.index()).map(|d| &d[..]));
        let Some(positions) = reader.read_positions() else {
            return Err(err("has no POSITION".into()));
        };
        let first = out.parsed.vertices.len() as u32;
        for p in positions {
            out.parsed.vertices.push(if identity {
                p
            } else {
                let q = m.transform_point3(DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64));
                q.as_vec3().to_array()
            });
        }
        let n = out.parsed.vertices.len() as u32 - first;
        if normals == Normals::Read {
            match reader.read_normals() {
                Some(ns) => {
                    for (k, v) in ns.enumerate() {
                        if v.iter().any(|x| !x.is_finite()) {
                            return Err(err(format!("normal {k} {v:?} is not finite")));
                        }
                        let w = if identity {
                            v
                        } else {
                            let d = normal_m * DVec3::new(v[0] as f64, v[1] as f64, v[2] as f64);
                            let l = d.length();
                            if l > 0.0 && l.is_finite() {
                                (d / l).as_vec3().to_array()
                            } else {
                                [0.0; 3]
                            }
                        };
                        out.parsed.normals.push(w);
                    }
                }
                None => out.parsed.normals.extend((0..n).map(|_| [0.0f32; 3])),
            }
            if out.parsed.normals.len() != out.parsed.vertices.len() {
                return Err(err("NORMAL and POSITION have different counts".into()));
            }
        }
        let indices: Vec<u32> = match reader.read_indices() {
            Some(ix) => ix.into_u32().collect(),
            None => (0..n).collect(),
        };
        if !indices.len().is_multiple_of(3) {
            return Err(err(format!(
                "{} indices: not a whole number of triangles",
                indices.len()
            )));
        }
        let material = prim
            .material()
            .index()
            .map_or(default_material, |k| k as u32);
        for t in indices.chunks_exact(3) {
            if let Some(&bad) = t.iter().find(|&&k| k >= n) {
                return Err(err(format!(
                    "index {bad} is out of range (the primitive has {n} vertices)"
                )));
            }
            let tri = [first + t[0], first + t[1], first + t[2]];
            out.parsed.triangles.push(tri);
            out.triangle_material.push(material);
            if normals == Normals::Read {
                out.parsed.normal_ix.push(tri.map(|k| {
                    if out.parsed.normals[k as usize] == [0.0; 3] {
                        NO_NORMAL
                    } else {
                        k
                    }
                }));
            }
        }
    }
    Ok(())
}
