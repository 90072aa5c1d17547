//! `glint view` in a real window, under Xvfb (the `xvfb` and `xdotool` packages, which
//! `.ci/test.sh` installs): the picture presented equals `glint render`'s PNG byte for
//! byte, for one sample a pixel and after an antialiased scene's refinement; a saved scene
//! reloads (a changed light colour), a broken one keeps the viewer running with its error
//! shown until it is fixed; a scripted orbit leaves a camera that renders the same in a
//! scene file; closing the window (the close button, or the window destroyed) exits 0; no
//! display is a one-line error.

mod common;

use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Child, ChildStdout, Command, Stdio};
use std::sync::mpsc::{Receiver, RecvTimeoutError, channel};
use std::time::{Duration, Instant};

use common::{Scratch, glint_command};

/// An X server of the test's own on a display number the server picks itself
/// (`-displayfd`: tests running at once never share or race for one); killed when dropped.
struct Xvfb {
    child: Child,
    display: String,
    /// Xvfb's stdout, held open so that nothing it writes later meets a closed pipe.
    _stdout: BufReader<ChildStdout>,
}

impl Xvfb {
    fn start() -> Xvfb {
        let mut child = Command::new("Xvfb")
            .args([
                "-displayfd",
                "1",
                "-screen",
                "0",
                "1280x1024x24",
                "-nolisten",
                "tcp",
            ])
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .expect("Xvfb: install the xvfb package (.ci/test.sh does)");
        // Xvfb writes the display number once it accepts connections.
        let mut stdout = BufReader::new(child.stdout.take().unwrap());
        let mut line = String::new();
        stdout.read_line(&mut line).unwrap();
        let n: u32 = line
            .trim()
            .parse()
            .unwrap_or_else(|_| panic!("Xvfb -displayfd printed {line:?}"));
        Xvfb {
            child,
            display: format!(":{n}"),
            _stdout: stdout,
        }
    }
}

