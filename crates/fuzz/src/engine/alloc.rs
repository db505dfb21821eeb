//! A counting global allocator: the system allocator, plus the bytes each thread has live and
//! the most it had live since [`reset_peak`]. Installed as `#[global_allocator]` by the fuzz
//! binary (and the CLI crate's tests), it tells the driver how much memory a reader took for
//! one input, so a header that makes a reader allocate far more than the file holds is caught
//! before it becomes an out-of-memory abort on a user's machine.
//!
//! The counts are per thread (the readers are single-threaded), so tests running beside each
//! other do not see each other's allocations.

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

/// The system allocator with per-thread live and peak byte counts.
pub struct Counting;

static INSTALLED: AtomicBool = AtomicBool::new(false);

/// Largest single allocation granted (bytes); larger ones fail, which aborts the process as
/// an out-of-memory would, after [`ON_LIMIT`] has saved the input.
static LIMIT: AtomicUsize = AtomicUsize::new(usize::MAX);

/// Called (once) with the size of a refused allocation, before it fails.
static ON_LIMIT: std::sync::OnceLock<fn(usize)> = std::sync::OnceLock::new();

/// Refuses single allocations above `bytes` (an allocation bomb aborts the process at once
/// instead of taking the machine's memory), calling `on_limit` first, e.g. to save the input.
pub fn set_limit(bytes: usize, on_limit: fn(usize)) {
    let _ = ON_LIMIT.set(on_limit);
    LIMIT.store(bytes, Ordering::Relaxed);
}

fn over_limit(size: usize) -> bool {
    if size <= LIMIT.load(Ordering::Relaxed) {
        return false;
    }
    // Lift the limit so that the callback may allocate, then report.
    LIMIT.store(usize::MAX, Ordering::Relaxed);
    if let Some(f) = ON_LIMIT.get() {
        f(size);
    }
    true
}

thread_local! {
    static LIVE: Cell<isize> = const { Cell::new(0) };
    static PEAK: Cell<isize> = const { Cell::new(0) };
}

fn add(bytes: isize) {
    let _ = LIVE.try_with(|live| {
        let now = live.get() + bytes;
        live.set(now);
        let _ = PEAK.try_with(|p| {
            if now > p.get() {
                p.set(now);
            }
        });
    });
}

// SAFETY: every call is forwarded to the system allocator unchanged; the counting touches only
// thread-local `Cell`s of plain integers (no allocation, no destructor).
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        if over_limit(layout.size()) {
            return std::ptr::null_mut();
        }
        // SAFETY: forwarded with the caller's layout.
        let p = unsafe { System.alloc(layout) };
        if !p.is_null() {
            add(layout.size() as isize);
        }
        p
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        if over_limit(layout.size()) {
            return std::ptr::null_mut();
        }
        // SAFETY: forwarded with the caller's layout.
        let p = unsafe { System.alloc_zeroed(layout) };
        if !p.is_null() {
            add(layout.size() as isize);
        }
        p
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: the pointer came from `alloc` with this layout.
        unsafe { System.dealloc(ptr, layout) };
        add(-(layout.size() as isize));
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        if over_limit(new_size) {
            return std::ptr::null_mut();
        }
        // SAFETY: forwarded unchanged.
        let p = unsafe { System.realloc(ptr, layout, new_size) };
        if !p.is_null() {
            add(new_size as isize - layout.size() as isize);
        }
        p
    }
}

impl Counting {
    /// Marks the allocator installed; the driver checks allocation only when it is.
    pub fn install_check() {
        let before = LIVE.try_with(|l| l.get()).unwrap_or(0);
        let probe = std::hint::black_box(vec![0u8; 4096]);
        let after = LIVE.try_with(|l| l.get()).unwrap_or(0);
        drop(std::hint::black_box(probe));
        if after - before >= 4096 {
            INSTALLED.store(true, Ordering::Relaxed);
        }
    }
}

/// Whether [`Counting`] is this process's global allocator (after [`Counting::install_check`]).
pub fn installed() -> bool {
    INSTALLED.load(Ordering::Relaxed)
}

/// Starts a new peak measurement on this thread; returns the bytes live now.
pub fn reset_peak() -> isize {
    let live = LIVE.try_with(|l| l.get()).unwrap_or(0);
    let _ = PEAK.try_with(|p| p.set(live));
    live
}

/// The most bytes live on this thread since [`reset_peak`].
pub fn peak() -> isize {
    PEAK.try_with(|p| p.get()).unwrap_or(0)
}
