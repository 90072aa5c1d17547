//! What the command line reads from its environment, once, at its start: the driver's
//! quiet, and the settings that `GLINT_*` variables give the library as values.

/// Asks Mesa not to print its conformance warning for lavapipe on every start, and gives
/// this process (only) a runtime folder when `XDG_RUNTIME_DIR` is unset, so Mesa's window
/// system code does not print "XDG_RUNTIME_DIR is invalid or not set" up to four times.
/// Called first in `main`, before any thread exists (the library sets no variable).
pub fn quiet_driver() {
    if std::env::var_os("MESA_VK_IGNORE_CONFORMANCE_WARNING").is_none() {
        // SAFETY: called at the start of `main`, before any other thread exists.
        unsafe { std::env::set_var("MESA_VK_IGNORE_CONFORMANCE_WARNING", "1") };
    }
    if std::env::var_os("XDG_RUNTIME_DIR").is_none()
        && let Some(dir) = private_runtime_dir()
    {
        // SAFETY: as above.
        unsafe { std::env::set_var("XDG_RUNTIME_DIR", dir) };
    }
}

/// A folder only this user can enter, under the temporary folder, made when missing; None
/// when it cannot be made or someone else owns it.
#[cfg(unix)]
fn private_runtime_dir() -> Option<std::path::PathBuf> {
    use std::os::unix::fs::{DirBuilderExt, MetadataExt, PermissionsExt};
    let uid = std::fs::metadata("/proc/self").ok()?.uid();
    let dir = std::env::temp_dir().join(format!("glint-runtime-{uid}"));
    let _ = std::fs::DirBuilder::new().mode(0o700).create(&dir);
    let m = std::fs::symlink_metadata(&dir).ok()?;
    (m.is_dir() && m.uid() == uid && m.permissions().mode() & 0o077 == 0).then_some(dir)
}

#[cfg(not(unix))]
fn private_runtime_dir() -> Option<std::path::PathBuf> {
    None
}

/// The GPU settings for `--adapter NAME`, with what the environment adds, read here once:
/// `GLINT_MAX_BUFFER_BYTES` (a smaller GPU's buffer limit), `GLINT_TRAVERSAL=ray` and
/// `GLINT_PACKET_SHADOWS=0|1`.
pub fn gpu_options(adapter: Option<&str>) -> glint::gpu::GpuOptions {
    glint::gpu::GpuOptions {
        adapter: adapter.map(str::to_string),
        max_buffer_bytes: std::env::var("GLINT_MAX_BUFFER_BYTES")
            .ok()
            .and_then(|v| v.trim().parse::<u64>().ok()),
        per_ray_traversal: std::env::var("GLINT_TRAVERSAL").as_deref() == Ok("ray"),
        packet_shadows: match std::env::var("GLINT_PACKET_SHADOWS").as_deref() {
            Ok("0") => Some(false),
            Ok("1") => Some(true),
            _ => None,
        },
    }
}

/// The cache's settings for `dir`, with what the environment adds, read here once:
/// `GLINT_CACHE_MIB` (the folder's size limit) and `GLINT_CACHE_MIN_PRIMS`.
pub fn cache_settings(dir: std::path::PathBuf) -> glint::cache::Settings {
    let var = |k: &str| {
        std::env::var(k)
            .ok()
            .and_then(|v| v.trim().parse::<u64>().ok())
    };
    let mut s = glint::cache::Settings::new(dir);
    if let Some(mib) = var("GLINT_CACHE_MIB") {
        s.max_bytes = mib.saturating_mul(1 << 20);
    }
    if let Some(n) = var("GLINT_CACHE_MIN_PRIMS") {
        s.min_prims = n as usize;
    }
    // The render waits for the writes before it ends (`FinishWrites` in main.rs).
    s.write_behind = true;
    s
}

/// The most bytes read from one input: `GLINT_MAX_INPUT_MIB` (MiB) when set to a number,
/// else the library's default; read here, once.
pub fn max_input_bytes() -> u64 {
    std::env::var("GLINT_MAX_INPUT_MIB")
        .ok()
        .and_then(|v| v.trim().parse::<u64>().ok())
        .map_or(
            glint::scene::LoadOptions::default().max_input_bytes,
            |mib| mib.saturating_mul(1 << 20),
        )
}

/// Every `GLINT_*` setting the command line reads, checked once at its start: a value that
/// is set but cannot be used is an error naming the variable, never ignored in silence.
pub fn check() -> Result<(), String> {
    let number = |k: &str| match std::env::var(k) {
        Ok(v) if v.trim().parse::<u64>().is_err() => Err(format!(
            "{k}={v:?}: expected a whole number (unset it for the default)"
        )),
        Ok(_) | Err(std::env::VarError::NotPresent) => Ok(()),
        Err(e) => Err(format!("{k}: {e}")),
    };
    let one_of = |k: &str, allowed: &[&str]| match std::env::var(k) {
        Ok(v) if !allowed.contains(&v.as_str()) => Err(format!(
            "{k}={v:?}: expected {} (unset it for the default)",
            allowed.join(" or ")
        )),
        Ok(_) | Err(std::env::VarError::NotPresent) => Ok(()),
        Err(e) => Err(format!("{k}: {e}")),
    };
    number("GLINT_MAX_BUFFER_BYTES")?;
    number("GLINT_CACHE_MIB")?;
    number("GLINT_CACHE_MIN_PRIMS")?;
    number("GLINT_MAX_INPUT_MIB")?;
    one_of("GLINT_TRAVERSAL", &["ray", "packet"])?;
    one_of("GLINT_PACKET_SHADOWS", &["0", "1"])
}
