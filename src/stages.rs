//! Where time to first image goes: each stage of a render (read, gunzip, OBJ check and
//! parse, transform, BVH build, flatten, trace, encode and write the image) records its wall time here, and
//! `glint render -v` prints them. Recording is a mutex push per stage, not per primitive.

use std::sync::Mutex;
use std::time::Duration;
use web_time::Instant;

static STAGES: Mutex<Vec<(&'static str, Duration)>> = Mutex::new(Vec::new());

/// Adds `d` to stage `name` (stages keep the order they were first recorded in).
pub fn record(name: &'static str, d: Duration) {
    if let Ok(mut s) = STAGES.lock() {
        match s.iter_mut().find(|(n, _)| *n == name) {
            Some((_, t)) => *t += d,
            None => s.push((name, d)),
        }
    }
}

/// Runs `f`, recording its wall time as stage `name`.
pub fn time<T>(name: &'static str, f: impl FnOnce() -> T) -> T {
    let t0 = Instant::now();
    let out = f();
    record(name, t0.elapsed());
    out
}

/// The stages recorded so far, in order, and clears them.
pub fn take() -> Vec<(&'static str, Duration)> {
    STAGES
        .lock()
        .map(|mut s| std::mem::take(&mut *s))
        .unwrap_or_default()
}
