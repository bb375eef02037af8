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
//! I_j(s) + Σ_{j∉S(s)} I_j(s). The first part is estimated at s itself with one shadow ray — one member
//! drawn in proportion to its exact unoccluded contribution there, so only its visibility is left to
//! chance; the second is the usual estimator with every draw that lands in S(s) counted as 0. S(s) depends
//! on s alone, never on a draw, so both parts stay unbiased for their sums and the whole for the same VPL
//! image (`placement none` is unchanged). A lobe counts as sharp where its microfacet density exceeds
//! [`D_MIN`] within a cone narrower than the `splitcone` angle; wider lobes are left to the estimator
//! (their cones would hold hundreds of VPLs). The ball holds a handful of VPLs (the VPLs lie on surfaces,
//! and d_c is 2.5 % of the scene's diagonal).
//!
//! Depends on the VPLs and the shading layer's lobes; never on placement or the caches.

use glam::Vec3A;

use super::vpl::{Emitter, Receiver, Vpls};
use crate::render::lighting::Shading;
use crate::sampling::Rng;
use crate::scene::Scene;
use crate::scene::ray::RayCounters;
use crate::shading::bsdf::Bsdf;
use crate::shading::bxdf::Bxdf;
use crate::shading::{Spectrum, luminance};

/// Microfacet density (sr⁻¹) above which a lobe's directions are split off. CHOICE: 1 — below it a glossy
/// lobe's value is of the order of a diffuse one's (1/π), which the cached distributions handle.
pub const D_MIN: f32 = 1.0;

/// VPLs per leaf of the query tree.
const LEAF: usize = 8;

/// A cone of unit directions around `axis` with half-angle `angle`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cone {
    /// Unit axis.
    pub axis: Vec3A,
    /// cos of the half-angle.
    pub cos: f32,
    /// The half-angle, radians.
    pub angle: f32,
}

impl Cone {
    /// Whether unit direction `w` lies inside.
    #[inline]
    pub fn contains(&self, w: Vec3A) -> bool {
        w.dot(self.axis) >= self.cos
    }
}

/// tan of the half-vector angle within which a lobe's Trowbridge–Reitz density exceeds [`D_MIN`]
/// (D = 1 / (π α² (1 + tan²θ_h/α²)²), its cos⁴θ_h left out), with α the larger of the two; `None` when the
/// lobe is not a microfacet reflection or its peak 1 / (π α_x α_y) does not exceed `D_MIN`.
fn lobe_tan(b: &Bxdf) -> Option<f32> {
    let d = match b {
        Bxdf::MicrofacetReflection(m) => &m.distribution,
        Bxdf::FresnelBlend(m) => &m.distribution,
        _ => return None,
    };
    let peak = 1.0 / (std::f32::consts::PI * d.alpha_x * d.alpha_y);
    (peak > D_MIN && peak.is_finite()).then(|| d.alpha_x.max(d.alpha_y) * ((peak / D_MIN).sqrt() - 1.0).sqrt())
}

/// The cone holding every direction ω in which a sharp reflection lobe of `bsdf`, seen from `wo`, has a
/// density above [`D_MIN`]: around the mirror direction of `wo` about the shading normal, twice the lobe's
/// half-vector angle wide (reflecting about a half vector θ_h away from the normal turns ω by at most 2θ_h).
/// `None` when no lobe is that sharp or the cone would be wider than `max_angle` radians.
pub fn sharp_cone(bsdf: &Bsdf, wo: Vec3A, max_angle: f32) -> Option<Cone> {
    let t = bsdf.lobes().filter(|(_, s)| s.max_element() > 0.0).filter_map(|(b, _)| lobe_tan(b)).reduce(f32::max)?;
    let angle = 2.0 * t.atan();
    if angle.is_nan() || angle > max_angle {
        return None;
    }
    let n = bsdf.shading_normal();
    let axis = (2.0 * wo.dot(n) * n - wo).normalize();
    axis.is_finite().then(|| Cone { axis, cos: angle.cos(), angle })
}

/// A node of the query tree: a bounding sphere of VPLs `lo..hi` (in the VPL list's Morton order);
/// the nodes are stored in preorder and `skip` is the index past this node's subtree.
#[derive(Clone, Copy, Debug)]
struct Node {
    center: Vec3A,
    radius: f32,
    lo: u32,
    hi: u32,
    skip: u32,
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
    nodes: Vec<Node>,
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
        split.build(vpls, 0, positional);
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

