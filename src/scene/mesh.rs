//! `[[meshes]]`: Wavefront OBJ (glint's reader, else `tobj`) and Stanford PLY
//! ([`super::ply`]), polygons triangulated, the material from the
//! scene or from the OBJ's MTL, then scale, rotate (x, then y, then z) and translate.

use std::io::BufReader;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering};

use toml::Spanned;

use super::format::MeshFile;
use super::obj::{NO_NORMAL, Normals, ObjError, Parsed};
use super::texture::{TextureError, TextureSet};
use super::{
    Material, Model, ReadError, SceneError, SmoothNormals, TextureCoords, Triangle, Validator,
    line_of,
};
use crate::cache::{Cache, Key};

/// What is wrong with a mesh file (an OBJ, or the MTL it names), in its own terms: where
/// the scene names it, [`SceneError::Mesh`] says (scene file, line, key, mesh file).
#[derive(Debug, thiserror::Error)]
pub enum MeshError {
    /// The OBJ could not be read.
    #[error("{0}")]
    Read(ReadError),
    /// The mesh is missing beside a scene whose folder has the script that fetches its
    /// meshes (glint's own `scenes/`).
    #[error("{error} (glint's scenes get their meshes with `bash {script}`)")]
    NotFetched {
        /// Why it could not be read.
        error: ReadError,
        /// The script, beside the scene.
        script: PathBuf,
    },
    /// The `.gz` does not inflate.
    #[error("cannot gunzip: {0}")]
    Gunzip(std::io::Error),
    /// The `.gz` inflates to more than the input limit.
    #[error(
        "unpacks to more than the input limit of {} MiB (set GLINT_MAX_INPUT_MIB to raise it)",
        .limit >> 20
    )]
    Unpacked {
        /// The limit, bytes ([`super::LoadOptions::max_input_bytes`]).
        limit: u64,
    },
    /// The OBJ is not UTF-8.
    #[error("not UTF-8 at line {line}")]
    NotUtf8 {
        /// The line (from 1) of its first byte that is not.
        line: usize,
    },
    /// The OBJ's text is wrong at one of its lines.
    #[error("{0}")]
    Obj(ObjError),
    /// A triangle of glint's reader (numbered from 0 in file order) cannot be placed.
    #[error("face {face}: {why}")]
    Face {
        /// The triangle.
        face: usize,
        /// What is wrong with it.
        why: FaceError,
    },
    /// An MTL the OBJ names could not be read.
    #[error("MTL {path}: {error}")]
    MtlRead {
        /// The MTL, as found next to the OBJ.
        path: PathBuf,
        /// Why.
        error: ReadError,
    },
    /// An MTL the OBJ names is wrong at one of its lines.
    #[error("{file}: {error}")]
    Mtl {
        /// The MTL, as the OBJ names it.
        file: PathBuf,
        /// What is wrong, at its line.
        error: ObjError,
    },
    /// tobj refused the OBJ.
    #[error("cannot parse OBJ: {0}")]
    Tobj(tobj::LoadError),
    /// tobj refused the OBJ's MTL.
    #[error("cannot load its MTL: {0}")]
    TobjMtl(tobj::LoadError),
    /// An MTL material with a negative or non-finite value.
    #[error("MTL material {name:?} has a negative or non-finite value")]
    MtlValue {
        /// Its name in the MTL.
        name: String,
    },
    /// An MTL material with a colour component above [`super::MAX_COLOUR`].
    #[error(
        "MTL material {name:?} has a colour component above {:e}",
        super::MAX_COLOUR
    )]
    MtlColour {
        /// Its name in the MTL.
        name: String,
    },
    /// An object of the OBJ has no material: neither the scene nor an MTL gives one.
    #[error("object {object:?} has no material: name one with `material =` or give the OBJ an MTL")]
    NoMaterial {
        /// The object's name.
        object: String,
    },
    /// A face of a tobj object names a position the object does not have.
    #[error(
        "object {object:?}, face {face}: vertex index {index} is out of range (the object has {vertices} vertices)"
    )]
    ObjectIndex {
        /// The object's name.
        object: String,
        /// The triangle, from 0 within the object.
        face: usize,
        /// The index, from 1.
        index: usize,
        /// The object's positions.
        vertices: usize,
    },
    /// A face of a tobj object names a texture coordinate the file does not have.
    #[error(
        "object {object:?}, face {face}: texture coordinate index {index} is out of range (the file has {texcoords})"
    )]
    TexcoordIndex {
        /// The object's name.
        object: String,
        /// The triangle, from 0 within the object.
        face: usize,
        /// The index, from 1.
        index: usize,
        /// The file's texture coordinates.
        texcoords: usize,
    },
    /// A face of a tobj object has a texture coordinate that is not finite.
    #[error("object {object:?}, face {face}: a texture coordinate is not finite")]
    TexcoordValue {
        /// The object's name.
        object: String,
        /// The triangle, from 0 within the object.
        face: usize,
    },
    /// A triangle of a tobj object cannot be placed.
    #[error("object {object:?}, face {face}: {why}")]
    ObjectFace {
        /// The object's name.
        object: String,
        /// The triangle, from 0 within the object.
        face: usize,
        /// What is wrong with it.
        why: FaceError,
    },
    /// A smooth mesh whose triangles glint's reader and tobj count differently, so its
    /// normals cannot be paired with its faces.
    #[error(
        "smooth: the OBJ reader found {ours} triangles where tobj found {tobj}; cannot pair normals with faces"
    )]
    Unpaired {
        /// glint's count.
        ours: usize,
        /// tobj's count.
        tobj: usize,
    },
    /// No triangles.
    #[error("no triangles: the mesh is empty")]
    Empty,
    /// A PLY file is wrong: its header line, or the element and its index.
    #[error("{0}")]
    Ply(super::PlyError),
    /// A glTF file is wrong.
    #[error("{0}")]
    Gltf(super::GltfError),
    /// A texture an MTL or a glTF names cannot be used.
    #[error("texture {path}: {error}")]
    Texture {
        /// The image, as found (next to the MTL, or the glTF).
        path: PathBuf,
        /// Why.
        error: TextureError,
    },
    /// A PLY mesh without `material =` (PLY files carry no materials).
    #[error("a PLY file has no materials: name one with `material =`")]
    PlyMaterial,
}

/// What is wrong with one triangle as the entry's transform places it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
pub enum FaceError {
    /// A corner of the file's is not finite.
    #[error("a vertex is not finite")]
    NotFinite,
    /// A corner is finite in the file but not once transformed.
    #[error("the transform overflows f32")]
    Overflow,
    /// A corner's normal has no direction once transformed.
    #[error("its normal does not survive the transform (a zero scale component?)")]
    NormalLost,
}