impl Drop for Xvfb {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

fn scene(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenes")
        .join(format!("{name}.toml"))
}

/// `glint render SCENE -o OUT` on the CPU tracer (what `auto` picks on lavapipe).
fn render(scene: &Path, out: &Path) -> Vec<u8> {
    let s = glint_command()
        .args(["render", "--backend", "cpu", "-o"])
        .arg(out)
        .arg(scene)
        .output()
        .unwrap();
    assert!(s.status.success(), "{}", String::from_utf8_lossy(&s.stderr));
    std::fs::read(out).unwrap()
}

/// `glint view SCENE --frames N --screenshot OUT` under `x` (and `extra` arguments): its
/// PNG, the exit status checked.
fn view_frames(x: &Xvfb, scene: &Path, frames: u32, out: &Path, extra: &[&str]) -> Vec<u8> {
    let s = glint_command()
        .env("DISPLAY", &x.display)
        .args(["view", "--frames", &frames.to_string()])
        .args(extra)
        .arg("--screenshot")
        .arg(out)
        .arg(scene)
        .output()
        .unwrap();
    assert!(
        s.status.success(),
        "glint view: {}",
        String::from_utf8_lossy(&s.stderr)
    );
    std::fs::read(out).unwrap()
}

/// The presented picture of bb8 after 3 frames is `glint render`'s PNG in every byte, with
/// the CPU tracer (what `auto` picks on lavapipe) and with the shader (`--backend gpu`,
/// lavapipe being bit-exact); the antialiased bb8 after its 16 sample positions too, and
/// after 2 it is not yet (the twin, which also shows the refinement is seen).
#[test]
fn the_window_shows_what_glint_render_writes() {
    let x = Xvfb::start();
    let dir = Scratch::new("view-shot");
    let want = render(&scene("bb8"), &dir.join("r.png"));
    assert!(view_frames(&x, &scene("bb8"), 3, &dir.join("v.png"), &[]) == want);
    let gpu = view_frames(
        &x,
        &scene("bb8"),
        3,
        &dir.join("g.png"),
        &["--backend", "gpu"],
    );
    assert!(gpu == want, "--backend gpu");
    let want = render(&scene("bb8-aa"), &dir.join("ra.png"));
    assert!(view_frames(&x, &scene("bb8-aa"), 16, &dir.join("va.png"), &[]) == want);
    assert!(view_frames(&x, &scene("bb8-aa"), 2, &dir.join("vb.png"), &[]) != want);
}

/// The X server's own screen (`xwd -root`), where the window sits at (0, 0) without a
/// window manager, holds `glint render`'s pixels: the surface, its format and the copy
/// onto it lose nothing. The twin: a pixel changed by one step is seen.
#[test]
fn the_screen_holds_the_pixels_of_the_png() {
    let x = Xvfb::start();
    let dir = Scratch::new("view-xwd");
    let png = render(&scene("bb8"), &dir.join("r.png"));
    let want = image::load_from_memory(&png).unwrap().to_rgb8();
    let v = Viewer::start(&x, &scene("bb8"), &dir);
    // The first frame is drawn within a few milliseconds of the window; wait for it.
    let t0 = Instant::now();
    let mut got = grab(&x.display, want.width(), want.height());
    while got != *want && t0.elapsed() < Duration::from_secs(20) {
        std::thread::sleep(Duration::from_millis(100));
        got = grab(&x.display, want.width(), want.height());
    }
    assert!(got == *want, "the screen differs from the PNG");
    let mut one = got.clone();
    one[1000] ^= 1;
    assert!(one != *want, "the twin");
    assert!(v.quit().success());
}

/// The top-left `w`×`h` pixels of the screen, RGB, from `xwd -root` (a ZPixmap of 32 bits a
/// pixel with masks, after a big-endian header, its name and its colour map).
fn grab(display: &str, w: u32, h: u32) -> Vec<u8> {
    let out = Command::new("xwd")
        .env("DISPLAY", display)
        .args(["-root", "-silent"])
        .output()
        .expect("xwd: install the x11-apps package (.ci/test.sh does)");
    let d = out.stdout;
    let word = |k: usize| u32::from_be_bytes(d[4 * k..4 * k + 4].try_into().unwrap());
    let (header, bpp, line, ncolors) = (word(0) as usize, word(11), word(12) as usize, word(19));
    let (lsb, masks) = (word(7) == 0, [word(14), word(15), word(16)]);
    assert_eq!(bpp, 32, "xwd: {bpp} bits a pixel");
    let pixels = header + 12 * ncolors as usize;
    let mut rgb = Vec::with_capacity(3 * (w * h) as usize);
    for y in 0..h as usize {
        for x in 0..w as usize {
            let b: [u8; 4] = d[pixels + y * line + 4 * x..][..4].try_into().unwrap();
            let p = if lsb {
                u32::from_le_bytes(b)
            } else {
                u32::from_be_bytes(b)
            };
            for m in masks {
                rgb.push(((p & m) >> m.trailing_zeros()) as u8);
            }
        }
    }
    rgb
}

/// A running viewer with its output read line by line.
struct Viewer {
    child: Child,
    out: Receiver<String>,
    err: Receiver<String>,
    window: String,
    display: String,
    /// P presses so far.
    saves: u32,
}

impl Viewer {
    fn start(x: &Xvfb, scene: &Path, dir: &Path) -> Viewer {
        let mut child = glint_command()
            .current_dir(dir)
            .env("DISPLAY", &x.display)
            .arg("view")
            .arg(scene)
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        let lines = |r: Box<dyn std::io::Read + Send>| {
            let (tx, rx) = channel();
            std::thread::spawn(move || {
                for l in BufReader::new(r).lines().map_while(Result::ok) {
                    if tx.send(l).is_err() {
                        break;
                    }
                }
            });
            rx
        };
        let out = lines(Box::new(child.stdout.take().unwrap()));
        let err = lines(Box::new(child.stderr.take().unwrap()));
        let mut v = Viewer {
            child,
            out,
            err,
            window: String::new(),
            display: x.display.clone(),
            saves: 0,
        };
        v.wait_err("glint view:");
        let id = Command::new("xdotool")
            .env("DISPLAY", &x.display)
            .args(["search", "--sync", "--name", "^glint view"])
            .output()
            .expect("xdotool: install the xdotool package (.ci/test.sh does)");
        v.window = String::from_utf8_lossy(&id.stdout)
            .lines()
            .next()
            .expect("the viewer's window")
            .to_string();
        v
    }

