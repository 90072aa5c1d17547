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

mod error;
mod gunzip;
mod place;
#[cfg(test)]
mod tests;
mod transform;

pub use error::{FaceError, MeshError};
use gunzip::{GUNZIP_PIECE, ObjParse, gunzip, gunzip_parse, inflate};
use place::{mesh_transform, place_models, place_parsed};
pub(super) use transform::Transform;
use transform::corner_normals;

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
