//! Synthetic STAGE 4 inputs without a scene: G-buffers from a tiny analytic ray caster (planes, spheres,
//! boxes) and a mock [`CacheOracle`] whose records are 1024-bit visibility masks that change across a hidden
//! step. Shared by the placement tests (`test_scenes` builds its scenes and contracts on these) and by
//! `cachert bench micro placement` / `selection`, which time the strategies on [`room`] at 1920×1080.
//!
//! Depends on `gbuffer` only; nothing here reaches a rendered image.

use glam::Vec3A;

use super::{CacheId, CacheOracle, Prediction};
use crate::gbuffer::{GBuffer, PixelId, ShadingPoint};

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
            flipped: [false; 2],
        })
    })
}

/// A room (floor, ceiling, three walls) with spheres, a staircase of boxes and a row of pillars: planes and
/// curved surfaces, depths from about 1 m to 14 m. The scene of `cachert bench micro placement` and
/// `selection`.
pub fn room(w: usize, h: usize) -> GBuffer {
    let mut prims = vec![
        Prim::Plane(Vec3A::ZERO, Vec3A::Y),
        Prim::Plane(Vec3A::new(0.0, 4.0, 0.0), -Vec3A::Y),
        Prim::Plane(Vec3A::new(0.0, 0.0, -14.0), Vec3A::Z),
        Prim::Plane(Vec3A::new(-5.0, 0.0, 0.0), Vec3A::X),
        Prim::Plane(Vec3A::new(5.0, 0.0, 0.0), -Vec3A::X),
    ];
    for i in 0..7 {
        let z = -2.0 - 1.6 * i as f32;
        prims.push(Prim::Sphere(Vec3A::new(-2.5 + 0.3 * i as f32, 0.6, z), 0.6));
        prims.push(Prim::Cuboid(Vec3A::new(3.0, 0.0, z - 0.8), Vec3A::new(4.2, 0.35 * (i + 1) as f32, z)));
        prims.push(Prim::Sphere(Vec3A::new(0.5 * i as f32 - 1.0, 2.8, z - 0.5), 0.25));
    }
    cast(w, h, Vec3A::new(0.0, 1.7, 1.0), Vec3A::new(0.0, 1.2, -8.0), &prims, 24.0)
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

/// The value a mask stands for: its fraction of set bits.
pub fn mask_value(m: &[u64; 16]) -> f32 {
    m.iter().map(|x| x.count_ones()).sum::<u32>() as f32 / 1024.0
}

/// A mock oracle: records are [`mask_at`] of the site position; counts calls.
#[derive(Debug)]
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
    /// The "AO" of a mask is its fraction of set bits; a blend is the weighted mean of the others'.
    fn predict_many(&mut self, asks: &[(CacheId, Vec<(CacheId, f32)>)]) -> Vec<Option<Prediction>> {
        asks.iter()
            .map(|(c, others)| {
                let own = mask_value(&self.masks[*c as usize]);
                let blend: f32 = others.iter().map(|&(o, w)| w * mask_value(&self.masks[o as usize])).sum();
                Some(Prediction { sq_err: (blend - own).powi(2), noise: 0.0, floor: 0.0, value: own })
            })
            .collect()
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
