//! The value checks every scene passes, written once: the file loader puts the failing
//! key's line in front of the message, and [`Scene::validate`] checks a scene built or
//! edited in memory with the same keys and the same messages.
//!
//! Each check returns the message of its failure, without the file or the key.

use super::{MAX_COLOUR, MAX_DEPTH, MAX_IMAGE_SIDE, MAX_SAMPLES, Scene, SceneError};

/// All three components are finite.
pub(super) fn finite3(a: [f32; 3]) -> Result<[f32; 3], String> {
    if a.iter().any(|x| !x.is_finite()) {
        return Err(format!("{a:?} is not finite"));
    }
    Ok(a)
}

/// A colour: finite, ≥ 0 and at most [`MAX_COLOUR`] in every component.
pub(super) fn colour(a: [f32; 3]) -> Result<[f32; 3], String> {
    finite3(a)?;
    if a.iter().any(|&x| x < 0.0) {
        return Err(format!("{a:?} has a negative component"));
    }
    if a.iter().any(|&x| x > MAX_COLOUR) {
        return Err(format!(
            "{a:?} has a component above {MAX_COLOUR:e}, more than shading can add up in f32 without overflow"
        ));
    }
    Ok(a)
}

/// `camera.fov`, in (0, 180) degrees.
pub(super) fn fov(fov: f32) -> Result<f32, String> {
    if !(fov > 0.0 && fov < 180.0) {
        return Err(format!("{fov} must be in (0, 180) degrees"));
    }
    Ok(fov)
}

/// `camera.width` or `camera.height`, 1..=[`MAX_IMAGE_SIDE`].
pub(super) fn side(x: i64) -> Result<u32, String> {
    if !(1..=MAX_IMAGE_SIDE).contains(&x) {
        return Err(format!("{x} must be in 1..={MAX_IMAGE_SIDE}"));
    }
    Ok(x as u32)
}

/// `camera.samples`, 1..=[`MAX_SAMPLES`].
pub(super) fn samples(n: i64) -> Result<u32, String> {
    if !(1..=MAX_SAMPLES as i64).contains(&n) {
        return Err(format!(
            "{n} must be in 1..={MAX_SAMPLES} (N×N rays per pixel; 1 is one ray through the centre)"
        ));
    }
    Ok(n as u32)
}

/// Which camera key a bad view names.
pub(crate) enum ViewFault {
    /// `camera.look_at` equals `camera.eye`.
    LookAt(String),
    /// `camera.up` is zero or parallel to the view.
    Up(String),
}

/// The camera's basis, checked in f64: the view must have a length and up must not be
/// parallel to it.
pub(crate) fn view(eye: [f32; 3], look_at: [f32; 3], up: [f32; 3]) -> Result<(), ViewFault> {
    let d = [
        look_at[0] as f64 - eye[0] as f64,
        look_at[1] as f64 - eye[1] as f64,
        look_at[2] as f64 - eye[2] as f64,
    ];
    let dl = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
    if dl == 0.0 {
        return Err(ViewFault::LookAt(
            "equals camera.eye: no view direction".into(),
        ));
    }
    let u = up.map(|x| x as f64);
    let ul = (u[0] * u[0] + u[1] * u[1] + u[2] * u[2]).sqrt();
    let cr = [
        d[1] * u[2] - d[2] * u[1],
        d[2] * u[0] - d[0] * u[2],
        d[0] * u[1] - d[1] * u[0],
    ];
    let cl = (cr[0] * cr[0] + cr[1] * cr[1] + cr[2] * cr[2]).sqrt();
    if ul == 0.0 || cl <= 1e-6 * dl * ul {
        return Err(ViewFault::Up(format!(
            "{up:?} is zero or parallel to the view direction"
        )));
    }
    Ok(())
}

/// A light's direction: finite and not zero.
pub(super) fn direction(d: [f32; 3]) -> Result<[f32; 3], String> {
    finite3(d)?;
    if d.iter().all(|&x| x == 0.0) {
        return Err(format!("{d:?} has no direction"));
    }
    Ok(d)
}

