//! Frames of a camera path (`glint render --frames`): which frames, where each goes, and
//! the loop that renders them with the scene's buffers (BVH included) made once.

use std::path::{Path, PathBuf};

use super::{Job, Output, RenderError, RenderOptions, RenderReport, Renderer};
use crate::buffers::SceneBuffers;
use crate::scene::{CameraPathError, MAX_FRAME, Scene};

/// Frames `first..=last` (both written), as `--frames FIRST..LAST` or `--frames N` spell
/// them.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FrameRange {
    /// The first frame.
    pub first: u32,
    /// The last frame (included).
    pub last: u32,
}

/// Why a frame range or an output template was refused, or a frame not made.
#[derive(Debug, thiserror::Error)]
pub enum FramesError {
    /// `--frames` is not `FIRST..LAST` or `N` with 0 <= FIRST <= LAST <= [`MAX_FRAME`].
    #[error(
        "--frames {0:?}: expected FIRST..LAST (both included) or one frame N, 0 <= FIRST <= LAST <= {MAX_FRAME}"
    )]
    Range(String),
    /// The output path has no place for the frame number in its file name.
    #[error(
        "{}: the output of --frames needs {{}} or {{:0N}} (N in 1..=9: zero-padded to N digits) in its file name, where each frame's number goes",
        .0.display()
    )]
    Template(PathBuf),
    /// The camera path has no camera at this frame.
    #[error(transparent)]
    Camera(#[from] CameraPathError),
    /// A frame's render failed.
    #[error("frame {frame}: {error}")]
    Render {
        /// The frame.
        frame: u32,
        /// What failed.
        error: RenderError,
    },
}

impl std::str::FromStr for FrameRange {
    type Err = FramesError;
    fn from_str(s: &str) -> Result<FrameRange, FramesError> {
        let bad = || FramesError::Range(s.to_string());
        let num = |t: &str| {
            t.trim()
                .parse::<u32>()
                .ok()
                .filter(|&n| n as i64 <= MAX_FRAME)
        };
        let (first, last) = match s.split_once("..") {
            Some((a, b)) => (num(a).ok_or_else(bad)?, num(b).ok_or_else(bad)?),
            None => {
                let n = num(s).ok_or_else(bad)?;
                (n, n)
            }
        };
        if first > last {
            return Err(bad());
        }
        Ok(FrameRange { first, last })
    }
}

impl FrameRange {
    /// The frames, in order.
    pub fn iter(self) -> impl Iterator<Item = u32> {
        self.first..=self.last
    }
}

/// Checks that `template`'s file name holds one `{}` or `{:0N}` (N in 1..=9).
pub fn check_template(template: &Path) -> Result<(), FramesError> {
    frame_path(template, 0).map(|_| ())
}

/// `template` with the frame number in its file name's `{}` (plain) or `{:0N}` (at least N
/// digits, zero-padded): `out/frame_{:04}.png` at frame 7 is `out/frame_0007.png`.
pub fn frame_path(template: &Path, frame: u32) -> Result<PathBuf, FramesError> {
    let bad = || FramesError::Template(template.to_owned());
    let name = template
        .file_name()
        .and_then(|n| n.to_str())
        .ok_or_else(bad)?;
    let start = name.find('{').ok_or_else(bad)?;
    let len = name[start..].find('}').ok_or_else(bad)? + 1;
    let spec = &name[start + 1..start + len - 1];
    let number = match spec {
        "" => frame.to_string(),
        _ => {
            let width = spec
                .strip_prefix(":0")
                .and_then(|w| w.parse::<usize>().ok())
                .filter(|w| (1..=9).contains(w))
                .ok_or_else(bad)?;
            format!("{frame:0width$}")
        }
    };
    let rest = &name[start + len..];
    if rest.contains('{') || rest.contains('}') || name[..start].contains('}') {
        return Err(bad());
    }
    let file = format!("{}{number}{rest}", &name[..start]);
    Ok(template.with_file_name(file))
}

/// What became of one frame.
pub enum FrameDone {
    /// Rendered and written.
    Written(PathBuf, Box<RenderReport>),
    /// Left as it was: its file exists and `resume` was asked.
    Kept(PathBuf),
}

/// Renders `frames` of `scene`'s camera path ([`Scene::camera_at`]) with `options`, each
/// to [`frame_path`]`(template, frame)`, written atomically (a frame cut short leaves no
/// file); with `resume`, a frame whose file exists is left as it is. The scene's buffers,
/// its BVH included, are made once for all frames; each frame changes only the camera.
/// `each` is called after every frame, in order. Stops at the first frame that fails.
pub fn render_frames(
    scene: &mut Scene,
    renderer: &Renderer,
    options: &RenderOptions,
    (template, frames, resume): (&Path, FrameRange, bool),
    each: &mut dyn FnMut(u32, FrameDone),
) -> Result<(), FramesError> {
    check_template(template)?;
    let fail = |frame: u32| move |error: RenderError| FramesError::Render { frame, error };
    let mut buf: Option<SceneBuffers> = None;
    for frame in frames.iter() {
        let path = frame_path(template, frame)?;
        if resume && path.exists() {
            each(frame, FrameDone::Kept(path));
            continue;
        }
        scene.camera = scene.camera_at(frame as f64)?;
        let output = Output::file(&path).map_err(|e| fail(frame)(e.into()))?;
        let mut b = match buf.take() {
            Some(b) => b,
            None => {
                let (w, h) = options.checked_size(scene).map_err(fail(frame))?;
                let algo = options.triangle.unwrap_or(scene.triangle);
                SceneBuffers::new(scene, w, h, algo)
            }
        };
        let report = Job::borrowed(scene, output)
            .options(options.clone())
            .buffers(&mut b)
            .run(renderer)
            .map_err(fail(frame))?;
        buf = Some(b);
        each(frame, FrameDone::Written(path, Box::new(report)));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::{FrameRange, frame_path};
    use std::path::{Path, PathBuf};

    /// Ranges are inclusive; one number is one frame; a reversed or signed range, or one
    /// past the last frame allowed, is refused.
    #[test]
    fn ranges_parse_inclusive_and_bad_ones_are_refused() {
        let r: FrameRange = "0..120".parse().unwrap();
        assert_eq!((r.first, r.last, r.iter().count()), (0, 120, 121));
        assert_eq!("7".parse::<FrameRange>().unwrap().iter().count(), 1);
        for bad in ["5..2", "-1..3", "a..b", "", "0..1000000001", "1.5"] {
            let e = bad.parse::<FrameRange>().unwrap_err().to_string();
            assert!(e.contains("FIRST..LAST"), "{bad}: {e}");
        }
    }

    /// `{}` and `{:0N}` become the frame number; a name without one, or with two, is
    /// refused and named.
    #[test]
    fn templates_take_the_frame_number() {
        let t = |s: &str, f| frame_path(Path::new(s), f).map_err(|e| e.to_string());
        assert_eq!(t("out/f_{:04}.png", 7), Ok(PathBuf::from("out/f_0007.png")));
        assert_eq!(t("out/f_{}.exr", 12), Ok(PathBuf::from("out/f_12.exr")));
        assert_eq!(t("{:02}.png", 123), Ok(PathBuf::from("123.png")));
        for bad in [
            "out/f.png",
            "out/f_{x}.png",
            "f_{}_{}.png",
            "f_{:00}.png",
            "{/x.png",
        ] {
            let e = t(bad, 1).unwrap_err();
            assert!(e.contains("needs {} or {:0N}"), "{bad}: {e}");
        }
    }
}