/// Whether a triangle has zero area in f64 (collinear or coincident vertices).
pub fn is_degenerate(v: &[[f32; 3]; 3]) -> bool {
    let d = |i: usize, k: usize| v[i][k] as f64 - v[0][k] as f64;
    let (e1, e2) = ([d(1, 0), d(1, 1), d(1, 2)], [d(2, 0), d(2, 1), d(2, 2)]);
    let c = [
        e1[1] * e2[2] - e1[2] * e2[1],
        e1[2] * e2[0] - e1[0] * e2[2],
        e1[0] * e2[1] - e1[1] * e2[0],
    ];
    c == [0.0; 3]
}

/// The affine map of a mesh entry, in f64 with glam: scale, then rotate (x, then y, then
/// z: Rz·Ry·Rx), then translate, rounded to f32 once at the end. Host-side geometry: both
/// tracers read the same transformed f32 vertices, so its rounding is shared by
/// construction (glam's `DMat3 * DVec3` sums each row left to right, without FMA).
struct Transform {
    scale: glam::DVec3,
    rot: glam::DMat3,
    translate: glam::DVec3,
}

impl Transform {
    fn new(scale: [f32; 3], rotate_deg: [f32; 3], translate: [f32; 3]) -> Self {
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

    fn apply(&self, p: [f32; 3]) -> [f32; 3] {
        let p = glam::DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64);
        (self.rot * (p * self.scale) + self.translate)
            .as_vec3()
            .to_array()
    }

