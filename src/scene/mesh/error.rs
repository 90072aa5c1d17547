//! What is wrong with a mesh file or one of its faces.

use super::*;

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
        /// The limit, bytes ([`crate::scene::LoadOptions::max_input_bytes`]).
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
    /// An MTL material with a colour component above [`crate::scene::MAX_COLOUR`].
    #[error(
        "MTL material {name:?} has a colour component above {:e}",
        crate::scene::MAX_COLOUR
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
    Ply(crate::scene::PlyError),
    /// A glTF file is wrong.
    #[error("{0}")]
    Gltf(crate::scene::GltfError),
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
