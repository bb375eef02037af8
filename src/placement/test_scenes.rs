//! Test support for STAGE 4: synthetic scenes built with the analytic ray caster of [`super::synthetic`]
//! (re-exported here, with its mock [`super::CacheOracle`]), noisy-normal and degenerate variants, and the
//! contract every first stage must meet.
//!
//! Compiled only for tests; depends on `gbuffer` and `sampling`.

use glam::Vec3A;

pub use super::synthetic::{MaskOracle, Prim, STEP_X, cast};
use super::{AdaptivePlacement, InitialPlacement, PlacementParams, Stage1};
use crate::gbuffer::{GBuffer, PixelId};
use crate::sampling::{Rng, hash3};

/// Seed used by the contract checks.
pub const SEED: u64 = 0x7e57_5eed;

/// A ground plane seen at a grazing angle up to a far wall: a depth ramp.
pub fn plane(w: usize, h: usize) -> GBuffer {
    let prims = [Prim::Plane(Vec3A::ZERO, Vec3A::Y), Prim::Plane(Vec3A::new(0.0, 0.0, -12.0), Vec3A::Z)];
    cast(w, h, Vec3A::new(0.0, 1.5, 2.0), Vec3A::new(0.0, 0.0, -4.0), &prims, 25.0)
}

/// A ground plane seen from above: one flat surface, every pixel valid.
pub fn flat(w: usize, h: usize) -> GBuffer {
    cast(w, h, Vec3A::new(0.0, 5.0, 0.0), Vec3A::new(0.0, 0.0, -1.0), &[Prim::Plane(Vec3A::ZERO, Vec3A::Y)], 20.0)
}

/// A sphere on a ground plane, with sky above the horizon.
pub fn sphere_on_plane(w: usize, h: usize) -> GBuffer {
    let prims = [Prim::Plane(Vec3A::ZERO, Vec3A::Y), Prim::Sphere(Vec3A::new(0.0, 1.0, -4.0), 1.0)];
    cast(w, h, Vec3A::new(0.0, 1.6, 1.5), Vec3A::new(0.0, 0.6, -4.0), &prims, 20.0)
}

/// A staircase of boxes on a floor in front of a wall.
pub fn staircase(w: usize, h: usize) -> GBuffer {
    let mut prims = vec![Prim::Plane(Vec3A::ZERO, Vec3A::Y), Prim::Plane(Vec3A::new(0.0, 0.0, -9.0), Vec3A::Z)];
    for i in 0..6 {
        let z = -3.0 - 0.6 * i as f32;
        prims.push(Prim::Cuboid(Vec3A::new(-1.5, 0.0, z - 0.6), Vec3A::new(1.5, 0.3 * (i + 1) as f32, z)));
    }
    cast(w, h, Vec3A::new(2.0, 2.5, 1.0), Vec3A::new(0.0, 0.8, -5.0), &prims, 20.0)
}

/// The plane scene with uniformly random normals (hashed per pixel).
pub fn noise_normals(w: usize, h: usize) -> GBuffer {
    let mut g = plane(w, h);
    for (i, sp) in g.points.iter_mut().enumerate() {
        if let Some(sp) = sp {
            let mut r = Rng::new(hash3(0x401e, 0, i as u64));
            let v = Vec3A::new(r.uniform() - 0.5, r.uniform() - 0.5, r.uniform() - 0.5).normalize_or(Vec3A::Y);
            sp.n = v;
        }
    }
    g
}

/// Every pixel of the left half sees the same point with the same normal (instanced duplicates); the right
/// half is the plane scene.
pub fn coincident(w: usize, h: usize) -> GBuffer {
    let base = plane(w, h);
    let dup = base.points.iter().flatten().next().copied();
    GBuffer::from_fn(w, h, base.scale, |x, y| if x < w / 2 { dup } else { base.points[y * w + x] })
}

/// The sphere scene with NaN normals on every third pixel.
pub fn nan_normals(w: usize, h: usize) -> GBuffer {
    let base = sphere_on_plane(w, h);
    GBuffer::from_fn(w, h, base.scale, |x, y| {
        let mut sp = base.points[y * w + x]?;
        if (x + y) % 3 == 0 {
            sp.n = Vec3A::new(f32::NAN, 0.0, 1.0);
        }
        Some(sp)
    })
}

/// Nothing but sky.
pub fn all_sky(w: usize, h: usize) -> GBuffer {
    GBuffer::from_fn(w, h, 10.0, |_, _| None)
}

/// Pixels that can host a cache.
pub fn usable_count(g: &GBuffer) -> usize {
    (0..g.points.len() as PixelId).filter(|&id| super::points::is_usable(g, id)).count()
}

/// Sites are distinct usable pixels.
pub fn check_sites(g: &GBuffer, sites: &[PixelId]) {
    let mut s = sites.to_vec();
    s.sort_unstable();
    s.dedup();
    assert_eq!(s.len(), sites.len(), "duplicate sites");
    assert!(sites.iter().all(|&id| super::points::is_usable(g, id)), "a site is not a usable pixel");
}

/// Clusters (when present) are disjoint, contain their site, and hold only usable pixels.
pub fn check_clusters(g: &GBuffer, s: &Stage1) {
    let Some(c) = &s.clusters else { return };
    assert_eq!(c.ranges.len(), s.sites.len());
    let mut all = c.members.clone();
    all.sort_unstable();
    all.dedup();
    assert_eq!(all.len(), c.members.len(), "a pixel in two clusters");
    for (site, r) in s.sites.iter().zip(&c.ranges) {
        assert!(c.members[r.start as usize..r.end as usize].contains(site), "site outside its cluster");
    }
    check_sites(g, &c.members);
}

