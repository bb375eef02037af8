//! STAGE 4 (shared by SD, VGC and AS): measuring a node of shading points and splitting it in two, in
//! place. Every split leaves both sides non-empty for two or more points: the planned split (a box midpoint)
//! falls back to the median — ordered by (key, pixel id), so the result never depends on input order
//! accidents — when one side would be empty (ALGORITHMS.md §4.2 and §4.4, CHOICE A5).
//!
//! Depends only on `points` and the `SplitRule` of this module's parent; knows nothing of budgets or seeds.

use glam::Vec3A;

use super::SplitRule;
use super::points::{DepthScale, Pt};

/// Moves the points with `left(q)` to the front and returns how many there are (Hoare partition; the
/// resulting order is a pure function of the input order).
pub(crate) fn partition(pts: &mut [Pt], left: impl Fn(&Pt) -> bool) -> usize {
    let (mut i, mut j) = (0usize, pts.len());
    loop {
        while i < j && left(&pts[i]) {
            i += 1;
        }
        while i < j && !left(&pts[j - 1]) {
            j -= 1;
        }
        if i + 1 >= j {
            return i;
        }
        pts.swap(i, j - 1);
        i += 1;
        j -= 1;
    }
}

/// Splits at the median of `key`, ties broken by pixel id; `pts.len() ≥ 2`. Returns len/2.
pub(crate) fn median_split(pts: &mut [Pt], key: impl Fn(&Pt) -> f32) -> usize {
    let mid = pts.len() / 2;
    pts.select_nth_unstable_by(mid, |a, b| key(a).total_cmp(&key(b)).then(a.id.cmp(&b.id)));
    mid
}

/// Splits where `key < value` (the planned split), falling back to the median when a side is empty.
/// Returns the size of the left part, in 1..len, or `None` for fewer than two points.
pub(crate) fn split_at(pts: &mut [Pt], key: impl Fn(&Pt) -> f32, value: f32) -> Option<usize> {
    if pts.len() < 2 {
        return None;
    }
    let m = partition(pts, |q| key(q) < value);
    Some(if m == 0 || m == pts.len() { median_split(pts, key) } else { m })
}

/// Tight box of positions and the sum of depths of a node (one pass).
pub(crate) fn spatial_stats(pts: &[Pt]) -> (Vec3A, Vec3A, f32) {
    let s = node_stats(pts);
    (s.lo, s.hi, s.depth_sum)
}

/// One pass over a node: position box, normal box and depth sum.
pub(crate) struct NodeStats {
    pub lo: Vec3A,
    pub hi: Vec3A,
    pub n_lo: Vec3A,
    pub n_hi: Vec3A,
    pub depth_sum: f32,
}

/// Position box, normal box and depth sum of a node.
pub(crate) fn node_stats(pts: &[Pt]) -> NodeStats {
    let inf = Vec3A::splat(f32::INFINITY);
    let mut s = NodeStats { lo: inf, hi: -inf, n_lo: inf, n_hi: -inf, depth_sum: 0.0 };
    let mut depth = 0f64;
    for q in pts {
        s.lo = s.lo.min(q.pos());
        s.hi = s.hi.max(q.pos());
        s.n_lo = s.n_lo.min(q.normal());
        s.n_hi = s.n_hi.max(q.normal());
        depth += q.depth as f64;
    }
    s.depth_sum = depth as f32;
    s
}

/// An upper bound, in degrees, of the cone spread ([`cone_spread`]) of unit normals inside a box: any two
/// differ by at most its diagonal δ, so by an angle ≤ 2·asin(δ/2); every normal is within that angle of the
/// mean normal, so the spread (twice the largest angle to the mean) is ≤ 4·asin(δ/2).
pub(crate) fn cone_spread_bound(n_lo: Vec3A, n_hi: Vec3A) -> f32 {
    let delta = (n_hi - n_lo).length();
    if !delta.is_finite() {
        return f32::INFINITY;
    }
    4.0 * (0.5 * delta).min(1.0).asin().to_degrees()
}

/// Index of the largest component (first on ties).
#[inline]
fn argmax3(v: Vec3A) -> usize {
    if v.x >= v.y && v.x >= v.z {
        0
    } else if v.y >= v.z {
        1
    } else {
        2
    }
}

