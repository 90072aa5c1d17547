//! A cache of derived geometry on disk: a large mesh as placed in the scene, and a large
//! scene's BVH, so that a render that changes only the lights, the camera or the materials
//! skips the gunzip, the parse, the transform and the build.
//!
//! Off unless the program turns it on ([`enable`]; `glint render` does, `--no-cache` skips
//! it), so the library never writes to a user's folders by itself. An entry's key is an
//! XXH3-128 hash of everything its value is made from: the input bytes and settings, and
//! the source of the code that makes the value (`CODE`), so a new glint never reads an
//! old glint's entry. An entry carries an XXH3-64 checksum of its payload; an entry that
//! fails it, or is cut short, or names another key, is deleted and rebuilt, with one
//! warning. Entries are written to a temporary name and renamed into place, so a reader
//! never sees half of one (an interrupted process removes its temporary files, and a prune
//! removes any left an hour old), and the folder is kept under a size limit (oldest entries
//! go first). Imports nothing from glint.

use std::io::{Read, Write};
use std::path::{Path, PathBuf};
use std::sync::Mutex;

/// The source of the code whose output is cached, hashed into every key.
const CODE: &[&[u8]] = &[
    include_bytes!("cache.rs"),
    include_bytes!("bvh.rs"),
    include_bytes!("kernel/layout.rs"),
    include_bytes!("scene/mesh.rs"),
    include_bytes!("scene/obj.rs"),
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
/// line from its flags and environment) and hands to [`enable`].
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Settings {
    /// The folder.
    pub dir: PathBuf,
    /// The folder's size limit in bytes: the least recently used entries go beyond it.
    pub max_bytes: u64,
    /// The least number of primitives a value must be made from to be worth an entry.
    pub min_prims: usize,
}

impl Settings {
    /// `dir` with the default limits.
    pub fn new(dir: PathBuf) -> Settings {
        Settings {
            dir,
            max_bytes: DEFAULT_MIB << 20,
            min_prims: DEFAULT_MIN_PRIMS,
        }
    }
}

/// How old a temporary file in the folder must be for a prune to take it for one that a
/// killed process left (a live writer renames its file within seconds).
pub const STALE_TEMP: std::time::Duration = std::time::Duration::from_secs(3600);

/// The temporary files being written now ([`remove_pending_temps`]).
static TEMPS: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

/// The settings, once [`enable`]d.
static SETTINGS: Mutex<Option<Settings>> = Mutex::new(None);

/// What the cache did during this process, for `glint render -v` and the tests.
static EVENTS: Mutex<Vec<String>> = Mutex::new(Vec::new());

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
/// `$HOME/.cache/glint`; `None` when none of them is set.
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

/// Turns the cache on, as `settings` say.
pub fn enable(settings: Settings) {
    *SETTINGS.lock().unwrap_or_else(|e| e.into_inner()) = Some(settings);
}

/// Turns the cache off.
pub fn disable() {
    *SETTINGS.lock().unwrap_or_else(|e| e.into_inner()) = None;
}

/// The settings while the cache is on.
fn settings() -> Option<Settings> {
    SETTINGS.lock().unwrap_or_else(|e| e.into_inner()).clone()
}

/// Whether the cache is on (so a key is worth computing).
pub fn enabled() -> bool {
    dir().is_some()
}

/// Whether a value made from `primitives` primitives is worth an entry (the cache is on
/// and the count reaches [`Settings::min_prims`]).
pub fn worth(primitives: usize) -> bool {
    settings().is_some_and(|s| primitives >= s.min_prims)
}

/// What the cache did so far in this process ("hit mesh", "stored bvh", warnings), and
/// forgets it.
pub fn take_events() -> Vec<String> {
    std::mem::take(&mut *EVENTS.lock().unwrap_or_else(|e| e.into_inner()))
}

/// Whether [`store_owned`] writes on a thread of its own ([`write_behind`]).
static WRITE_BEHIND: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

/// The threads writing entries for [`store_owned`], until [`finish_writes`] joins them.
static PENDING: Mutex<Vec<std::thread::JoinHandle<()>>> = Mutex::new(Vec::new());

/// Lets [`store_owned`] write its entries on threads of their own, so that the work after
/// it (a mesh's entry is written while its BVH is built) does not wait for the write. A
/// program that turns this on must call [`finish_writes`] before it exits (`glint render`
/// does), or an entry may never be written; never half of one, as entries are renamed into
/// place whole. Off by default, so a library caller's stores are done when they return.
pub fn write_behind(on: bool) {
    WRITE_BEHIND.store(on, std::sync::atomic::Ordering::Relaxed);
}

/// Waits until every entry that [`store_owned`] is writing is written (or has failed, as a
/// warning among the events); returns how many it waited for.
pub fn finish_writes() -> usize {
    let pending = std::mem::take(&mut *PENDING.lock().unwrap_or_else(|e| e.into_inner()));
    let n = pending.len();
    for h in pending {
        let _ = h.join();
    }
    n
}

/// [`store`] for sections the caller gives away: written on a thread of its own where
/// [`write_behind`] is on, else here and now.
pub fn store_owned(kind: &'static str, key: Key, sections: Vec<Vec<u32>>) {
    let write = move || {
        let parts: Vec<&[u32]> = sections.iter().map(Vec::as_slice).collect();
        store(kind, &key, &parts);
    };
    if !WRITE_BEHIND.load(std::sync::atomic::Ordering::Relaxed) {
        return write();
    }
    match std::thread::Builder::new()
        .name(format!("cache {kind}"))
        .spawn(write)
    {
        Ok(h) => PENDING.lock().unwrap_or_else(|e| e.into_inner()).push(h),
        Err(e) => event(format!(
            "warning: cannot start the {kind} cache writer: {e}"
        )),
    }
}

fn event(e: String) {
    EVENTS.lock().unwrap_or_else(|e| e.into_inner()).push(e);
}

fn dir() -> Option<PathBuf> {
    settings().map(|s| s.dir)
}

/// The entry of `key`, as the sections it was stored with; `None` when the cache is off,
/// the entry is missing, or it is damaged (then it is deleted, and a warning recorded).
pub fn load(kind: &str, key: &Key) -> Option<Vec<Vec<u32>>> {
    let path = dir()?.join(key.file_name());
    let mut file = std::fs::File::open(&path).ok()?;
    match read_entry(&mut file, key) {
        Ok(sections) => {
            // Touched, so the size limit drops the entries least recently used.
            let _ = file.set_modified(std::time::SystemTime::now());
            event(format!("hit {kind}"));
            Some(sections)
        }
        Err(why) => {
            drop(file);
            let _ = std::fs::remove_file(&path);
            event(format!(
                "warning: cache entry {} was damaged ({why}); deleted, and the {kind} rebuilt",
                path.display()
            ));
            None
        }
    }
}

fn read_entry(file: &mut std::fs::File, key: &Key) -> Result<Vec<Vec<u32>>, String> {
    let mut head = [0u8; 8 + 16 + 8 + 4];
    file.read_exact(&mut head)
        .map_err(|_| "shorter than its header")?;
    if &head[..8] != MAGIC {
        return Err("not a glint cache entry of this format".into());
    }
    if head[8..24] != key.0.to_le_bytes() {
        return Err("it holds another key".into());
    }
    let sum = u64::from_le_bytes(head[24..32].try_into().expect("8 bytes"));
    let n = u32::from_le_bytes(head[32..36].try_into().expect("4 bytes")) as usize;
    if n > 64 {
        return Err(format!("{n} sections"));
    }
    let mut lens = vec![0u8; 8 * n];
    file.read_exact(&mut lens).map_err(|_| "cut short")?;
    let total: u64 = lens
        .chunks_exact(8)
        .map(|c| u64::from_le_bytes(c.try_into().expect("8 bytes")))
        .try_fold(0u64, |a, l| a.checked_add(l))
        .ok_or("section lengths overflow")?;
    let size = file.metadata().map_err(|e| e.to_string())?.len();
    if total.checked_mul(4).is_none_or(|b| b > size) {
        return Err("cut short".into());
    }
    let mut h = xxhash_rust::xxh3::Xxh3::new();
    let mut sections = Vec::with_capacity(n);
    for c in lens.chunks_exact(8) {
        let len = u64::from_le_bytes(c.try_into().expect("8 bytes")) as usize;
        let mut words = vec![0u32; len];
        file.read_exact(bytemuck::cast_slice_mut(&mut words))
            .map_err(|_| "cut short")?;
        h.update(bytemuck::cast_slice(&words));
        sections.push(words);
    }
    if file.read(&mut [0u8; 1]).map_err(|e| e.to_string())? != 0 {
        return Err("longer than its sections".into());
    }
    if h.digest() != sum {
        return Err("checksum mismatch".into());
    }
    Ok(sections)
}

/// Stores `sections` under `key` (nothing when the cache is off). A failure to write is
/// recorded as a warning and otherwise ignored: the render goes on without the entry.
pub fn store(kind: &str, key: &Key, sections: &[&[u32]]) {
    let Some(dir) = dir() else { return };
    match write_entry(&dir, key, sections) {
        Ok(()) => {
            event(format!("stored {kind}"));
            prune(&dir, limit_bytes());
        }
        Err(e) => event(format!(
            "warning: cannot write the {kind} cache entry in {}: {e}",
            dir.display()
        )),
    }
}

fn write_entry(dir: &Path, key: &Key, sections: &[&[u32]]) -> std::io::Result<()> {
    std::fs::create_dir_all(dir)?;
    let mut h = xxhash_rust::xxh3::Xxh3::new();
    for s in sections {
        h.update(bytemuck::cast_slice(s));
    }
    let tmp = dir.join(format!("{}.{}.tmp", key.file_name(), std::process::id()));
    let temps = || TEMPS.lock().unwrap_or_else(|e| e.into_inner());
    temps().push(tmp.clone());
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
    temps().retain(|p| *p != tmp);
    result
}

/// Removes the temporary files of the entries being written now (for an interrupted
/// process: `glint render`'s Ctrl-C handler calls it, so that no half-written file is left
/// in the folder). A file that an interrupt leaves anyway is removed by a later prune once
/// it is [`STALE_TEMP`] old.
pub fn remove_pending_temps() {
    for p in std::mem::take(&mut *TEMPS.lock().unwrap_or_else(|e| e.into_inner())) {
        let _ = std::fs::remove_file(p);
    }
}

/// The folder's size limit ([`Settings::max_bytes`]; the default when the cache is off).
fn limit_bytes() -> u64 {
    settings().map_or(DEFAULT_MIB << 20, |s| s.max_bytes)
}

/// Deletes the least recently used entries while the folder's entries exceed `limit`
/// bytes.
fn prune(dir: &Path, limit: u64) {
    let Ok(read) = std::fs::read_dir(dir) else {
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
            event(format!("removed {}", e.path().display()));
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
            event(format!("evicted {}", path.display()));
        }
    }
}

