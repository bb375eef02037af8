//! STAGE 5 (application, importance caching): the split — the VPLs closer to a shading point than the
//! clamp distance d_c, the few its sharp reflection lobe points at, and those whose own sharp lobe points
//! at it, are summed apart from the cached (or baseline) estimator.
//!
//! Why, near-specular lobes: a reflection lobe of roughness 0.001–0.01 (the bathroom's bathtub, vase and
//! taps) turns the one VPL it happens to point at into a spike hundreds of times the pixel's diffuse light,
//! and a VPL on such a surface sends a beam of that strength onto whatever it hits. The many-light solution
//! has these spikes (they are the VPLs' glints), but a cache's distributions are built with the cache's own
//! lobe and region, so they neither predict which VPL a neighbour's lobe meets nor which receivers a VPL's
//! beam lights: the spikes were found rarely and then with a tiny probability — fireflies and holes that
//! decided the scene's RMSE (in a 320×180 bathroom, 0.1 % of the pixels held 96–99 % of the squared error
//! of every estimator).
//!
//! Why, near VPLs: within d_c of a receiver a VPL's light is at its clamped maximum (1/d_c² instead of
//! 1/d²), yet the caches, a little farther away and often on another facet, may see it behind their tangent
//! plane or occluded and give it no density, so only the uniform technique draws it, with probability
//! 1/(4·VPLs) — after the lobes were split off, such draws were the bathroom's largest fireflies (a VPL
//! 0.02 from a receiver on a bevel, none of its two caches able to draw it, one pixel 225 against 15).
//! The standard power estimator suffers from them alike (its weight is Σflux·f/d²).
//!
//! What: for a shading point s, the set S(s) holds every positional VPL within `near` (= `splitnear`·d_c)
//! of s, every VPL whose direction from s lies in the cone of s's sharp lobes ([`sharp_cone`]), and every
//! VPL with a sharp lobe whose beam cone contains s. The VPL sum splits exactly: Σ_j I_j(s) = Σ_{j∈S(s)}
//! I_j(s) + Σ_{j∉S(s)} I_j(s). The first part is estimated at s itself with as many shadow rays as the
//! estimator draws VPLs (as many as F, U, B and C draw for importance caching, 32 by default; `draws` for
//! the baselines): exactly when S(s) has no more members with light, else by that many members drawn
//! systematically in proportion to their exact unoccluded contribution there, so only their visibility is
//! left to chance; the second is the usual estimator with every draw that lands in S(s) counted as 0. (With
//! one draw, as before, the split's variance was 36 % of the 640×360 bathroom's squared error at 2800
//! caches, seed 0; with four, the estimator's draws at one per technique then, 10 %, for 15 % more shadow
//! rays.) S(s) depends on s alone, never on a draw, so both parts stay unbiased for their
//! sums and the whole for the same VPL image (`placement none` is unchanged). A lobe counts as sharp where
//! its microfacet density exceeds [`D_MIN`] within a cone narrower than the `splitcone` angle; wider lobes
//! are left to the estimator (their cones would hold hundreds of VPLs). The ball holds a handful of VPLs
//! (the VPLs lie on surfaces, and d_c is 2.5 % of the scene's length scale L).
//!
//! Depends on the VPLs and the shading layer's lobes; never on placement or the caches.

use glam::Vec3A;

use super::spheres::SphereTree;
use super::vpl::{Emitter, Receiver, Vpls};
use crate::sampling::Rng;
use crate::scene::Scene;
use crate::scene::ray::RayCounters;
use crate::shading::bsdf::Bsdf;
use crate::shading::bxdf::Bxdf;
use crate::shading::lighting::Shading;
use crate::shading::{Spectrum, luminance};

/// Microfacet density (sr⁻¹) above which a lobe's directions are split off. CHOICE: 1 — below it a glossy
/// lobe's value is of the order of a diffuse one's (1/π), which the cached distributions handle.
pub const D_MIN: f32 = 1.0;

/// Members with light whose values [`Local::estimate`] keeps from its first walk over the set.
const KEPT: usize = 16;

/// A cone of unit directions around `axis` with half-angle `angle`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cone {
    /// Unit axis.
    pub axis: Vec3A,
    /// cos of the half-angle.
    pub cos: f32,
    /// sin of the half-angle.
    pub sin: f32,
    /// The half-angle, radians.
    pub angle: f32,
}

impl Cone {
    /// The cone around unit `axis` with half-angle `angle` radians.
    pub fn new(axis: Vec3A, angle: f32) -> Cone {
        Cone { axis, cos: angle.cos(), sin: angle.sin(), angle }
    }

