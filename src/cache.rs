//! A cache of derived geometry on disk: a large mesh as placed in the scene, and a large
//! scene's BVH, so that a render that changes only the lights, the camera or the materials
//! skips the gunzip, the parse, the transform and the build.
//!
//! A [`Cache`] is a value the program makes from [`Settings`] and hands to the scene
//! loader ([`crate::scene::LoadOptions::cache`]), which passes it on to the BVH build
//! through [`crate::scene::Scene::cache`]; without one nothing is cached, so the library
//! never writes to a user's folders by itself (`glint render` makes one, `--no-cache`
//! skips it). An entry's key is an XXH3-128 hash of everything its value is made from: the
//! input bytes and settings, and the source of the code that makes the value (`CODE`), so
//! a new glint never reads an old glint's entry. An entry carries an XXH3-64 checksum of
//! its payload; an entry that fails it, or is cut short, or names another key, is deleted
//! and rebuilt, with one warning. Entries are written to a temporary name and renamed into
//! place, so a reader never sees half of one (an interrupted process removes its temporary
//! files, and a prune removes any left an hour old), and the folder is kept under a size
//! limit (oldest entries go first). Imports nothing from glint.

use std::io::{Read, Write};
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

/// The source of the code whose output is cached, hashed into every key.
const CODE: &[&[u8]] = &[
    include_bytes!("cache.rs"),
    include_bytes!("bvh.rs"),
    include_bytes!("shared/layout.rs"),
    include_bytes!("scene/mesh/mod.rs"),
    include_bytes!("scene/mesh/gunzip.rs"),
    include_bytes!("scene/mesh/place.rs"),
    include_bytes!("scene/mesh/transform.rs"),
    include_bytes!("scene/obj.rs"),
    include_bytes!("scene/ply.rs"),
    include_bytes!("scene/gltf.rs"),
];

/// First bytes of every entry (the last one is the format's version).
const MAGIC: &[u8; 8] = b"glintc\0\x01";

/// Default size limit of the folder, MiB (`glint render` reads `GLINT_CACHE_MIB`).
pub const DEFAULT_MIB: u64 = 2048;

/// Default least number of primitives worth an entry (`glint render` reads
/// `GLINT_CACHE_MIN_PRIMS`): below it, the work takes a few milliseconds and an entry
/// would only take disk.
pub const DEFAULT_MIN_PRIMS: usize = 100_000;

/// Where the cache keeps its entries and how much: a value the program makes (the command
/// line from its flags and environment) and hands to [`Cache::new`].
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Settings {
    /// The folder.
    pub dir: PathBuf,
    /// The folder's size limit in bytes: the least recently used entries go beyond it.
    pub max_bytes: u64,
    /// The least number of primitives a value must be made from to be worth an entry.
    pub min_prims: usize,
    /// Whether [`Cache::store_owned`] writes on a thread of its own, so that the work after
    /// it (a mesh's entry is written while its BVH is built) does not wait for the write.
    /// A program that turns this on must call [`Cache::finish_writes`] before it exits
    /// (`glint render` does), or an entry may never be written; never half of one, as
    /// entries are renamed into place whole. Off by default, so a library caller's stores
    /// are done when they return.
    pub write_behind: bool,
}

impl Settings {
    /// `dir` with the default limits, written in the foreground.
    pub fn new(dir: PathBuf) -> Settings {
        Settings {
            dir,
            max_bytes: DEFAULT_MIB << 20,
            min_prims: DEFAULT_MIN_PRIMS,
            write_behind: false,
        }
    }
}

/// How old a temporary file in the folder must be for a prune to take it for one that a
/// killed process left (a live writer renames its file within seconds).
pub const STALE_TEMP: std::time::Duration = std::time::Duration::from_secs(3600);

/// The temporary files being written now, by every [`Cache`] of the process
/// ([`remove_pending_temps`]). Process-wide, unlike the rest of the cache's state, because
/// the one that reads it is a signal handler: `glint render`'s Ctrl-C handler runs on a
/// thread of its own, holds no [`Cache`], and must find every half-written file (a writer
/// thread's too) before the process exits.
static TEMPS: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

/// The key of an entry: a hash of its inputs and of `CODE` (the source of the code that makes entries).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Key(u128);

