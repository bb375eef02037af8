//! Test support for STAGE 4: synthetic G-buffers from a tiny analytic ray caster (planes, spheres, boxes),
//! noisy-normal and degenerate variants, a mock [`CacheOracle`] whose records are 1024-bit visibility masks
//! that change across a hidden step, and the contract every first stage must meet.
//!
//! Compiled only for tests; depends on `gbuffer` and `sampling`.

use glam::Vec3A;

use super::{AdaptivePlacement, CacheId, CacheOracle, InitialPlacement, PlacementParams, Stage1};
use crate::gbuffer::{GBuffer, PixelId, ShadingPoint};
use crate::sampling::{Rng, hash3};

/// Seed used by the contract checks.
pub const SEED: u64 = 0x7e57_5eed;

/// An analytic primitive.
#[derive(Clone, Copy, Debug)]
pub enum Prim {
    /// Plane through `p` with normal `n`.
    Plane(Vec3A, Vec3A),
    /// Sphere (centre, radius).
    Sphere(Vec3A, f32),
    /// Axis-aligned box (min, max).
    Cuboid(Vec3A, Vec3A),
}

fn hit(prim: &Prim, o: Vec3A, d: Vec3A) -> Option<(f32, Vec3A)> {
    match *prim {
        Prim::Plane(p, n) => {
            let den = n.dot(d);
            let t = (p - o).dot(n) / den;
            (den.abs() > 1e-8 && t > 1e-4).then_some((t, n))
        }
        Prim::Sphere(c, r) => {
            let oc = o - c;
            let b = oc.dot(d);
            let disc = b * b - (oc.length_squared() - r * r);
            if disc < 0.0 {
                return None;
            }
            let t = -b - disc.sqrt();
            (t > 1e-4).then(|| (t, (o + t * d - c) / r))
        }
        Prim::Cuboid(lo, hi) => {
            let inv = d.recip();
            let (t0, t1) = ((lo - o) * inv, (hi - o) * inv);
            let (tn, tf) = (t0.min(t1), t0.max(t1));
            let (enter, exit) = (tn.max_element(), tf.min_element());
            if enter > exit || enter <= 1e-4 {
                return None;
            }
            let axis = if tn.x >= tn.y && tn.x >= tn.z {
                0
            } else if tn.y >= tn.z {
                1
            } else {
                2
            };
            let mut n = Vec3A::ZERO;
            n[axis] = -d[axis].signum();
            Some((enter, n))
        }
    }
}

/// Renders a G-buffer of `prims` seen from `eye` looking at `at` (60° vertical field of view, y up).
pub fn cast(w: usize, h: usize, eye: Vec3A, at: Vec3A, prims: &[Prim], diagonal: f32) -> GBuffer {
    let fwd = (at - eye).normalize();
    let right = fwd.cross(Vec3A::Y).normalize();
    let up = right.cross(fwd);
    let tan = (30f32).to_radians().tan();
    GBuffer::from_fn(w, h, diagonal, |x, y| {
        let sx = ((x as f32 + 0.5) / w as f32 * 2.0 - 1.0) * tan * w as f32 / h as f32;
        let sy = (1.0 - (y as f32 + 0.5) / h as f32 * 2.0) * tan;
        let d = (fwd + sx * right + sy * up).normalize();
        let (t, n) = prims.iter().filter_map(|p| hit(p, eye, d)).min_by(|a, b| a.0.total_cmp(&b.0))?;
        let n = if n.dot(d) > 0.0 { -n } else { n };
        let p = eye + t * d;
        Some(ShadingPoint {
            p,
            p_error: Vec3A::ZERO,
            n,
            ng: n,
            wo: -d,
            depth: t,
            dpdu: Vec3A::ZERO,
            uv: [0.0; 2],
            material: 0,
            area_light: None,
            origin: None,
        })
    })
}

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
    GBuffer::from_fn(w, h, base.scene_diagonal, |x, y| if x < w / 2 { dup } else { base.points[y * w + x] })
}

/// The sphere scene with NaN normals on every third pixel.
pub fn nan_normals(w: usize, h: usize) -> GBuffer {
    let base = sphere_on_plane(w, h);
    GBuffer::from_fn(w, h, base.scene_diagonal, |x, y| {
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

/// Where the hidden visibility step lies: x = 0 in world space.
pub const STEP_X: f32 = 0.0;

/// A 1024-bit "visibility mask" for a point: the fraction of set bits is 0.85 left of the step and 0.15
/// right of it, with a small smooth variation along z, so Diff (Hamming distance) is large only across
/// the step.
pub fn mask_at(p: Vec3A) -> [u64; 16] {
    let frac = if p.x < STEP_X { 0.85 } else { 0.15 } + 0.02 * (p.z * 0.7).sin();
    let set = (frac * 1024.0).round().clamp(0.0, 1024.0) as usize;
    let mut m = [0u64; 16];
    for k in 0..set {
        m[k / 64] |= 1 << (k % 64);
    }
    m
}

/// A mock oracle: records are [`mask_at`] of the site position; counts calls.
pub struct MaskOracle<'a> {
    /// The G-buffer the sites index.
    pub g: &'a GBuffer,
    /// Sites by cache id.
    pub sites: Vec<PixelId>,
    /// Records by cache id.
    pub masks: Vec<[u64; 16]>,
    /// How many times `diff_many` was called.
    pub diff_many_calls: std::cell::Cell<usize>,
    /// How many times `evaluate` was called.
    pub evaluate_calls: usize,
}

impl<'a> MaskOracle<'a> {
    /// An oracle with the stage-1 `sites` evaluated.
    pub fn new(g: &'a GBuffer, sites: &[PixelId]) -> Self {
        let mut o = MaskOracle {
            g,
            sites: Vec::new(),
            masks: Vec::new(),
            diff_many_calls: Default::default(),
            evaluate_calls: 0,
        };
        o.evaluate(sites);
        o.evaluate_calls = 0;
        o
    }
}

impl CacheOracle for MaskOracle<'_> {
    fn len(&self) -> usize {
        self.sites.len()
    }
    fn site(&self, c: CacheId) -> PixelId {
        self.sites[c as usize]
    }
    fn diff(&self, a: CacheId, b: CacheId) -> f32 {
        let (ma, mb) = (&self.masks[a as usize], &self.masks[b as usize]);
        ma.iter().zip(mb).map(|(x, y)| (x ^ y).count_ones()).sum::<u32>() as f32
    }
    fn diff_many(&self, pairs: &[(CacheId, CacheId)]) -> Vec<f32> {
        self.diff_many_calls.set(self.diff_many_calls.get() + 1);
        pairs.iter().map(|&(a, b)| self.diff(a, b)).collect()
    }
    fn evaluate(&mut self, sites: &[PixelId]) {
        self.evaluate_calls += 1;
        for &s in sites {
            let p = self.g.get(s).map_or(Vec3A::ZERO, |sp| sp.p);
            self.sites.push(s);
            self.masks.push(mask_at(p));
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