    /// Whether unit direction `w` lies inside.
    #[inline]
    pub fn contains(&self, w: Vec3A) -> bool {
        w.dot(self.axis) >= self.cos
    }

    /// Whether a sphere may hold a point whose direction from `apex` lies in the cone (conservative): the
    /// angle between the axis and the sphere's centre is at most the half-angle plus the angle the sphere
    /// subtends, compared as cosines (no trigonometric calls). The half-angle must be at most π/2, so that
    /// the sum stays within [0, π], where the cosine falls monotonically.
    #[inline]
    pub fn meets_sphere(&self, apex: Vec3A, center: Vec3A, radius: f32) -> bool {
        let v = center - apex;
        let d2 = v.length_squared();
        if d2 <= radius * radius {
            return true;
        }
        // cos(to) ≥ cos(half-angle + spread), with cos(to) = v·axis / d, sin(spread) = r / d and
        // cos(spread) = √(d² − r²) / d, multiplied through by d: one square root, no division.
        let along = v.dot(self.axis);
        let (a, b) = (self.cos * (d2 - radius * radius).sqrt(), self.sin * radius);
        // A little slack for rounding, relative to the terms' size: culling must never drop a member.
        along >= a - b - 1e-5 * (along.abs() + a.abs() + b)
    }
}

/// tan of the half-vector angle within which a lobe's Trowbridge–Reitz density exceeds [`D_MIN`]
/// (D = 1 / (π α² (1 + tan²θ_h/α²)²), its cos⁴θ_h left out), with α the larger of the two; `None` when the
/// lobe is not a microfacet reflection or its peak 1 / (π α_x α_y) does not exceed `D_MIN`.
/// Also returned: that α.
fn lobe_tan(b: &Bxdf) -> Option<(f32, f32)> {
    let d = match b {
        Bxdf::MicrofacetReflection(m) => &m.distribution,
        Bxdf::FresnelBlend(m) => &m.distribution,
        _ => return None,
    };
    let peak = 1.0 / (std::f32::consts::PI * d.alpha_x * d.alpha_y);
    let alpha = d.alpha_x.max(d.alpha_y);
    (peak > D_MIN && peak.is_finite()).then(|| (alpha * ((peak / D_MIN).sqrt() - 1.0).sqrt(), alpha))
}

/// The cone holding every direction ω in which a sharp reflection lobe of `bsdf`, seen from `wo`, has a
/// density above [`D_MIN`]: around the mirror direction of `wo` about the shading normal, twice the lobe's
/// half-vector angle wide (reflecting about a half vector θ_h away from the normal turns ω by at most 2θ_h).
/// `None` when no lobe is that sharp or the cone would be wider than `max_angle` radians.
pub fn sharp_cone(bsdf: &Bsdf, wo: Vec3A, max_angle: f32) -> Option<Cone> {
    sharp_lobe(bsdf, wo, max_angle).map(|(cone, _)| cone)
}

/// [`sharp_cone`]'s cone with the α (the larger of its two) of the widest sharp lobe, the one that sets it.
pub fn sharp_lobe(bsdf: &Bsdf, wo: Vec3A, max_angle: f32) -> Option<(Cone, f32)> {
    let (t, alpha) = bsdf
        .lobes()
        .filter(|(_, s)| s.max_element() > 0.0)
        .filter_map(|(b, _)| lobe_tan(b))
        .reduce(|a, b| if b.0 > a.0 { b } else { a })?;
    let angle = 2.0 * t.atan();
    if angle.is_nan() || angle > max_angle {
        return None;
    }
    let n = bsdf.shading_normal();
    let axis = (2.0 * wo.dot(n) * n - wo).normalize();
    axis.is_finite().then(|| (Cone::new(axis, angle), alpha))
}

/// A uniform grid over the positional VPLs: cell (x, y, z) holds `members[start[c]..start[c + 1]]` with
/// c = x + dims.x·(y + dims.y·z), each cell's members in ascending order. Cells are at least twice the ball's
/// radius wide, so a ball meets at most two cells along each axis (three with the rounding margin).
#[derive(Clone, Debug, Default)]
struct Grid {
    origin: Vec3A,
    /// 1 / the cell width.
    inv_cell: f32,
    dims: [u32; 3],
    start: Vec<u32>,
    members: Vec<u32>,
}

/// Most members a grid query gathers on the stack before it falls back to the tree walk.
const GRID_GATHER: usize = 64;

