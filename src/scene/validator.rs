//! The TOML validator: checks each value of the scene file and turns the file's structs
//! into the scene's, every error naming the file, the line and the key.

use super::*;

/// Checks values and turns the file's structs into the scene's.
pub(super) struct Validator<'a> {
    pub(super) src: &'a str,
    pub(super) path: &'a Path,
    pub(super) read: &'a ReadFile<'a>,
    /// The most bytes unpacked from one `.gz` mesh ([`LoadOptions::max_input_bytes`]).
    pub(super) limit: u64,
    /// [`LoadOptions::cache`].
    pub(super) cache: Option<&'a Arc<crate::cache::Cache>>,
    /// Where the stages of reading are timed ([`Scene::load_stages`]).
    pub(super) stages: &'a crate::stages::Stages,
}

impl Validator<'_> {
    pub(super) fn err<T>(
        &self,
        span: std::ops::Range<usize>,
        key: &str,
        message: String,
    ) -> Result<T, SceneError> {
        Err(SceneError::Invalid {
            file: self.path.to_owned(),
            line: line_of(self.src, span.start),
            key: key.to_string(),
            message,
        })
    }

    /// `check`'s verdict on `v`, its failure placed at `span` under `key`.
    pub(super) fn check<T, U>(
        &self,
        v: T,
        span: std::ops::Range<usize>,
        key: &str,
        check: impl FnOnce(T) -> Result<U, String>,
    ) -> Result<U, SceneError> {
        check(v).or_else(|m| self.err(span, key, m))
    }

    pub(super) fn finite3(&self, v: &Vec3File, key: &str) -> Result<[f32; 3], SceneError> {
        self.check(*v.get_ref(), v.span(), key, validate::finite3)
    }

    pub(super) fn colour(&self, v: &Vec3File, key: &str) -> Result<[f32; 3], SceneError> {
        self.check(*v.get_ref(), v.span(), key, validate::colour)
    }

    pub(super) fn material_index(
        &self,
        names: &[String],
        name: &Spanned<String>,
        key: &str,
    ) -> Result<u32, SceneError> {
        match names.iter().position(|n| n == name.get_ref()) {
            Some(i) => Ok(i as u32),
            None => self.err(
                name.span(),
                key,
                validate::no_material(name.get_ref(), names),
            ),
        }
    }

    pub(super) fn scene(&self, f: SceneFile) -> Result<Scene, SceneError> {
        let mut warnings = Vec::new();
        let ambient = match &f.ambient {
            Some(v) => self.colour(v, "ambient")?,
            None => [0.0; 3],
        };
        let background = match &f.background {
            Some(v) => self.colour(v, "background")?,
            None => [0.0; 3],
        };
        let triangle = match &f.triangle {
            Some(s) => match s.get_ref().parse() {
                Ok(a) => a,
                Err(m) => return self.err(s.span(), "triangle", m),
            },
            None => TriangleAlgorithm::MollerTrumbore,
        };
        let camera = self.camera(&f.camera)?;
        let camera_keys = self.camera_keys(f.camera.get_ref(), &camera)?;

        let mut lights = Vec::new();
        for (i, l) in f.lights.iter().enumerate() {
            let l = l.get_ref();
            lights.push(self.light(i, l)?);
        }

        let mut textures = texture::TextureSet::default();
        let mut materials = Vec::new();
        for (name, m) in &f.materials {
            materials.push(self.material(name, m, &mut textures)?);
        }
        if lights.is_empty() && materials.iter().any(|m| m.model != Model::Ambient) {
            warnings.push(format!(
                "{}: lights: none, so only the ambient term shows",
                self.path.display()
            ));
        }
        let names: Vec<String> = materials.iter().map(|m| m.name.clone()).collect();

        let mut spheres = Vec::new();
        let mut sphere_sources = Vec::new();
        for (i, s) in f.spheres.iter().enumerate() {
            let s = s.get_ref();
            let center = self.finite3(&s.center, &format!("spheres[{i}].center"))?;
            let radius = self.check(
                *s.radius.get_ref(),
                s.radius.span(),
                &format!("spheres[{i}].radius"),
                validate::radius,
            )?;
            let material =
                self.material_index(&names, &s.material, &format!("spheres[{i}].material"))?;
            spheres.push(Sphere {
                center,
                radius,
                material,
            });
            sphere_sources.push(format!(
                "{}:{}: spheres[{i}]",
                self.path.display(),
                line_of(self.src, s.center.span().start)
            ));
        }

        let mut triangles = Vec::new();
        let mut uvs = Vec::new();
        let mut triangle_sources = Vec::new();
        for (i, t) in f.triangles.iter().enumerate() {
            let t = t.get_ref();
            let key = format!("triangles[{i}].vertices");
            let v = *t.vertices.get_ref();
            if v.iter().flatten().any(|x| !x.is_finite()) {
                return self.err(t.vertices.span(), &key, format!("{v:?} is not finite"));
            }
            if mesh::is_degenerate(&v) {
                warnings.push(format!(
                    "{}:{}: {key}: zero area: never hit",
                    self.path.display(),
                    line_of(self.src, t.vertices.span().start)
                ));
            }
            let material =
                self.material_index(&names, &t.material, &format!("triangles[{i}].material"))?;
            let textured = materials[material as usize].maps() != (None, None);
            match &t.uvs {
                Some(uv) => {
                    let key = format!("triangles[{i}].uvs");
                    let u = *uv.get_ref();
                    if u.iter().flatten().any(|x| !x.is_finite()) {
                        return self.err(uv.span(), &key, format!("{u:?} is not finite"));
                    }
                    if textured {
                        uvs.push(TextureCoords {
                            first: triangles.len(),
                            uvs: vec![u],
                        });
                    } else {
                        warnings.push(format!(
                            "{}:{}: {key}: material {:?} has no map_kd or map_ka: unused",
                            self.path.display(),
                            line_of(self.src, uv.span().start),
                            t.material.get_ref()
                        ));
                    }
                }
                None if textured => warnings.push(format!(
                    "{}:{}: triangles[{i}].uvs: material {:?} is textured but the triangle has no uvs: untextured",
                    self.path.display(),
                    line_of(self.src, t.vertices.span().start),
                    t.material.get_ref()
                )),
                None => {}
            }
            triangle_sources.push((
                triangles.len(),
                format!(
                    "{}:{}: {key}",
                    self.path.display(),
                    line_of(self.src, t.vertices.span().start)
                ),
            ));
            triangles.push(Triangle {
                vertices: v,
                material,
            });
        }

        let mut smooth = Vec::new();
        let mut named = Vec::new();
        for (i, m) in f.meshes.iter().enumerate() {
            let start = triangles.len();
            triangle_sources.push((
                triangles.len(),
                format!(
                    "{}:{}: meshes[{i}].file ({})",
                    self.path.display(),
                    line_of(self.src, m.get_ref().file.span().start),
                    m.get_ref().file.get_ref()
                ),
            ));
            mesh::load(
                self,
                i,
                m.get_ref(),
                mesh::Out {
                    materials: &mut materials,
                    triangles: &mut triangles,
                    smooth: &mut smooth,
                    uvs: &mut uvs,
                    textures: &mut textures,
                    warnings: &mut warnings,
                },
            )?;
            let range = start..triangles.len();
            if let Some(n) = instance::named_mesh(self, i, m.get_ref(), range, &named)? {
                named.push(n);
            }
        }
        let names: Vec<String> = materials.iter().map(|m| m.name.clone()).collect();
        let instances = instance::instances(self, &f.instances, &named, &names, &uvs)?;
        instance::check_hidden_placed(self, &f.meshes, &named, &instances)?;
        let (textures, downscaled) = textures.into_fitted();
        warnings.extend(downscaled);

        Ok(Scene {
            path: self.path.to_owned(),
            ambient,
            background,
            triangle,
            shadows: f.shadows.unwrap_or(false),
            max_depth: self.max_depth(&f.max_depth)?,
            min_weight: self.min_weight(&f.min_weight)?,
            camera,
            encoding: match f.output.as_ref().and_then(|o| o.encoding.as_ref()) {
                Some(e) => match e.get_ref().parse() {
                    Ok(e) => e,
                    Err(m) => return self.err(e.span(), "output.encoding", m.to_string()),
                },
                None => crate::shared::encoding::Encoding::Linear,
            },
            lights,
            materials,
            spheres,
            triangles,
            smooth,
            uvs,
            textures,
            inputs: Vec::new(),
            warnings,
            sphere_sources,
            triangle_sources,
            cache: self.cache.cloned(),
            camera_keys,
            load_stages: crate::stages::Timings::default(),
            named,
            instances,
        })
    }

    /// `[[lights]]` entry `i`: the keys its kind needs, and no others.
    pub(super) fn light(&self, i: usize, l: &format::LightFile) -> Result<Light, SceneError> {
        let key = |k: &str| format!("lights[{i}].{k}");
        let kind_name = l.kind.as_ref().map_or("point", |k| k.get_ref().as_str());
        let kind_span = l.kind.as_ref().map_or(l.color.span(), |k| k.span());
        let needs = |present: bool, k: &str, wanted: bool| -> Result<(), SceneError> {
            match (present, wanted) {
                (false, true) => self.err(
                    kind_span.clone(),
                    &key(k),
                    format!("missing: a {kind_name} light needs it"),
                ),
                (true, false) => self.err(
                    kind_span.clone(),
                    &key(k),
                    format!("a {kind_name} light has none"),
                ),
                _ => Ok(()),
            }
        };
        let (point, dir, spot) = match kind_name {
            "point" => (true, false, false),
            "directional" => (false, true, false),
            "spot" => (true, true, true),
            other => {
                return self.err(
                    kind_span,
                    &key("kind"),
                    format!("unknown kind {other:?}: expected point, directional or spot"),
                );
            }
        };
        needs(l.position.is_some(), "position", point)?;
        needs(l.direction.is_some(), "direction", dir)?;
        needs(l.angle.is_some(), "angle", spot)?;
        if !spot && l.falloff.is_some() {
            needs(true, "falloff", false)?;
        }
        let position = match &l.position {
            Some(v) => self.finite3(v, &key("position"))?,
            None => [0.0; 3],
        };
        let direction = match &l.direction {
            Some(v) => self.check(
                *v.get_ref(),
                v.span(),
                &key("direction"),
                validate::direction,
            )?,
            None => [0.0; 3],
        };
        let kind = match (dir, spot) {
            (false, _) => LightKind::Point,
            (true, false) => LightKind::Directional { direction },
            (true, true) => {
                let a = l.angle.as_ref().expect("checked above");
                let angle =
                    self.check(*a.get_ref(), a.span(), &key("angle"), validate::spot_angle)?;
                let falloff = match &l.falloff {
                    Some(f) => self.check(*f.get_ref(), f.span(), &key("falloff"), |x| {
                        validate::spot_falloff(x, angle)
                    })?,
                    None => 0.0,
                };
                LightKind::Spot {
                    direction,
                    angle,
                    falloff,
                }
            }
        };
        Ok(Light {
            kind,
            position,
            color: self.colour(&l.color, &key("color"))?,
        })
    }

    pub(super) fn camera(&self, c: &Spanned<format::CameraFile>) -> Result<Camera, SceneError> {
        let span = c.span();
        let c = c.get_ref();
        let eye = self.finite3(&c.eye, "camera.eye")?;
        let look_at = self.finite3(&c.look_at, "camera.look_at")?;
        let up = match &c.up {
            Some(v) => self.finite3(v, "camera.up")?,
            None => [0.0, 1.0, 0.0],
        };
        let fov = self.check(*c.fov.get_ref(), c.fov.span(), "camera.fov", validate::fov)?;
        let side =
            |v: &Spanned<i64>, key: &str| self.check(*v.get_ref(), v.span(), key, validate::side);
        let width = side(&c.width, "camera.width")?;
        let height = side(&c.height, "camera.height")?;
        let samples = match &c.samples {
            None => 1,
            Some(v) => self.check(*v.get_ref(), v.span(), "camera.samples", validate::samples)?,
        };
        match validate::view(eye, look_at, up) {
            Ok(()) => {}
            Err(validate::ViewFault::LookAt(m)) => {
                return self.err(c.look_at.span(), "camera.look_at", m);
            }
            Err(validate::ViewFault::Up(m)) => {
                let up_span = c.up.as_ref().map(|u| u.span()).unwrap_or(span);
                return self.err(up_span, "camera.up", m);
            }
        }
        Ok(Camera {
            eye,
            look_at,
            up,
            fov,
            width,
            height,
            samples,
        })
    }

    /// `[[camera.keys]]`: each key's values, its own or the previous key's (the first's
    /// `camera`'s), checked as `[camera]`'s are; frames in 0..=[`MAX_FRAME`], increasing.
    pub(super) fn camera_keys(
        &self,
        c: &format::CameraFile,
        camera: &Camera,
    ) -> Result<Vec<CameraKey>, SceneError> {
        let mut keys: Vec<CameraKey> = Vec::new();
        for (i, k) in c.keys.iter().flatten().enumerate() {
            let span = k.span();
            let k = k.get_ref();
            let key = |name: &str| format!("camera.keys[{i}].{name}");
            let frame = *k.frame.get_ref();
            if !(0..=MAX_FRAME).contains(&frame) {
                return self.err(
                    k.frame.span(),
                    &key("frame"),
                    format!("{frame} is outside 0..={MAX_FRAME}"),
                );
            }
            let prev = keys.last().copied().unwrap_or(CameraKey {
                frame: 0,
                eye: camera.eye,
                look_at: camera.look_at,
                up: camera.up,
                fov: camera.fov,
            });
            if let Some(p) = keys.last()
                && frame <= p.frame as i64
            {
                return self.err(
                    k.frame.span(),
                    &key("frame"),
                    format!(
                        "{frame} is not after the previous key's frame, {}: keys go in increasing frames",
                        p.frame
                    ),
                );
            }
            let v3 = |v: &Option<format::Vec3File>, name: &str, old: [f32; 3]| match v {
                Some(v) => self.finite3(v, &key(name)),
                None => Ok(old),
            };
            let this = CameraKey {
                frame: frame as u32,
                eye: v3(&k.eye, "eye", prev.eye)?,
                look_at: v3(&k.look_at, "look_at", prev.look_at)?,
                up: v3(&k.up, "up", prev.up)?,
                fov: match &k.fov {
                    Some(f) => self.check(*f.get_ref(), f.span(), &key("fov"), validate::fov)?,
                    None => prev.fov,
                },
            };
            match validate::view(this.eye, this.look_at, this.up) {
                Ok(()) => {}
                Err(validate::ViewFault::LookAt(m)) => {
                    let s = k.look_at.as_ref().map_or(span, |v| v.span());
                    return self.err(s, &key("look_at"), m);
                }
                Err(validate::ViewFault::Up(m)) => {
                    let s = k.up.as_ref().map_or(span, |v| v.span());
                    return self.err(s, &key("up"), m);
                }
            }
            keys.push(this);
        }
        Ok(keys)
    }

    pub(super) fn material(
        &self,
        name: &str,
        m: &Spanned<format::MaterialFile>,
        textures: &mut texture::TextureSet,
    ) -> Result<Material, SceneError> {
        let span = m.span();
        let m = m.get_ref();
        let key = |k: &str| format!("materials.{name}.{k}");
        let model = match m.model.get_ref().as_str() {
            "ambient" => Model::Ambient,
            "diffuse" => Model::Diffuse,
            "phong" => Model::Phong,
            other => {
                return self.err(
                    m.model.span(),
                    &key("model"),
                    format!("unknown model {other:?}: expected ambient, diffuse or phong"),
                );
            }
        };
        let ka = self.colour(&m.ka, &key("ka"))?;
        let need = |v: &Option<Vec3File>, k: &str, needed: bool| -> Result<[f32; 3], SceneError> {
            match v {
                Some(v) => self.colour(v, &key(k)),
                None if needed => self.err(
                    span.clone(),
                    &key(k),
                    format!("missing: the {} model needs it", m.model.get_ref()),
                ),
                None => Ok([0.0; 3]),
            }
        };
        let kd = need(&m.kd, "kd", model != Model::Ambient)?;
        let ks = need(&m.ks, "ks", model == Model::Phong)?;
        let n = match &m.n {
            Some(n) => self.check(*n.get_ref(), n.span(), &key("n"), validate::shininess)?,
            None if model == Model::Phong => {
                return self.err(span, &key("n"), "missing: the phong model needs it".into());
            }
            None => 1.0,
        };
        let mut map = |v: &Option<Spanned<String>>, k: &str| -> Result<Option<u32>, SceneError> {
            let Some(file) = v else { return Ok(None) };
            let base = self.path.parent().unwrap_or(Path::new("."));
            let path = base.join(file.get_ref());
            textures
                .add(&path, self.read, self.stages)
                .map(Some)
                .or_else(|e| self.err(file.span(), &key(k), format!("{}: {e}", path.display())))
        };
        let map_kd = map(&m.map_kd, "map_kd")?;
        let map_ka = map(&m.map_ka, "map_ka")?;
        Ok(Material {
            name: name.to_string(),
            model,
            ka,
            kd,
            ks,
            n,
            optics: self.optics(name, m)?,
            map_kd,
            map_ka,
        })
    }

    /// A material's `kr`, `kt`, `ior` and `fresnel`: `ior` is needed with `kt`.
    pub(super) fn optics(
        &self,
        name: &str,
        m: &format::MaterialFile,
    ) -> Result<Optics, SceneError> {
        let key = |k: &str| format!("materials.{name}.{k}");
        let d = Optics::default();
        let kr =
            m.kr.as_ref()
                .map_or(Ok(d.kr), |v| self.colour(v, &key("kr")))?;
        let kt =
            m.kt.as_ref()
                .map_or(Ok(d.kt), |v| self.colour(v, &key("kt")))?;
        let ior = match (&m.ior, &m.kt) {
            (Some(i), _) => self.check(*i.get_ref(), i.span(), &key("ior"), validate::ior)?,
            (None, Some(kt)) => {
                return self.err(
                    kt.span(),
                    &key("ior"),
                    "missing: kt (transmittance) needs an index of refraction".into(),
                );
            }
            (None, None) => d.ior,
        };
        Ok(Optics {
            kr,
            kt,
            ior,
            fresnel: m.fresnel.unwrap_or(d.fresnel),
        })
    }

    /// The scene's `max_depth`, 0..=[`MAX_DEPTH`] (default [`DEFAULT_MAX_DEPTH`]).
    pub(super) fn max_depth(&self, v: &Option<Spanned<i64>>) -> Result<u32, SceneError> {
        match v {
            None => Ok(DEFAULT_MAX_DEPTH),
            Some(v) => self.check(*v.get_ref(), v.span(), "max_depth", validate::max_depth),
        }
    }

    /// The scene's `min_weight`, finite and ≥ 0 (default [`DEFAULT_MIN_WEIGHT`]).
    pub(super) fn min_weight(&self, v: &Option<Spanned<f32>>) -> Result<f32, SceneError> {
        match v {
            None => Ok(DEFAULT_MIN_WEIGHT),
            Some(v) => self.check(*v.get_ref(), v.span(), "min_weight", validate::min_weight),
        }
    }
}