/// VGC spatial split of a node with the given box: the longest world-space side at its midpoint (median
/// fallback).
pub(crate) fn split_spatial(pts: &mut [Pt], lo: Vec3A, hi: Vec3A) -> Option<usize> {
    let axis = argmax3(hi - lo);
    let mid = 0.5 * (lo[axis] + hi[axis]);
    split_at(pts, |q| q.p[axis], mid)
}

/// The 6-D SD coordinate `axis` of a point: (p_x, p_y, p_z, s·n_x, s·n_y, s·n_z).
#[inline]
fn sd_coord(q: &Pt, s: f32, axis: usize) -> f32 {
    if axis < 3 { q.p[axis] } else { s * q.n[axis - 3] }
}

/// Tight 6-D SD box of a node: (lo, hi) per coordinate.
pub(crate) fn sd_bounds(pts: &[Pt], s: f32) -> ([f32; 6], [f32; 6]) {
    let mut lo = [f32::INFINITY; 6];
    let mut hi = [f32::NEG_INFINITY; 6];
    for q in pts {
        for a in 0..6 {
            let v = sd_coord(q, s, a);
            lo[a] = lo[a].min(v);
            hi[a] = hi[a].max(v);
        }
    }
    (lo, hi)
}

/// The largest 6-D extent and its axis.
pub(crate) fn sd_extent(lo: &[f32; 6], hi: &[f32; 6]) -> (f32, usize) {
    (0..6).map(|a| (hi[a] - lo[a], a)).fold((f32::NEG_INFINITY, 0), |b, e| if e.0 > b.0 { e } else { b })
}

/// SD split [LS `_KdGatherGroup`]: longest 6-D axis at the box centre (median fallback).
pub(crate) fn split_sd(pts: &mut [Pt], s: f32, lo: &[f32; 6], hi: &[f32; 6]) -> Option<usize> {
    let (_, axis) = sd_extent(lo, hi);
    let mid = 0.5 * (lo[axis] + hi[axis]);
    split_at(pts, |q| sd_coord(q, s, axis), mid)
}

/// Splits a node once with a strategy's rule (used to add caches to a cluster: budget fill and AS).
pub(crate) fn split_with(pts: &mut [Pt], rule: SplitRule) -> Option<usize> {
    match rule {
        SplitRule::SpatialDirectional { normal_scale } => {
            let (lo, hi) = sd_bounds(pts, normal_scale);
            split_sd(pts, normal_scale, &lo, &hi)
        }
        SplitRule::ViewGuided => {
            let (lo, hi, _) = spatial_stats(pts);
            split_spatial(pts, lo, hi)
        }
    }
}

/// How a VGC angular node measures and splits its normals.
pub(crate) struct Angular {
    /// Use the literal (φ, θ) box instead of the cone around the mean normal.
    pub spherical: bool,
    /// σ_a in degrees.
    pub sigma_a: f32,
    /// Eq. 1 scaling.
    pub scale: DepthScale,
}

/// Spherical angles (φ, θ) of a unit normal in degrees: φ = atan2(n_y, n_x) ∈ (−180°, 180°], θ = acos(n_z).
#[inline]
fn sph(q: &Pt) -> [f32; 2] {
    [q.n[1].atan2(q.n[0]).to_degrees(), q.n[2].clamp(-1.0, 1.0).acos().to_degrees()]
}

impl Angular {
    /// Whether an angular node must be split: more than one point, normals not all equal, and spread above
    /// σ_a′ = σ_a·(1 + (α − 1)D²) (Eq. 1) for the node's mean depth.
    pub fn needs_split(&self, pts: &[Pt]) -> bool {
        if pts.len() < 2 {
            return false;
        }
        let st = node_stats(pts);
        let limit = self.sigma_a * self.scale.factor(st.depth_sum / pts.len() as f32);
        if st.n_lo == st.n_hi {
            return false;
        }
        if self.spherical {
            let (a, b) = sph_bounds(pts);
            (b[0] - a[0]).max(b[1] - a[1]) > limit
        } else {
            // The box bound settles flat nodes in this one pass; only curved ones need the exact spread.
            cone_spread_bound(st.n_lo, st.n_hi) > limit && cone_spread(pts) > limit
        }
    }

    /// Splits an angular node: the widest normal component (cone mode) or the wider of φ, θ (literal mode),
    /// at its midpoint, median fallback.
    pub fn split(&self, pts: &mut [Pt]) -> Option<usize> {
        if self.spherical {
            let (a, b) = sph_bounds(pts);
            let axis = usize::from(b[1] - a[1] > b[0] - a[0]);
            split_at(pts, |q| sph(q)[axis], 0.5 * (a[axis] + b[axis]))
        } else {
            let (lo, hi) = normal_bounds(pts);
            let axis = argmax3(hi - lo);
            split_at(pts, |q| q.n[axis], 0.5 * (lo[axis] + hi[axis]))
        }
    }
}