impl Grid {
    /// The grid over VPLs `0..positional` for balls of radius `near` (> 0), with at most about
    /// 8 cells per VPL (wider cells where the scene is large against `near`).
    fn new(vpls: &Vpls, positional: usize, near: f32) -> Grid {
        let points = &vpls.list[..positional];
        if points.is_empty() {
            return Grid::default();
        }
        let (mut lo, mut hi) = (Vec3A::splat(f32::INFINITY), Vec3A::splat(f32::NEG_INFINITY));
        for v in points {
            (lo, hi) = (lo.min(v.p), hi.max(v.p));
        }
        let extent = (hi - lo).max(Vec3A::ZERO);
        let max_cells = (8 * positional).max(4096) as f32;
        let mut cell = 2.0 * near;
        let count = |cell: f32| (extent / cell).floor() + Vec3A::ONE;
        loop {
            let n = count(cell);
            if n.x * n.y * n.z <= max_cells {
                break;
            }
            cell *= 1.5;
        }
        let n = count(cell);
        let dims = [n.x as u32, n.y as u32, n.z as u32];
        let mut grid = Grid { origin: lo, inv_cell: 1.0 / cell, dims, start: Vec::new(), members: Vec::new() };
        let cells = dims.iter().map(|&d| d as usize).product::<usize>();
        let of: Vec<u32> = points.iter().map(|v| grid.cell_of(v.p)).collect();
        let mut start = vec![0u32; cells + 1];
        for &c in &of {
            start[c as usize + 1] += 1;
        }
        for c in 0..cells {
            start[c + 1] += start[c];
        }
        let mut fill = start.clone();
        let mut members = vec![0u32; positional];
        for (j, &c) in of.iter().enumerate() {
            members[fill[c as usize] as usize] = j as u32;
            fill[c as usize] += 1;
        }
        (grid.start, grid.members) = (start, members);
        grid
    }

    /// The cell index along each axis of `p`, clamped to the grid.
    #[inline]
    fn coords(&self, p: Vec3A) -> [u32; 3] {
        let q = (p - self.origin) * self.inv_cell;
        // `as u32` saturates: below the grid (and NaN) gives 0.
        [0, 1, 2].map(|k| (q[k] as u32).min(self.dims[k] - 1))
    }

    #[inline]
    fn cell_of(&self, p: Vec3A) -> u32 {
        let [x, y, z] = self.coords(p);
        x + self.dims[0] * (y + self.dims[1] * z)
    }

    /// Calls `f` with every VPL of every cell the axis-aligned box around `apex` of half-width `r` meets
    /// (a superset of the ball's members).
    #[inline]
    fn candidates(&self, apex: Vec3A, r: f32, mut f: impl FnMut(u32)) {
        if self.start.is_empty() {
            return;
        }
        let (lo, hi) = (self.coords(apex - Vec3A::splat(r)), self.coords(apex + Vec3A::splat(r)));
        for z in lo[2]..=hi[2] {
            for y in lo[1]..=hi[1] {
                let row = self.dims[0] * (y + self.dims[1] * z);
                let (a, b) = (self.start[(row + lo[0]) as usize], self.start[(row + hi[0]) as usize + 1]);
                self.members[a as usize..b as usize].iter().for_each(|&j| f(j));
            }
        }
    }
}

/// The split's data for a VPL set: a tree for ball and cone queries over the positional VPLs and the
/// beams of the VPLs with a sharp lobe.
#[derive(Clone, Debug, Default)]
pub struct Split {
    /// Widest lobe cone split off, radians (0: no cones).
    max_angle: f32,
    /// Radius of the ball around the shading point whose VPLs are split off (0: no ball).
    near: f32,
    /// Positional VPLs are `0..positional`, directional ones after them.
    positional: usize,
    tree: SphereTree,
    /// The positional VPLs bucketed by a uniform grid of cells at least 2·`near` wide, for the ball query
    /// alone (the common case: a shading point without a sharp lobe).
    grid: Grid,
    /// Per VPL, its index in `beams` (u32::MAX: none).
    beam_of: Vec<u32>,
    /// The VPLs with a sharp lobe: index, position, beam.
    beams: Vec<(u32, Vec3A, Cone)>,
}

/// The split at one shading point: its apex (the centre of the ball) and lobe cone.
#[derive(Clone, Copy, Debug)]
pub struct Local<'a> {
    split: &'a Split,
    apex: Vec3A,
    cone: Option<Cone>,
}