impl Key {
    /// The key of a value of `kind` (e.g. "mesh", "bvh") made from `parts`.
    pub fn new(kind: &str, parts: &[&[u8]]) -> Key {
        let mut h = xxhash_rust::xxh3::Xxh3::new();
        for c in CODE {
            h.update(&(c.len() as u64).to_le_bytes());
            h.update(c);
        }
        h.update(kind.as_bytes());
        for p in parts {
            // Lengths first, so ("ab", "c") and ("a", "bc") differ.
            h.update(&(p.len() as u64).to_le_bytes());
            h.update(p);
        }
        Key(h.digest128())
    }

    fn file_name(&self) -> String {
        format!("{:032x}.bin", self.0)
    }
}

/// The folder the cache would use: `GLINT_CACHE_DIR`, else `$XDG_CACHE_HOME/glint`, else
/// `$HOME/.cache/glint`; `None` when none of them is set. For the program to call (the
/// library itself reads no environment variable).
pub fn default_dir() -> Option<PathBuf> {
    let var = |k: &str| {
        std::env::var_os(k)
            .filter(|v| !v.is_empty())
            .map(PathBuf::from)
    };
    var("GLINT_CACHE_DIR")
        .or_else(|| var("XDG_CACHE_HOME").map(|d| d.join("glint")))
        .or_else(|| var("HOME").map(|d| d.join(".cache").join("glint")))
}

/// What a [`Cache`] did, for `glint render -v` and the tests. Its `Display` is the line the
/// command line prints: a warning ([`Event::is_warning`]) as it is, anything else after
/// `cache: ` when asked to be verbose.
#[derive(Debug)]
pub enum Event {
    /// An entry of `kind` ("mesh", "bvh") was read: "hit mesh".
    Hit {
        /// What the entry holds.
        kind: &'static str,
    },
    /// An entry of `kind` was written: "stored mesh".
    Stored {
        /// What the entry holds.
        kind: &'static str,
    },
    /// A prune removed a temporary file that a killed process left ([`STALE_TEMP`]).
    RemovedTemp(PathBuf),
    /// A prune removed an entry to keep the folder under its size limit.
    Evicted(PathBuf),
    /// A warning: the entry at `path` was damaged, so it was deleted and its value rebuilt.
    Damaged {
        /// What the entry held.
        kind: &'static str,
        /// The entry's file.
        path: PathBuf,
        /// What was wrong with it.
        why: CacheError,
    },
    /// A warning: an entry could not be written in `dir` (the render goes on without it).
    WriteFailed {
        /// What the entry would have held.
        kind: &'static str,
        /// The cache's folder.
        dir: PathBuf,
        /// What the OS said.
        error: std::io::Error,
    },
    /// A warning: the thread that was to write an entry behind could not be started, so the
    /// entry is not written.
    WriterNotStarted {
        /// What the entry would have held.
        kind: &'static str,
        /// What the OS said.
        error: std::io::Error,
    },
}

impl Event {
    /// Whether the event is a warning, which the command line prints whatever its
    /// verbosity (its text starts with "warning").
    pub fn is_warning(&self) -> bool {
        matches!(
            self,
            Event::Damaged { .. } | Event::WriteFailed { .. } | Event::WriterNotStarted { .. }
        )
    }
}

impl std::fmt::Display for Event {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Event::Hit { kind } => write!(f, "hit {kind}"),
            Event::Stored { kind } => write!(f, "stored {kind}"),
            Event::RemovedTemp(path) => write!(f, "removed {}", path.display()),
            Event::Evicted(path) => write!(f, "evicted {}", path.display()),
            Event::Damaged { kind, path, why } => write!(
                f,
                "warning: cache entry {} was damaged ({why}); deleted, and the {kind} rebuilt",
                path.display()
            ),
            Event::WriteFailed { kind, dir, error } => write!(
                f,
                "warning: cannot write the {kind} cache entry in {}: {error}",
                dir.display()
            ),
            Event::WriterNotStarted { kind, error } => {
                write!(f, "warning: cannot start the {kind} cache writer: {error}")
            }
        }
    }
}

/// Why an entry was taken for damaged (then deleted, and its value rebuilt).
#[derive(Debug, thiserror::Error)]
pub enum CacheError {
    /// The file ends before its header does.
    #[error("shorter than its header")]
    ShortHeader,
    /// The first bytes are not those of an entry of this format: another file, or an entry
    /// of another format version.
    #[error("not a glint cache entry of this format")]
    Format,
    /// The header names another key: the file was renamed or copied.
    #[error("it holds another key")]
    OtherKey,
    /// More sections than any entry has.
    #[error("{0} sections")]
    Sections(usize),
    /// The file ends before its sections do.
    #[error("cut short")]
    CutShort,
    /// The sections' lengths add up beyond `u64`.
    #[error("section lengths overflow")]
    Overflow,
    /// Bytes follow the last section.
    #[error("longer than its sections")]
    TooLong,
    /// The payload's checksum is not the one in the header.
    #[error("checksum mismatch")]
    Checksum,
    /// The OS refused to read on.
    #[error("{0}")]
    Io(std::io::Error),
}

