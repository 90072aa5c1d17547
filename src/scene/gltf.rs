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
//!   without one takes glTF's default, white. A `baseColorTexture` on TEXCOORD_0 multiplies
//!   both (the image from a buffer view, a `data:` URI or a file beside the glTF), its
//!   coordinates turned from glTF's v-down to glint's v-up (v' = 1 − v); its sampler's wrap
//!   is taken as REPEAT, and other texture sets and wrap modes get a warning.
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
    /// A GLB's header or chunk lengths disagree with the file.
    #[error("GLB {0}")]
    Container(String),
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
    /// An image could not be read.
    #[error("glTF image {index}: {message}")]
    Image {
        /// The image's index.
        index: usize,
        /// What is wrong.
        message: String,
    },
    /// No scene to draw.
    #[error("glTF: the file has no scene")]
    NoScene,
    /// The node graph is not a forest: a node reached twice (its own ancestor, or the
    /// child of two parents), which glTF forbids and which would draw it without end.
    #[error("glTF node {index}: {message}")]
    Node {
        /// The node's index.
        index: usize,
        /// What is wrong.
        message: String,
    },
}

/// A glTF material as glint takes it.
pub struct GltfMaterial {
    /// Its name (or `materialK`).
    pub name: String,
    /// `baseColorFactor`'s RGB.
    pub base_colour: [f32; 3],
    /// The index into [`GltfMesh::images`] of its `baseColorTexture`'s image.
    pub texture: Option<usize>,
}

/// A glTF file's triangles, their materials and what was left out.
pub struct GltfMesh {
    /// Positions, triangles and (for a smooth mesh) normals, in the file's order: nodes
    /// depth-first, then primitives.
    pub parsed: Parsed,
    /// Per material of the file (then glTF's default, white, last).
    pub materials: Vec<GltfMaterial>,
    /// The images the materials' textures use, by the file's image index: a name for
    /// messages (`file#imageK`) and the encoded bytes; `None` for an image no texture uses.
    pub images: Vec<Option<(std::path::PathBuf, Vec<u8>)>>,
    /// Per triangle, its index into `materials`.
    pub triangle_material: Vec<u32>,
    /// Whether the file's buffers are all inside it (a `.glb`, or `data:` URIs): then its
    /// bytes say everything, and it may be cached by them.
    pub self_contained: bool,
    /// One line per thing left out.
    pub warnings: Vec<String>,
}

/// The glTF document of `bytes`, validated. The container is checked first
/// ([`check_glb`]); then, before the `gltf` crate validates, every accessor glint reads
/// ([`check_accessor`]): the crate's validation indexes POSITION's unchecked (gltf-json
/// 1.4.1, mesh.rs) and its readers take indices of another type for unreachable code and
/// an empty accessor for a count to subtract one from (gltf 1.4.1), panics the fuzzer
/// found.
fn document(bytes: &[u8]) -> Result<gltf::Gltf, GltfError> {
    check_glb(bytes)?;
    let g = gltf::Gltf::from_slice_without_validation(bytes).map_err(GltfError::Document)?;
    let json = g.document.into_json();
    use gltf::json::accessor::{ComponentType as C, Type};
    use gltf::json::validation::Checked;
    for (m, mesh) in json.meshes.iter().enumerate() {
        for (p, prim) in mesh.primitives.iter().enumerate() {
            let bad = |message: String| GltfError::Primitive {
                mesh: m,
                primitive: p,
                message,
            };
            let attribute = |s: gltf::Semantic| prim.attributes.get(&Checked::Valid(s)).copied();
            let read: [(&str, Option<usize>, &[C], Type); 4] = [
                (
                    "POSITION",
                    attribute(gltf::Semantic::Positions).map(|i| i.value()),
                    &[C::F32],
                    Type::Vec3,
                ),
                (
                    "NORMAL",
                    attribute(gltf::Semantic::Normals).map(|i| i.value()),
                    &[C::F32],
                    Type::Vec3,
                ),
                (
                    "TEXCOORD_0",
                    attribute(gltf::Semantic::TexCoords(0)).map(|i| i.value()),
                    &[C::F32, C::U8, C::U16],
                    Type::Vec2,
                ),
                (
                    "indices",
                    prim.indices.map(|i| i.value()),
                    &[C::U8, C::U16, C::U32],
                    Type::Scalar,
                ),
            ];
            for (what, index, types, dims) in read {
                let Some(index) = index else { continue };
                check_accessor(&json, index, types, dims)
                    .map_err(|e| bad(format!("{what}: accessor {index} {e}")))?;
            }
        }
    }
    let document = gltf::Document::from_json(json).map_err(GltfError::Document)?;
    Ok(gltf::Gltf {
        document,
        blob: g.blob,
    })
}

