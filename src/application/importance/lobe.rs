//! STAGE 5 (application, importance caching): the lobe technique G — at a shading point whose glossy
//! reflection lobe is wider than the split's cones but no wider than `lobecone`, one more VPL is drawn
//! among those in the lobe's cone, in proportion to their flux over their clamped squared distance, times
//! the lobe's falloff toward them.
//!
//! Why: a glossy receiver (roughness 0.05–0.2: the bathroom's window frame, sill, cabinet, tiles and metal
//! plate) multiplies the light of the VPLs its lobe points at by several times its diffuse value, but its
//! caches — on another facet, or a little way off where the lobe meets other VPLs, or behind the blinds'
//! slats from them — may give those VPLs almost no density. Then only the conservative technique draws
//! them, and a draw is worth thousands of times its light: the bathroom's fireflies (a window-frame sample at
//! 234 with weight 4453, drawn by C; a metal-plate sample at 504 with weight 1375). The split sums the VPLs
//! of lobes up to `splitcone` exactly, but a 20–30° lobe's cone holds hundreds of VPLs, too many to
//! evaluate (BSDF and all) at every sample; their flux, distance and angle from the lobe's axis are cheap.
//!
//! The first form of G (commit d35f740) drew in proportion to flux among 128 clusters of VPLs whose bounding
//! spheres the cone met: every VPL of such a cluster got about one over the clusters' population, in the
//! cone or not, near or far. The bathroom's largest remaining samples were then VPLs half a metre from a
//! tiled receiver, in its 24° lobe, drawn by U with weights 389 and 577 where G gave them 1/1700 (seed 0,
//! 2800 caches).
//!
//! What: at a shading point s with such a lobe, K(s) is the cone [`sharp_cone`] gives and α the lobe's
//! roughness, and a positional VPL j has the weight
//! w_j = Φ_j · c_j · D(θ_j / 2) / D(0) / max(|p_j − s|², d_c²) when its direction from s lies in K(s), else 0
//! (Φ: the luminance of its flux; c_j: the cosine at a cosine emitter toward s — 0 behind a one-sided one —,
//! |cos| at a glossy surface VPL, 1 for point and spot lights; θ_j: the angle between its direction and the
//! cone's axis, the mirror direction, so that D(θ_j / 2) / D(0) = 1 / (1 + tan²(θ_j / 2) / α²)² is the
//! Trowbridge–Reitz lobe's falloff with the half-vector angle taken as half of θ_j). p_G(j) = w_j / W with
//! W = Σ w_j, the sum over the cone's VPLs found by walking the VPLs' sphere tree ([`SphereTree`]); the same
//! walk makes the draws ([`LobeTree::at`]). W depends on s alone and w_j is evaluated alike by draw and
//! density, so p_G is exactly the probability of drawing j and the MIS combination can evaluate it for every
//! other technique's draw; the estimate stays unbiased (C still reaches every VPL). Directional VPLs are
//! never drawn by G. Without the falloff (flux over distance alone), a wall VPL 2 m from an 18° lobe, near
//! its axis, got 1/1800 of G's density and was drawn by U with weight 786 (bathroom, seed 3).
//!
//! Depends on the VPLs and the shading layer's lobes; never on placement or the caches.

use glam::Vec3A;

use super::spheres::SphereTree;
#[cfg(doc)]
use super::split::sharp_cone;
use super::split::{Cone, sharp_lobe};
use super::vpl::{Emitter, Receiver, Vpls};
use crate::sampling::unit_f64;

/// Most draws of G per shading point (its letters in `distributions` times `lightsamples` may reach 16).
pub const MAX_DRAWS: usize = 16;

/// What G needs of the VPLs: their sphere tree and the range of lobe widths it serves.
#[derive(Clone, Debug, Default)]
pub struct LobeTree {
    /// Lobes wider than this (radians) and no wider than `max_angle` make G active.
    min_angle: f32,
    max_angle: f32,
    /// The positional VPLs (those before the first directional one).
    positional: usize,
    tree: SphereTree,
}

