//! Irradiance caching's gather loop allocates nothing per path (issue 11, "Fast"): a counting global
//! allocator sees the same number of allocations for a record gathered along 4×4 directions as along
//! 64×64 (256 times the paths, each up to `maxdepth` vertices with a BSDF, light sampling and a shadow ray),
//! and none at all while a sample is shaded from its caches.
//!
//! Its own test binary because it installs a global allocator; every call runs on the test's thread, whose
//! allocations alone are counted.

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::path::Path;

use cachert::Warnings;
use cachert::application::irradiance::{IrradianceCache, Output};
use cachert::application::{Application, Neighbour};
use cachert::gbuffer::shading_point;
use cachert::sampling::{Rng, Stratum};
use cachert::scene::ray::RayCounters;
use cachert::scene::{LoadOptions, load};

struct Counting;

thread_local! {
    static ALLOCATIONS: Cell<usize> = const { Cell::new(0) };
}

fn count() {
    // `try_with`: allocations made while the thread's storage is being torn down are not counted.
    let _ = ALLOCATIONS.try_with(|c| c.set(c.get() + 1));
}

// SAFETY: every call is passed on to the system allocator unchanged; counting touches only a const-initialised
// thread-local `Cell`, which neither allocates nor unwinds.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        count();
        // SAFETY: the caller's contract for `alloc` is the system allocator's.
        unsafe { System.alloc(layout) }
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        count();
        // SAFETY: as for `alloc`.
        unsafe { System.alloc_zeroed(layout) }
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        count();
        // SAFETY: `ptr` was allocated by `System` with `layout` (every allocation here goes through it).
        unsafe { System.realloc(ptr, layout, new_size) }
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: as for `realloc`.
        unsafe { System.dealloc(ptr, layout) }
    }
}

#[global_allocator]
static ALLOCATOR: Counting = Counting;

/// Allocations `f` makes on this thread.
fn allocations<T>(f: impl FnOnce() -> T) -> (usize, T) {
    let before = ALLOCATIONS.with(Cell::get);
    let out = f();
    (ALLOCATIONS.with(Cell::get) - before, out)
}

#[test]
fn gathering_allocates_per_record_not_per_path_and_shading_allocates_nothing() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/room.pbrt");
    let loaded = load(&path, LoadOptions::default()).expect("the shipped room loads");
    let scene = &loaded.scene;
    let [w, h] = scene.film.resolution.map(|r| r as f32);
    let points: Vec<_> = [(0.3, 0.6), (0.5, 0.5), (0.7, 0.8), (0.2, 0.2)]
        .iter()
        .filter_map(|&(x, y)| shading_point(scene, [x * w, y * h]))
        .collect();
    assert_eq!(points.len(), 4, "every probe should see a surface of the room");
    let mut counts = Vec::new();
    for n in [4, 64] {
        let app = IrradianceCache::new(n, 3, Output::Indirect);
        let cx = app.prepare(scene, &mut Warnings::default()).expect("prepared");
        let (mut rng, mut rays) = (Rng::new(7), RayCounters::default());
        // The first record may fill lazily built tables; the next ones are what is counted.
        let first = app.compute_record(&cx, &points[0], &mut rng, &mut rays);
        let before = rays.camera;
        let (made, records) = allocations(|| {
            points[1..].iter().map(|p| app.compute_record(&cx, p, &mut rng, &mut rays)).collect::<Vec<_>>()
        });
        let paths = rays.camera - before;
        assert!(paths >= 3 * (n * n / 4) as u64, "{n}×{n}: the gathers traced too little ({paths} path segments)");
        eprintln!("{n}×{n} directions: {made} allocations for 3 records ({paths} path segments)");
        counts.push(made);
        let near: Vec<Neighbour<'_, _>> = std::iter::once(&first)
            .chain(&records)
            .zip(&points)
            .map(|(record, p)| Neighbour { record, p: p.p, n: p.n, weight: 1.0 })
            .collect();
        let (shaded, value) =
            allocations(|| app.shade(&cx, &points[1], &near, &mut rng, Stratum::alone(0, 0), &mut rays));
        assert!(value.iter().all(|v| v.is_finite()), "{value:?}");
        assert_eq!(shaded, 0, "{n}×{n}: shading from the caches allocated");
    }
    // One buffer per record for the per-direction radiance (DGS) and the collected Vec's growth: the
    // count must not grow with the paths.
    assert_eq!(counts[0], counts[1], "allocations grow with the number of gathering paths: {counts:?}");
    assert!(counts[1] <= 3 + 3, "more than a buffer per record: {counts:?}");
}