/// Checks accessor `index` of `json` as the specification states it for what glint reads
/// through the `gltf` crate, whose readers assume it (and panic, or read unreachable
/// code, where it does not hold): it exists, its component type is one of `types` and its
/// type `dims`, it holds at least one element (so does a sparse part), and its buffer
/// view's stride, where given, is at least the element's size.
fn check_accessor(
    json: &gltf::json::Root,
    index: usize,
    types: &[gltf::json::accessor::ComponentType],
    dims: gltf::json::accessor::Type,
) -> Result<(), String> {
    use gltf::json::validation::Checked;
    let Some(a) = json.accessors.get(index) else {
        return Err(format!("is missing: the file has {}", json.accessors.len()));
    };
    let kind = match a.component_type {
        Checked::Valid(k) => Some(k.0),
        Checked::Invalid => None,
    };
    if !kind.is_some_and(|k| types.contains(&k)) || a.type_ != Checked::Valid(dims) {
        return Err(format!("is not a {dims:?} of {types:?}"));
    }
    if a.count.0 == 0 || a.sparse.as_ref().is_some_and(|s| s.count.0 == 0) {
        return Err("holds no element".into());
    }
    let size = kind.map_or(0, |k| k.size()) * dims.multiplicity();
    let stride = a
        .buffer_view
        .and_then(|v| json.buffer_views.get(v.value()))
        .and_then(|v| v.byte_stride);
    if let Some(s) = stride
        && s.0 < size
    {
        return Err(format!(
            "has a stride of {} bytes, under its element's {size}",
            s.0
        ));
    }
    Ok(())
}