impl LobeTree {
    /// G's data for `vpls` and lobes wider than `min_angle` and up to `max_angle` radians (`max_angle`
    /// ≤ `min_angle`: G is never active).
    pub fn new(vpls: &Vpls, min_angle: f32, max_angle: f32) -> LobeTree {
        let positional = vpls.list.iter().take_while(|v| !matches!(v.emitter, Emitter::Directional)).count();
        if positional == 0 || max_angle.is_nan() || max_angle <= min_angle.max(0.0) {
            return LobeTree::default();
        }
        LobeTree { min_angle: min_angle.max(0.0), max_angle, positional, tree: SphereTree::new(vpls, positional) }
    }

    /// G at receiver `x`, with its draws made at the 64 uniform bits of each of `us` (at most
    /// [`MAX_DRAWS`]): `None` when its lobe is not in G's range of widths or no VPL in its cone has weight.
    ///
    /// The walk that sums W also makes the draws, so that it need not be walked again (the cone holds some
    /// 300 VPLs at the bathroom's tiles). First a leaf of the tree, by sequential (reservoir) selection with
    /// one uniform number per draw: the k-th leaf with weight replaces the choice with probability
    /// S_k / (S_1 + … + S_k) (S: the sum of its VPLs' weights), decided by whether the number is below it,
    /// and the number is rescaled to the part of [0, 1) it fell in, so that it stays uniform for the next
    /// decision; the leaf chosen last is leaf k with probability S_k / W. Then, within it, the VPL whose
    /// interval of the leaf's running sum holds the rescaled number times S_k: j with probability w_j / W
    /// in all, the density [`Lobe::pdf`] gives.
    #[inline]
    pub fn at<'a>(&'a self, vpls: &'a Vpls, x: &Receiver, us: &[u64]) -> Option<Lobe<'a>> {
        if self.positional == 0 {
            return None;
        }
        let (cone, alpha) = sharp_lobe(&x.bsdf, x.wo, self.max_angle).filter(|(c, _)| c.angle > self.min_angle)?;
        let inv_alpha2 = 1.0 / (alpha * alpha);
        let mut lobe = Lobe { tree: self, vpls, apex: x.si.p, cone, inv_alpha2, total: 0.0, picks: [0; MAX_DRAWS] };
        let us = &us[..us.len().min(MAX_DRAWS)];
        let mut u: [f64; MAX_DRAWS] = std::array::from_fn(|k| us.get(k).map_or(0.0, |&u| unit_f64(u)));
        let mut leaf = [(0u32, 0u32, 0.0f64); MAX_DRAWS];
        let mut total = 0.0f64;
        self.tree.walk(
            |center, radius| cone.meets_sphere(lobe.apex, center, radius),
            |lo, hi| {
                let sum: f64 = (lo..hi).map(|j| lobe.weight(j) as f64).sum();
                if sum <= 0.0 {
                    return;
                }
                total += sum;
                let p = sum / total;
                for (u, chosen) in u.iter_mut().zip(leaf.iter_mut()).take(us.len()) {
                    if *u < p {
                        (*u, *chosen) = (*u / p, (lo as u32, hi as u32, sum));
                    } else {
                        *u = ((*u - p) / (1.0 - p)).min(ONE_BELOW);
                    }
                }
            },
        );
        if !(total > 0.0 && total.is_finite()) {
            return None;
        }
        lobe.total = total;
        let mut picks = [0u32; MAX_DRAWS];
        for ((&u, &(lo, hi, sum)), pick) in u.iter().zip(&leaf).zip(picks.iter_mut()).take(us.len()) {
            let target = u * sum;
            let (mut acc, mut last) = (0.0f64, lo);
            *pick = (lo..hi)
                .find(|&j| {
                    let w = lobe.weight(j as usize) as f64;
                    if w > 0.0 {
                        acc += w;
                        last = j;
                    }
                    w > 0.0 && target < acc
                })
                .unwrap_or(last);
        }
        lobe.picks = picks;
        Some(lobe)
    }
}

/// The largest f64 below 1.
const ONE_BELOW: f64 = 1.0 - f64::EPSILON / 2.0;