impl Split {
    /// The split for `vpls` with lobe cones up to `max_angle` radians (0: no cones) and the VPLs within
    /// distance `near` of the shading point (0: none).
    pub fn new(vpls: &Vpls, max_angle: f32, near: f32) -> Split {
        let max_angle = if max_angle > 0.0 { max_angle } else { 0.0 };
        let near = if near > 0.0 && near.is_finite() { near } else { 0.0 };
        if (max_angle == 0.0 && near == 0.0) || vpls.is_empty() {
            return Split::default();
        }
        let positional = vpls.list.iter().take_while(|v| !matches!(v.emitter, Emitter::Directional)).count();
        let mut split = Split { max_angle, near, positional, beam_of: vec![u32::MAX; vpls.len()], ..Split::default() };
        split.tree = SphereTree::new(vpls, positional);
        if near > 0.0 {
            split.grid = Grid::new(vpls, positional, near);
        }
        if max_angle == 0.0 {
            return split;
        }
        for (j, v) in vpls.list.iter().enumerate() {
            if let Emitter::Bsdf { index } = v.emitter {
                let g = &vpls.bsdfs[index as usize];
                // f(w, ω_in) is symmetric: its peak is the mirror direction of ω_in.
                if let Some(beam) = sharp_cone(&g.bsdf, g.wi, max_angle) {
                    split.beam_of[j] = split.beams.len() as u32;
                    split.beams.push((j as u32, v.p, beam));
                }
            }
        }
        split
    }

    /// Whether nothing is ever split off.
    pub fn is_off(&self) -> bool {
        self.max_angle <= 0.0 && self.near <= 0.0
    }

    /// VPLs with a sharp lobe (a beam).
    pub fn beam_count(&self) -> usize {
        self.beams.len()
    }

    /// The split at receiver `x`.
    #[inline]
    pub fn at<'a>(&'a self, x: &Receiver) -> Local<'a> {
        let cone = if self.max_angle <= 0.0 { None } else { sharp_cone(&x.bsdf, x.wo, self.max_angle) };
        Local { split: self, apex: x.si.p, cone }
    }
}

