//! AOVs (arbitrary output variables): which of them a render writes ([`Aov`]), a frame of
//! them ([`AovImage`]), and how they are stored: as channels of the colour's EXR, or as
//! PNGs beside the colour's (docs/aov.md says what each one means).

use std::fmt;
use std::path::{Path, PathBuf};
use std::str::FromStr;

use crate::buffers::{AovOut, PRIM_NONE, TRIANGLE_BIT};
use crate::cpu::packet::AovLanes;
use crate::image::{ChannelData, ImageError};
use crate::scene::Scene;

/// One AOV. Each describes the primary ray through the pixel's centre, whatever the
/// antialiasing, so ids and normals are never blends of two surfaces.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Aov {
    /// Distance along the unit primary ray to the hit (−1 on a miss).
    T,
    /// Camera-space depth: the hit's distance along the camera's forward axis (−1 on a miss).
    Depth,
    /// The hit point, world space.
    Position,
    /// The geometric normal, unit, world space, turned to face the camera.
    GeoNormal,
    /// The shading normal (the interpolated vertex normals of a smooth mesh, else the
    /// geometric normal), unit, world space, on the geometric normal's side.
    Normal,
    /// The diffuse reflectance kd, after textures.
    Albedo,
    /// The primitive hit: spheres 0.. in file order, then triangles.
    PrimId,
    /// The object hit: each sphere, then each `[[triangles]]` entry and each mesh.
    ObjectId,
    /// The material's index in [`Scene::materials`].
    MaterialId,
    /// 1 where the ray hit something, else 0.
    Mask,
}

/// An AOV name that is not one.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("unknown AOV {0:?}: the AOVs are {names}", names = Aov::names())]
pub struct UnknownAov(pub String);

/// Why AOVs could not be written where they were asked for.
#[derive(Debug, thiserror::Error)]
pub enum AovError {
    /// An unknown name.
    #[error(transparent)]
    Unknown(#[from] UnknownAov),
    /// `position` has no PNG form.
    #[error(
        "{}: the AOV `{aov}` needs an EXR output (-o NAME.exr): a PNG holds no signed \
         coordinates",
        path.display()
    )]
    NotInPng {
        /// The colour's PNG.
        path: PathBuf,
        /// The AOV.
        aov: Aov,
    },
    /// An id beyond a PNG's 24 bits.
    #[error(
        "{}: {aov} {id} does not fit the PNG's 24 bits: write an EXR (-o NAME.exr)",
        path.display()
    )]
    IdTooLarge {
        /// The AOV's PNG.
        path: PathBuf,
        /// The AOV.
        aov: Aov,
        /// The id.
        id: u32,
    },
}

impl Aov {
    /// Every AOV, in the order files and reports list them.
    pub const ALL: [Aov; 10] = [
        Aov::T,
        Aov::Depth,
        Aov::Position,
        Aov::GeoNormal,
        Aov::Normal,
        Aov::Albedo,
        Aov::PrimId,
        Aov::ObjectId,
        Aov::MaterialId,
        Aov::Mask,
    ];

