//! The viewer's watch on the scene's files (notify): a reload is asked for when one of
//! them changes.

use std::collections::HashSet;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use anyhow::{Context, Result};
use winit::event_loop::EventLoopProxy;

use super::UserEvent;

/// The watch on the scene's files: their folders watched (editors often save by writing a
/// new file and renaming it over the old), events kept for the files the scene read.
pub(super) struct Watch {
    watcher: notify::RecommendedWatcher,
    files: Arc<std::sync::Mutex<HashSet<PathBuf>>>,
    folders: HashSet<PathBuf>,
}

impl Watch {
    pub(super) fn new(proxy: EventLoopProxy<UserEvent>) -> Result<Watch> {
        let files: Arc<std::sync::Mutex<HashSet<PathBuf>>> = Arc::default();
        let seen = files.clone();
        let watcher = notify::recommended_watcher(move |r: notify::Result<notify::Event>| {
            let Ok(event) = r else { return };
            if matches!(event.kind, notify::EventKind::Access(_)) {
                return;
            }
            let files = seen.lock().expect("the watch's file list");
            if event.paths.iter().any(|p| files.contains(&absolute(p))) {
                let _ = proxy.send_event(UserEvent::Changed);
            }
        })
        .context("cannot watch the scene's files")?;
        Ok(Watch {
            watcher,
            files,
            folders: HashSet::new(),
        })
    }

    /// Watches `inputs` (a scene's files), and their folders.
    pub(super) fn follow(&mut self, inputs: &[PathBuf]) {
        use notify::Watcher;
        let files: HashSet<PathBuf> = inputs.iter().map(|p| absolute(p)).collect();
        for f in &files {
            if let Some(dir) = f.parent()
                && self.folders.insert(dir.to_owned())
                && let Err(e) = self.watcher.watch(dir, notify::RecursiveMode::NonRecursive)
            {
                eprintln!("warning: cannot watch {}: {e}", dir.display());
            }
        }
        *self.files.lock().expect("the watch's file list") = files;
    }
}

/// `p` made absolute (against the current folder) and with `.` and `..` resolved as far as
/// the file system allows, so that paths from the scene and from the watcher compare.
fn absolute(p: &Path) -> PathBuf {
    let p = std::path::absolute(p).unwrap_or_else(|_| p.to_owned());
    match (
        p.parent().and_then(|d| d.canonicalize().ok()),
        p.file_name(),
    ) {
        (Some(dir), Some(name)) => dir.join(name),
        _ => p,
    }
}