impl Local<'_> {
    /// Whether VPL `j` is near the receiver, or the receiver's lobe cone holds it, or `j`'s beam holds
    /// the receiver: j ∈ S(s).
    #[inline]
    pub fn holds(&self, vpls: &Vpls, j: usize) -> bool {
        let sp = self.split;
        if sp.is_off() {
            return false;
        }
        if self.in_ball(vpls, j) {
            return true;
        }
        if let Some(cone) = &self.cone
            && self.in_cone(vpls, cone, j)
        {
            return true;
        }
        match sp.beam_of.get(j) {
            Some(&b) if b != u32::MAX => self.in_beam(b as usize),
            _ => false,
        }
    }

    /// Whether member `j` of S(s) is a member of S(s') for every s' within `region` of the apex, as far as
    /// the ball goes: true when it lies within `near` − `region` of the apex, or when the cone or a beam
    /// holds it (taken as held throughout). B, a bound over the region a cache serves, leaves out only these
    /// of its cache's split: a VPL near the cache but farther than `near` from some point of its region
    /// would otherwise have no density from the cache at that point.
    pub fn holds_throughout(&self, vpls: &Vpls, j: usize, region: f32) -> bool {
        let sp = self.split;
        let beam = matches!(sp.beam_of.get(j), Some(&b) if b != u32::MAX && self.in_beam(b as usize));
        if beam || self.cone.is_some_and(|c| self.in_cone(vpls, &c, j)) {
            return true;
        }
        let r = sp.near - region;
        r > 0.0 && j < sp.positional && (vpls.list[j].p - self.apex).length_squared() < r * r
    }

    /// Whether positional VPL `j` lies within the split's `near` distance of the apex.
    #[inline]
    fn in_ball(&self, vpls: &Vpls, j: usize) -> bool {
        let near = self.split.near;
        near > 0.0 && j < self.split.positional && (vpls.list[j].p - self.apex).length_squared() < near * near
    }

    #[inline]
    fn in_cone(&self, vpls: &Vpls, cone: &Cone, j: usize) -> bool {
        let v = &vpls.list[j];
        if j >= self.split.positional {
            return cone.contains(v.ng);
        }
        cone.contains((v.p - self.apex).normalize_or_zero())
    }

    #[inline]
    fn in_beam(&self, b: usize) -> bool {
        let (_, p, beam) = &self.split.beams[b];
        beam.contains((self.apex - *p).normalize_or_zero())
    }

    /// Calls `f` with every member of S(s), each once, positional VPLs in ascending order (the order
    /// [`Local::estimate`]'s systematic draws see them in).
    pub fn for_each(&self, vpls: &Vpls, mut f: impl FnMut(usize)) {
        let sp = self.split;
        if self.cone.is_none() && sp.near > 0.0 && self.ball_from_grid(vpls, &mut f) {
            return self.for_each_beam(vpls, f);
        }
        self.for_each_tree(vpls, f);
    }

    /// The ball's members from the grid, sorted, when there are at most [`GRID_GATHER`] (`false`, having
    /// called nothing, when there are more).
    #[inline]
    fn ball_from_grid(&self, vpls: &Vpls, f: &mut impl FnMut(usize)) -> bool {
        let (mut found, mut n) = ([0u32; GRID_GATHER], 0usize);
        let mut overflow = false;
        // The box is widened a little so that rounding in the cell coordinates never drops a member.
        let r = self.split.near * (1.0 + 1e-4) + 1e-6 * self.apex.abs().max_element().max(1.0);
        self.split.grid.candidates(self.apex, r, |j| {
            if self.in_ball(vpls, j as usize) {
                if n < GRID_GATHER {
                    found[n] = j;
                    n += 1;
                } else {
                    overflow = true;
                }
            }
        });
        if overflow {
            return false;
        }
        let found = &mut found[..n];
        found.sort_unstable();
        found.iter().for_each(|&j| f(j as usize));
        true
    }

    /// Every member of S(s) by walking the tree (balls and cones), then the beams.
    fn for_each_tree(&self, vpls: &Vpls, mut f: impl FnMut(usize)) {
        let sp = self.split;
        if self.cone.is_some() || sp.near > 0.0 {
            sp.tree.walk(
                |center, radius| {
                    (sp.near > 0.0 && (center - self.apex).length_squared() <= (radius + sp.near).powi(2))
                        || self.cone.is_some_and(|c| c.meets_sphere(self.apex, center, radius))
                },
                |lo, hi| {
                    for j in lo..hi {
                        if self.in_ball(vpls, j) || self.cone.is_some_and(|c| self.in_cone(vpls, &c, j)) {
                            f(j);
                        }
                    }
                },
            );
        }
        if let Some(cone) = &self.cone {
            for j in sp.positional..vpls.len() {
                if self.in_cone(vpls, cone, j) {
                    f(j);
                }
            }
        }
        self.for_each_beam(vpls, f);
    }

    /// The members of S(s) that neither the ball nor the cone holds: those whose beam holds the apex.
    fn for_each_beam(&self, vpls: &Vpls, mut f: impl FnMut(usize)) {
        for (b, &(j, _, _)) in self.split.beams.iter().enumerate() {
            let j = j as usize;
            if self.in_beam(b) && !self.in_ball(vpls, j) && !self.cone.is_some_and(|c| self.in_cone(vpls, &c, j)) {
                f(j);
            }
        }
    }

    /// The split's part of the VPL sum at `x`, Σ_{j∈S(s)} I_j(x), estimated with at most `draws` shadow
    /// rays: exact (one ray per member) when S(s) has no more members with light than that, else `draws`
    /// members drawn by systematic sampling in proportion to their exact unoccluded contribution, so only
    /// their visibility is left to chance (a member drawn m times gets one ray and weight m/draws). The
    /// members' values are kept from the walk that sums them; a set too large for `KEPT` is walked again.
    #[allow(clippy::too_many_arguments)]
    pub fn estimate(
        &self,
        scene: &Scene,
        sh: &Shading<'_>,
        vpls: &Vpls,
        x: &Receiver,
        draws: u32,
        rng: &mut Rng,
        rays: &mut RayCounters,
    ) -> Spectrum {
        let weight = |j: usize| {
            let u = vpls.unoccluded_value(sh, j, x)?;
            let w = luminance(u);
            (w > 0.0 && w.is_finite()).then_some((u, w))
        };
        let mut kept = [(0u32, Spectrum::ZERO, 0.0f32); KEPT];
        let (mut total, mut count) = (0.0f32, 0usize);
        self.for_each(vpls, |j| {
            if let Some((u, w)) = weight(j) {
                if let Some(k) = kept.get_mut(count) {
                    *k = (j as u32, u, w);
                }
                total += w;
                count += 1;
            }
        });
        if count == 0 {
            return Spectrum::ZERO;
        }
        let mut visible = |j: usize| {
            rays.shadow += 1;
            !scene.geometry.occluded(&vpls.shadow_ray(j, x))
        };
        let draws = draws.max(1);
        // Systematic sampling: targets (i + ξ)·total/draws, i = 0..draws, each in the member whose interval of
        // the running sum holds it (the running sum repeats `total`'s additions, so the last member with light
        // ends at `total` exactly; a target rounded past it goes to that member).
        let step = total / draws as f32;
        let mut next = if count <= draws as usize { 0.0 } else { rng.uniform() * step };
        let (mut acc, mut left, mut sum) = (0.0f32, draws, Spectrum::ZERO);
        let mut member = |j: usize, u: Spectrum, w: f32| {
            if count <= draws as usize {
                if visible(j) {
                    sum += u;
                }
                return;
            }
            acc += w;
            let mut hits = 0u32;
            while left > 0 && (next < acc || acc >= total) {
                hits += 1;
                left -= 1;
                next += step;
            }
            if hits > 0 && visible(j) {
                sum += u * (hits as f32 * step / w);
            }
        };
        if count <= KEPT {
            kept[..count].iter().for_each(|&(j, u, w)| member(j as usize, u, w));
        } else {
            self.for_each(vpls, |j| {
                if let Some((u, w)) = weight(j) {
                    member(j, u, w);
                }
            });
        }
        sum
    }
}