/// Component-wise box of the normals.
fn normal_bounds(pts: &[Pt]) -> (Vec3A, Vec3A) {
    pts.iter().fold((Vec3A::splat(f32::INFINITY), Vec3A::splat(f32::NEG_INFINITY)), |(lo, hi), q| {
        (lo.min(q.normal()), hi.max(q.normal()))
    })
}

/// Box of (φ, θ) in degrees.
fn sph_bounds(pts: &[Pt]) -> ([f32; 2], [f32; 2]) {
    pts.iter().fold(([f32::INFINITY; 2], [f32::NEG_INFINITY; 2]), |(lo, hi), q| {
        let a = sph(q);
        ([lo[0].min(a[0]), lo[1].min(a[1])], [hi[0].max(a[0]), hi[1].max(a[1])])
    })
}

/// CHOICE A4: 2 × the largest angle (degrees) between a normal and the normalised mean normal — exact for a
/// pair, an upper bound of the largest pairwise angle in general. 360° when the normals cancel out.
pub(crate) fn cone_spread(pts: &[Pt]) -> f32 {
    let sum: Vec3A = pts.iter().map(|q| q.normal()).sum();
    let len = sum.length();
    if len.is_nan() || len <= 1e-6 * pts.len() as f32 {
        return 360.0;
    }
    let mean = sum / len;
    let min_dot = pts.iter().map(|q| q.normal().dot(mean)).fold(1.0f32, f32::min);
    2.0 * min_dot.clamp(-1.0, 1.0).acos().to_degrees()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pt(p: [f32; 3], n: [f32; 3], id: u32) -> Pt {
        let n = Vec3A::from_array(n).normalize().to_array();
        Pt { p, n, depth: 1.0, id }
    }

    #[test]
    fn splits_are_never_empty_even_for_identical_points() {
        let mut pts: Vec<Pt> = (0..7).map(|i| pt([1.0; 3], [0.0, 0.0, 1.0], i)).collect();
        for rule in [SplitRule::ViewGuided, SplitRule::SpatialDirectional { normal_scale: 0.5 }] {
            let m = split_with(&mut pts, rule);
            assert_eq!(m, Some(3));
        }
        assert_eq!(split_with(&mut pts[..1], SplitRule::ViewGuided), None);
    }

    #[test]
    fn spatial_split_is_at_the_midpoint_of_the_longest_side() {
        let mut pts: Vec<Pt> = (0..10).map(|i| pt([i as f32, 0.1 * i as f32, 0.0], [0.0, 0.0, 1.0], i)).collect();
        let (lo, hi, _) = spatial_stats(&pts);
        let m = split_spatial(&mut pts, lo, hi).unwrap();
        assert_eq!(m, 5);
        assert!(pts[..m].iter().all(|q| q.p[0] < 4.5) && pts[m..].iter().all(|q| q.p[0] >= 4.5));
    }

    #[test]
    fn cone_spread_of_a_pair_is_their_angle() {
        let a = 40f32.to_radians();
        let pts = [pt([0.0; 3], [0.0, 0.0, 1.0], 0), pt([0.0; 3], [a.sin(), 0.0, a.cos()], 1)];
        assert!((cone_spread(&pts) - 40.0).abs() < 1e-3);
        let opposite = [pt([0.0; 3], [0.0, 0.0, 1.0], 0), pt([0.0; 3], [0.0, 0.0, -1.0], 1)];
        assert_eq!(cone_spread(&opposite), 360.0);
    }

    #[test]
    fn angular_nodes_split_only_above_the_scaled_threshold() {
        let a = 20f32.to_radians();
        let mut pts = vec![pt([0.0; 3], [0.0, 0.0, 1.0], 0), pt([0.0; 3], [a.sin(), 0.0, a.cos()], 1)];
        for spherical in [false, true] {
            let ang = |s| Angular { spherical, sigma_a: s, scale: DepthScale::new(1.0, 1.0, 0.2) };
            assert!(ang(15.0).needs_split(&pts));
            assert!(!ang(25.0).needs_split(&pts));
            assert_eq!(ang(15.0).split(&mut pts), Some(1));
        }
    }
}