    fn build(&mut self, vpls: &Vpls, lo: usize, hi: usize) {
        if lo >= hi {
            return;
        }
        let (mut min, mut max) = (Vec3A::splat(f32::INFINITY), Vec3A::splat(f32::NEG_INFINITY));
        for v in &vpls.list[lo..hi] {
            (min, max) = (min.min(v.p), max.max(v.p));
        }
        let center = 0.5 * (min + max);
        let radius = vpls.list[lo..hi].iter().map(|v| (v.p - center).length()).fold(0.0f32, f32::max);
        // Rounding of the query's distances: the sphere is grown so that culling never drops a member.
        let radius = radius * (1.0 + 1e-4) + 1e-6 * center.abs().max_element().max(1.0);
        let at = self.nodes.len();
        self.nodes.push(Node { center, radius, lo: lo as u32, hi: hi as u32, skip: 0 });
        if hi - lo > LEAF {
            let mid = lo + (hi - lo) / 2;
            self.build(vpls, lo, mid);
            self.build(vpls, mid, hi);
        }
        self.nodes[at].skip = self.nodes.len() as u32;
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

    /// Calls `f` with every member of S(s), each once.
    pub fn for_each(&self, vpls: &Vpls, mut f: impl FnMut(usize)) {
        let sp = self.split;
        if self.cone.is_some() || sp.near > 0.0 {
            let mut i = 0;
            while i < sp.nodes.len() {
                let n = &sp.nodes[i];
                let meets_ball =
                    sp.near > 0.0 && (n.center - self.apex).length_squared() <= (n.radius + sp.near).powi(2);
                if !meets_ball && !self.cone.is_some_and(|c| self.sphere_meets(&c, n.center, n.radius)) {
                    i = n.skip as usize;
                    continue;
                }
                if n.hi - n.lo <= LEAF as u32 {
                    for j in n.lo as usize..n.hi as usize {
                        if self.in_ball(vpls, j) || self.cone.is_some_and(|c| self.in_cone(vpls, &c, j)) {
                            f(j);
                        }
                    }
                }
                i += 1;
            }
        }
        if let Some(cone) = &self.cone {
            for j in sp.positional..vpls.len() {
                if self.in_cone(vpls, cone, j) {
                    f(j);
                }
            }
        }
        for (b, &(j, _, _)) in sp.beams.iter().enumerate() {
            let j = j as usize;
            if self.in_beam(b) && !self.in_ball(vpls, j) && !self.cone.is_some_and(|c| self.in_cone(vpls, &c, j)) {
                f(j);
            }
        }
    }

    /// Whether a sphere may hold a point whose direction from the apex is in the cone (conservative).
    #[inline]
    fn sphere_meets(&self, cone: &Cone, center: Vec3A, radius: f32) -> bool {
        let v = center - self.apex;
        let d = v.length();
        if d <= radius {
            return true;
        }
        let to_center = (v.dot(cone.axis) / d).clamp(-1.0, 1.0).acos();
        let spread = (radius / d).min(1.0).asin();
        to_center <= cone.angle + spread + 1e-3
    }

    /// An estimate of Σ_{j∈S(s)} I_j(s) at receiver `x`: one member drawn in proportion to the luminance
    /// of its unoccluded contribution (weighted reservoir sampling, one uniform per member), its
    /// visibility decided by one shadow ray.
    pub fn estimate(
        &self,
        scene: &Scene,
        sh: &Shading<'_>,
        vpls: &Vpls,
        x: &Receiver,
        rng: &mut Rng,
        rays: &mut RayCounters,
    ) -> Spectrum {
        let mut total = 0.0f32;
        let mut pick: Option<(usize, Spectrum, f32)> = None;
        self.for_each(vpls, |j| {
            let Some(u) = vpls.unoccluded_value(sh, j, x) else { return };
            let w = luminance(u);
            if w <= 0.0 || !w.is_finite() {
                return;
            }
            total += w;
            if rng.uniform() * total < w {
                pick = Some((j, u, w));
            }
        });
        let Some((j, u, w)) = pick else { return Spectrum::ZERO };
        rays.shadow += 1;
        if scene.geometry.occluded(&vpls.shadow_ray(j, x)) { Spectrum::ZERO } else { u * (total / w) }
    }
}

#[cfg(test)]
mod tests {
    use super::super::vpl::{GeneralVpl, Vpl};
    use super::*;
    use crate::shading::bxdf::distribution::TrowbridgeReitz;
    use crate::shading::bxdf::fresnel::Fresnel;
    use crate::shading::bxdf::microfacet::MicrofacetReflection;

    fn glossy(alpha: f32, n: Vec3A) -> Bsdf {
        let mut bsdf = Bsdf::new(n, n, n.any_orthonormal_vector(), 1.0);
        bsdf.add(Bxdf::MicrofacetReflection(MicrofacetReflection {
            r: Spectrum::splat(1.0),
            distribution: TrowbridgeReitz::new(alpha, alpha),
            fresnel: Fresnel::NoOp,
        }));
        bsdf
    }

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
    fn the_tree_query_finds_exactly_the_members_once() {
        let mut rng = Rng::new(17);
        let v = vpls(&mut rng);
        // Cones alone, a ball alone, and both.
        for (angle, near) in [(0.5, 0.0), (0.0, 0.3), (0.5, 0.3)] {
            let split = Split::new(&v, angle, near);
            assert_eq!(split.beam_count(), if angle > 0.0 { 300 } else { 0 }, "every sharp VPL has a beam");
            let (mut members, mut in_ball) = (0, 0);
            for k in 0..300 {
                let apex = Vec3A::new(4.0 * rng.uniform() - 2.0, 4.0 * rng.uniform() - 2.0, 2.0 * rng.uniform() - 0.5);
                let axis = crate::sampling::warp::uniform_sphere(rng.uniform2());
                let half = 0.01 + 0.4 * rng.uniform();
                let cone = (k % 5 != 0 && angle > 0.0).then_some(Cone { axis, cos: half.cos(), angle: half });
                let local = Local { split: &split, apex, cone };
                let mut found = Vec::new();
                local.for_each(&v, |j| found.push(j));
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