    /// Its name on the command line, in Python and in channel names.
    pub fn name(self) -> &'static str {
        match self {
            Aov::T => "t",
            Aov::Depth => "depth",
            Aov::Position => "position",
            Aov::GeoNormal => "geo_normal",
            Aov::Normal => "normal",
            Aov::Albedo => "albedo",
            Aov::PrimId => "prim_id",
            Aov::ObjectId => "object_id",
            Aov::MaterialId => "material_id",
            Aov::Mask => "mask",
        }
    }

    /// Every name, comma-separated.
    pub fn names() -> String {
        Aov::ALL.map(Aov::name).join(", ")
    }

    /// Its channels' suffixes: `X`, `Y`, `Z` for a point or a direction, `R`, `G`, `B` for
    /// the albedo, none for a scalar.
    pub fn components(self) -> &'static [&'static str] {
        match self {
            Aov::Position | Aov::GeoNormal | Aov::Normal => &["X", "Y", "Z"],
            Aov::Albedo => &["R", "G", "B"],
            _ => &[],
        }
    }

    /// Its channels' names in an EXR: `depth`, or `normal.X`, `normal.Y`, `normal.Z`.
    pub fn channel_names(self) -> Vec<String> {
        match self.components() {
            [] => vec![self.name().to_string()],
            c => c.iter().map(|s| format!("{}.{s}", self.name())).collect(),
        }
    }

    /// Whether it is an integer id (stored as 32-bit unsigned integers, exactly).
    pub fn is_id(self) -> bool {
        matches!(self, Aov::PrimId | Aov::ObjectId | Aov::MaterialId)
    }

    /// A comma-separated list (`depth,normal,prim_id`): the AOVs in [`Aov::ALL`]'s order,
    /// each once.
    pub fn parse_list(list: &str) -> Result<Vec<Aov>, UnknownAov> {
        let mut out = list
            .split(',')
            .map(|s| s.trim().parse::<Aov>())
            .collect::<Result<Vec<_>, _>>()?;
        out.sort();
        out.dedup();
        Ok(out)
    }
}

impl FromStr for Aov {
    type Err = UnknownAov;

    fn from_str(s: &str) -> Result<Aov, UnknownAov> {
        Aov::ALL
            .into_iter()
            .find(|a| a.name() == s)
            .ok_or_else(|| UnknownAov(s.to_string()))
    }
}

impl fmt::Display for Aov {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// How a frame's ids are numbered for its user, from the shader's primitive ids.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct IdMap {
    /// The scene's spheres (ids 0..spheres).
    spheres: u32,
    /// The first triangle of each triangle object (`[[triangles]]` entry or mesh), in
    /// [`Scene::triangle_sources`]' order.
    object_firsts: Vec<u32>,
}

impl IdMap {
    /// The numbering of `scene`'s primitives and objects.
    pub fn new(scene: &Scene) -> IdMap {
        IdMap {
            spheres: scene.sphere_sources.len() as u32,
            object_firsts: scene
                .triangle_sources
                .iter()
                .map(|(first, _)| *first as u32)
                .collect(),
        }
    }

    /// The primitive id of shader id `prim` (`TRIANGLE_BIT` for triangles): spheres
    /// first, then triangles; `PRIM_NONE` stays.
    pub fn prim_id(&self, prim: u32) -> u32 {
        match prim {
            PRIM_NONE => PRIM_NONE,
            p if p & TRIANGLE_BIT != 0 => self.spheres + (p & !TRIANGLE_BIT),
            p => p,
        }
    }

    /// The object id of shader id `prim`: a sphere's own index, or the spheres' count plus
    /// the index of the triangle's object; `PRIM_NONE` stays.
    pub fn object_id(&self, prim: u32) -> u32 {
        match prim {
            PRIM_NONE => PRIM_NONE,
            p if p & TRIANGLE_BIT != 0 => {
                let k = p & !TRIANGLE_BIT;
                let group = self.object_firsts.partition_point(|&f| f <= k);
                self.spheres + group.saturating_sub(1) as u32
            }
            p => p,
        }
    }
}

/// Where a channel of an EXR with AOVs comes from ([`AovImage::exr_layout`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum ExrSource {
    /// Component `c` of the colour's `[r, g, b, t]`.
    Colour(usize),
    /// The frame's plane `k` (the AOVs' channels in the order held).
    Plane(usize),
}

/// A frame of AOVs, row-major, top row first: the AOVs asked for, each as planes of its
/// channels (one a component), so a frame holds only what was asked (depth, normal and
/// three ids: 28 bytes a pixel, where the shader's whole record is 64). The planes share
/// one block of memory, whose pages are first touched where the tracer writes them.
#[derive(Clone, Debug, PartialEq)]
pub struct AovImage {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// The AOVs held, each once, in the order asked.
    aovs: Vec<Aov>,
    /// Every channel's plane, one after the other in `aovs`' order; a float's bits or an
    /// id (numbered by [`AovImage::ids`]).
    data: Vec<u32>,
    /// The numbering of the scene's primitives and objects.
    pub ids: IdMap,
}

