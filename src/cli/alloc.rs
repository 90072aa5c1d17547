//! The process's allocator: glibc's, with huge pages for large blocks.

/// The system allocator, asking Linux to back each block of 4 MiB or more with huge pages
/// (`MADV_HUGEPAGE`: 2 MiB a page fault instead of 4 KiB) where transparent huge pages are
/// on "madvise". A mesh's big vectors (the inflated text, the faces, the triangles, the
/// tree) are written once each, so their first touch was a page fault every 4 KiB.
#[cfg(all(target_os = "linux", target_env = "gnu"))]
pub struct HugeBlocks;

#[cfg(all(target_os = "linux", target_env = "gnu"))]
impl HugeBlocks {
    const MIN: usize = 4 << 20;
    const HUGE: usize = 2 << 20;

    /// Advises the whole huge pages inside `len` bytes at `p`.
    fn advise(p: *mut u8, len: usize) {
        if p.is_null() || len < Self::MIN {
            return;
        }
        let start = (p as usize).next_multiple_of(Self::HUGE);
        let end = (p as usize + len) / Self::HUGE * Self::HUGE;
        if end > start {
            // SAFETY: the range lies inside the block just allocated; madvise only hints.
            unsafe { libc::madvise(start as *mut libc::c_void, end - start, libc::MADV_HUGEPAGE) };
        }
    }
}

// SAFETY: every call is the system allocator's, with a hint added after it.
#[cfg(all(target_os = "linux", target_env = "gnu"))]
unsafe impl std::alloc::GlobalAlloc for HugeBlocks {
    unsafe fn alloc(&self, layout: std::alloc::Layout) -> *mut u8 {
        // SAFETY: as the caller's contract for `alloc`.
        let p = unsafe { std::alloc::System.alloc(layout) };
        Self::advise(p, layout.size());
        p
    }
    unsafe fn alloc_zeroed(&self, layout: std::alloc::Layout) -> *mut u8 {
        // SAFETY: as the caller's contract for `alloc_zeroed`.
        let p = unsafe { std::alloc::System.alloc_zeroed(layout) };
        Self::advise(p, layout.size());
        p
    }
    unsafe fn dealloc(&self, p: *mut u8, layout: std::alloc::Layout) {
        // SAFETY: as the caller's contract for `dealloc`.
        unsafe { std::alloc::System.dealloc(p, layout) }
    }
    unsafe fn realloc(&self, p: *mut u8, layout: std::alloc::Layout, size: usize) -> *mut u8 {
        // SAFETY: as the caller's contract for `realloc`.
        let q = unsafe { std::alloc::System.realloc(p, layout, size) };
        Self::advise(q, size);
        q
    }
}

#[cfg(all(target_os = "linux", target_env = "gnu"))]
/// glibc raises its mmap threshold to the size of the largest block freed (up to 32 MiB),
/// after which a mesh's big vectors come from the heap, whose freed middle is never given
/// back: the dragon's peak was 225 MB, 145 MB with the threshold fixed at 1 MiB (each block
/// of a MiB or more is mapped, and unmapped when freed). Called first in `main`.
pub fn fix_mmap_threshold() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: mallopt only sets a parameter of the allocator; called before any thread.
    unsafe {
        libc::mallopt(libc::M_MMAP_THRESHOLD, 1 << 20);
    }
}

#[cfg(all(target_os = "linux", target_env = "gnu"))]
#[global_allocator]
static ALLOCATOR: HugeBlocks = HugeBlocks;