/// Runs `f` inside a rayon pool of `threads` threads.
pub fn in_pool<T: Send>(threads: usize, f: impl FnOnce() -> T + Send) -> T {
    rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap().install(f)
}

/// The first-stage contract on every synthetic scene: exact count, distinct usable sites, same seed ⇒ same
/// sites on 1 and 2 threads, different seed ⇒ different sites (when `random`). Budgets 0, 1, mid, usable
/// and above. A strategy may refuse a budget only with an error that names σ_a (VGC on curved scenes).
pub fn check_initial(strategy: &dyn InitialPlacement, random: bool) {
    let scenes = [
        ("flat", flat(48, 32)),
        ("plane", plane(48, 32)),
        ("sphere", sphere_on_plane(48, 32)),
        ("staircase", staircase(48, 32)),
        ("noise", noise_normals(48, 32)),
        ("coincident", coincident(48, 32)),
        ("nan", nan_normals(48, 32)),
        ("sky", all_sky(48, 32)),
    ];
    let params = PlacementParams::default();
    for (name, g) in &scenes {
        let usable = usable_count(g);
        for budget in [0, 1, 37, usable / 3, usable.saturating_sub(1), usable, usable + 5] {
            let run = |threads, seed| in_pool(threads, || strategy.place(g, budget, &params, seed));
            let one = match run(1, SEED) {
                Ok(s) => s,
                Err(e) => {
                    eprintln!("{name}, budget {budget}: {e}");
                    assert!(
                        e.to_string().contains("σ_a") && e.to_string().contains(&budget.to_string()),
                        "{name}: {e}"
                    );
                    continue;
                }
            };
            assert_eq!(one.sites.len(), budget.min(usable), "{name}, budget {budget}");
            check_sites(g, &one.sites);
            check_clusters(g, &one);
            let two = run(2, SEED).unwrap();
            assert_eq!(one, two, "{name}, budget {budget}: thread count changed the result");
            if budget > usable && usable > 0 {
                assert!(one.info.notes.iter().any(|n| n.contains("exceeds")), "{name}: {:?}", one.info.notes);
            }
            if usable == 0 {
                assert!(one.info.notes.iter().any(|n| n.contains("background")));
            }
            if random && *name == "sphere" && budget == usable / 3 {
                assert_ne!(one.sites, run(2, SEED + 1).unwrap().sites, "{name}: the seed changed nothing");
            }
        }
    }
}

/// Fraction of `sites` within 0.3 world units of the hidden step, over the same fraction of usable pixels
/// (1 = no preference, as uniform sampling would give).
pub fn step_preference(g: &GBuffer, sites: &[PixelId]) -> f64 {
    let near = |id: PixelId| g.get(id).is_some_and(|sp| (sp.p.x - STEP_X).abs() < 0.3);
    let all: Vec<PixelId> = (0..g.points.len() as PixelId).filter(|&id| super::points::is_usable(g, id)).collect();
    let base = all.iter().filter(|&&id| near(id)).count() as f64 / all.len() as f64;
    let got = sites.iter().filter(|&&id| near(id)).count() as f64 / sites.len().max(1) as f64;
    got / base
}

/// The second-stage contract: exactly N2 new distinct usable pixels that are not caches, evaluated through
/// the oracle; same seed ⇒ same result on 1 and 2 threads, different seed ⇒ different; a strong preference
/// for the hidden step (when `seeks_step`, on the flat scene); budgets 0 and above the free pixel count.
pub fn check_adaptive(strategy: &dyn AdaptivePlacement, first: &dyn InitialPlacement, seeks_step: bool) {
    let params = PlacementParams::default();
    for (name, g) in
        [("sphere", sphere_on_plane(160, 120)), ("staircase", staircase(160, 120)), ("flat", flat(160, 120))]
    {
        let s1 = first.place(&g, 1000, &params, SEED).unwrap();
        let run = |threads, budget, seed| {
            in_pool(threads, || {
                let mut o = MaskOracle::new(&g, &s1.sites);
                let info = strategy.place(&g, &s1, &mut o, budget, &params, seed).unwrap();
                (o.sites, info)
            })
        };
        let (sites, info) = run(1, 300, SEED);
        assert_eq!(info.added, 300, "{name}");
        assert_eq!(sites.len(), 1300, "{name}");
        check_sites(&g, &sites);
        assert_eq!(sites[..1000], s1.sites[..], "{name}: stage-1 caches changed");
        assert_eq!(run(2, 300, SEED), (sites.clone(), info.clone()), "{name}: thread count changed the result");
        assert_ne!(run(1, 300, SEED + 1).0, sites, "{name}: the seed changed nothing");
        if name == "flat" && seeks_step {
            let pref = step_preference(&g, &sites[1000..]);
            assert!(pref > 2.0, "{name}: preference for the step only {pref}");
        }
        let (none, info0) = run(1, 0, SEED);
        assert_eq!((none.len(), info0.added), (1000, 0));
        let free = usable_count(&g) - 1000;
        let (all, info_all) = run(1, free + 10, SEED);
        assert_eq!(all.len(), usable_count(&g), "{name}");
        assert_eq!(info_all.added, free);
        assert!(!info_all.notes.is_empty());
        check_sites(&g, &all);
    }
}