/// Fills `out` with `f` of each record.
#[inline(always)]
fn fill(out: &mut [u32], records: &[AovOut], f: impl Fn(&AovOut) -> u32) {
    for (o, r) in out.iter_mut().zip(records) {
        *o = f(r);
    }
}

/// A block of whole rows of an [`AovImage`], written by one thread: what the CPU tracer
/// gives its records to ([`crate::cpu::RecordRows`]), keeping the AOVs asked for.
pub struct AovRows<'a> {
    width: usize,
    ids: &'a IdMap,
    /// Each channel's rows: the AOV, its component, the plane's part.
    planes: Vec<(Aov, usize, &'a mut [u32])>,
}

const PW: usize = crate::cpu::packet::PACKET_W as usize;

/// Writes `packets` (consecutive, of the same rows; `put_lanes` gives one) into `plane`'s
/// rows `0 .. rows` from column `x`, the last packet `last_cols` wide: `f(packet, y)`
/// gives a packet's row y. (Written for a run of packets, it compiles to faster code for
/// one than a loop written for one packet did: bb8 with five AOVs, 17.0 against 23.0 ms.)
#[inline(always)]
fn put_packets(
    plane: &mut [u32],
    width: usize,
    (x, rows, last_cols): (usize, usize, usize),
    packets: &[AovLanes],
    f: impl Fn(&AovLanes, usize) -> [u32; PW],
) {
    let cols = (packets.len() - 1) * PW + last_cols;
    for y in 0..rows {
        let row = &mut plane[y * width + x..y * width + x + cols];
        let mut chunks = row.chunks_exact_mut(PW);
        for (out, lanes) in (&mut chunks).zip(packets) {
            out.copy_from_slice(&f(lanes, y));
        }
        let rest = chunks.into_remainder();
        if !rest.is_empty() {
            let n = rest.len();
            rest.copy_from_slice(&f(&packets[packets.len() - 1], y)[..n]);
        }
    }
}

/// Row y of a packet's lane array, as bits.
#[inline(always)]
fn quad(a: &[f32; crate::cpu::packet::LANES], y: usize) -> [u32; PW] {
    let mut out = [0u32; PW];
    for (d, o) in out.iter_mut().enumerate() {
        *o = a[y * PW + d].to_bits();
    }
    out
}

/// Row y of a packet's ids, each through `f`.
#[inline(always)]
fn quad_ids(a: &[u32; crate::cpu::packet::LANES], y: usize, f: impl Fn(u32) -> u32) -> [u32; PW] {
    let mut out = [0u32; PW];
    for (d, o) in out.iter_mut().enumerate() {
        *o = f(a[y * PW + d]);
    }
    out
}

