//! A counting global allocator for the fuzz harness: the live heap total, the peak since the last
//! [`reset_peak`], and a limit. An allocation that would bring the live total over the limit is a finding:
//! the hook set with [`set_over_limit_hook`] is called once (it saves the input and aborts the process).
//!
//! The binary that uses it declares `#[global_allocator] static A: alloc::Counting = alloc::Counting;`.

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicBool, AtomicPtr, AtomicUsize, Ordering::Relaxed};

/// The counting allocator (wraps the system allocator).
pub struct Counting;

static LIVE: AtomicUsize = AtomicUsize::new(0);
static PEAK: AtomicUsize = AtomicUsize::new(0);
static LIMIT: AtomicUsize = AtomicUsize::new(usize::MAX);
static TRIPPED: AtomicBool = AtomicBool::new(false);
static HOOK: AtomicPtr<()> = AtomicPtr::new(std::ptr::null_mut());

/// Bytes allocated and not yet freed.
pub fn live() -> usize {
    LIVE.load(Relaxed)
}

/// The highest live total since the last [`reset_peak`].
pub fn peak() -> usize {
    PEAK.load(Relaxed)
}

/// Starts a new peak measurement from the current live total.
pub fn reset_peak() {
    PEAK.store(LIVE.load(Relaxed), Relaxed);
}

/// Allocations that would bring the live total above `bytes` call the over-limit hook.
pub fn set_limit(bytes: usize) {
    LIMIT.store(bytes, Relaxed);
}

/// The function called (once per process) with the requested size and the live total it would give.
pub fn set_over_limit_hook(hook: fn(usize, usize)) {
    HOOK.store(hook as *mut (), Relaxed);
}

#[cold]
fn over_limit(size: usize, total: usize) {
    // Allocations made by the hook pass: TRIPPED is already set, so this runs once.
    let hook = HOOK.load(Relaxed);
    if hook.is_null() {
        eprintln!("fuzz: allocation of {size} bytes would bring the heap to {total} bytes: over the limit");
        std::process::abort();
    }
    // SAFETY: HOOK only ever holds a `fn(usize, usize)` stored by `set_over_limit_hook`.
    let hook: fn(usize, usize) = unsafe { std::mem::transmute::<*mut (), fn(usize, usize)>(hook) };
    hook(size, total);
}

/// Counts `grow` more bytes; calls the over-limit hook when that passes the limit.
#[inline]
fn grow(bytes: usize) {
    let total = LIVE.fetch_add(bytes, Relaxed).saturating_add(bytes);
    if total > LIMIT.load(Relaxed) && !TRIPPED.swap(true, Relaxed) {
        over_limit(bytes, total);
    }
    PEAK.fetch_max(total, Relaxed);
}

// SAFETY: every call is forwarded to `System` with the same arguments; only counters are added.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        grow(layout.size());
        // SAFETY: forwarded unchanged.
        let p = unsafe { System.alloc(layout) };
        if p.is_null() {
            LIVE.fetch_sub(layout.size(), Relaxed);
        }
        p
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        grow(layout.size());
        // SAFETY: forwarded unchanged.
        let p = unsafe { System.alloc_zeroed(layout) };
        if p.is_null() {
            LIVE.fetch_sub(layout.size(), Relaxed);
        }
        p
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: forwarded unchanged.
        unsafe { System.dealloc(ptr, layout) };
        LIVE.fetch_sub(layout.size(), Relaxed);
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        let old = layout.size();
        if new_size > old {
            grow(new_size - old);
        }
        // SAFETY: forwarded unchanged.
        let p = unsafe { System.realloc(ptr, layout, new_size) };
        if p.is_null() {
            if new_size > old {
                LIVE.fetch_sub(new_size - old, Relaxed);
            }
        } else if new_size < old {
            LIVE.fetch_sub(old - new_size, Relaxed);
        }
        p
    }
}
