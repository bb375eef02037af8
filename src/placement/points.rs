//! STAGE 4 (shared by the strategies): the shading points that placement works on, in a compact form that
//! clustering partitions in place, and the per-node threshold scale of Eq. 1.
//!
//! A pixel is *usable* when it is valid and its position, normal and depth are finite and the normal has
//! non-zero length; everything else (background, NaN normals, …) never becomes a cache. Depends only on
//! `gbuffer`; must not depend on any strategy.

use glam::Vec3A;
use rayon::prelude::*;

use crate::gbuffer::{GBuffer, PixelId, ShadingPoint};

/// One usable shading point: position, unit normal, depth in metres and its pixel. 32 bytes, so
/// partitioning the array itself (rather than an index array) keeps every node contiguous in memory.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Pt {
    /// World position.
    pub p: [f32; 3],
    /// Unit shading normal.
    pub n: [f32; 3],
    /// Camera distance in metres (`depth × meters_per_unit`).
    pub depth: f32,
    /// The pixel.
    pub id: PixelId,
}

impl Pt {
    /// Position as a vector.
    #[inline]
    pub fn pos(&self) -> Vec3A {
        Vec3A::from_array(self.p)
    }

    /// Normal as a vector.
    #[inline]
    pub fn normal(&self) -> Vec3A {
        Vec3A::from_array(self.n)
    }
}

/// The unit normal of a shading point when it can take part in placement, else `None`.
pub(crate) fn usable_normal(sp: &ShadingPoint) -> Option<Vec3A> {
    if !(sp.p.is_finite() && sp.n.is_finite() && sp.depth.is_finite()) {
        return None;
    }
    let n = sp.n.normalize_or_zero();
    (n != Vec3A::ZERO).then_some(n)
}

/// Whether pixel `id` can host a cache.
pub(crate) fn is_usable(g: &GBuffer, id: PixelId) -> bool {
    g.get(id).and_then(usable_normal).is_some()
}

/// The usable points of a G-buffer, in pixel order.
pub(crate) fn collect(g: &GBuffer, meters_per_unit: f32) -> Vec<Pt> {
    let mpu = if meters_per_unit.is_finite() && meters_per_unit > 0.0 { meters_per_unit } else { 1.0 };
    g.points
        .par_iter()
        .enumerate()
        .filter_map(|(i, sp)| {
            let sp = sp.as_ref()?;
            let n = usable_normal(sp)?;
            Some(Pt { p: sp.p.to_array(), n: n.to_array(), depth: sp.depth * mpu, id: i as PixelId })
        })
        .collect()
}

/// A usable length scale for a G-buffer: its scene scale L, or the points' bounding-box diagonal when L
/// is missing, or 1.
pub(crate) fn length_scale(g: &GBuffer, pts: &[Pt]) -> f32 {
    if g.scale.is_finite() && g.scale > 0.0 {
        return g.scale;
    }
    let (lo, hi) = pts
        .iter()
        .fold((Vec3A::splat(f32::MAX), Vec3A::splat(f32::MIN)), |(lo, hi), q| (lo.min(q.pos()), hi.max(q.pos())));
    let d = (hi - lo).length();
    if d.is_finite() && d > 0.0 { d } else { 1.0 }
}

/// The depth scaling of Eq. 1 with the corrected sign (ALGORITHMS.md §4.4, ambiguity A1): a threshold σ
/// becomes σ·(1 + (α − 1)·D²), D = (d − d_min)/(d_max − d_min), α = 1 + Γ·(d_max − d_min), depths in metres.
/// So σ at d_min, α·σ at d_max, growing with the square of the normalised depth in between.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct DepthScale {
    d_min: f32,
    inv_range: f32,
    alpha_minus_1: f32,
}

impl DepthScale {
    /// The scale for depths in [d_min, d_max] (metres) and growth Γ per metre.
    pub fn new(d_min: f32, d_max: f32, gamma: f32) -> Self {
        let range = d_max - d_min;
        let ok = range.is_finite() && range > 0.0;
        let gamma = if gamma.is_finite() { gamma.max(0.0) } else { 0.0 };
        DepthScale {
            d_min: if d_min.is_finite() { d_min } else { 0.0 },
            inv_range: if ok { 1.0 / range } else { 0.0 },
            alpha_minus_1: if ok { gamma * range } else { 0.0 },
        }
    }

    /// The scale over all points (their min and max depth).
    pub fn of(pts: &[Pt], gamma: f32) -> Self {
        let (lo, hi) =
            pts.iter().fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), q| (lo.min(q.depth), hi.max(q.depth)));
        if pts.is_empty() { DepthScale::new(0.0, 0.0, gamma) } else { DepthScale::new(lo, hi, gamma) }
    }

    /// The factor 1 + (α − 1)·D² for a node of (mean) depth `d`; D is clamped to [0, 1].
    #[inline]
    pub fn factor(&self, d: f32) -> f32 {
        let dn = ((d - self.d_min) * self.inv_range).clamp(0.0, 1.0);
        1.0 + self.alpha_minus_1 * dn * dn
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn eq1_endpoints_and_monotone() {
        // Depths 2 m … 12 m, Γ = 0.2 ⇒ α = 3.
        let s = DepthScale::new(2.0, 12.0, 0.2);
        assert_eq!(s.factor(2.0), 1.0, "σ at d_min");
        assert!((s.factor(12.0) - 3.0).abs() < 1e-6, "α·σ at d_max");
        assert_eq!(s.factor(20.0), s.factor(12.0), "clamped beyond d_max");
        let mut prev = 0.0;
        for i in 0..=100 {
            let f = s.factor(2.0 + 0.1 * i as f32);
            assert!(f >= prev);
            prev = f;
        }
        // Quadratic in the normalised depth: half way is 1 + (α − 1)/4.
        assert!((s.factor(7.0) - 1.5).abs() < 1e-6);
        // A flat depth range scales nothing.
        assert_eq!(DepthScale::new(3.0, 3.0, 0.2).factor(3.0), 1.0);
    }

    #[test]
    fn unusable_points_are_left_out() {
        let g = GBuffer::from_fn(4, 1, 1.0, |x, _| {
            let n = match x {
                0 => Vec3A::Z,
                1 => Vec3A::new(f32::NAN, 0.0, 1.0),
                2 => Vec3A::ZERO,
                _ => return None,
            };
            Some(ShadingPoint {
                p: Vec3A::ZERO,
                p_error: Vec3A::ZERO,
                n,
                ng: n,
                wo: Vec3A::Z,
                depth: 1.0,
                dpdu: Vec3A::ZERO,
                uv: [0.0; 2],
                material: 0,
                area_light: None,
                origin: None,
                flipped: [false; 2],
            })
        });
        let pts = collect(&g, 1.0);
        assert_eq!(pts.iter().map(|q| q.id).collect::<Vec<_>>(), vec![0]);
        assert!(is_usable(&g, 0) && !is_usable(&g, 1) && !is_usable(&g, 2) && !is_usable(&g, 3) && !is_usable(&g, 9));
    }
}