    /// A normal carried along: by the inverse transpose of the linear part, (R·S)⁻ᵀ =
    /// R·S⁻¹, then normalised, in f64, rounded to f32 once. None when it is not finite
    /// and nonzero (a zero scale component).
    fn apply_normal(&self, n: [f32; 3]) -> Option<[f32; 3]> {
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
fn area_weighted(vertices: &[[f32; 3]], triangles: &[[u32; 3]]) -> Vec<glam::DVec3> {
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
fn corner_normals(parsed: &Parsed, xf: &Transform) -> Result<Vec<[[f32; 3]; 3]>, MeshError> {
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

/// A mesh's read error, with the way to fetch it where the scene's folder has
/// `fetch-meshes.sh` and the file is not there.
fn not_fetched(scene: &Path, error: ReadError) -> MeshError {
    let missing = matches!(&error, ReadError::Io(e) if e.kind() == std::io::ErrorKind::NotFound);
    let script = scene
        .parent()
        .unwrap_or(Path::new(""))
        .join("fetch-meshes.sh");
    if missing && script.is_file() {
        MeshError::NotFetched { error, script }
    } else {
        MeshError::Read(error)
    }
}

/// Loads mesh entry `i` into `triangles` (and its MTL materials into `materials`). Three
/// ways, each ending in [`Entry::complete`]: from the cache (a large mesh that glint's
/// reader placed before), by glint's reader (the scene names the material and the OBJ holds
/// only positions and faces), or by tobj (anything else).
pub(super) fn load(
    v: &Validator<'_>,
    i: usize,
    m: &MeshFile,
    mut out: Out<'_>,
) -> Result<(), SceneError> {
    let entry = Entry::new(v, i, m);
    let raw = v
        .stages
        .time("read", || (v.read)(&entry.obj_path))
        .map_err(|e| entry.fail(not_fetched(v.path, e)))?;
    let xf = mesh_transform(v, i, m)?;
    // A textured material needs the file's texture coordinates: such a mesh is neither
    // cached (the cache holds positions) nor read by glint's OBJ reader (which skips `vt`).
    let named_textured = m.material.as_ref().is_some_and(|name| {
        out.materials
            .iter()
            .any(|x| x.name == *name.get_ref() && x.maps() != (None, None))
    });
    let cached = entry.cache_key(&raw, &xf).filter(|_| !named_textured);
    if let (Some(name), Some((cache, key))) = (&m.material, &cached)
        && let Some(hit) = v.stages.time("cache read", || CachedMesh::load(cache, key))
    {
        drop(raw);
        return entry.add_cached(name, hit, &mut out);
    }
    if entry.is_ply() {
        let Some(name) = &m.material else {
            return Err(entry.fail(MeshError::PlyMaterial));
        };
        let bytes = v
            .stages
            .time("gunzip", || inflate(&entry.obj_path, raw, v.limit))
            .map_err(|e| entry.fail(e))?;
        let parsed = v
            .stages
            .time("PLY parse", || super::ply::parse(&bytes, entry.normals))
            .map_err(|e| entry.fail(MeshError::Ply(e)))?;
        drop(bytes);
        return entry.add_parsed(name, parsed, &xf, cached, &mut out);
    }
    if entry.is_gltf() {
        let g = v
            .stages
            .time("glTF parse", || {
                super::gltf::read(&raw, &entry.obj_path, v.read, entry.normals)
            })
            .map_err(|e| entry.fail(MeshError::Gltf(e)))?;
        drop(raw);
        return entry.add_gltf(g, &xf, cached, &mut out);
    }
    let (mut bytes, early) = entry.unpack(raw)?;
    let t_check = web_time::Instant::now();
    // A UTF-8 byte-order mark is allowed (some exporters write one); tobj would read the
    // first line as an unknown keyword.
    if bytes.starts_with(b"\xEF\xBB\xBF") {
        bytes.drain(..3);
    }
    let text = std::str::from_utf8(&bytes).map_err(|e| {
        entry.fail(MeshError::NotUtf8 {
            line: super::error::line_of_bytes(&bytes, e.valid_up_to()),
        })
    })?;
    if let Some(name) = m.material.as_ref().filter(|_| !named_textured) {
        let parsed = match early {
            Some(parsed) => parsed,
            None => v
                .stages
                .time("OBJ parse", || super::obj::parse(text, entry.normals)),
        }
        .map_err(|e| entry.fail(MeshError::Obj(e)))?;
        if let Some(parsed) = parsed {
            drop(bytes); // the text is parsed: free it before the triangles are placed
            return entry.add_parsed(name, parsed, &xf, cached, &mut out);
        }
    }
    entry.add_with_tobj(&bytes, text, &xf, t_check, &mut out)
}

/// One `[[meshes]]` entry being loaded: where the scene names it (for its errors and
/// warnings) and how its file is read.
struct Entry<'e> {
    v: &'e Validator<'e>,
    /// Its index in `[[meshes]]`.
    i: usize,
    m: &'e MeshFile,
    /// `meshes[i].file`.
    key: String,
    /// The scene's line of the entry's `file`.
    line: usize,
    /// The OBJ, relative to the scene's folder.
    obj_path: PathBuf,
    /// Whether the normals are read (a smooth mesh).
    normals: Normals,
}

/// What a mesh entry adds to: the scene's lists as far as they are built.
pub(super) struct Out<'o> {
    /// The scene's materials (a mesh's own are appended).
    pub materials: &'o mut Vec<Material>,
    /// The scene's triangles.
    pub triangles: &'o mut Vec<Triangle>,
    /// The smooth triangles' normals.
    pub smooth: &'o mut Vec<SmoothNormals>,
    /// The textured triangles' coordinates.
    pub uvs: &'o mut Vec<TextureCoords>,
    /// The textures read so far.
    pub textures: &'o mut TextureSet,
    /// The scene's warnings.
    pub warnings: &'o mut Vec<String>,
}

/// The faces of fewer than three vertices that a mesh dropped: how many, and the line of
/// the first.
#[derive(Clone, Copy)]
struct ShortFaces {
    count: usize,
    first: usize,
}

impl ShortFaces {
    /// Those of a parse's `short_faces` (lines in file order); `None` when there are none.
    fn of(lines: &[usize]) -> Option<ShortFaces> {
        lines.first().map(|&first| ShortFaces {
            count: lines.len(),
            first,
        })
    }
}

impl<'e> Entry<'e> {
    fn new(v: &'e Validator<'e>, i: usize, m: &'e MeshFile) -> Entry<'e> {
        let base = v.path.parent().unwrap_or(Path::new("."));
        Entry {
            v,
            i,
            m,
            key: format!("meshes[{i}].file"),
            line: line_of(v.src, m.file.span().start),
            obj_path: base.join(m.file.get_ref()),
            normals: if m.smooth == Some(true) {
                Normals::Read
            } else {
                Normals::Skip
            },
        }
    }

    /// Whether the entry's file name ends in one of `endings` (lower case), in any case.
    fn named(&self, endings: &[&str]) -> bool {
        let name = self.obj_path.to_string_lossy().to_ascii_lowercase();
        endings.iter().any(|e| name.ends_with(e))
    }

    /// Whether the entry's file is a PLY (`.ply` or `.ply.gz`, in any case).
    fn is_ply(&self) -> bool {
        self.named(&[".ply", ".ply.gz"])
    }

    /// Whether the entry's file is a glTF (`.gltf` or `.glb`, in any case).
    fn is_gltf(&self) -> bool {
        self.named(&[".gltf", ".glb"])
    }

    /// A glTF's triangles: all of the material the entry names, else each of its glTF
    /// material (added to the scene's, named `file#k:name`: diffuse, ka = kd = the base
    /// colour). Cached like an OBJ where the file holds its buffers and the entry names
    /// the material.
    fn add_gltf(
        &self,
        g: super::gltf::GltfMesh,
        xf: &Transform,
        cached: Option<(&Arc<Cache>, Key)>,
        out: &mut Out<'_>,
    ) -> Result<(), SceneError> {
        let (path, line, key) = (self.v.path.display(), self.line, &self.key);
        for w in &g.warnings {
            out.warnings.push(format!(
                "{path}:{line}: {key}: {}: {w}",
                self.obj_path.display()
            ));
        }
        if let Some(name) = &self.m.material {
            let cached = cached.filter(|_| g.self_contained);
            return self.add_parsed(name, g.parsed, xf, cached, out);
        }
        let base = out.materials.len() as u32;
        let mut images: Vec<Option<u32>> = vec![None; g.images.len()];
        for (k, image) in g.images.into_iter().enumerate() {
            if let Some((path, bytes)) = image {
                let id = out
                    .textures
                    .add_bytes(&path, &bytes, self.v.stages)
                    .map_err(|error| self.fail(MeshError::Texture { path, error }))?;
                images[k] = Some(id);
            }
        }
        for (k, gm) in g.materials.iter().enumerate() {
            let (name, c) = (&gm.name, &gm.base_colour);
            // The scene's own colour check, for the materials the scene takes from the file.
            super::validate::colour(*c).map_err(|message| {
                self.fail(MeshError::Gltf(super::GltfError::Material {
                    index: k,
                    name: name.clone(),
                    message,
                }))
            })?;
            out.materials.push(Material {
                name: format!("{}#{k}:{name}", self.m.file.get_ref()),
                model: Model::Diffuse,
                ka: *c,
                kd: *c,
                ks: [0.0; 3],
                n: 0.0,
                optics: super::Optics::default(),
                map_kd: gm.texture.and_then(|i| images[i]),
                map_ka: None,
            });
        }
        self.add_placed(g.parsed, xf, base, Some(&g.triangle_material), None, out)
    }

    /// `error` as the scene's: naming the scene file, the line, the key and the mesh.
    fn fail(&self, error: MeshError) -> SceneError {
        SceneError::Mesh {
            file: self.v.path.to_owned(),
            line: self.line,
            key: self.key.clone(),
            mesh: self.obj_path.clone(),
            error: Box::new(error),
        }
    }

    /// The index of the material the entry names, among the scene's `materials` so far.
    fn material(&self, name: &Spanned<String>, materials: &[Material]) -> Result<u32, SceneError> {
        let names: Vec<String> = materials.iter().map(|m| m.name.clone()).collect();
        let key = format!("meshes[{}].material", self.i);
        self.v.material_index(&names, name, &key)
    }

    /// Where a mesh that glint's reader places may be cached (see `crate::cache`), and its
    /// key: the file's bytes as read (`raw`), the transform, how normals are read, whether
    /// it is gzipped, and the input limit. `None` without a cache or a named material.
    fn cache_key(&self, raw: &[u8], xf: &Transform) -> Option<(&'e Arc<Cache>, Key)> {
        let cache = self.v.cache.filter(|_| self.m.material.is_some())?;
        let xf_bits: Vec<u8> = [xf.scale.to_array(), xf.translate.to_array()]
            .into_iter()
            .flatten()
            .chain(xf.rot.to_cols_array())
            .flat_map(f64::to_le_bytes)
            .collect();
        let settings = [
            (self.normals == Normals::Read) as u8,
            self.obj_path.extension().is_some_and(|e| e == "gz") as u8,
        ];
        let limit = self.v.limit.to_le_bytes();
        Some((cache, Key::new("mesh", &[raw, &xf_bits, &settings, &limit])))
    }

    /// The OBJ's text bytes from the file's (`raw`), and the parse when it came with them:
    /// a gzipped OBJ for glint's own reader is parsed as it is inflated (`gunzip_parse`);
    /// where that does not apply (see there) it is gunzipped whole (`gunzip`), then parsed.
    fn unpack(&self, raw: Vec<u8>) -> Result<(Vec<u8>, Option<ObjParse>), SceneError> {
        let is_gz = self.obj_path.extension().is_some_and(|e| e == "gz");
        let early = (self.m.material.is_some() && is_gz)
            .then(|| {
                gunzip_parse(
                    &raw,
                    self.normals,
                    GUNZIP_PIECE,
                    self.v.limit,
                    self.v.stages,
                )
            })
            .flatten();
        Ok(match early {
            Some((bytes, parsed)) => (bytes, Some(parsed)),
            None => (
                self.v
                    .stages
                    .time("gunzip", || gunzip(&self.obj_path, raw, self.v.limit))
                    .map_err(|e| self.fail(e))?,
                None,
            ),
        })
    }

    /// A mesh from the cache, of the material `name`.
    fn add_cached(
        &self,
        name: &Spanned<String>,
        hit: CachedMesh,
        out: &mut Out<'_>,
    ) -> Result<(), SceneError> {
        let material = self.material(name, out.materials)?;
        let before = out.triangles.len();
        out.triangles.extend(
            hit.vertices
                .into_iter()
                .map(|vertices| Triangle { vertices, material }),
        );
        self.complete(before, hit.short_faces, hit.normals, out)
    }

    /// A mesh that glint's reader parsed, of the material `name`: placed, its corner
    /// normals computed when it is smooth, and stored in `cached` when it is worth it.
    fn add_parsed(
        &self,
        name: &Spanned<String>,
        parsed: Parsed,
        xf: &Transform,
        cached: Option<(&Arc<Cache>, Key)>,
        out: &mut Out<'_>,
    ) -> Result<(), SceneError> {
        let material = self.material(name, out.materials)?;
        self.add_placed(parsed, xf, material, None, cached, out)
    }

    /// `parsed`'s triangles placed by `xf`, each of `material`, or of `material` plus its
    /// entry in `per_triangle` (a glTF's own materials, appended to the scene's from
    /// `material` on); its corner normals computed when it is smooth, and stored in
    /// `cached` when it is worth it.
    fn add_placed(
        &self,
        parsed: Parsed,
        xf: &Transform,
        material: u32,
        per_triangle: Option<&[u32]>,
        cached: Option<(&Arc<Cache>, Key)>,
        out: &mut Out<'_>,
    ) -> Result<(), SceneError> {
        let mut placed = self
            .v
            .stages
            .time("transform", || place_parsed(&parsed, xf, material))
            .map_err(|e| self.fail(e))?;
        if let Some(own) = per_triangle {
            for (t, m) in placed.iter_mut().zip(own) {
                t.material = material + m;
            }
        }
        let corner = match self.normals {
            Normals::Read => Some(
                self.v
                    .stages
                    .time("normals", || corner_normals(&parsed, xf))
                    .map_err(|e| self.fail(e))?,
            ),
            Normals::Skip => None,
        };
        if let Some((cache, key)) = cached.filter(|(c, _)| c.worth(placed.len())) {
            self.v.stages.time("cache write", || {
                CachedMesh::store(cache, &key, &placed, corner.as_deref(), &parsed.short_faces)
            });
        }
        let short = ShortFaces::of(&parsed.short_faces);
        let uvs = parsed.uvs;
        drop((
            parsed.vertices,
            parsed.triangles,
            parsed.normals,
            parsed.normal_ix,
        ));
        let before = out.triangles.len();
        if out.triangles.is_empty() {
            *out.triangles = placed; // moved, not copied (35 MB for the dragon)
        } else {
            out.triangles.extend(placed);
        }
        let end = out.triangles.len();
        self.add_uvs(before..end, uvs, out);
        self.complete(before, short, corner, out)
    }

    /// The texture coordinates of the triangles in `range` (`uvs`, one per triangle, or
    /// none), kept where some of those triangles' materials are textured; a warning where
    /// they are textured and the file has no coordinates.
    fn add_uvs(&self, range: std::ops::Range<usize>, uvs: Vec<[[f32; 2]; 3]>, out: &mut Out<'_>) {
        let textured = |t: &Triangle| out.materials[t.material as usize].maps() != (None, None);
        let added = &out.triangles[range.clone()];
        let Some(first) = added.iter().position(textured) else {
            return;
        };
        if uvs.len() == added.len() {
            out.uvs.push(TextureCoords {
                first: range.start,
                uvs,
            });
            return;
        }
        let name = &out.materials[added[first].material as usize].name;
        out.warnings.push(format!(
            "{}:{}: {}: {}: material {name:?} is textured but the file has no texture coordinates: untextured",
            self.v.path.display(),
            self.line,
            self.key,
            self.obj_path.display()
        ));
    }

    /// A mesh that tobj reads (`bytes`, whose `text` glint's reader checks first, so that
    /// its errors name lines), with the materials of its MTL unless the entry names one.
    fn add_with_tobj(
        &self,
        bytes: &[u8],
        text: &str,
        xf: &Transform,
        t_check: web_time::Instant,
        out: &mut Out<'_>,
    ) -> Result<(), SceneError> {
        let checked =
            super::obj::check(text, self.normals).map_err(|e| self.fail(MeshError::Obj(e)))?;
        self.v.stages.record("OBJ check", t_check.elapsed());
        let t_parse = web_time::Instant::now();
        let (models, mtl) = self.tobj_parse(bytes)?;
        let named = match &self.m.material {
            Some(name) => Some(self.material(name, out.materials)?),
            None => None,
        };
        // The MTL's materials, appended once, in file order.
        let mtl_base = out.materials.len() as u32;
        let mtl = match (named, mtl) {
            (Some(_), _) => Vec::new(),
            (None, Ok(m)) => m,
            (None, Err(e)) => return Err(self.fail(e)),
        };
        self.add_mtl_materials(&mtl, out.materials, out.textures)
            .map_err(|e| self.fail(e))?;
        self.v.stages.record("OBJ parse", t_parse.elapsed());
        let before = out.triangles.len();
        let material = |model: &tobj::Model| match (named, model.mesh.material_id) {
            (Some(k), _) => Some(k),
            (None, Some(id)) if id < mtl.len() => Some(mtl_base + id as u32),
            _ => None,
        };
        let runs = self
            .v
            .stages
            .time("transform", || {
                place_models(&models, material, xf, out.triangles)
            })
            .map_err(|e| self.fail(e))?;
        for (range, uvs) in runs {
            self.add_uvs(range, uvs, out);
        }
        let corner = match self.normals {
            Normals::Read => {
                // glint's reader gives tobj's triangles in tobj's order (tested in `obj`),
                // so the corner normals line up with the triangles just placed.
                let placed = out.triangles.len() - before;
                if checked.triangles.len() != placed {
                    return Err(self.fail(MeshError::Unpaired {
                        ours: checked.triangles.len(),
                        tobj: placed,
                    }));
                }
                Some(
                    self.v
                        .stages
                        .time("normals", || corner_normals(&checked, xf))
                        .map_err(|e| self.fail(e))?,
                )
            }
            Normals::Skip => None,
        };
        self.complete(before, ShortFaces::of(&checked.short_faces), corner, out)
    }

    /// tobj's objects in `bytes`, and the materials of the MTL it names (or why not: what
    /// the MTL's reader found wrong, else what tobj said).
    #[allow(clippy::type_complexity)]
    fn tobj_parse(
        &self,
        bytes: &[u8],
    ) -> Result<(Vec<tobj::Model>, Result<Vec<tobj::Material>, MeshError>), SceneError> {
        let opts = tobj::LoadOptions {
            triangulate: true,
            single_index: false,
            ignore_points: true,
            ignore_lines: true,
        };
        let obj_dir = self.obj_path.parent().unwrap_or(Path::new("."));
        let problem = std::cell::RefCell::new(None::<MeshError>);
        let (models, mtl) = tobj::load_obj_buf(&mut BufReader::new(bytes), &opts, |p| {
            self.read_mtl(obj_dir, p, &problem)
        })
        .map_err(|e| self.fail(problem.borrow_mut().take().unwrap_or(MeshError::Tobj(e))))?;
        let mtl = mtl.map_err(|e| problem.borrow_mut().take().unwrap_or(MeshError::TobjMtl(e)));
        Ok((models, mtl))
    }

    /// The MTL `p` that the OBJ names, for tobj: read through the scene's reader, and
    /// refused before tobj sees it when it is not an MTL text or has a colour that tobj 4
    /// would panic on. What was wrong is left in `problem`, for the error.
    fn read_mtl(
        &self,
        obj_dir: &Path,
        p: &Path,
        problem: &std::cell::RefCell<Option<MeshError>>,
    ) -> tobj::MTLLoadResult {
        let path = obj_dir.join(p);
        let mtl = (self.v.read)(&path).map_err(|error| {
            *problem.borrow_mut() = Some(MeshError::MtlRead { path, error });
            tobj::LoadError::OpenFileFailed
        })?;
        if let Some(error) = mtl_junk(&mtl).or_else(|| short_colour(&mtl)) {
            *problem.borrow_mut() = Some(MeshError::Mtl {
                file: p.to_owned(),
                error,
            });
            return Err(tobj::LoadError::MaterialParseError);
        }
        tobj::load_mtl_buf(&mut BufReader::new(&mtl[..]))
    }

    /// The MTL's materials appended to `materials`, in file order, each checked (finite,
    /// not negative, no colour above `MAX_COLOUR`) and named `file#k:name`.
    fn add_mtl_materials(
        &self,
        mtl: &[tobj::Material],
        materials: &mut Vec<Material>,
        textures: &mut TextureSet,
    ) -> Result<(), MeshError> {
        let dir = self.obj_path.parent().unwrap_or(Path::new("."));
        let mut map = |file: &Option<String>| -> Result<Option<u32>, MeshError> {
            let Some(file) = file else { return Ok(None) };
            let path = dir.join(file.trim());
            textures
                .add(&path, self.v.read, self.v.stages)
                .map(Some)
                .map_err(|error| MeshError::Texture { path, error })
        };
        for (k, mm) in mtl.iter().enumerate() {
            let ka = mm.ambient.unwrap_or([0.0; 3]);
            let kd = mm.diffuse.unwrap_or([0.8; 3]);
            let ks = mm.specular.unwrap_or([0.0; 3]);
            let n = mm.shininess.unwrap_or(0.0);
            let name = || mm.name.clone();
            if [ka, kd, ks]
                .iter()
                .flatten()
                .chain([&n])
                .any(|x| !x.is_finite() || *x < 0.0)
            {
                return Err(MeshError::MtlValue { name: name() });
            }
            if [ka, kd, ks]
                .iter()
                .flatten()
                .any(|&x| x > super::MAX_COLOUR)
            {
                return Err(MeshError::MtlColour { name: name() });
            }
            materials.push(Material {
                name: format!("{}#{k}:{}", self.m.file.get_ref(), mm.name),
                model: if ks == [0.0; 3] {
                    Model::Diffuse
                } else {
                    Model::Phong
                },
                ka,
                kd,
                ks,
                n,
                optics: super::Optics::default(),
                map_kd: map(&mm.diffuse_texture)?,
                map_ka: map(&mm.ambient_texture)?,
            });
        }
        Ok(())
    }

    /// The end of every way in: the warning for the faces dropped, the smooth normals of
    /// the triangles from `before` on, and the checks on those triangles: none is an
    /// error, zero-area ones a warning.
    fn complete(
        &self,
        before: usize,
        short: Option<ShortFaces>,
        normals: Option<Vec<[[f32; 3]; 3]>>,
        out: &mut Out<'_>,
    ) -> Result<(), SceneError> {
        let (path, line, key) = (self.v.path.display(), self.line, &self.key);
        if let Some(short) = short {
            out.warnings.push(format!(
                "{path}:{line}: {key}: {}: {}",
                self.obj_path.display(),
                short_face_warning(short)
            ));
        }
        if let Some(normals) = normals {
            out.smooth.push(SmoothNormals {
                first: before,
                normals,
            });
        }
        let added = &out.triangles[before..];
        if added.is_empty() {
            return Err(self.fail(MeshError::Empty));
        }
        let degenerate = {
            use rayon::prelude::*;
            added
                .par_iter()
                .filter(|t| is_degenerate(&t.vertices))
                .count()
        };
        if degenerate > 0 {
            out.warnings.push(format!(
                "{path}:{line}: {key}: {degenerate} zero-area triangles (never hit)"
            ));
        }
        Ok(())
    }
}

/// `parsed`'s triangles placed by `xf`, of `material`. Each position is transformed once,
/// then the triangles gathered from them: the same numbers as transforming each
/// triangle's corners (`Transform::apply` is a pure function of the position).
fn place_parsed(
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
fn place_models(
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
fn model_uvs(model: &tobj::Model) -> Result<Vec<[[f32; 2]; 3]>, MeshError> {
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
fn mesh_transform(v: &Validator<'_>, i: usize, m: &MeshFile) -> Result<Transform, SceneError> {
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
fn place(xf: &Transform, ps: [[f32; 3]; 3]) -> Result<[[f32; 3]; 3], FaceError> {
    check_placed(ps, ps.map(|p| xf.apply(p)))
}

/// `vs`, the transformed `ps`, when both are finite.
fn check_placed(ps: [[f32; 3]; 3], vs: [[f32; 3]; 3]) -> Result<[[f32; 3]; 3], FaceError> {
    if ps.iter().flatten().any(|x| !x.is_finite()) {
        return Err(FaceError::NotFinite);
    }
    if vs.iter().flatten().any(|x| !x.is_finite()) {
        return Err(FaceError::Overflow);
    }
    Ok(vs)
}

/// The warning for the faces of fewer than three vertices that a mesh dropped.
fn short_face_warning(short: ShortFaces) -> String {
    let ShortFaces { count: n, first } = short;
    format!(
        "{n} face(s) with fewer than three vertices dropped (line {first}{})",
        if n > 1 { " and others" } else { "" }
    )
}

/// Why an MTL's bytes are not an MTL text, at its line: not UTF-8, a NUL byte, or a line
/// longer than `obj::MAX_LINE_BYTES`.
fn mtl_junk(mtl: &[u8]) -> Option<ObjError> {
    if let Err(e) = std::str::from_utf8(mtl) {
        let line = super::error::line_of_bytes(mtl, e.valid_up_to()) as u32;
        return Some(ObjError::NotUtf8 { line });
    }
    super::obj::junk(mtl, true)
}

/// The first line of an MTL whose Ka, Kd, Ks or Ke has fewer than three values: tobj 4
/// panics on those, so they are refused before it sees them.
fn short_colour(mtl: &[u8]) -> Option<ObjError> {
    let text = String::from_utf8_lossy(mtl);
    text.lines()
        .position(|l| {
            let mut words = l.split_whitespace();
            matches!(words.next(), Some("Ka" | "Kd" | "Ks" | "Ke")) && words.count() < 3
        })
        .map(|k| ObjError::ShortColour { line: k as u32 + 1 })
}

/// What the cache holds for a mesh read by glint's own reader: its triangles as placed,
/// their corner normals when smooth, and its short faces (for the warning).
struct CachedMesh {
    vertices: Vec<[[f32; 3]; 3]>,
    normals: Option<Vec<[[f32; 3]; 3]>>,
    short_faces: Option<ShortFaces>,
}

impl CachedMesh {
    fn load(cache: &Cache, key: &Key) -> Option<CachedMesh> {
        let mut s = cache.load("mesh", key)?.into_iter();
        let (vertices, normals, short) = (s.next()?, s.next()?, s.next()?);
        let (count, first) = (*short.first()? as usize, *short.get(1)? as usize);
        Some(CachedMesh {
            vertices: crate::cache::section_as(vertices),
            normals: (!normals.is_empty()).then(|| crate::cache::section_as(normals)),
            short_faces: (count > 0).then_some(ShortFaces { count, first }),
        })
    }

    fn store(
        cache: &Arc<Cache>,
        key: &Key,
        placed: &[Triangle],
        normals: Option<&[[[f32; 3]; 3]]>,
        short_faces: &[usize],
    ) {
        let mut vertices: Vec<u32> = Vec::with_capacity(placed.len() * 9);
        for t in placed {
            for v in t.vertices {
                vertices.extend(v.map(f32::to_bits));
            }
        }
        let short = [
            short_faces.len() as u32,
            short_faces.first().copied().unwrap_or(0) as u32,
        ];
        let normals: Vec<u32> = normals.map_or(Vec::new(), |n| bytemuck::cast_slice(n).to_vec());
        // The text's vertices are already a copy of their own: written on a thread of
        // their own where the program lets the cache write behind (`glint render` does),
        // while the scene is flattened and its BVH built.
        cache.store_owned("mesh", *key, vec![vertices, normals, short.to_vec()]);
    }
}

/// The bytes of an OBJ file as read (`raw`), gunzipped (at most `limit` bytes) when the
/// name ends in `.gz`.
/// A binary file's bytes, inflated where its name ends in `.gz`, at most `limit` of them
/// (unlike [`gunzip`], which refuses what no OBJ text holds).
fn inflate(path: &Path, raw: Vec<u8>, limit: u64) -> Result<Vec<u8>, MeshError> {
    if path.extension().is_none_or(|e| e != "gz") {
        return Ok(raw);
    }
    use std::io::Read;
    let mut out = Vec::new();
    flate2::read::GzDecoder::new(&raw[..])
        .take(limit + 1)
        .read_to_end(&mut out)
        .map_err(MeshError::Gunzip)?;
    if out.len() as u64 > limit {
        return Err(MeshError::Unpacked { limit });
    }
    Ok(out)
}

fn gunzip(path: &Path, raw: Vec<u8>, limit: u64) -> Result<Vec<u8>, MeshError> {
    if path.extension().is_some_and(|e| e == "gz") {
        use std::io::Read;
        let mut out = Vec::new();
        let mut dec = flate2::read::GzDecoder::new(&raw[..]).take(limit + 1);
        // Inflated a block at a time and watched for what no OBJ has (a NUL byte, a line
        // longer than `obj::MAX_LINE_BYTES`), so that binary junk is refused after the
        // first megabyte of it, not after the whole input limit.
        let mut line_start = 0usize;
        loop {
            let old = out.len();
            out.resize(old + GUNZIP_BLOCK, 0);
            let n = dec.read(&mut out[old..]).map_err(MeshError::Gunzip)?;
            out.truncate(old + n);
            if n == 0 {
                break;
            }
            let new = &out[old..];
            let first_nl = new.iter().position(|&b| b == b'\n');
            let long = match first_nl {
                Some(k) => old + k - line_start > super::obj::MAX_LINE_BYTES,
                None => out.len() - line_start > super::obj::MAX_LINE_BYTES,
            };
            if long || new.contains(&0) {
                let why = super::obj::junk(&out, false).unwrap_or(ObjError::NotText { line: 1 });
                return Err(MeshError::Obj(why));
            }
            if first_nl.is_some() {
                line_start = old + 1 + new.iter().rposition(|&b| b == b'\n').unwrap_or(0);
            }
        }
        if out.len() as u64 > limit {
            return Err(MeshError::Unpacked { limit });
        }
        return Ok(out);
    }
    Ok(raw)
}

/// What `obj::parse` returns.
type ObjParse = Result<Option<Parsed>, ObjError>;

/// The bytes of text `gunzip_parse` inflates before it hands them to a parse.
const GUNZIP_PIECE: usize = 2 << 20;

/// The bytes `gunzip` inflates at a time, at most a line's length
/// (`obj::MAX_LINE_BYTES`): a line that ends inside a block is no longer than the block.
const GUNZIP_BLOCK: usize = 1 << 20;
const _: () = assert!(GUNZIP_BLOCK <= super::obj::MAX_LINE_BYTES);

/// Gunzips `raw` and parses the OBJ with glint's reader at once: pieces of about `piece`
/// bytes of whole lines are parsed in parallel (`obj::parse_piece`) while the rest is
/// inflated, then joined in file order (`obj::join_pieces`), which gives what `obj::parse`
/// gives for the whole text. Returns the text's bytes and the parse, or `None` where this
/// does not apply and the caller reads the file the ordinary way, which then reports
/// whatever is wrong as it always has: the gzip trailer's size (ISIZE) is 0, above the
/// input limit, or not the size inflated (a multi-member or damaged file); the inflate
/// fails; a piece is not UTF-8; the text starts with a byte-order mark.
/// Stages: "gunzip" is the time spent inflating, "OBJ parse" the wait after it.
fn gunzip_parse(
    raw: &[u8],
    normals: Normals,
    piece: usize,
    limit: u64,
    stages: &crate::stages::Stages,
) -> Option<(Vec<u8>, ObjParse)> {
    use std::io::Read;
    use std::sync::Mutex;
    let t0 = web_time::Instant::now();
    let isize_bytes: [u8; 4] = raw.get(raw.len().checked_sub(4)?..)?.try_into().ok()?;
    let size = u32::from_le_bytes(isize_bytes) as usize;
    if size == 0 || size as u64 > limit {
        return None;
    }
    let mut buf = vec![0u8; size];
    let mut inflating = std::time::Duration::ZERO;
    let mut ok = true;
    let mut junk = None;
    let pieces: Mutex<Vec<(usize, Option<super::obj::Piece>)>> = Mutex::new(Vec::new());
    rayon::scope(|s| {
        let mut dec = flate2::read::GzDecoder::new(raw);
        let mut rest: &mut [u8] = &mut buf[..];
        // Bytes at the head of `rest` inflated but not yet handed out.
        let mut filled = 0usize;
        // The pieces handed out, to number the line of a junk error.
        let mut handed: Vec<&[u8]> = Vec::new();
        for index in 0.. {
            let t = web_time::Instant::now();
            let mut want = (filled + piece).min(rest.len());
            let mut cut = None;
            // Bytes of `rest` already searched for a line end (each byte once: a long line
            // read on is not searched again from its start).
            let mut searched = 0usize;
            while cut.is_none() {
                while filled < want {
                    match dec.read(&mut rest[filled..want]) {
                        Ok(0) => break,
                        Ok(n) => filled += n,
                        Err(_) => {
                            ok = false;
                            break;
                        }
                    }
                }
                if !ok {
                    break;
                }
                if filled < want || filled == rest.len() {
                    // The end of the stream, or of the buffer: all that is left.
                    cut = Some(filled);
                } else if let Some(nl) = rest[searched..filled].iter().rposition(|&b| b == b'\n') {
                    cut = Some(searched + nl + 1);
                } else if filled > super::obj::MAX_LINE_BYTES || rest[searched..filled].contains(&0)
                {
                    // No line end in more than a line's length, or a NUL: not an OBJ text.
                    let before: usize = handed
                        .iter()
                        .map(|h| super::error::line_of_bytes(h, h.len()) - 1)
                        .sum();
                    let why = super::obj::junk(&rest[..filled], false)
                        .unwrap_or(ObjError::NotText { line: 1 });
                    junk = Some(why.after(before as u32));
                    break;
                } else {
                    searched = filled;
                    want = (want + piece).min(rest.len()); // one long line: read on
                }
            }
            if junk.is_some() {
                break;
            }
            let at_end = filled < want || filled == rest.len();
            if at_end && ok {
                // The stream must end where ISIZE said.
                ok = filled == rest.len() && matches!(dec.read(&mut [0u8; 1]), Ok(0));
            }
            inflating += t.elapsed();
            let Some(cut) = cut.filter(|_| ok) else { break };
            let (head, tail) = std::mem::take(&mut rest).split_at_mut(cut);
            rest = tail;
            filled -= cut;
            let head: &[u8] = head;
            handed.push(head);
            if index == 0 && head.starts_with(b"\xEF\xBB\xBF") {
                ok = false;
                break;
            }
            let pieces = &pieces;
            s.spawn(move |_| {
                let parsed = std::str::from_utf8(head)
                    .ok()
                    .map(|text| super::obj::parse_piece(text, normals));
                if let Ok(mut p) = pieces.lock() {
                    p.push((index, parsed));
                }
            });
            if at_end {
                break;
            }
        }
    });
    stages.record("gunzip", inflating);
    if let Some(why) = junk {
        return Some((Vec::new(), Err(why)));
    }
    let mut pieces = pieces.into_inner().ok()?;
    if !ok {
        return None;
    }
    pieces.sort_by_key(|(index, _)| *index);
    let pieces: Option<Vec<super::obj::Piece>> = pieces.into_iter().map(|(_, p)| p).collect();
    let parsed = super::obj::join_pieces(pieces?, normals);
    stages.record("OBJ parse", t0.elapsed().saturating_sub(inflating));
    Some((buf, parsed))
}

#[cfg(test)]
mod tests {
    use super::{FaceError, MeshError, Normals, Transform, gunzip_parse};
    use crate::scene::{ObjError, ReadError, Scene, SceneError, obj};
    use crate::stages::Stages;
    use std::path::Path;

    /// A scene of one mesh `m.obj` (scaled by `scale` in x), read through `read`.
    fn one_mesh(scale: &str, read: &crate::scene::ReadFile<'_>) -> Result<Scene, SceneError> {
        let src = format!(
            "[camera]\neye = [0.0, 0.0, 5.0]\nlook_at = [0.0, 0.0, 0.0]\nfov = 45.0\n\
             width = 4\nheight = 4\n[materials.m]\nmodel = \"ambient\"\nka = [1.0, 1.0, 1.0]\n\
             [[meshes]]\nfile = \"m.obj\"\nmaterial = \"m\"\nscale = [{scale}, 1.0, 1.0]\n"
        );
        Scene::parse_with(&src, Path::new("s.toml"), read)
    }

    /// `one_mesh` with `obj` as the mesh's text.
    fn with_obj(scale: &str, obj: &str) -> Result<Scene, SceneError> {
        one_mesh(scale, &|_: &Path| Ok(obj.as_bytes().to_vec()))
    }

    /// The mesh error inside a scene error, which must name the entry's line and key.
    fn mesh_error(e: &SceneError) -> &MeshError {
        match e {
            SceneError::Mesh {
                line, key, error, ..
            } => {
                assert_eq!((*line, key.as_str()), (11, "meshes[0].file"), "{e}");
                error
            }
            _ => panic!("not a mesh error: {e}"),
        }
    }

    #[test]
    fn mesh_errors_are_typed_and_print_file_line_key_and_the_meshs_line() {
        let tri = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
        let e = with_obj("1.0", &format!("{tri}f 1 2 9\n")).unwrap_err();
        assert!(matches!(
            mesh_error(&e),
            MeshError::Obj(ObjError::VertexIndex {
                line: 4,
                index: 9,
                defined: 3
            })
        ));
        assert_eq!(
            e.to_string(),
            "s.toml:11: meshes[0].file: mesh m.obj: line 4: face vertex index 9 is out of range (3 vertices defined before it)"
        );
        let e = with_obj("1e30", &format!("v 1e10 0 0\n{tri}f 1 2 3\nf 2 3 4\n")).unwrap_err();
        assert!(matches!(
            mesh_error(&e),
            MeshError::Face {
                face: 0,
                why: FaceError::Overflow
            }
        ));
        assert!(
            e.to_string()
                .ends_with("mesh m.obj: face 0: the transform overflows f32")
        );
        let e = one_mesh("1.0", &|_: &Path| Err(ReadError::Other("gone".into()))).unwrap_err();
        assert!(matches!(
            mesh_error(&e),
            MeshError::Read(ReadError::Other(_))
        ));
        assert_eq!(e.to_string(), "s.toml:11: meshes[0].file: mesh m.obj: gone");
        let e = with_obj("1.0", "# nothing\n").unwrap_err();
        assert!(matches!(mesh_error(&e), MeshError::Empty));
        // The twins: the same mesh with its faces in range, and a scale that keeps f32,
        // loads.
        let ok = with_obj("1e30", &format!("{tri}f 1 2 3\n")).unwrap();
        assert_eq!(ok.triangles.len(), 1);
        assert!(with_obj("1e20", &format!("v 1e10 0 0\n{tri}f 1 2 3\n")).is_ok());
    }

    fn gz(bytes: &[u8]) -> Vec<u8> {
        use std::io::Write;
        let mut e = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
        e.write_all(bytes).unwrap();
        e.finish().unwrap()
    }

    /// `obj::parse`'s result (or error) as text, to compare whole results.
    fn shown(r: &Result<Option<obj::Parsed>, obj::ObjError>) -> String {
        format!("{r:?}")
    }

    /// An OBJ with comments, groups, polygons, negative indices, normals, CRLF line ends,
    /// a long line and a short face.
    fn sample() -> String {
        let mut s = String::from("# a comment\r\no thing\r\n");
        for k in 0..3000 {
            s += &format!("v {k} 0.5 -1e-3\nv {k} 1 0\r\nv {k} 0 1\nvn 0 0 1\n");
            s += &format!(
                "f -3//1 -2//1 -1//1\ng g{k}\nf {} {} {} {}\n",
                1,
                2,
                3,
                3 * k + 3
            );
        }
        s += &format!("# {}\nf 1 2\nf 1 2 3", "x".repeat(5000));
        s
    }

    #[test]
    fn parsing_while_inflating_gives_what_parsing_the_whole_text_gives() {
        let text = sample();
        let gzipped = gz(text.as_bytes());
        for normals in [Normals::Skip, Normals::Read] {
            let whole = obj::parse(&text, normals);
            assert!(matches!(whole, Ok(Some(_))), "{}", shown(&whole));
            for piece in [1, 7, 100, 4096, 1 << 20] {
                let (bytes, parsed) =
                    gunzip_parse(&gzipped, normals, piece, 1 << 30, &Stages::new())
                        .expect("streamed");
                assert_eq!(bytes, text.as_bytes(), "piece {piece}");
                assert_eq!(shown(&parsed), shown(&whole), "piece {piece}");
            }
        }
        // The twin: the same two pieces joined in the wrong order give another result, and
        // the comparison sees it.
        let cut = text[..text.len() / 2].rfind('\n').unwrap() + 1;
        let (a, b) = text.split_at(cut);
        let piece = |t| obj::parse_piece(t, Normals::Skip);
        let swapped = obj::join_pieces(vec![piece(b), piece(a)], Normals::Skip);
        assert_ne!(shown(&swapped), shown(&obj::parse(&text, Normals::Skip)));
    }

    #[test]
    fn errors_and_tobj_files_come_out_as_from_the_whole_text() {
        let bad = sample() + "\nv 1 2\nf 1 2 3\n";
        let needs_tobj = sample() + "\nusemtl red\nf 1 2 3\n";
        for text in [bad, needs_tobj] {
            let whole = obj::parse(&text, Normals::Skip);
            assert!(!matches!(whole, Ok(Some(_))));
            for piece in [1, 100, 1 << 20] {
                let (_, parsed) = gunzip_parse(
                    &gz(text.as_bytes()),
                    Normals::Skip,
                    piece,
                    1 << 30,
                    &Stages::new(),
                )
                .unwrap();
                assert_eq!(shown(&parsed), shown(&whole), "piece {piece}");
            }
        }
    }

    #[test]
    fn what_it_cannot_stream_is_left_to_the_ordinary_path() {
        let text = sample();
        let good = gz(text.as_bytes());
        // A trailer that lies about the size, either way.
        for delta in [1u32, u32::MAX] {
            let mut lying = good.clone();
            let n = lying.len();
            let size = u32::from_le_bytes(lying[n - 4..].try_into().unwrap());
            lying[n - 4..].copy_from_slice(&size.wrapping_add(delta).to_le_bytes());
            assert!(
                gunzip_parse(&lying, Normals::Skip, 100, 1 << 30, &Stages::new()).is_none(),
                "{delta}"
            );
        }
        // Two members (the first's size alone in the last trailer), a damaged stream, a
        // byte-order mark, bytes that are not UTF-8, an empty file, a short one.
        let two = [gz(text.as_bytes()), gz(b"v 1 2 3\n")].concat();
        let mut damaged = good.clone();
        damaged[good.len() / 2] ^= 0x55;
        let bom = gz(&[b"\xEF\xBB\xBF".as_slice(), text.as_bytes()].concat());
        let latin1 = gz(&[text.as_bytes(), b"\n# caf\xE9\n"].concat());
        for (what, raw) in [
            ("two members", two),
            ("damaged", damaged),
            ("bom", bom),
            ("latin-1", latin1),
            ("empty", gz(b"")),
            ("short", vec![0x1f, 0x8b]),
        ] {
            assert!(
                gunzip_parse(&raw, Normals::Skip, 100, 1 << 30, &Stages::new()).is_none(),
                "{what}"
            );
        }
    }

    /// The transform as it was written out by hand before glam: rows of Rz·Ry·Rx summed
    /// left to right. glam's must give the same f32 vertices, bit for bit.
    fn by_hand(scale: [f32; 3], rot: [f32; 3], tr: [f32; 3], p: [f32; 3]) -> [f32; 3] {
        let [ax, ay, az] = rot.map(|d| (d as f64).to_radians());
        let (sx, cx) = ax.sin_cos();
        let (sy, cy) = ay.sin_cos();
        let (sz, cz) = az.sin_cos();
        let rx = [[1.0, 0.0, 0.0], [0.0, cx, -sx], [0.0, sx, cx]];
        let ry = [[cy, 0.0, sy], [0.0, 1.0, 0.0], [-sy, 0.0, cy]];
        let rz = [[cz, -sz, 0.0], [sz, cz, 0.0], [0.0, 0.0, 1.0]];
        let mul = |a: [[f64; 3]; 3], b: [[f64; 3]; 3]| {
            let mut m = [[0.0; 3]; 3];
            for (i, row) in m.iter_mut().enumerate() {
                for (j, x) in row.iter_mut().enumerate() {
                    *x = a[i][0] * b[0][j] + a[i][1] * b[1][j] + a[i][2] * b[2][j];
                }
            }
            m
        };
        let r = mul(rz, mul(ry, rx));
        let s = [0, 1, 2].map(|k| p[k] as f64 * scale[k] as f64);
        [0, 1, 2].map(|i| (r[i][0] * s[0] + r[i][1] * s[1] + r[i][2] * s[2] + tr[i] as f64) as f32)
    }

    #[test]
    fn glam_transform_equals_the_written_out_one() {
        let mut x = 7u64;
        let mut r = |lo: f32, hi: f32| {
            x = x
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            lo + (hi - lo) * ((x >> 40) as f32 / (1u64 << 24) as f32)
        };
        for _ in 0..10_000 {
            let scale = [r(-3.0, 3.0), r(-3.0, 3.0), r(-3.0, 3.0)];
            let rot = [r(-360.0, 360.0), r(-360.0, 360.0), r(-360.0, 360.0)];
            let tr = [r(-100.0, 100.0), r(-100.0, 100.0), r(-100.0, 100.0)];
            let p = [r(-50.0, 50.0), r(-50.0, 50.0), r(-50.0, 50.0)];
            let xf = Transform::new(scale, rot, tr);
            let (a, b) = (xf.apply(p), by_hand(scale, rot, tr, p));
            assert_eq!(
                a.map(f32::to_bits),
                b.map(f32::to_bits),
                "{scale:?} {rot:?} {tr:?} {p:?}"
            );
        }
    }
}
