//! Camera paths: `[[camera.keys]]` in a scene file, and the camera at any frame.
//!
//! A key names a frame (an integer, 0..=[`MAX_FRAME`], each key's above the one before)
//! and any of `eye`, `look_at`, `up` and `fov`; what a key leaves out is the previous
//! key's, and the first key's is `[camera]`'s. Between two keys every value is linear in
//! the frame: `a + (b − a) · u` with `u = (frame − f₀) / (f₁ − f₀)`, per component, in f64,
//! rounded once to f32. Before the first key the camera is the first key's, after the last
//! the last key's. Only `+ − × /` are used, so the camera at a frame is the same in every
//! bit on every machine, and at a key's own frame it is exactly the key. Width, height and
//! samples are `[camera]`'s at every frame. A scene rendered without a frame (`glint render`
//! without `--frames`) uses `[camera]` as written.
//!
//! Linear interpolation moves the eye and the point looked at along straight lines; an
//! orbit is written as keys around it (eight keys give a 45° step; the view turns at a
//! constant rate only where the segments are short).

use super::{Camera, Scene, validate};

/// The largest frame number a key may name.
pub const MAX_FRAME: i64 = 1_000_000_000;

/// One key of a camera path, every value given (a key's own or inherited, see the module
/// documentation).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraKey {
    /// The frame at which the camera is exactly this key.
    pub frame: u32,
    /// Position.
    pub eye: [f32; 3],
    /// Point looked at.
    pub look_at: [f32; 3],
    /// Up hint.
    pub up: [f32; 3],
    /// Vertical field of view in degrees.
    pub fov: f32,
}

/// Why there is no camera at a frame.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum CameraPathError {
    /// The frame asked for is NaN or infinite.
    #[error("frame {0}: not a finite number")]
    NotFinite(f64),
    /// The camera between two valid keys has no view (the eye on the point looked at, or
    /// the up hint along the view): a path through such a place needs another key.
    #[error("frame {frame}: camera.{key} {message} (between the keys at frames {from} and {to})")]
    NoView {
        /// The frame asked for.
        frame: f64,
        /// `look_at` or `up`.
        key: &'static str,
        /// What is wrong.
        message: String,
        /// The key before the frame.
        from: u32,
        /// The key after the frame.
        to: u32,
    },
}

impl Scene {
    /// The camera at `frame` (fractional frames allowed) on the scene's camera path, or
    /// `[camera]` itself where the scene has no path ([`Scene::camera_keys`] empty).
    pub fn camera_at(&self, frame: f64) -> Result<Camera, CameraPathError> {
        if !frame.is_finite() {
            return Err(CameraPathError::NotFinite(frame));
        }
        let keys = &self.camera_keys;
        let (Some(first), Some(last)) = (keys.first(), keys.last()) else {
            return Ok(self.camera.clone());
        };
        let with = |k: &CameraKey| Camera {
            eye: k.eye,
            look_at: k.look_at,
            up: k.up,
            fov: k.fov,
            ..self.camera.clone()
        };
        if frame <= first.frame as f64 {
            return Ok(with(first));
        }
        if frame >= last.frame as f64 {
            return Ok(with(last));
        }
        // The segment [a, b) holding the frame: a.frame <= frame < b.frame.
        let i = keys.partition_point(|k| k.frame as f64 <= frame) - 1;
        let (a, b) = (&keys[i], &keys[i + 1]);
        let u = (frame - a.frame as f64) / (b.frame as f64 - a.frame as f64);
        let lerp = |x: f32, y: f32| (x as f64 + (y as f64 - x as f64) * u) as f32;
        let lerp3 = |x: [f32; 3], y: [f32; 3]| [0, 1, 2].map(|c| lerp(x[c], y[c]));
        let key = CameraKey {
            frame: a.frame,
            eye: lerp3(a.eye, b.eye),
            look_at: lerp3(a.look_at, b.look_at),
            up: lerp3(a.up, b.up),
            fov: lerp(a.fov, b.fov),
        };
        let no_view = |key: &'static str, message: String| CameraPathError::NoView {
            frame,
            key,
            message,
            from: a.frame,
            to: b.frame,
        };
        match validate::view(key.eye, key.look_at, key.up) {
            Ok(()) => Ok(with(&key)),
            Err(validate::ViewFault::LookAt(m)) => Err(no_view("look_at", m)),
            Err(validate::ViewFault::Up(m)) => Err(no_view("up", m)),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::CameraPathError;
    use crate::scene::Scene;

    fn scene(keys: &str) -> Scene {
        let text = format!(
            "ambient = [0.1, 0.1, 0.1]\nbackground = [0.0, 0.0, 0.0]\n\
             [camera]\neye = [0.0, 0.0, 5.0]\nlook_at = [0.0, 0.0, 0.0]\nfov = 40.0\n\
             width = 8\nheight = 6\n{keys}"
        );
        Scene::parse(&text, std::path::Path::new("path.toml")).expect("a valid scene")
    }

    /// At a key's frame the camera is the key in every bit; halfway it is the mean;
    /// before the first and after the last key it holds; an omitted value is inherited.
    #[test]
    fn keys_are_exact_and_the_middle_is_linear() {
        let s = scene(
            "[[camera.keys]]\nframe = 10\neye = [0.0, 0.0, 5.0]\n\
             [[camera.keys]]\nframe = 20\neye = [4.0, 0.0, 3.0]\nfov = 60.0\n",
        );
        let at = |f: f64| s.camera_at(f).unwrap();
        assert_eq!(at(10.0).eye, [0.0, 0.0, 5.0]);
        assert_eq!(at(20.0).eye, [4.0, 0.0, 3.0]);
        assert_eq!(at(15.0).eye, [2.0, 0.0, 4.0]);
        assert_eq!(at(15.0).fov, 50.0);
        assert_eq!(at(0.0), at(10.0));
        assert_eq!(at(1e6), at(20.0));
        assert_eq!(at(12.5).look_at, [0.0, 0.0, 0.0]);
        assert_eq!(at(12.5).width, 8);
        // The twin: a frame off the key is not the key.
        assert_ne!(at(10.5).eye, at(10.0).eye);
    }

    /// A scene without keys has [camera] at every frame; a frame that is not a number is
    /// an error, not a camera.
    #[test]
    fn no_keys_is_the_camera_and_nan_is_an_error() {
        let s = scene("");
        assert_eq!(s.camera_at(3.5).unwrap(), s.camera);
        assert_eq!(
            s.camera_at(f64::NAN).map(|_| ()).unwrap_err().to_string(),
            "frame NaN: not a finite number"
        );
        assert!(matches!(
            s.camera_at(f64::INFINITY),
            Err(CameraPathError::NotFinite(_))
        ));
    }

    /// A path whose eye passes through the point looked at has no camera there, and says
    /// between which keys.
    #[test]
    fn a_path_through_the_target_is_an_error_there() {
        let s = scene(
            "[[camera.keys]]\nframe = 0\neye = [0.0, 0.0, 5.0]\n\
             [[camera.keys]]\nframe = 10\neye = [0.0, 0.0, -5.0]\n",
        );
        let e = s.camera_at(5.0).unwrap_err().to_string();
        assert!(e.contains("frame 5: camera.look_at"), "{e}");
        assert!(e.contains("frames 0 and 10"), "{e}");
        // The twin: beside it, there is a camera.
        assert!(s.camera_at(4.0).is_ok());
    }
}