impl crate::cpu::RecordRows for AovRows<'_> {
    fn put(&mut self, row: usize, x: usize, records: &[AovOut]) {
        let at = row * self.width + x;
        let ids = self.ids;
        for (aov, c, plane) in &mut self.planes {
            let (out, c) = (&mut plane[at..at + records.len()], *c);
            match aov {
                Aov::T => fill(out, records, |r| r.t.to_bits()),
                Aov::Depth => fill(out, records, |r| r.depth.to_bits()),
                Aov::Position => fill(out, records, |r| r.position[c].to_bits()),
                Aov::GeoNormal => fill(out, records, |r| r.geo_normal[c].to_bits()),
                Aov::Normal => fill(out, records, |r| r.normal[c].to_bits()),
                Aov::Albedo => fill(out, records, |r| r.albedo[c].to_bits()),
                Aov::PrimId => fill(out, records, |r| ids.prim_id(r.prim)),
                Aov::ObjectId => fill(out, records, |r| ids.object_id(r.prim)),
                Aov::MaterialId => fill(out, records, |r| r.material),
                Aov::Mask => fill(out, records, |r| {
                    (if r.prim == PRIM_NONE { 0.0f32 } else { 1.0 }).to_bits()
                }),
            }
        }
    }

    /// Each plane's rows straight from the packet's lane arrays, a row of a packet at a
    /// time (through records, a 64-byte struct a pixel gathered back into planes, this
    /// was most of an AOV frame's extra time on a small scene).
    fn put_lanes(&mut self, x: usize, rows: usize, cols: usize, lanes: &AovLanes) {
        let (w, ids) = (self.width, self.ids);
        let at = (x, rows, cols);
        let one = std::slice::from_ref(lanes);
        for (aov, c, plane) in &mut self.planes {
            let c = *c;
            match aov {
                Aov::T => put_packets(plane, w, at, one, |s, y| quad(&s.t, y)),
                Aov::Depth => put_packets(plane, w, at, one, |s, y| quad(&s.depth, y)),
                Aov::Position => put_packets(plane, w, at, one, |s, y| quad(&s.position[c], y)),
                Aov::GeoNormal => put_packets(plane, w, at, one, |s, y| quad(&s.geo_normal[c], y)),
                Aov::Normal => put_packets(plane, w, at, one, |s, y| quad(&s.normal[c], y)),
                Aov::Albedo => put_packets(plane, w, at, one, |s, y| quad(&s.albedo[c], y)),
                Aov::PrimId => put_packets(plane, w, at, one, |s, y| {
                    quad_ids(&s.prim, y, |p| ids.prim_id(p))
                }),
                Aov::ObjectId => put_packets(plane, w, at, one, |s, y| {
                    quad_ids(&s.prim, y, |p| ids.object_id(p))
                }),
                Aov::MaterialId => {
                    put_packets(plane, w, at, one, |s, y| quad_ids(&s.material, y, |m| m))
                }
                Aov::Mask => put_packets(plane, w, at, one, |s, y| {
                    quad_ids(&s.prim, y, |p| {
                        (if p == PRIM_NONE { 0.0f32 } else { 1.0 }).to_bits()
                    })
                }),
            }
        }
    }
}

impl AovImage {
    /// A `width`×`height` frame of `aovs` (each once, as asked), every value zero until
    /// written.
    pub fn new(width: u32, height: u32, aovs: &[Aov], ids: IdMap) -> AovImage {
        let mut held: Vec<Aov> = Vec::new();
        for &a in aovs {
            if !held.contains(&a) {
                held.push(a);
            }
        }
        let channels: usize = held.iter().map(|a| a.components().len().max(1)).sum();
        AovImage {
            width,
            height,
            data: bytemuck::zeroed_vec(channels * width as usize * height as usize),
            aovs: held,
            ids,
        }
    }

    /// The frame of `aovs` that the records `records` (whole rows, as the shader writes
    /// them) describe.
    pub fn from_records(
        width: u32,
        height: u32,
        aovs: &[Aov],
        ids: IdMap,
        records: &[AovOut],
    ) -> AovImage {
        let mut a = AovImage::new(width, height, aovs, ids);
        a.put_rows(0, records);
        a
    }

    /// Writes `records`, whole rows from row `y0`.
    pub fn put_rows(&mut self, y0: u32, records: &[AovOut]) {
        use crate::cpu::RecordRows;
        let w = (self.width as usize).max(1);
        let rows = (records.len() / w) as u32;
        if let Some(block) = self.blocks(y0, rows, rows).first_mut() {
            for (k, line) in records.chunks(w).enumerate() {
                block.put(k, 0, line);
            }
        }
    }