/// Reinterprets a section as a vector of `T` (copying only if its size does not divide).
pub fn section_as<T: bytemuck::Pod>(words: Vec<u32>) -> Vec<T> {
    bytemuck::try_cast_vec(words).unwrap_or_else(|(_, w)| bytemuck::pod_collect_to_vec(&w))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The tests here share the process-wide folder, so they run as one test.
    #[test]
    fn entries_round_trip_and_damage_is_caught() {
        let dir = std::env::temp_dir().join(format!("glint-cache-unit-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        enable(Settings::new(dir.clone()));
        let key = Key::new("test", &[b"abc"]);
        assert_ne!(key, Key::new("test", &[b"abd"]), "the key sees its input");
        assert_ne!(key, Key::new("test", &[b"ab", b"c"]), "parts are delimited");
        assert!(load("test", &key).is_none());
        let a: Vec<u32> = (0..1000).collect();
        let b: Vec<u32> = vec![7; 3];
        store("test", &key, &[&a, &b]);
        assert_eq!(load("test", &key), Some(vec![a.clone(), b.clone()]));

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
            take_events();
            std::fs::write(&path, &bad).unwrap();
            assert!(load("test", &key).is_none(), "{why}");
            assert!(!path.exists());
            let events = take_events();
            assert!(events.iter().any(|e| e.contains(why)), "{why}: {events:?}");
        }
        std::fs::write(dir.join(other.file_name()), &good).unwrap();
        assert!(load("test", &other).is_none(), "a renamed entry is refused");

        // The size limit drops the least recently used entries first.
        store("test", &key, &[&a]);
        store("test", &other, &[&b]);
        let old = std::time::SystemTime::now() - std::time::Duration::from_secs(60);
        let f = std::fs::File::options().write(true).open(&path).unwrap();
        f.set_modified(old).unwrap();
        prune(
            &dir,
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
        prune(&dir, u64::MAX);
        assert!(!stale.exists(), "a stale temporary file goes");
        assert!(fresh.exists(), "a fresh one stays");
        // And an interrupt's handler removes the files being written.
        TEMPS.lock().unwrap().push(fresh.clone());
        remove_pending_temps();
        assert!(!fresh.exists());

        // Written behind: the entry is there once `finish_writes` has waited for it, and
        // the events say so; without write-behind, `store_owned` is done when it returns.
        let behind = Key::new("test", &[b"behind"]);
        take_events();
        write_behind(true);
        store_owned("test", behind, vec![a.clone(), b.clone()]);
        assert_eq!(finish_writes(), 1);
        write_behind(false);
        assert_eq!(load("test", &behind), Some(vec![a.clone(), b.clone()]));
        assert!(take_events().iter().any(|e| e == "stored test"));
        let now = Key::new("test", &[b"now"]);
        store_owned("test", now, vec![b.clone()]);
        assert_eq!(finish_writes(), 0);
        assert_eq!(load("test", &now), Some(vec![b.clone()]));
        disable();
        assert!(load("test", &key).is_none());
        let _ = std::fs::remove_dir_all(&dir);
    }
}
