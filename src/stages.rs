//! Where time to first image goes: each stage of a render (read, gunzip, OBJ check and
//! parse, transform, BVH build, flatten, trace, encode and write the image) is timed into
//! a [`Stages`] that belongs to the work being timed: [`crate::scene::Scene::load_stages`]
//! for the scene's reading, [`crate::buffers::SceneBuffers::stages`] for its flattening and
//! BVH, and [`crate::render::RenderReport::stages`] for a whole render. Nothing is process-wide, so
//! two renders at once each get their own figures. Recording is a mutex push per stage, not
//! per primitive (stages are timed from rayon's threads too).

use std::sync::Mutex;
use std::time::Duration;
use web_time::Instant;

/// Stage names and their wall times, in the order each stage was first recorded.
pub type StageTimes = Vec<(&'static str, Duration)>;

/// A recorder of stage times (shared by reference between threads).
#[derive(Debug, Default)]
pub struct Stages(Mutex<StageTimes>);

impl Stages {
    /// An empty recorder.
    pub fn new() -> Stages {
        Stages::default()
    }

    /// Adds `d` to stage `name` (stages keep the order they were first recorded in).
    pub fn record(&self, name: &'static str, d: Duration) {
        if let Ok(mut s) = self.0.lock() {
            match s.iter_mut().find(|(n, _)| *n == name) {
                Some((_, t)) => *t += d,
                None => s.push((name, d)),
            }
        }
    }

    /// Adds each of `times` ([`Stages::record`] one by one).
    pub fn record_all(&self, times: &[(&'static str, Duration)]) {
        for &(n, d) in times {
            self.record(n, d);
        }
    }

    /// Runs `f`, recording its wall time as stage `name`.
    pub fn time<T>(&self, name: &'static str, f: impl FnOnce() -> T) -> T {
        let t0 = Instant::now();
        let out = f();
        self.record(name, t0.elapsed());
        out
    }

    /// The stages recorded, in order.
    pub fn into_times(self) -> StageTimes {
        self.0.into_inner().unwrap_or_else(|e| e.into_inner())
    }
}

/// The stage times of one piece of work, kept with what it made. Two of them always compare
/// equal: how long a scene took to read is not part of what the scene is.
#[derive(Clone, Debug, Default)]
pub struct Timings(pub StageTimes);

impl PartialEq for Timings {
    fn eq(&self, _: &Timings) -> bool {
        true
    }
}

#[cfg(test)]
mod tests {
    use super::Stages;
    use std::time::Duration;

    /// Two recorders keep their own figures (the process-wide timer that this replaced
    /// mixed two renders' stages); a stage recorded twice adds up, in first-seen order.
    #[test]
    fn recorders_are_separate_and_add_up() {
        let (a, b) = (Stages::new(), Stages::new());
        a.record("read", Duration::from_millis(2));
        b.record("trace", Duration::from_millis(5));
        a.record("parse", Duration::from_millis(1));
        a.record("read", Duration::from_millis(3));
        assert_eq!(
            a.into_times(),
            vec![
                ("read", Duration::from_millis(5)),
                ("parse", Duration::from_millis(1))
            ]
        );
        // The twin: b saw only its own stage.
        assert_eq!(b.into_times(), vec![("trace", Duration::from_millis(5))]);
    }
}