/// Test set-up: a BSDF of one Trowbridge–Reitz reflection lobe of roughness `alpha` (no Fresnel) about the
/// normal `n`.
#[cfg(test)]
pub(crate) fn glossy(alpha: f32, n: Vec3A) -> Bsdf {
    use crate::shading::bxdf::distribution::TrowbridgeReitz;
    use crate::shading::bxdf::fresnel::Fresnel;
    use crate::shading::bxdf::microfacet::MicrofacetReflection;
    let mut bsdf = Bsdf::new(n, n, n.any_orthonormal_vector(), 1.0);
    bsdf.add(Bxdf::MicrofacetReflection(MicrofacetReflection {
        r: Spectrum::splat(1.0),
        distribution: TrowbridgeReitz::new(alpha, alpha),
        fresnel: Fresnel::NoOp,
    }));
    bsdf
}

#[cfg(test)]
mod tests {
    use super::super::vpl::{GeneralVpl, Vpl};
    use super::*;
    use crate::shading::bxdf::distribution::TrowbridgeReitz;

    #[test]
    fn outside_the_cone_the_lobe_is_below_the_density_threshold() {
        let n = Vec3A::new(0.2, 0.1, 1.0).normalize();
        let mut rng = Rng::new(5);
        for alpha in [0.001f32, 0.003, 0.01, 0.02] {
            let bsdf = glossy(alpha, n);
            let wo = Vec3A::new(0.5, -0.3, 0.8).normalize();
            let cone = sharp_cone(&bsdf, wo, 1.0).expect("sharp");
            let d = TrowbridgeReitz::new(alpha, alpha);
            let (wo_l, mut outside) = (bsdf.to_local(wo), 0);
            for _ in 0..20_000 {
                let wi = crate::sampling::warp::uniform_sphere(rng.uniform2());
                let wi_l = bsdf.to_local(wi);
                if wi_l.z <= 0.0 || cone.contains(wi) {
                    continue;
                }
                outside += 1;
                let wh = (wo_l + wi_l).normalize();
                // The threshold is met up to the cos⁴θ_h the cone's width leaves out.
                assert!(d.d(wh) * wh.z.powi(4) <= D_MIN * 1.0001, "α {alpha}: D {} at {wi:?}", d.d(wh));
            }
            assert!(outside > 1000);
            // And the cone is not wastefully wide: its edge is near the threshold.
            assert!(cone.angle < 8.0 * alpha.sqrt(), "α {alpha}: {}", cone.angle);
        }
        assert_eq!(sharp_cone(&glossy(0.6, n), Vec3A::Z, 1.5), None, "a lobe whose peak is below D_MIN is not split");
        assert!(sharp_cone(&glossy(0.3, n), Vec3A::Z, 1.0).is_some());
        assert_eq!(sharp_cone(&glossy(0.01, n), Vec3A::Z, 0.01), None, "nor one wider than the limit");
    }

    /// Random VPLs: positional cosine emitters, every tenth with a sharp lobe, and directional ones last.
    fn vpls(rng: &mut Rng) -> Vpls {
        let mut v = Vpls::none(0.01);
        for k in 0..3000 {
            let [a, b] = rng.uniform2();
            let p = Vec3A::new(4.0 * a - 2.0, 4.0 * b - 2.0, 2.0 * rng.uniform() - 1.0);
            let n = crate::sampling::warp::uniform_sphere(rng.uniform2());
            let emitter = if k % 10 == 0 {
                v.bsdfs.push(GeneralVpl { bsdf: glossy(0.002 + 0.004 * rng.uniform(), n), wi: n });
                Emitter::Bsdf { index: v.bsdfs.len() as u32 - 1 }
            } else {
                Emitter::Cosine { two_sided: false }
            };
            v.list.push(Vpl { p, p_error: Vec3A::ZERO, ng: n, ns: n, power: Spectrum::splat(1.0), emitter });
        }
        for _ in 0..50 {
            let w = crate::sampling::warp::uniform_sphere(rng.uniform2());
            let emitter = Emitter::Directional;
            v.list.push(Vpl {
                p: Vec3A::ZERO,
                p_error: Vec3A::ZERO,
                ng: w,
                ns: w,
                power: Spectrum::splat(1.0),
                emitter,
            });
        }
        v
    }