/// A spot's half-angle, degrees, in (0, 90].
pub(super) fn spot_angle(a: f32) -> Result<f32, String> {
    if !(a > 0.0 && a <= 90.0) {
        return Err(format!("{a} must be in (0, 90] degrees"));
    }
    Ok(a)
}

/// A spot's soft edge, degrees, in [0, angle].
pub(super) fn spot_falloff(f: f32, angle: f32) -> Result<f32, String> {
    if !(f >= 0.0 && f <= angle) {
        return Err(format!("{f} must be in [0, angle = {angle}] degrees"));
    }
    Ok(f)
}

/// A sphere's radius, finite and > 0.
pub(super) fn radius(r: f32) -> Result<f32, String> {
    if !(r.is_finite() && r > 0.0) {
        return Err(format!("{r} must be finite and > 0"));
    }
    Ok(r)
}

/// A Phong exponent `n`, finite and ≥ 0.
pub(super) fn shininess(x: f32) -> Result<f32, String> {
    if !(x.is_finite() && x >= 0.0) {
        return Err(format!("{x} must be finite and ≥ 0"));
    }
    Ok(x)
}

/// An index of refraction, finite and > 0.
pub(super) fn ior(x: f32) -> Result<f32, String> {
    if !(x.is_finite() && x > 0.0) {
        return Err(format!("{x} must be finite and > 0"));
    }
    Ok(x)
}

/// The scene's `max_depth`, 0..=[`MAX_DEPTH`].
pub(super) fn max_depth(x: i64) -> Result<u32, String> {
    if !(0..=MAX_DEPTH as i64).contains(&x) {
        return Err(format!("{x} is not in 0..={MAX_DEPTH}"));
    }
    Ok(x as u32)
}

/// The scene's `min_weight`, finite and ≥ 0.
pub(super) fn min_weight(x: f32) -> Result<f32, String> {
    if !(x.is_finite() && x >= 0.0) {
        return Err(format!("{x} must be finite and ≥ 0"));
    }
    Ok(x)
}

/// The message of a reference to a material that is not there.
pub(super) fn no_material(name: &str, names: &[String]) -> String {
    format!(
        "no material named {name:?} (defined: {})",
        if names.is_empty() {
            "none".to_string()
        } else {
            names.join(", ")
        }
    )
}

