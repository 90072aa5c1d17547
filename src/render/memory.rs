//! Whether a frame fits in this process's memory, asked before any work.

/// Why a frame was refused before any work.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error(
    "a {width}x{height} frame needs about {} MiB of memory at once and this process has {} MiB \
     (available memory, and the ulimit -v address-space limit): choose a smaller size",
    .needed >> 20,
    .room >> 20
)]
pub struct MemoryError {
    /// The frame's width.
    pub width: u32,
    /// The frame's height.
    pub height: u32,
    /// Bytes needed at once, with the margin.
    pub needed: u64,
    /// Bytes this process has.
    pub room: u64,
}

/// Fails, before any work, when the `bytes` a `w`×`h` frame needs at once cannot fit in
/// this process's memory: what the system has available and what the address-space limit
/// (`ulimit -v`) leaves, with 512 MiB to spare for the scene, the driver and the encoder.
/// Where the system says neither (not Linux), every frame passes.
pub fn check_memory(w: u32, h: u32, bytes: u64) -> Result<(), MemoryError> {
    let needed = bytes.saturating_add(512 << 20);
    let read = |path: &str| std::fs::read_to_string(path).unwrap_or_default();
    let field = |text: &str, key: &str| -> Option<u64> {
        text.lines()
            .find(|l| l.starts_with(key))
            .and_then(|l| l.split_whitespace().nth(1))
            .and_then(|v| v.parse().ok())
    };
    let available = field(&read("/proc/meminfo"), "MemAvailable:").map(|kb| kb << 10);
    let limit = read("/proc/self/limits")
        .lines()
        .find(|l| l.starts_with("Max address space"))
        .and_then(|l| l.split_whitespace().nth(3).map(str::to_owned))
        .and_then(|v| v.parse::<u64>().ok());
    let used = field(&read("/proc/self/status"), "VmSize:").map_or(0, |kb| kb << 10);
    let room = [available, limit.map(|l| l.saturating_sub(used))]
        .into_iter()
        .flatten()
        .min();
    match room {
        Some(room) if needed > room => Err(MemoryError {
            width: w,
            height: h,
            needed,
            room,
        }),
        _ => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::check_memory;

    /// A frame of a few bytes passes; one of an exabyte is refused, naming its size.
    #[test]
    fn absurd_frames_are_refused() {
        assert!(check_memory(2, 2, 64).is_ok());
        if std::path::Path::new("/proc/meminfo").exists() {
            let e = check_memory(1 << 20, 1 << 20, 1 << 60).unwrap_err();
            assert!(e.to_string().contains("1048576x1048576"), "{e}");
        }
    }
}