    #[test]
    fn b_leaves_out_only_the_members_held_throughout_the_region() {
        let mut v = Vpls::none(0.01);
        let at = |x: f32| Vpl {
            p: Vec3A::new(x, 0.0, 0.0),
            p_error: Vec3A::ZERO,
            ng: Vec3A::Z,
            ns: Vec3A::Z,
            power: Spectrum::splat(1.0),
            emitter: Emitter::Cosine { two_sided: false },
        };
        v.list.extend([at(0.5), at(0.9), at(3.0)]);
        let split = Split::new(&v, 0.5, 1.0);
        let ball = Local { split: &split, apex: Vec3A::ZERO, cone: None };
        let mut members = Vec::new();
        ball.for_each(&v, |j| members.push(j));
        assert_eq!(members, [0, 1], "the ball of radius 1");
        // Within 1 − 0.3 of the apex: in every ball of a point within 0.3 of it; 0.9 is not.
        assert!(ball.holds_throughout(&v, 0, 0.3));
        assert!(!ball.holds_throughout(&v, 1, 0.3));
        assert!(!ball.holds_throughout(&v, 0, 0.6), "0.5 is beyond 1 − 0.6");
        // A cone's member is taken as held throughout, however far.
        let cone = Local { split: &split, apex: Vec3A::ZERO, cone: Some(Cone::new(Vec3A::X, 0.2)) };
        assert!(cone.holds(&v, 2) && cone.holds_throughout(&v, 2, 0.6));
    }

    #[test]
    fn the_tree_query_finds_exactly_the_members_once() {
        let mut rng = Rng::new(17);
        let v = vpls(&mut rng);
        // Cones alone, a ball alone (one that the grid answers, and one too full for its gather, ~130
        // members, that falls back to the tree), and both.
        for (angle, near) in [(0.5, 0.0), (0.0, 0.3), (0.0, 1.0), (0.5, 0.3)] {
            let split = Split::new(&v, angle, near);
            assert_eq!(split.beam_count(), if angle > 0.0 { 300 } else { 0 }, "every sharp VPL has a beam");
            let (mut members, mut in_ball) = (0, 0);
            for k in 0..300 {
                let apex = Vec3A::new(4.0 * rng.uniform() - 2.0, 4.0 * rng.uniform() - 2.0, 2.0 * rng.uniform() - 0.5);
                let axis = crate::sampling::warp::uniform_sphere(rng.uniform2());
                let half = 0.01 + 0.4 * rng.uniform();
                let cone = (k % 5 != 0 && angle > 0.0).then_some(Cone::new(axis, half));
                let local = Local { split: &split, apex, cone };
                let mut found = Vec::new();
                local.for_each(&v, |j| found.push(j));
                // The grid gives the tree's members in the tree's order (the systematic draws depend on it).
                let mut walked = Vec::new();
                local.for_each_tree(&v, |j| walked.push(j));
                assert_eq!(found, walked, "apex {apex:?} cone {cone:?}");
                let mut unique = found.clone();
                unique.sort_unstable();
                unique.dedup();
                assert_eq!(unique.len(), found.len(), "a member came twice");
                let want: Vec<usize> = (0..v.len()).filter(|&j| local.holds(&v, j)).collect();
                assert_eq!(unique, want, "apex {apex:?} cone {cone:?}");
                members += want.len();
                // The ball is what its name says: the positional VPLs closer than `near`, and no other.
                let close = |j: usize| j < split.positional && (v.list[j].p - apex).length() < near;
                in_ball += (0..v.len()).filter(|&j| close(j)).count();
                assert!((0..v.len()).filter(|&j| close(j)).all(|j| local.holds(&v, j)));
                if angle == 0.0 {
                    assert!(want.iter().all(|&j| close(j)), "without cones only the ball holds VPLs");
                }
            }
            assert!(members > 1000, "the queries should find members ({members})");
            assert_eq!(in_ball > 100, near > 0.0, "balls of radius {near} should hold VPLs ({in_ball})");
        }
        // Off: nothing is ever held.
        let off = Split::new(&v, 0.0, 0.0);
        let local = Local { split: &off, apex: Vec3A::ZERO, cone: None };
        assert!((0..v.len()).all(|j| !local.holds(&v, j)));
    }
}