    /// Rows `y0 .. y0 + rows` as blocks of `block` rows (fewer in the last), each written
    /// by one thread: what [`crate::cpu::render_f32_rows_aov`] takes.
    pub fn blocks(&mut self, y0: u32, rows: u32, block: u32) -> Vec<AovRows<'_>> {
        let w = self.width as usize;
        let n = w * self.height as usize;
        let (start, len) = (y0 as usize * w, rows as usize * w);
        let step = (block as usize * w).max(1);
        let count = (rows as usize).div_ceil(block.max(1) as usize);
        let mut out: Vec<AovRows<'_>> = (0..count)
            .map(|_| AovRows {
                width: w,
                ids: &self.ids,
                planes: Vec::new(),
            })
            .collect();
        let channels = self
            .aovs
            .iter()
            .flat_map(|&a| (0..a.components().len().max(1)).map(move |c| (a, c)));
        for ((aov, c), plane) in channels.zip(self.data.chunks_mut(n.max(1))) {
            for (b, part) in plane[start..start + len].chunks_mut(step).enumerate() {
                out[b].planes.push((aov, c, part));
            }
        }
        out
    }

    /// The AOVs held, in the order asked.
    pub fn aovs(&self) -> &[Aov] {
        &self.aovs
    }

    /// Component `c` of `aov` (0 for a scalar), one value a pixel: `F32`, or `U32` for an
    /// id; `None` where the frame does not hold `aov`.
    pub fn channel(&self, aov: Aov, c: usize) -> Option<ChannelData<'_>> {
        let n = self.width as usize * self.height as usize;
        let mut first = 0;
        for &a in &self.aovs {
            let k = a.components().len().max(1);
            if a == aov {
                let plane = self.data.get((first + c) * n..(first + c + 1) * n)?;
                return Some(match a.is_id() {
                    true => ChannelData::U32(plane.into()),
                    false => ChannelData::F32(bytemuck::cast_slice::<u32, f32>(plane).into()),
                });
            }
            first += k;
        }
        None
    }

    /// Component `c` of `aov` at pixel `k` (row-major), as the bits of its channel's type;
    /// `None` where the frame does not hold `aov`.
    pub fn bits(&self, aov: Aov, c: usize, k: usize) -> Option<u32> {
        Some(match self.channel(aov, c)? {
            ChannelData::F32(v) => v.get(k)?.to_bits(),
            ChannelData::U32(v) => *v.get(k)?,
        })
    }

    /// The values of `aov` at every pixel, named as in an EXR: one `F32` channel a
    /// component, or one `U32` channel for an id. Empty where the frame does not hold
    /// `aov`.
    pub fn channels(&self, aov: Aov) -> Vec<(String, ChannelData<'_>)> {
        aov.channel_names()
            .into_iter()
            .enumerate()
            .filter_map(|(c, name)| Some((name, self.channel(aov, c)?)))
            .collect()
    }

    /// Where `aov`'s PNG goes beside the colour's `colour` (`out.png`: `out.normal.png`).
    pub fn png_path(colour: &Path, aov: Aov) -> PathBuf {
        let stem = colour.file_stem().unwrap_or_default().to_string_lossy();
        colour.with_file_name(format!("{stem}.{}.png", aov.name()))
    }

    /// Checks, before any work, that every AOV of `aovs` has a PNG form.
    pub fn check_png(colour: &Path, aovs: &[Aov]) -> Result<(), AovError> {
        match aovs.iter().find(|&&a| a == Aov::Position) {
            Some(&aov) => Err(AovError::NotInPng {
                path: colour.to_owned(),
                aov,
            }),
            None => Ok(()),
        }
    }

    /// The colour's `[r, g, b, t]` pixels as the EXR channels `R`, `G`, `B` and `A`, then
    /// each AOV's channels ([`AovImage::channels`]): what [`crate::image::write_channels`]
    /// writes for a render with AOVs to an EXR.
    pub fn with_colour(&self, colour: &crate::image::Image) -> Vec<(String, ChannelData<'_>)> {
        let mut out: Vec<(String, ChannelData<'_>)> = ["R", "G", "B", "A"]
            .iter()
            .enumerate()
            .map(|(c, name)| {
                let v: Vec<f32> = colour.pixels.iter().map(|p| p[c]).collect();
                (name.to_string(), ChannelData::F32(v.into()))
            })
            .collect();
        for &a in &self.aovs {
            out.extend(self.channels(a));
        }
        out
    }

    /// The channels of an EXR of the colour and this frame's AOVs, in the file's order
    /// (sorted by name): each name, whether it holds ids (u32), and where its values
    /// come from. What [`AovImage::exr_row`] writes a row of.
    pub(crate) fn exr_layout(&self) -> Vec<(String, bool, ExrSource)> {
        let mut out: Vec<(String, bool, ExrSource)> = ["R", "G", "B", "A"]
            .iter()
            .enumerate()
            .map(|(c, n)| (n.to_string(), false, ExrSource::Colour(c)))
            .collect();
        let mut plane = 0;
        for &a in &self.aovs {
            for name in a.channel_names() {
                out.push((name, a.is_id(), ExrSource::Plane(plane)));
                plane += 1;
            }
        }
        out.sort_by(|a, b| a.0.as_bytes().cmp(b.0.as_bytes()));
        out
    }

    /// Appends row `r` of this frame, with `colour` (that row's `[r, g, b, t]` pixels),
    /// as an EXR row of `layout` ([`AovImage::exr_layout`]): each channel's values as
    /// little-endian bytes, in the layout's order.
    pub(crate) fn exr_row(
        &self,
        layout: &[(String, bool, ExrSource)],
        colour: &[[f32; 4]],
        r: usize,
        out: &mut Vec<u8>,
    ) {
        let (w, n) = (
            self.width as usize,
            self.width as usize * self.height as usize,
        );
        for (_, _, source) in layout {
            match *source {
                ExrSource::Colour(c) => colour
                    .iter()
                    .for_each(|p| out.extend_from_slice(&p[c].to_le_bytes())),
                ExrSource::Plane(k) => {
                    let row = &self.data[k * n + r * w..k * n + (r + 1) * w];
                    ChannelData::U32(row.into()).extend_row(out, 0..w);
                }
            }
        }
    }

    /// Writes each AOV of the frame to its PNG beside `colour` ([`AovImage::png_path`]), each
    /// atomically, as docs/aov.md maps it: `t` and `depth` 16-bit grey, linear from 65535
    /// at the frame's nearest hit to 1 at its farthest (their values in the file's
    /// `glint:min` and `glint:max` text chunks), 0 on a miss; normals 8-bit RGB of (n + 1) / 2, black on a miss; `albedo` 8-bit RGB; ids
    /// 8-bit RGB of id + 1 (red the lowest byte; 0 on a miss); `mask` 8-bit grey, 255 on
    /// a hit. Returns the files written.
    pub fn write_pngs(&self, colour: &Path) -> Result<Vec<PathBuf>, super::RenderError> {
        AovImage::check_png(colour, &self.aovs)?;
        let mut written = Vec::new();
        for &aov in &self.aovs {
            let path = AovImage::png_path(colour, aov);
            let (bytes, color, depth, text) = self.png_bytes(aov, &path)?;
            let (w, h) = (self.width, self.height);
            crate::image::write_atomically(&path, |tmp| {
                write_png(tmp, w, h, color, depth, &bytes, &text)
            })?;
            written.push(path);
        }
        Ok(written)
    }

    /// The PNG bytes of `aov`, its colour type and bit depth, and its text chunks.
    #[allow(clippy::type_complexity)]
    fn png_bytes(
        &self,
        aov: Aov,
        path: &Path,
    ) -> Result<
        (
            Vec<u8>,
            png::ColorType,
            png::BitDepth,
            Vec<(String, String)>,
        ),
        AovError,
    > {
        use png::{BitDepth, ColorType};
        let unit = |x: f32| crate::image::to_u8(x);
        if !self.aovs.contains(&aov) {
            return Ok((
                Vec::new(),
                ColorType::Grayscale,
                BitDepth::Eight,
                Vec::new(),
            ));
        }
        let f32s = |c: usize| match self.channel(aov, c) {
            Some(ChannelData::F32(v)) => v,
            _ => unreachable!("{aov} is a float AOV the frame holds"),
        };
        Ok(match aov {
            Aov::T | Aov::Depth => {
                // A miss holds −1; a hit's distance and depth are never negative.
                let values = f32s(0);
                let hit = |v: f32| v >= 0.0;
                let (lo, hi) = values
                    .iter()
                    .copied()
                    .filter(|&v| hit(v))
                    .fold((f32::INFINITY, 0.0f32), |(lo, hi), v| {
                        (if v < lo { v } else { lo }, if v > hi { v } else { hi })
                    });
                let span = hi - lo;
                let bytes = values
                    .iter()
                    .flat_map(|&v| {
                        let q = match hit(v) {
                            false => 0,
                            true if span > 0.0 => {
                                1 + (((hi - v) / span).clamp(0.0, 1.0) * 65534.0).round() as u16
                            }
                            true => 65535,
                        };
                        q.to_be_bytes()
                    })
                    .collect();
                let text = vec![
                    ("glint:min".to_string(), format!("{lo:?}")),
                    ("glint:max".to_string(), format!("{hi:?}")),
                ];
                (bytes, ColorType::Grayscale, BitDepth::Sixteen, text)
            }
            Aov::GeoNormal | Aov::Normal => {
                // A miss holds the zero vector; a hit's normal is a unit vector.
                let (x, y, z) = (f32s(0), f32s(1), f32s(2));
                let bytes = (0..x.len())
                    .flat_map(|k| match [x[k], y[k], z[k]] {
                        [0.0, 0.0, 0.0] => [0; 3],
                        n => n.map(|v| unit(v * 0.5 + 0.5)),
                    })
                    .collect();
                (bytes, ColorType::Rgb, BitDepth::Eight, Vec::new())
            }
            Aov::Albedo => {
                let (r, g, b) = (f32s(0), f32s(1), f32s(2));
                let bytes = (0..r.len())
                    .flat_map(|k| [r[k], g[k], b[k]].map(unit))
                    .collect();
                (bytes, ColorType::Rgb, BitDepth::Eight, Vec::new())
            }
            Aov::PrimId | Aov::ObjectId | Aov::MaterialId => {
                let Some(ChannelData::U32(ids)) = self.channel(aov, 0) else {
                    unreachable!("ids are u32 channels")
                };
                let mut bytes = Vec::with_capacity(ids.len() * 3);
                for &id in ids.iter() {
                    let v = id.wrapping_add(1);
                    if v >= 1 << 24 {
                        return Err(AovError::IdTooLarge {
                            path: path.to_owned(),
                            aov,
                            id,
                        });
                    }
                    bytes.extend_from_slice(&v.to_le_bytes()[..3]);
                }
                (bytes, ColorType::Rgb, BitDepth::Eight, Vec::new())
            }
            Aov::Mask => {
                let bytes = f32s(0)
                    .iter()
                    .map(|&m| if m > 0.0 { 255 } else { 0 })
                    .collect();
                (bytes, ColorType::Grayscale, BitDepth::Eight, Vec::new())
            }
            Aov::Position => {
                return Err(AovError::NotInPng {
                    path: path.to_owned(),
                    aov,
                });
            }
        })
    }
}

/// Writes one PNG of raw samples (`depth` bits, big-endian where 16), with `text`'s
/// (keyword, text) chunks.
fn write_png(
    path: &Path,
    width: u32,
    height: u32,
    color: png::ColorType,
    depth: png::BitDepth,
    bytes: &[u8],
    text: &[(String, String)],
) -> Result<(), ImageError> {
    let io = |error: std::io::Error| ImageError::Io {
        path: path.to_owned(),
        error,
    };
    let file = std::fs::File::create(path).map_err(io)?;
    let mut enc = png::Encoder::new(std::io::BufWriter::new(file), width, height);
    enc.set_color(color);
    enc.set_depth(depth);
    let png_err = |e: png::EncodingError| io(std::io::Error::other(e.to_string()));
    for (keyword, value) in text {
        enc.add_text_chunk(keyword.clone(), value.clone())
            .map_err(png_err)?;
    }
    let mut w = enc.write_header().map_err(png_err)?;
    w.write_image_data(bytes).map_err(png_err)?;
    w.finish().map_err(png_err)
}