/// The cache: its [`Settings`], what it did ([`Event`]s) and the entries being written
/// behind. Shared as `Arc<Cache>`: the scene loader and the BVH build each use it through
/// [`crate::scene::Scene::cache`], and [`Cache::store_owned`] lends it to its writer
/// threads. `Send + Sync`: its state is behind mutexes.
pub struct Cache {
    settings: Settings,
    events: Mutex<Vec<Event>>,
    /// The threads writing entries for [`Cache::store_owned`], until
    /// [`Cache::finish_writes`] joins them.
    pending: Mutex<Vec<std::thread::JoinHandle<()>>>,
}

impl std::fmt::Debug for Cache {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Cache")
            .field("settings", &self.settings)
            .finish_non_exhaustive()
    }
}

/// A cache equals only itself (the same value, as two clones of one `Arc` are): two caches
/// with the same settings are still two, each with its own events and writes. So scenes
/// that hold a cache ([`crate::scene::Scene::cache`]) compare equal only when they hold
/// the same one, or none.
impl PartialEq for Cache {
    fn eq(&self, other: &Cache) -> bool {
        std::ptr::eq(self, other)
    }
}

impl Eq for Cache {}

/// A mutex's value, even if a thread panicked while holding it (each value here is whole
/// after every step).
fn lock<T>(m: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|e| e.into_inner())
}

impl Cache {
    /// A cache as `settings` say. Nothing is read or written until it is used.
    pub fn new(settings: Settings) -> Cache {
        Cache {
            settings,
            events: Mutex::new(Vec::new()),
            pending: Mutex::new(Vec::new()),
        }
    }

    /// Its settings.
    pub fn settings(&self) -> &Settings {
        &self.settings
    }

    /// Whether a value made from `primitives` primitives is worth an entry (the count
    /// reaches [`Settings::min_prims`]).
    pub fn worth(&self, primitives: usize) -> bool {
        primitives >= self.settings.min_prims
    }

    /// What the cache did so far ("hit mesh", "stored bvh", warnings), in order, and
    /// forgets it.
    pub fn take_events(&self) -> Vec<Event> {
        std::mem::take(&mut *lock(&self.events))
    }

    fn event(&self, e: Event) {
        lock(&self.events).push(e);
    }

    /// Waits until every entry that [`Cache::store_owned`] is writing is written (or has
    /// failed, as a warning among the events); returns how many it waited for.
    pub fn finish_writes(&self) -> usize {
        let pending = std::mem::take(&mut *lock(&self.pending));
        let n = pending.len();
        for h in pending {
            let _ = h.join();
        }
        n
    }

    /// [`Cache::store`] for sections the caller gives away: written on a thread of its own
    /// where [`Settings::write_behind`] is on, else here and now.
    pub fn store_owned(self: &Arc<Self>, kind: &'static str, key: Key, sections: Vec<Vec<u32>>) {
        let cache = Arc::clone(self);
        let write = move || {
            let parts: Vec<&[u32]> = sections.iter().map(Vec::as_slice).collect();
            cache.store(kind, &key, &parts);
        };
        if !self.settings.write_behind {
            return write();
        }
        match std::thread::Builder::new()
            .name(format!("cache {kind}"))
            .spawn(write)
        {
            Ok(h) => lock(&self.pending).push(h),
            Err(error) => self.event(Event::WriterNotStarted { kind, error }),
        }
    }

    /// The entry of `key`, as the sections it was stored with; `None` when the entry is
    /// missing, or it is damaged (then it is deleted, and a warning recorded).
    pub fn load(&self, kind: &'static str, key: &Key) -> Option<Vec<Vec<u32>>> {
        let path = self.settings.dir.join(key.file_name());
        let read = {
            let mut file = std::fs::File::open(&path).ok()?;
            let read = read_entry(&mut file, key);
            if read.is_ok() {
                // Touched, so the size limit drops the entries least recently used.
                let _ = file.set_modified(std::time::SystemTime::now());
            }
            read
        }; // the file closed, so that a damaged one can be deleted (on Windows too)
        match read {
            Ok(sections) => {
                self.event(Event::Hit { kind });
                Some(sections)
            }
            Err(why) => {
                let _ = std::fs::remove_file(&path);
                self.event(Event::Damaged { kind, path, why });
                None
            }
        }
    }