impl Scene {
    /// Checks a scene's values as loading a scene file does, with the same keys and
    /// messages: what a scene built or edited in memory must pass before it renders
    /// ([`crate::render::Job`] calls it). A loaded scene passes unchanged.
    ///
    /// The error is [`SceneError::Value`]: the scene's path and the key, without a line.
    pub fn validate(&self) -> Result<(), SceneError> {
        let err = |key: String, message: String| SceneError::Value {
            file: self.path.clone(),
            key,
            message,
        };
        let at = |key: &str| {
            let key = key.to_string();
            move |m: String| err(key.clone(), m)
        };
        colour(self.ambient).map_err(at("ambient"))?;
        colour(self.background).map_err(at("background"))?;
        max_depth(self.max_depth as i64).map_err(at("max_depth"))?;
        min_weight(self.min_weight).map_err(at("min_weight"))?;
        let c = &self.camera;
        finite3(c.eye).map_err(at("camera.eye"))?;
        finite3(c.look_at).map_err(at("camera.look_at"))?;
        finite3(c.up).map_err(at("camera.up"))?;
        fov(c.fov).map_err(at("camera.fov"))?;
        side(c.width as i64).map_err(at("camera.width"))?;
        side(c.height as i64).map_err(at("camera.height"))?;
        samples(c.samples as i64).map_err(at("camera.samples"))?;
        view(c.eye, c.look_at, c.up).map_err(|f| match f {
            ViewFault::LookAt(m) => err("camera.look_at".into(), m),
            ViewFault::Up(m) => err("camera.up".into(), m),
        })?;
        for (i, l) in self.lights.iter().enumerate() {
            finite3(l.position).map_err(at(&format!("lights[{i}].position")))?;
            colour(l.color).map_err(at(&format!("lights[{i}].color")))?;
            match l.kind {
                super::LightKind::Point => {}
                super::LightKind::Directional { direction: d } => {
                    direction(d).map_err(at(&format!("lights[{i}].direction")))?;
                }
                super::LightKind::Spot {
                    direction: d,
                    angle,
                    falloff,
                } => {
                    direction(d).map_err(at(&format!("lights[{i}].direction")))?;
                    spot_angle(angle).map_err(at(&format!("lights[{i}].angle")))?;
                    spot_falloff(falloff, angle).map_err(at(&format!("lights[{i}].falloff")))?;
                }
            }
        }
        for m in &self.materials {
            let key = |k: &str| format!("materials.{}.{k}", m.name);
            colour(m.ka).map_err(at(&key("ka")))?;
            colour(m.kd).map_err(at(&key("kd")))?;
            colour(m.ks).map_err(at(&key("ks")))?;
            shininess(m.n).map_err(at(&key("n")))?;
            colour(m.optics.kr).map_err(at(&key("kr")))?;
            colour(m.optics.kt).map_err(at(&key("kt")))?;
            ior(m.optics.ior).map_err(at(&key("ior")))?;
        }
        let names: Vec<String> = self.materials.iter().map(|m| m.name.clone()).collect();
        // The key is written only for a failure: a mesh scene has a million triangles.
        let material = |i: u32, key: &dyn Fn() -> String| match names.get(i as usize) {
            Some(_) => Ok(()),
            None => Err(err(key(), no_material(&format!("#{i}"), &names))),
        };
        for (i, s) in self.spheres.iter().enumerate() {
            finite3(s.center).map_err(at(&format!("spheres[{i}].center")))?;
            radius(s.radius).map_err(at(&format!("spheres[{i}].radius")))?;
            material(s.material, &|| format!("spheres[{i}].material"))?;
        }
        for (k, m) in self.named.iter().enumerate() {
            let r = &m.triangles;
            if r.is_empty() || r.end > self.triangles.len() {
                return Err(err(
                    format!("named[{k}].triangles"),
                    format!(
                        "mesh {:?}: {r:?} is not a nonempty range of the scene's {} triangles",
                        m.name,
                        self.triangles.len()
                    ),
                ));
            }
        }
        if self.instances.len() > super::MAX_INSTANCES {
            return Err(err(
                "instances".into(),
                format!("more than {} instances", super::MAX_INSTANCES),
            ));
        }
        for (i, x) in self.instances.iter().enumerate() {
            if x.mesh >= self.named.len() {
                return Err(err(
                    format!("instances[{i}].mesh"),
                    format!("#{} names no mesh ({} are named)", x.mesh, self.named.len()),
                ));
            }
            if let Some(m) = x.material {
                material(m, &|| format!("instances[{i}].material"))?;
            }
            for (key, map) in [("to_world", &x.to_world), ("to_object", &x.to_object)] {
                if !map.iter().flatten().all(|v| v.is_finite()) {
                    return Err(err(
                        format!("instances[{i}].{key}"),
                        format!("{map:?} is not finite"),
                    ));
                }
            }
        }
        // A mesh scene has a million triangles: one branch-free pass over them on every
        // core, and the loop that names the culprit only where that pass finds one.
        use rayon::prelude::*;
        let n = names.len() as u32;
        let all_good = self.triangles.par_chunks(4096).all(|c| {
            c.iter().fold(true, |ok, t| {
                ok & (t.material < n)
                    & t.vertices
                        .as_flattened()
                        .iter()
                        .fold(true, |a, x| a & x.is_finite())
            })
        });
        if all_good {
            return Ok(());
        }
        for (i, t) in self.triangles.iter().enumerate() {
            if t.vertices.iter().flatten().any(|x| !x.is_finite()) {
                return Err(err(
                    format!("triangles[{i}].vertices"),
                    format!("{:?} is not finite", t.vertices),
                ));
            }
            material(t.material, &|| format!("triangles[{i}].material"))?;
        }
        Ok(())
    }
}