/// G at one shading point: its lobe's cone and the sum of the weights in it.
#[derive(Clone, Copy, Debug)]
pub struct Lobe<'a> {
    tree: &'a LobeTree,
    vpls: &'a Vpls,
    apex: Vec3A,
    cone: Cone,
    /// 1 / α² of the lobe (the larger α of the widest sharp lobe).
    inv_alpha2: f32,
    /// W.
    total: f64,
    /// The VPL each draw chose (for the draws [`LobeTree::at`] was given bits for).
    picks: [u32; MAX_DRAWS],
}

impl Lobe<'_> {
    /// w_j for a positional VPL `j`.
    #[inline]
    fn weight(&self, j: usize) -> f32 {
        let v = &self.vpls.list[j];
        let d = v.p - self.apex;
        let d2 = d.length_squared();
        // In the cone: d·axis ≥ cos·|d|, tested without the square root first (cos > 0: half-angles of
        // G's lobes are below 90°).
        let along = d.dot(self.cone.axis);
        if !(along > 0.0 && along * along >= self.cone.cos * self.cone.cos * d2) {
            return 0.0;
        }
        let dist = d2.sqrt();
        if along < self.cone.cos * dist {
            return 0.0;
        }
        let cos = -v.ns.dot(d) / dist;
        let c = match v.emitter {
            Emitter::Cosine { two_sided: false } => cos.max(0.0),
            Emitter::Cosine { two_sided: true } | Emitter::Bsdf { .. } => cos.abs(),
            _ => 1.0,
        };
        // The lobe's shape: Trowbridge–Reitz D(θ_h) / D(0) = 1 / (1 + tan²θ_h / α²)², with θ_h taken as half
        // the angle θ from the axis (tan²(θ/2) = (1 − cos θ) / (1 + cos θ)).
        let cos_axis = along / dist;
        let t2 = (1.0 - cos_axis) / (1.0 + cos_axis);
        let shape = 1.0 / (1.0 + t2 * self.inv_alpha2).powi(2);
        let w = self.vpls.flux[j] * c * shape / d2.max(self.vpls.clamp2);
        if w.is_finite() && w > 0.0 { w } else { 0.0 }
    }

    /// p_G(j).
    #[inline]
    pub fn pdf(&self, j: usize) -> f32 {
        if j >= self.tree.positional {
            return 0.0;
        }
        (self.weight(j) as f64 / self.total) as f32
    }

    /// The VPL draw `d` chose.
    #[inline]
    pub fn pick(&self, d: u32) -> usize {
        self.picks[(d as usize).min(MAX_DRAWS - 1)] as usize
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::application::importance::vpl::with_lit_scene;
    use crate::sampling::Rng;
    use crate::scene::Scene;
    use crate::scene::ray::Ray;
    use crate::shading::light::LightSelect;
    use crate::shading::lighting::Shading;

    /// A glossy floor (roughness 0.1: a lobe about 24° wide) under a large lamp, and the floor's receiver
    /// at its centre seen at 45°.
    const SCENE: &str = r#"
        LookAt 0 -3 3  0 0 0  0 0 1
        Camera "perspective" "float fov" 50
        Film "image" "integer xresolution" 16 "integer yresolution" 16
        WorldBegin
        AttributeBegin
          AreaLightSource "diffuse" "rgb L" [4 4 4] "bool twosided" "true"
          Shape "trianglemesh" "integer indices" [0 1 2 0 2 3]
            "point P" [-3 -3 2  3 -3 2  3 3 2  -3 3 2]
        AttributeEnd
        Material "metal" "float roughness" 0.1 "bool remaproughness" "false"
        Shape "trianglemesh" "integer indices" [0 1 2 0 2 3] "point P" [-3 -3 0  3 -3 0  3 3 0  -3 3 0]
        WorldEnd
    "#;

    fn with_lobe<T>(f: impl FnOnce(&Vpls, &LobeTree, &Receiver) -> T) -> T {
        with_lit_scene(SCENE, |scene: &Scene, sh: &Shading<'_>, select: &LightSelect| {
            let mut rng = Rng::new(3);
            let vpls = Vpls::generate(scene, sh, select, 2000, 1, 0.01, &mut rng);
            let tree = LobeTree::new(&vpls, 10f32.to_radians(), 45f32.to_radians());
            let si = scene.geometry.intersect(&Ray::new(Vec3A::new(0.0, 0.0, 1.0), -Vec3A::Z)).expect("the floor");
            let x = Receiver::new(si, sh.bsdf(&si).expect("a BSDF"), Vec3A::new(0.0, -1.0, 1.0).normalize());
            f(&vpls, &tree, &x)
        })
    }

    #[test]
    fn the_density_sums_to_one_and_draws_follow_it() {
        with_lobe(|vpls, tree, x| {
            let lobe = tree.at(vpls, x, &[]).expect("a 24° lobe is in G's range");
            let sum: f64 = (0..vpls.len()).map(|j| lobe.pdf(j) as f64).sum();
            assert!((sum - 1.0).abs() < 1e-4, "{sum}");
            let mut hits = vec![0u32; vpls.len()];
            let n = 100_000u64;
            let mut rng = Rng::new(5);
            for _ in 0..n / 4 {
                let us: [u64; 4] = std::array::from_fn(|_| rng.next_u64());
                let drawn = tree.at(vpls, x, &us).unwrap();
                (0..4).for_each(|d| hits[drawn.pick(d)] += 1);
            }
            for (j, &h) in hits.iter().enumerate() {
                let p = lobe.pdf(j) as f64;
                assert!(h == 0 || p > 0.0, "VPL {j} drawn without density");
                let sd = (p * (1.0 - p) / n as f64).sqrt();
                assert!((h as f64 / n as f64 - p).abs() <= 5.0 * sd + 1e-9, "VPL {j}: {h} draws, pdf {p}");
            }
        });
    }

    #[test]
    fn exactly_the_vpls_in_the_lobes_cone_are_drawable_and_near_ones_are_favoured() {
        with_lobe(|vpls, tree, x| {
            let lobe = tree.at(vpls, x, &[]).unwrap();
            let cone = crate::application::importance::split::sharp_cone(&x.bsdf, x.wo, 45f32.to_radians()).unwrap();
            // Seen along (0, −1, 1)/√2 the mirror direction is (0, 1, 1)/√2: toward the lamp's +y half.
            assert!(cone.axis.y > 0.6 && cone.axis.z > 0.6, "{:?}", cone.axis);
            let mut inside = Vec::new();
            for (j, v) in vpls.list.iter().enumerate() {
                let w = (v.p - x.si.p).normalize();
                let drawable = lobe.pdf(j) > 0.0;
                assert_eq!(drawable, cone.contains(w) && vpls.flux[j] > 0.0 && v.ns.dot(w).abs() > 0.0, "VPL {j}");
                if drawable {
                    inside.push(j);
                }
            }
            assert!(!inside.is_empty() && inside.len() < vpls.len() / 4, "{} of {}", inside.len(), vpls.len());
            // Per unit flux, the nearer half of the cone's VPLs has the larger mean density.
            let dist = |j: usize| (vpls.list[j].p - x.si.p).length();
            inside.sort_by(|&a, &b| dist(a).total_cmp(&dist(b)));
            let mean = |s: &[usize]| s.iter().map(|&j| lobe.pdf(j) / vpls.flux[j]).sum::<f32>() / s.len() as f32;
            let (near, far) = inside.split_at(inside.len() / 2);
            assert!(mean(near) > mean(far), "near {} far {}", mean(near), mean(far));
        });
    }

    #[test]
    fn lobes_outside_its_range_of_widths_leave_g_inactive() {
        with_lobe(|vpls, _, x| {
            assert!(
                LobeTree::new(vpls, 10f32.to_radians(), 20f32.to_radians()).at(vpls, x, &[]).is_none(),
                "24° > 20°"
            );
            assert!(
                LobeTree::new(vpls, 30f32.to_radians(), 45f32.to_radians()).at(vpls, x, &[]).is_none(),
                "24° < 30°"
            );
            assert!(LobeTree::new(vpls, 0.0, 0.0).at(vpls, x, &[]).is_none(), "off");
        });
    }
}