    /// Stores `sections` under `key`. A failure to write is recorded as a warning and
    /// otherwise ignored: the render goes on without the entry.
    pub fn store(&self, kind: &'static str, key: &Key, sections: &[&[u32]]) {
        let dir = &self.settings.dir;
        match write_entry(dir, key, sections) {
            Ok(()) => {
                self.event(Event::Stored { kind });
                self.prune(self.settings.max_bytes);
            }
            Err(error) => self.event(Event::WriteFailed {
                kind,
                dir: dir.clone(),
                error,
            }),
        }
    }

    /// Deletes the least recently used entries while the folder's entries exceed `limit`
    /// bytes, and the temporary files that killed processes left.
    fn prune(&self, limit: u64) {
        let Ok(read) = std::fs::read_dir(&self.settings.dir) else {
            return;
        };
        let files: Vec<std::fs::DirEntry> = read.filter_map(|e| e.ok()).collect();
        // Temporary files that a killed process left (see `STALE_TEMP`).
        let now = std::time::SystemTime::now();
        for e in files
            .iter()
            .filter(|e| e.file_name().to_string_lossy().ends_with(".tmp"))
        {
            let age = e.metadata().and_then(|m| m.modified()).ok();
            let age = age.and_then(|t| now.duration_since(t).ok());
            if age.is_some_and(|a| a > STALE_TEMP) && std::fs::remove_file(e.path()).is_ok() {
                self.event(Event::RemovedTemp(e.path()));
            }
        }
        let mut entries: Vec<(std::time::SystemTime, u64, PathBuf)> = files
            .iter()
            .filter(|e| e.file_name().to_string_lossy().ends_with(".bin"))
            .filter_map(|e| {
                let m = e.metadata().ok()?;
                Some((m.modified().ok()?, m.len(), e.path()))
            })
            .collect();
        let mut total: u64 = entries.iter().map(|e| e.1).sum();
        entries.sort();
        for (_, len, path) in entries {
            if total <= limit {
                break;
            }
            if std::fs::remove_file(&path).is_ok() {
                total -= len;
                self.event(Event::Evicted(path));
            }
        }
    }
}

fn read_entry(file: &mut std::fs::File, key: &Key) -> Result<Vec<Vec<u32>>, CacheError> {
    let mut head = [0u8; 8 + 16 + 8 + 4];
    file.read_exact(&mut head)
        .map_err(|_| CacheError::ShortHeader)?;
    if &head[..8] != MAGIC {
        return Err(CacheError::Format);
    }
    if head[8..24] != key.0.to_le_bytes() {
        return Err(CacheError::OtherKey);
    }
    let sum = u64::from_le_bytes(head[24..32].try_into().expect("8 bytes"));
    let n = u32::from_le_bytes(head[32..36].try_into().expect("4 bytes")) as usize;
    if n > 64 {
        return Err(CacheError::Sections(n));
    }
    let mut lens = vec![0u8; 8 * n];
    file.read_exact(&mut lens)
        .map_err(|_| CacheError::CutShort)?;
    let total: u64 = lens
        .chunks_exact(8)
        .map(|c| u64::from_le_bytes(c.try_into().expect("8 bytes")))
        .try_fold(0u64, |a, l| a.checked_add(l))
        .ok_or(CacheError::Overflow)?;
    let size = file.metadata().map_err(CacheError::Io)?.len();
    if total.checked_mul(4).is_none_or(|b| b > size) {
        return Err(CacheError::CutShort);
    }
    let mut h = xxhash_rust::xxh3::Xxh3::new();
    let mut sections = Vec::with_capacity(n);
    for c in lens.chunks_exact(8) {
        let len = u64::from_le_bytes(c.try_into().expect("8 bytes")) as usize;
        let mut words = vec![0u32; len];
        file.read_exact(bytemuck::cast_slice_mut(&mut words))
            .map_err(|_| CacheError::CutShort)?;
        h.update(bytemuck::cast_slice(&words));
        sections.push(words);
    }
    if file.read(&mut [0u8; 1]).map_err(CacheError::Io)? != 0 {
        return Err(CacheError::TooLong);
    }
    if h.digest() != sum {
        return Err(CacheError::Checksum);
    }
    Ok(sections)
}