    /// The first line from `rx` containing `what`; a panic listing the lines seen if the
    /// viewer closes the stream or none comes within 60 s.
    fn wait(rx: &Receiver<String>, what: &str) -> String {
        let t0 = Instant::now();
        let mut seen = Vec::new();
        while t0.elapsed() < Duration::from_secs(60) {
            match rx.recv_timeout(Duration::from_millis(100)) {
                Ok(l) if l.contains(what) => return l,
                Ok(l) => seen.push(l),
                Err(RecvTimeoutError::Timeout) => {}
                Err(RecvTimeoutError::Disconnected) => {
                    panic!("the viewer closed its output before {what:?}; it printed {seen:#?}")
                }
            }
        }
        panic!("no line with {what:?} within 60 s; the viewer printed {seen:#?}");
    }

    fn wait_err(&mut self, what: &str) -> String {
        Viewer::wait(&self.err, what)
    }

    fn wait_out(&mut self, what: &str) -> String {
        Viewer::wait(&self.out, what)
    }

    fn xdotool(&self, args: &[&str]) {
        let s = Command::new("xdotool")
            .env("DISPLAY", &self.display)
            .args(args)
            .status()
            .unwrap();
        assert!(s.success(), "xdotool {args:?}");
    }

    /// Gives the window the keyboard focus (there is no window manager to do it), trying
    /// again while the server says another window has it: `windowfocus` alone sometimes
    /// fails on a window mapped a moment before.
    fn focus(&self) {
        for _ in 0..50 {
            let _ = Command::new("xdotool")
                .env("DISPLAY", &self.display)
                .args(["windowfocus", &self.window])
                .status();
            let now = Command::new("xdotool")
                .env("DISPLAY", &self.display)
                .arg("getwindowfocus")
                .output()
                .unwrap();
            if String::from_utf8_lossy(&now.stdout).trim() == self.window {
                return;
            }
            std::thread::sleep(Duration::from_millis(100));
        }
        panic!("the viewer's window never got the keyboard focus");
    }

    /// A key pressed and released, as a keyboard would (XTEST, to the focused window).
    fn key(&self, key: &str) {
        self.focus();
        self.xdotool(&["key", key]);
    }

    /// P: the view saved; the file's bytes. Each press saves once (the n-th press writes
    /// `…-view-n.png`), so a key delivered twice is seen.
    fn save(&mut self, dir: &Path) -> Vec<u8> {
        self.key("p");
        self.saves += 1;
        let line = self.wait_out("saved ");
        let name = line.trim_start_matches("saved ").trim().to_string();
        assert!(
            name.ends_with(&format!("-view-{}.png", self.saves)),
            "{name}: press {}",
            self.saves
        );
        std::fs::read(dir.join(name)).unwrap()
    }

    fn running(&mut self) -> bool {
        self.child.try_wait().unwrap().is_none()
    }

    /// Esc, and the exit status.
    fn quit(mut self) -> std::process::ExitStatus {
        self.key("Escape");
        self.exit_status()
    }

