//! The progress bar on stderr.

use std::io::IsTerminal;
use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

/// A one-line progress bar on stderr for renders that take longer than half a second,
/// drawn only when stderr is a terminal (logs get no carriage returns).
pub struct ProgressBar {
    start: Instant,
    shown: AtomicBool,
    lock: Mutex<()>,
}

impl ProgressBar {
    pub fn new(start: Instant) -> Self {
        ProgressBar {
            start,
            shown: AtomicBool::new(false),
            lock: Mutex::new(()),
        }
    }

    pub fn show(&self, done: u32, total: u32) {
        if !std::io::stderr().is_terminal() || self.start.elapsed().as_secs_f64() < 0.5 {
            return;
        }
        let Ok(_guard) = self.lock.try_lock() else {
            return;
        };
        let width = 40;
        let filled = (done as u64 * width / total.max(1) as u64) as usize;
        eprint!(
            "\r[{}{}] {done}/{total} rows, {:.1} s",
            "#".repeat(filled),
            ".".repeat(width as usize - filled),
            self.start.elapsed().as_secs_f64()
        );
        self.shown.store(true, Ordering::Relaxed);
    }

    pub fn finish(&self) {
        if self.shown.load(Ordering::Relaxed) {
            eprintln!();
        }
    }
}