fn write_entry(dir: &Path, key: &Key, sections: &[&[u32]]) -> std::io::Result<()> {
    std::fs::create_dir_all(dir)?;
    let mut h = xxhash_rust::xxh3::Xxh3::new();
    for s in sections {
        h.update(bytemuck::cast_slice(s));
    }
    let tmp = dir.join(format!("{}.{}.tmp", key.file_name(), std::process::id()));
    lock(&TEMPS).push(tmp.clone());
    let result = (|| {
        let mut f = std::io::BufWriter::new(std::fs::File::create(&tmp)?);
        f.write_all(MAGIC)?;
        f.write_all(&key.0.to_le_bytes())?;
        f.write_all(&h.digest().to_le_bytes())?;
        f.write_all(&(sections.len() as u32).to_le_bytes())?;
        for s in sections {
            f.write_all(&(s.len() as u64).to_le_bytes())?;
        }
        for s in sections {
            f.write_all(bytemuck::cast_slice(s))?;
        }
        // Not synced to disk: an entry that a crash leaves half written fails its
        // checksum on the next read and is rebuilt, and syncing 60 MB costs a third of a
        // second.
        f.flush()?;
        drop(f);
        std::fs::rename(&tmp, dir.join(key.file_name()))
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    lock(&TEMPS).retain(|p| *p != tmp);
    result
}

/// Removes the temporary files of the entries being written now, by any [`Cache`] (for an
/// interrupted process: `glint render`'s Ctrl-C handler calls it, so that no half-written
/// file is left in the folder). A file that an interrupt leaves anyway is removed by a
/// later prune once it is [`STALE_TEMP`] old.
pub fn remove_pending_temps() {
    for p in std::mem::take(&mut *lock(&TEMPS)) {
        let _ = std::fs::remove_file(p);
    }
}

/// Reinterprets a section as a vector of `T` (copying only if its size does not divide).
pub fn section_as<T: bytemuck::Pod>(words: Vec<u32>) -> Vec<T> {
    bytemuck::try_cast_vec(words).unwrap_or_else(|(_, w)| bytemuck::pod_collect_to_vec(&w))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A cache in a fresh folder of its own, named `name`.
    fn fresh(name: &str) -> (Arc<Cache>, PathBuf) {
        let dir =
            std::env::temp_dir().join(format!("glint-cache-unit-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        (Arc::new(Cache::new(Settings::new(dir.clone()))), dir)
    }

    #[test]
    fn entries_round_trip_and_damage_is_caught() {
        let (cache, dir) = fresh("round-trip");
        let key = Key::new("test", &[b"abc"]);
        assert_ne!(key, Key::new("test", &[b"abd"]), "the key sees its input");
        assert_ne!(key, Key::new("test", &[b"ab", b"c"]), "parts are delimited");
        assert!(cache.load("test", &key).is_none());
        let a: Vec<u32> = (0..1000).collect();
        let b: Vec<u32> = vec![7; 3];
        cache.store("test", &key, &[&a, &b]);
        assert_eq!(cache.load("test", &key), Some(vec![a.clone(), b.clone()]));

        // One flipped bit in the payload, a cut, another key's entry: each is caught, the
        // entry deleted, and a warning recorded.
        let path = dir.join(key.file_name());
        let good = std::fs::read(&path).unwrap();
        let mut flipped = good.clone();
        *flipped.last_mut().unwrap() ^= 1;
        let other = Key::new("test", &[b"xyz"]);
        for (bad, why) in [
            (flipped, "checksum"),
            (good[..good.len() - 4].to_vec(), "cut short"),
            (good[..20].to_vec(), "header"),
        ] {
            cache.take_events();
            std::fs::write(&path, &bad).unwrap();
            assert!(cache.load("test", &key).is_none(), "{why}");
            assert!(!path.exists());
            let events = cache.take_events();
            assert!(
                events
                    .iter()
                    .any(|e| e.is_warning() && e.to_string().contains(why)),
                "{why}: {events:?}"
            );
        }
        std::fs::write(dir.join(other.file_name()), &good).unwrap();
        assert!(
            cache.load("test", &other).is_none(),
            "a renamed entry is refused"
        );

        // The size limit drops the least recently used entries first.
        cache.store("test", &key, &[&a]);
        cache.store("test", &other, &[&b]);
        let old = std::time::SystemTime::now() - std::time::Duration::from_secs(60);
        let f = std::fs::File::options().write(true).open(&path).unwrap();
        f.set_modified(old).unwrap();
        cache.prune(
            std::fs::metadata(dir.join(other.file_name()))
                .unwrap()
                .len(),
        );
        assert!(!path.exists(), "the older entry goes");
        assert!(dir.join(other.file_name()).exists(), "the newer stays");

        // A temporary file that a killed writer left goes once it is stale; one that may
        // still be being written stays.
        let (stale, fresh) = (dir.join("a.1.tmp"), dir.join("b.2.tmp"));
        std::fs::write(&stale, b"half").unwrap();
        std::fs::write(&fresh, b"half").unwrap();
        let long_ago = std::time::SystemTime::now() - STALE_TEMP * 2;
        let f = std::fs::File::options().write(true).open(&stale).unwrap();
        f.set_modified(long_ago).unwrap();
        cache.prune(u64::MAX);
        assert!(!stale.exists(), "a stale temporary file goes");
        assert!(fresh.exists(), "a fresh one stays");
        // And an interrupt's handler removes the files being written.
        lock(&TEMPS).push(fresh.clone());
        remove_pending_temps();
        assert!(!fresh.exists());
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn written_behind_entries_are_there_once_finished() {
        // Written behind: the entry is there once `finish_writes` has waited for it, and
        // the events say so.
        let (now, dir) = fresh("behind");
        let behind = Arc::new(Cache::new(Settings {
            write_behind: true,
            ..now.settings().clone()
        }));
        let (a, b): (Vec<u32>, Vec<u32>) = ((0..100).collect(), vec![7; 3]);
        let key = Key::new("test", &[b"behind"]);
        behind.store_owned("test", key, vec![a.clone(), b.clone()]);
        assert_eq!(behind.finish_writes(), 1);
        assert_eq!(behind.load("test", &key), Some(vec![a.clone(), b.clone()]));
        let events = behind.take_events();
        assert!(
            matches!(
                events[..],
                [Event::Stored { kind: "test" }, Event::Hit { kind: "test" }]
            ),
            "{events:?}"
        );
        // Without write-behind, `store_owned` is done when it returns; each cache has its
        // own events.
        let key = Key::new("test", &[b"now"]);
        now.store_owned("test", key, vec![b.clone()]);
        assert_eq!(now.finish_writes(), 0);
        assert_eq!(now.load("test", &key), Some(vec![b.clone()]));
        assert!(behind.take_events().is_empty());
        assert_eq!(now.take_events().len(), 2);
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn events_print_as_before_and_warnings_are_told_apart() {
        let io = || std::io::Error::other("disk full");
        let path = PathBuf::from("/c/x.bin");
        let cases = [
            (Event::Hit { kind: "mesh" }, "hit mesh"),
            (Event::Stored { kind: "bvh" }, "stored bvh"),
            (Event::RemovedTemp(path.clone()), "removed /c/x.bin"),
            (Event::Evicted(path.clone()), "evicted /c/x.bin"),
            (
                Event::Damaged {
                    kind: "mesh",
                    path: path.clone(),
                    why: CacheError::Checksum,
                },
                "warning: cache entry /c/x.bin was damaged (checksum mismatch); deleted, and the mesh rebuilt",
            ),
            (
                Event::WriteFailed {
                    kind: "bvh",
                    dir: PathBuf::from("/c"),
                    error: io(),
                },
                "warning: cannot write the bvh cache entry in /c: disk full",
            ),
            (
                Event::WriterNotStarted {
                    kind: "mesh",
                    error: io(),
                },
                "warning: cannot start the mesh cache writer: disk full",
            ),
        ];
        for (event, text) in &cases {
            assert_eq!(event.to_string(), *text);
            // The front end told warnings apart by their text: the two ways agree.
            assert_eq!(event.is_warning(), text.starts_with("warning"), "{text}");
        }
        // The twin: the comparison sees a different text.
        assert_ne!(Event::Hit { kind: "bvh" }.to_string(), "hit mesh");
        assert!(cases.iter().any(|(e, _)| !e.is_warning()));
        assert!(cases.iter().any(|(e, _)| e.is_warning()));
    }

    #[test]
    fn a_cache_equals_only_itself() {
        let (a, dir) = fresh("equal");
        let b = Arc::new(Cache::new(a.settings().clone()));
        assert_eq!(a, Arc::clone(&a));
        assert_ne!(a, b, "the same settings, another cache");
        assert!(format!("{a:?}").contains("glint-cache-unit-equal"));
        let _ = std::fs::remove_dir_all(&dir);
    }
}