#[cfg(test)]
mod estimate_tests {
    use super::super::vpl::with_lit_scene;
    use super::*;
    use crate::scene::ray::Ray;

    /// A floor, a wall standing on it lit from one side by a lamp, and a low post in front of the wall: a
    /// floor point near the wall has dozens of the wall's VPLs within a small ball, and the post hides some.
    const WALLED: &str = "LookAt -3 2 0 0 0 0 0 1 0\nCamera \"perspective\"\nWorldBegin\n\
        Material \"matte\" \"rgb Kd\" [0.7 0.6 0.5]\n\
        Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] \"point P\" [-2 0 -2  2 0 -2  2 0 2  -2 0 2]\n\
        Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] \"point P\" [0 0 -2  0 0 2  0 1.5 2  0 1.5 -2]\n\
        Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] \"point P\" [-0.15 0 -0.1  -0.15 0 0.1  -0.15 0.3 0.1  -0.15 0.3 -0.1]\n\
        AttributeBegin\nAreaLightSource \"diffuse\" \"rgb L\" [5 5 5]\n\
        Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] \"point P\" [-1.5 2.5 -0.5  -0.5 2.5 -0.5  -0.5 2.5 0.5  -1.5 2.5 0.5]\n\
        AttributeEnd\nWorldEnd\n";

    #[test]
    fn the_split_sum_is_exact_up_to_its_draws_and_unbiased_beyond() {
        with_lit_scene(WALLED, |scene, sh, select| {
            let v = Vpls::generate(scene, sh, select, 2000, 5, 0.05, &mut Rng::new(3));
            let split = Split::new(&v, 0.0, 0.6);
            let mut rng = Rng::new(4);
            let (mut systematic, mut occluded_some) = (0, 0);
            for k in 0..12 {
                let at = Vec3A::new(-0.3, 1.0, 0.08 * k as f32 - 0.44);
                let si = scene.geometry.intersect(&Ray::new(at, -Vec3A::Y)).unwrap();
                let x = Receiver::new(si, sh.bsdf(&si).unwrap(), Vec3A::new(0.2, 1.0, -0.4).normalize());
                let local = split.at(&x);
                let mut rays = RayCounters::default();
                let (mut exact, mut unoccluded, mut lit) = (Spectrum::ZERO, Spectrum::ZERO, 0u32);
                local.for_each(&v, |j| {
                    if let Some(u) = v.unoccluded_value(sh, j, &x) {
                        lit += 1;
                        unoccluded += u;
                        exact += v.contribution(scene, sh, j, &x, &mut rays);
                    }
                });
                occluded_some += (luminance(exact) < 0.999 * luminance(unoccluded)) as u32;
                // Up to `draws` members with light: every one is traced, the sum is exact, no draw is made.
                let mut rays = RayCounters::default();
                let before = rng.clone();
                let whole = local.estimate(scene, sh, &v, &x, lit.max(1), &mut rng, &mut rays);
                assert_eq!(whole, exact, "receiver {k}: {lit} members");
                assert_eq!(rays.shadow, lit as u64);
                assert_eq!(rng.uniform(), before.clone().uniform(), "no random number is used");
                if lit <= 4 {
                    continue;
                }
                // Beyond: at most `draws` rays, and the mean of many estimates is the exact sum.
                systematic += 1;
                for draws in [1u32, 4] {
                    let n = 4000;
                    let (mut sum, mut sum2) = (0.0f64, 0.0f64);
                    for _ in 0..n {
                        let mut rays = RayCounters::default();
                        let e = luminance(local.estimate(scene, sh, &v, &x, draws, &mut rng, &mut rays)) as f64;
                        assert!(rays.shadow <= draws as u64);
                        sum += e;
                        sum2 += e * e;
                    }
                    let mean = sum / n as f64;
                    let se = ((sum2 / n as f64 - mean * mean).max(0.0) / n as f64).sqrt();
                    let want = luminance(exact) as f64;
                    assert!(
                        (mean - want).abs() <= 4.0 * se + 1e-6 * want,
                        "receiver {k}, {draws} draws over {lit} members: mean {mean} vs {want} (se {se})"
                    );
                }
            }
            assert!(systematic >= 6, "most receivers should have more members than draws ({systematic})");
            assert!(occluded_some >= 3, "the wall should hide members from some receivers ({occluded_some})");
        });
    }
}