/// Checks a GLB's container (a file that starts with the magic `glTF`) as the
/// specification states it: a 12-byte header whose length is the file's, then a JSON
/// chunk and at most one BIN chunk, each inside the file. The `gltf` crate takes a
/// header that claims less than the file holds, and one under 12 bytes overflows its
/// arithmetic; a file of any other kind is left to it.
fn check_glb(bytes: &[u8]) -> Result<(), GltfError> {
    if !bytes.starts_with(b"glTF") {
        return Ok(());
    }
    let word = |at: usize| -> Option<u32> {
        let b = bytes.get(at..at + 4)?;
        Some(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    };
    let bad = |m: String| Err(GltfError::Container(m));
    let Some(total) = word(8) else {
        return bad(format!("header: {} bytes, where it takes 12", bytes.len()));
    };
    if total as usize != bytes.len() {
        return bad(format!(
            "header: a total length of {total} bytes, but the file holds {}",
            bytes.len()
        ));
    }
    let mut at = 12usize;
    let mut chunk = 0;
    while at < bytes.len() {
        let (Some(len), Some(kind)) = (word(at), bytes.get(at + 4..at + 8)) else {
            return bad(format!("chunk {chunk}: a header cut short at byte {at}"));
        };
        let end = (at + 8).checked_add(len as usize);
        if end.is_none_or(|e| e > bytes.len()) {
            return bad(format!(
                "chunk {chunk} ({}): a length of {len} bytes from byte {}, past the file's end \
                 at {}",
                String::from_utf8_lossy(kind).trim_end_matches('\0'),
                at + 8,
                bytes.len()
            ));
        }
        at = end.unwrap_or(bytes.len());
        chunk += 1;
    }
    Ok(())
}

/// Reads the glTF at `path` (its bytes `bytes`), its external buffers through `read`.
pub fn read(
    bytes: &[u8],
    path: &Path,
    read: &super::ReadFile<'_>,
    normals: Normals,
) -> Result<GltfMesh, GltfError> {
    let g = document(bytes)?;
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

    let mut materials: Vec<GltfMaterial> = Vec::new();
    let mut images: Vec<Option<(std::path::PathBuf, Vec<u8>)>> =
        g.document.images().map(|_| None).collect();
    let mut other_sets = 0;
    let mut other_wraps = 0;
    for (k, m) in g.document.materials().enumerate() {
        let pbr = m.pbr_metallic_roughness();
        let c = pbr.base_color_factor();
        let mut texture = None;
        if let Some(info) = pbr.base_color_texture() {
            if info.tex_coord() != 0 {
                other_sets += 1;
            } else {
                let t = info.texture();
                use gltf::texture::WrappingMode::Repeat;
                if t.sampler().wrap_s() != Repeat || t.sampler().wrap_t() != Repeat {
                    other_wraps += 1;
                }
                let image = t.source();
                let index = image.index();
                if images[index].is_none() {
                    let bytes = image_bytes(&image, &buffers, folder, read, &mut self_contained)?;
                    images[index] =
                        Some((format!("{}#image{index}", path.display()).into(), bytes));
                }
                texture = Some(index);
            }
        }
        let name = m
            .name()
            .map_or_else(|| format!("material{k}"), str::to_string);
        materials.push(GltfMaterial {
            name,
            base_colour: [c[0], c[1], c[2]],
            texture,
        });
    }
    let default_material = materials.len() as u32;
    materials.push(GltfMaterial {
        name: "default".into(),
        base_colour: [1.0; 3],
        texture: None,
    });
    let textured: Vec<bool> = materials.iter().map(|m| m.texture.is_some()).collect();

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
            uvs: Vec::new(),
        },
        materials,
        images,
        triangle_material: Vec::new(),
        self_contained,
        warnings: Vec::new(),
    };
    let mut left = LeftOut::default();
    let mut stack: Vec<(gltf::Node<'_>, DMat4)> =
        scene.nodes().map(|n| (n, DMat4::IDENTITY)).collect();
    stack.reverse();
    // glTF's nodes form disjoint trees: each is drawn once, and one reached again (a cycle,
    // a second parent, a root listed twice) is an error, not a loop.
    let mut seen = vec![false; g.document.nodes().len()];
    while let Some((node, parent)) = stack.pop() {
        if std::mem::replace(&mut seen[node.index()], true) {
            return Err(GltfError::Node {
                index: node.index(),
                message: "is reached twice (a cycle in `children`, a second parent, or a \
                          root listed twice); glTF's nodes must form disjoint trees"
                    .to_string(),
            });
        }
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
                &textured,
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
    if other_sets > 0 {
        out.warnings.push(format!(
            "{other_sets} material(s) with a base colour texture on a set other than TEXCOORD_0: untextured"
        ));
    }
    if other_wraps > 0 {
        out.warnings.push(format!(
            "{other_wraps} base colour texture(s) with a wrap mode other than REPEAT: repeated"
        ));
    }
    if left.no_uvs > 0 {
        out.warnings.push(format!(
            "{} textured primitive(s) without TEXCOORD_0: drawn with the texture's colour at (0, 0)",
            left.no_uvs
        ));
    }
    if !textured.iter().any(|&t| t) {
        out.parsed.uvs = Vec::new();
    }
    Ok(out)
}

/// The encoded bytes of `image`: from a buffer view, a `data:` URI, or a file beside the
/// glTF (read through `read`; then the file is not self-contained).
fn image_bytes(
    image: &gltf::Image<'_>,
    buffers: &[Vec<u8>],
    folder: &Path,
    read: &super::ReadFile<'_>,
    self_contained: &mut bool,
) -> Result<Vec<u8>, GltfError> {
    let index = image.index();
    let err = |message: String| GltfError::Image { index, message };
    match image.source() {
        gltf::image::Source::View { view, .. } => {
            let data = &buffers[view.buffer().index()];
            data.get(view.offset()..view.offset() + view.length())
                .map(<[u8]>::to_vec)
                .ok_or_else(|| err("its buffer view lies outside its buffer".into()))
        }
        gltf::image::Source::Uri { uri, .. } => match uri.strip_prefix("data:") {
            Some(rest) => {
                let (_, b64) = rest
                    .split_once(";base64,")
                    .ok_or_else(|| err("a data: URI that is not base64".into()))?;
                use base64::Engine as _;
                base64::engine::general_purpose::STANDARD
                    .decode(b64)
                    .map_err(|e| err(format!("bad base64: {e}")))
            }
            None => {
                *self_contained = false;
                read(&folder.join(uri)).map_err(|e| err(format!("{uri}: {e}")))
            }
        },
    }
}

#[derive(Default)]
struct LeftOut {
    modes: usize,
    skins: usize,
    morphs: usize,
    no_uvs: usize,
}

/// One mesh's primitives, placed by `m`, appended to `out` (`textured`: per material,
/// whether it has a texture, so whether coordinates are read).
#[allow(clippy::too_many_arguments)]
fn add_mesh(
    mesh: &gltf::Mesh<'_>,
    m: &DMat4,
    buffers: &[Vec<u8>],
    normals: Normals,
    default_material: u32,
    textured: &[bool],
    out: &mut GltfMesh,
    left: &mut LeftOut,
) -> Result<(), GltfError> {
    let any_textured = textured.iter().any(|&t| t);
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
        // Texture coordinates, v turned up, for every triangle once any material is
        // textured (so that `uvs` lines up with `triangles`).
        let mut tex: Vec<[f32; 2]> = Vec::new();
        if any_textured {
            match reader.read_tex_coords(0) {
                Some(tc) => {
                    tex = tc.into_f32().map(|[u, v]| [u, 1.0 - v]).collect();
                    if tex.len() != n as usize {
                        return Err(err("TEXCOORD_0 and POSITION have different counts".into()));
                    }
                    if let Some(k) = tex.iter().position(|t| !t.iter().all(|x| x.is_finite())) {
                        return Err(err(format!("TEXCOORD_0 {k} is not finite")));
                    }
                }
                None => {
                    if textured[material as usize] {
                        left.no_uvs += 1;
                    }
                    tex = vec![[0.0; 2]; n as usize];
                }
            }
        }
        for t in indices.chunks_exact(3) {
            if let Some(&bad) = t.iter().find(|&&k| k >= n) {
                return Err(err(format!(
                    "index {bad} is out of range (the primitive has {n} vertices)"
                )));
            }
            let tri = [first + t[0], first + t[1], first + t[2]];
            out.parsed.triangles.push(tri);
            if any_textured {
                out.parsed
                    .uvs
                    .push([t[0], t[1], t[2]].map(|k| tex[k as usize]));
            }
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