    /// The exit status, waited for up to 30 s.
    fn exit_status(&mut self) -> std::process::ExitStatus {
        let t0 = Instant::now();
        loop {
            if let Some(s) = self.child.try_wait().unwrap() {
                return s;
            }
            assert!(
                t0.elapsed() < Duration::from_secs(30),
                "the viewer did not exit"
            );
            std::thread::sleep(Duration::from_millis(50));
        }
    }
}

impl Drop for Viewer {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// Saving the scene with another light colour reloads it (the BVH kept) and the view then
/// renders as the new file does; a broken file keeps the viewer running with the error
/// on stderr (file, line, key), and fixing it brings the picture back.
#[test]
fn saved_scenes_reload_and_broken_ones_do_not_stop_the_viewer() {
    let x = Xvfb::start();
    let dir = Scratch::new("view-reload");
    let path = dir.join("s.toml");
    let original = std::fs::read_to_string(scene("bb8")).unwrap();
    std::fs::write(&path, &original).unwrap();
    let mut v = Viewer::start(&x, &path, &dir);
    let before = v.save(&dir);
    assert!(before == render(&path, &dir.join("r0.png")));
    // A light's colour changed.
    let at = original
        .find("color = [")
        .expect("bb8 has a coloured light");
    let end = at + original[at..].find(']').unwrap() + 1;
    let changed = format!(
        "{}color = [0.2, 0.9, 0.3]{}",
        &original[..at],
        &original[end..]
    );
    std::fs::write(&path, &changed).unwrap();
    let line = v.wait_err("reloaded");
    assert!(line.contains("the BVH kept"), "{line}");
    let after = v.save(&dir);
    assert!(after == render(&path, &dir.join("r1.png")));
    assert!(after != before, "the twin: the new colour shows");
    // Broken, then fixed.
    std::fs::write(&path, changed.replacen("radius = ", "radius = -", 1)).unwrap();
    let line = v.wait_err("error:");
    assert!(
        line.contains("s.toml:") && line.contains(".radius"),
        "{line}"
    );
    std::thread::sleep(Duration::from_millis(300));
    assert!(v.running(), "the viewer exited on a broken file");
    std::fs::write(&path, &original).unwrap();
    v.wait_err("reloaded");
    assert!(v.save(&dir) == before);
    assert!(v.quit().success(), "Esc exits 0");
}

/// A file caught half-written (the scene saved in two pieces, the viewer watching between
/// them) is an error on stderr while the last good picture stays; once the rest is written
/// the view is the whole file's. The twin: the whole file's picture is not the old one.
#[test]
fn a_scene_caught_half_written_keeps_the_last_picture() {
    use std::io::Write;
    let x = Xvfb::start();
    let dir = Scratch::new("view-half");
    let path = dir.join("s.toml");
    let original = std::fs::read_to_string(scene("bb8")).unwrap();
    std::fs::write(&path, &original).unwrap();
    let mut v = Viewer::start(&x, &path, &dir);
    let before = v.save(&dir);
    // The eye moved 0.5 along x.
    let at = original.find("eye = [").expect("bb8 has an eye") + "eye = [".len();
    let end = at + original[at..].find(',').unwrap();
    let x: f32 = original[at..end].trim().parse().unwrap();
    let whole = format!("{}{:?}{}", &original[..at], x + 0.5, &original[end..]);
    // Cut in the middle of a table, where the first piece cannot parse.
    let cut = whole.find("[[spheres]]").expect("bb8 has spheres") + 5;
    let mut f = std::fs::File::create(&path).unwrap();
    f.write_all(&whole.as_bytes()[..cut]).unwrap();
    f.flush().unwrap();
    let line = v.wait_err("error:");
    assert!(line.contains("s.toml:"), "{line}");
    assert!(v.running(), "the viewer exited on a half-written file");
    assert!(v.save(&dir) == before, "the last good picture stays");
    f.write_all(&whole.as_bytes()[cut..]).unwrap();
    f.flush().unwrap();
    drop(f);
    v.wait_err("reloaded");
    let after = v.save(&dir);
    assert!(after == render(&path, &dir.join("whole.png")));
    assert!(after != before, "the twin: the moved eye shows");
    assert!(v.quit().success(), "Esc exits 0");
}

/// A scripted drag with the left button orbits the camera; C prints it as a [camera]
/// table; a scene file with that table renders what P saves. The twin: the camera moved.
#[test]
fn an_orbit_leaves_a_camera_that_renders_the_same() {
    let x = Xvfb::start();
    let dir = Scratch::new("view-orbit");
    let path = dir.join("s.toml");
    let original = std::fs::read_to_string(scene("bb8")).unwrap();
    std::fs::write(&path, &original).unwrap();
    let mut v = Viewer::start(&x, &path, &dir);
    let w = v.window.clone();
    v.xdotool(&[
        "mousemove",
        "--window",
        &w,
        "400",
        "300",
        "mousedown",
        "1",
        "mousemove",
        "--window",
        &w,
        "470",
        "330",
        "mouseup",
        "1",
    ]);
    std::thread::sleep(Duration::from_millis(300));
    v.key("c");
    let mut camera = vec![v.wait_out("[camera]")];
    for key in ["eye", "look_at", "up", "fov", "width", "height", "samples"] {
        camera.push(v.wait_out(&format!("{key} = ")));
    }
    let saved = v.save(&dir);
    // The scene file with its [camera] table replaced by the printed one.
    let start = original.find("[camera]").unwrap();
    let rest = &original[start + 8..];
    let end = start + 8 + rest.find("\n[").map_or(rest.len(), |k| k + 1);
    let moved = format!(
        "{}{}\n{}",
        &original[..start],
        camera.join("\n"),
        &original[end..]
    );
    let moved_path = dir.join("moved.toml");
    std::fs::write(&moved_path, &moved).unwrap();
    assert!(saved == render(&moved_path, &dir.join("r.png")));
    assert!(
        saved != render(&path, &dir.join("r0.png")),
        "the twin: the orbit moved the camera"
    );
    assert!(v.quit().success());
}

/// What a window manager's close button sends: a WM_PROTOCOLS client message naming
/// WM_DELETE_WINDOW, to `window` on `display`.
fn close_button(display: &str, window: u32) {
    use x11rb::protocol::xproto::{ClientMessageEvent, ConnectionExt, EventMask};
    let (conn, _) = x11rb::connect(Some(display)).expect("connect to Xvfb");
    let atom = |name: &[u8]| conn.intern_atom(false, name).unwrap().reply().unwrap().atom;
    let (protocols, delete) = (atom(b"WM_PROTOCOLS"), atom(b"WM_DELETE_WINDOW"));
    let event = ClientMessageEvent::new(
        32,
        window,
        protocols,
        [delete, x11rb::CURRENT_TIME, 0, 0, 0],
    );
    conn.send_event(false, window, EventMask::NO_EVENT, event)
        .unwrap();
    // A round trip: the server has handled the request before the connection closes.
    conn.get_input_focus().unwrap().reply().unwrap();
}

/// A viewer on bb8 that has saved a view (so it runs, the twin), closed by `close`: its exit
/// status is 0 and its stderr has no error and no panic.
fn closes_cleanly(x: &Xvfb, how: &str, close: impl FnOnce(&Viewer)) {
    let dir = Scratch::new(&format!("view-{how}"));
    let mut v = Viewer::start(x, &scene("bb8"), &dir);
    v.save(&dir);
    assert!(
        v.running(),
        "{how}: the twin: the viewer runs until its window closes"
    );
    close(&v);
    let s = v.exit_status();
    let err: Vec<String> = v.err.iter().collect();
    assert_eq!(s.code(), Some(0), "{how}: {err:#?}");
    assert!(
        !err.iter()
            .any(|l| l.contains("error") || l.contains("panicked")),
        "{how}: {err:#?}"
    );
}

/// Closing the window exits 0 with no error: with the close button a window manager draws
/// (WM_DELETE_WINDOW), and with the window destroyed under the viewer (`xdotool
/// windowclose`). The twin: until then the viewer runs.
#[test]
fn closing_the_window_exits_0() {
    let x = Xvfb::start();
    closes_cleanly(&x, "close-button", |v| {
        close_button(&v.display, v.window.parse().unwrap())
    });
    closes_cleanly(&x, "destroyed", |v| v.xdotool(&["windowclose", &v.window]));
}

/// With a display but no Vulkan adapter (the loader pointed at no driver): one line, exit
/// status 1, no panic.
#[test]
fn no_adapter_is_a_one_line_error() {
    let x = Xvfb::start();
    let s = glint_command()
        .env("DISPLAY", &x.display)
        .env("VK_ICD_FILENAMES", "/nonexistent/icd.json")
        .env("VK_DRIVER_FILES", "/nonexistent/icd.json")
        .args(["view"])
        .arg(scene("bb8"))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&s.stderr);
    assert_eq!(s.status.code(), Some(1), "{err}");
    assert!(err.contains("no Vulkan adapter"), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    assert_eq!(
        err.lines().filter(|l| l.starts_with("error")).count(),
        1,
        "{err}"
    );
}

/// Without a display: one line, exit status 1, no panic.
#[test]
fn no_display_is_a_one_line_error() {
    let s = glint_command()
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .args(["view"])
        .arg(scene("bb8"))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&s.stderr);
    assert_eq!(s.status.code(), Some(1), "{err}");
    assert!(err.contains("DISPLAY is not set"), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    assert_eq!(err.trim().lines().count(), 1, "{err}");
    // The twin: a scene that does not load is the scene's error, before any window.
    let s = glint_command()
        .args(["view", "no-such-scene.toml"])
        .output()
        .unwrap();
    assert_eq!(s.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&s.stderr).contains("no-such-scene.toml"));
}
