//! STAGE 5 (application, importance caching): the lobe technique G — at a shading point whose glossy
//! reflection lobe is wider than the split's cones but no wider than `lobecone`, one more VPL is drawn in
//! proportion to flux among the VPL clusters the lobe's cone meets.
//!
//! Why: a glossy receiver (roughness 0.05–0.2: the bathroom's window frame, sill, cabinet and metal plate)
//! multiplies the light of the VPLs its lobe points at by several times its diffuse value, but its caches —
//! on another facet, or a little way off where the lobe meets other VPLs, or behind the blinds' slats from
//! them — may give those VPLs almost no density. Then only the conservative technique draws them, and a
//! draw is worth thousands of times its light: the bathroom's remaining fireflies (a window-frame sample at
//! 234 with weight 4453, drawn by C; a metal-plate sample at 504 with weight 1375). The split sums the VPLs
//! of lobes up to `splitcone` exactly, but a 20–30° lobe's cone holds hundreds of VPLs, too many to
//! evaluate at every sample. G gives them a density of about one over their number instead, from the
//! shading point's own lobe, at the price of a walk over the clusters and one shadow ray.
//!
//! What: the positional VPLs, in their (Morton) order, are cut into at most [`CLUSTERS`] runs of
//! consecutive VPLs, each with a bounding sphere. At a shading point s with such a lobe, the cone K(s) is
//! the one [`sharp_cone`] gives; the clusters whose sphere meets K(s) are accepted, and
//! p_G(j) = Φ_j / Σ_{k in accepted clusters} Φ_k for a VPL j of an accepted cluster (Φ: the luminance of
//! its flux), 0 for any other. The accepted set depends on s alone, so p_G is a density that the MIS
//! combination can evaluate for every other technique's draw, and the estimate stays unbiased (C still
//! reaches every VPL). Directional VPLs are never drawn by G.
//!
//! Depends on the VPLs and the shading layer's lobes; never on placement or the caches.

use glam::Vec3A;

use super::sharp::{Cone, sharp_cone};
use super::vpl::{Emitter, Receiver, Vpls};

/// Most clusters (the accepted ones are kept in fixed arrays on the stack).
pub const CLUSTERS: usize = 128;

/// The VPL clusters G draws from.
#[derive(Clone, Debug, Default)]
pub struct Clusters {
    /// Lobes wider than this (radians) and no wider than `max_angle` make G active.
    min_angle: f32,
    max_angle: f32,
    /// Cluster c holds VPLs `start[c]..start[c + 1]`.
    start: Vec<u32>,
    /// Each cluster's bounding sphere.
    spheres: Vec<(Vec3A, f32)>,
    /// Running sum of the flux over the positional VPLs (`prefix[j]`: VPLs before j).
    prefix: Vec<f64>,
    /// Each positional VPL's cluster.
    cluster_of: Vec<u8>,
}

impl Clusters {
    /// The clusters of `vpls` for lobes wider than `min_angle` and up to `max_angle` radians (`max_angle`
    /// ≤ `min_angle`: G is never active).
    pub fn new(vpls: &Vpls, min_angle: f32, max_angle: f32) -> Clusters {
        let positional = vpls.list.iter().take_while(|v| !matches!(v.emitter, Emitter::Directional)).count();
        if positional == 0 || max_angle.is_nan() || max_angle <= min_angle.max(0.0) {
            return Clusters::default();
        }
        let size = positional.div_ceil(CLUSTERS);
        let mut start: Vec<u32> = (0..positional).step_by(size).map(|j| j as u32).collect();
        start.push(positional as u32);
        let spheres = start
            .windows(2)
            .map(|w| {
                let members = &vpls.list[w[0] as usize..w[1] as usize];
                let (mut lo, mut hi) = (Vec3A::splat(f32::INFINITY), Vec3A::splat(f32::NEG_INFINITY));
                for v in members {
                    (lo, hi) = (lo.min(v.p), hi.max(v.p));
                }
                let center = 0.5 * (lo + hi);
                let radius = members.iter().map(|v| (v.p - center).length()).fold(0.0f32, f32::max);
                (center, radius)
            })
            .collect();
        let mut prefix = Vec::with_capacity(positional + 1);
        let mut acc = 0.0f64;
        prefix.push(0.0);
        for &f in &vpls.flux[..positional] {
            acc += if f.is_finite() && f > 0.0 { f as f64 } else { 0.0 };
            prefix.push(acc);
        }
        let cluster_of = (0..positional).map(|j| (j / size) as u8).collect();
        Clusters { min_angle: min_angle.max(0.0), max_angle, start, spheres, prefix, cluster_of }
    }

    /// G at receiver `x`: `None` when its lobe is not in G's range of widths or its cone meets no flux.
    #[inline]
    pub fn at(&self, x: &Receiver) -> Option<Lobe<'_>> {
        if self.spheres.is_empty() {
            return None;
        }
        let cone = sharp_cone(&x.bsdf, x.wo, self.max_angle).filter(|c| c.angle > self.min_angle)?;
        let mut lobe =
            Lobe { clusters: self, accepted: [0; CLUSTERS / 64], ids: [0; CLUSTERS], cum: [0.0; CLUSTERS], n: 0 };
        let mut total = 0.0f64;
        for (c, &(center, radius)) in self.spheres.iter().enumerate() {
            if meets(&cone, x.si.p, center, radius) {
                let flux = self.prefix[self.start[c + 1] as usize] - self.prefix[self.start[c] as usize];
                if flux > 0.0 {
                    total += flux;
                    lobe.accepted[c / 64] |= 1 << (c % 64);
                    lobe.ids[lobe.n] = c as u8;
                    lobe.cum[lobe.n] = total;
                    lobe.n += 1;
                }
            }
        }
        (lobe.n > 0 && total.is_finite()).then_some(lobe)
    }
}

/// Whether a sphere may hold a point whose direction from `apex` lies in `cone`: the angle between the axis
/// and the sphere's centre is at most the cone's half-angle plus the angle the sphere subtends (no
/// trigonometric calls: compared as cosines).
#[inline]
fn meets(cone: &Cone, apex: Vec3A, center: Vec3A, radius: f32) -> bool {
    let v = center - apex;
    let d = v.length();
    if d <= radius {
        return true;
    }
    let cos_to = v.dot(cone.axis) / d;
    let sin_s = radius / d;
    let cos_s = (1.0 - sin_s * sin_s).max(0.0).sqrt();
    let sin_c = (1.0 - cone.cos * cone.cos).max(0.0).sqrt();
    // cos(angle + spread): both are at most π/2 (`lobecone` ≤ 90°), so their sum is at most π, where the
    // cosine still falls monotonically.
    let cos_sum = cone.cos * cos_s - sin_c * sin_s;
    cos_to >= cos_sum
}

/// G at one shading point: the accepted clusters and their running flux.
#[derive(Clone, Copy, Debug)]
pub struct Lobe<'a> {
    clusters: &'a Clusters,
    /// Bit c: cluster c is accepted.
    accepted: [u64; CLUSTERS / 64],
    /// The accepted clusters in order, and the running sum of their flux.
    ids: [u8; CLUSTERS],
    cum: [f64; CLUSTERS],
    n: usize,
}

impl Lobe<'_> {
    /// Σ Φ over the accepted clusters.
    #[inline]
    fn total(&self) -> f64 {
        self.cum[self.n - 1]
    }

    /// p_G(j).
    #[inline]
    pub fn pdf(&self, j: usize) -> f32 {
        let cl = self.clusters;
        match cl.cluster_of.get(j) {
            Some(&c) if self.accepted[c as usize / 64] >> (c % 64) & 1 == 1 => {
                ((cl.prefix[j + 1] - cl.prefix[j]) / self.total()) as f32
            }
            _ => 0.0,
        }
    }

    /// The VPL at 64 uniform bits `u` of the accepted clusters' flux.
    #[inline]
    pub fn sample(&self, u: u64) -> usize {
        let cl = self.clusters;
        let target = (u >> 11) as f64 * (1.0 / (1u64 << 53) as f64) * self.total();
        let k = self.cum[..self.n].partition_point(|&c| c <= target).min(self.n - 1);
        let c = self.ids[k] as usize;
        let (lo, hi) = (cl.start[c] as usize, cl.start[c + 1] as usize);
        // The target within the cluster, then the VPL whose interval of the running sum holds it (a VPL
        // without flux has an empty interval and is never chosen).
        let local = (target - if k == 0 { 0.0 } else { self.cum[k - 1] }) + cl.prefix[lo];
        let j = lo + cl.prefix[lo + 1..=hi].partition_point(|&p| p <= local);
        let j = j.min(hi - 1);
        // Rounding can land on a VPL without flux at the cluster's end: the last one with flux instead.
        if cl.prefix[j + 1] > cl.prefix[j] {
            j
        } else {
            (lo..hi).rev().find(|&i| cl.prefix[i + 1] > cl.prefix[i]).unwrap_or(j)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::application::importance::vpl::with_lit_scene;
    use crate::render::lighting::Shading;
    use crate::sampling::Rng;
    use crate::scene::Scene;
    use crate::scene::ray::Ray;
    use crate::shading::light::LightSelect;

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

    fn with_lobe<T>(f: impl FnOnce(&Vpls, &Clusters, &Receiver) -> T) -> T {
        with_lit_scene(SCENE, |scene: &Scene, sh: &Shading<'_>, select: &LightSelect| {
            let mut rng = Rng::new(3);
            let vpls = Vpls::generate(scene, sh, select, 2000, 1, 0.01, &mut rng);
            let clusters = Clusters::new(&vpls, 10f32.to_radians(), 45f32.to_radians());
            let si = scene.geometry.intersect(&Ray::new(Vec3A::new(0.0, 0.0, 1.0), -Vec3A::Z)).expect("the floor");
            let x = Receiver::new(si, sh.bsdf(&si).expect("a BSDF"), Vec3A::new(0.0, -1.0, 1.0).normalize());
            f(&vpls, &clusters, &x)
        })
    }

    #[test]
    fn the_density_sums_to_one_and_draws_follow_it() {
        with_lobe(|vpls, clusters, x| {
            let lobe = clusters.at(x).expect("a 24° lobe is in G's range");
            let sum: f64 = (0..vpls.len()).map(|j| lobe.pdf(j) as f64).sum();
            assert!((sum - 1.0).abs() < 1e-4, "{sum}");
            let members = (0..vpls.len()).filter(|&j| lobe.pdf(j) > 0.0).count();
            assert!(members > 0 && members < vpls.len(), "the cone takes part of the lamp: {members}");
            let mut hits = vec![0u32; vpls.len()];
            let n = 200_000u64;
            let mut rng = Rng::new(5);
            for _ in 0..n {
                hits[lobe.sample(rng.next_u64())] += 1;
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
    fn every_vpl_in_the_lobes_cone_is_drawable_and_the_cone_leaves_most_of_the_lamp_out() {
        with_lobe(|vpls, clusters, x| {
            let lobe = clusters.at(x).unwrap();
            let cone = sharp_cone(&x.bsdf, x.wo, 45f32.to_radians()).unwrap();
            // Seen along (0, −1, 1)/√2 the mirror direction is (0, 1, 1)/√2: toward the lamp's +y half.
            assert!(cone.axis.y > 0.6 && cone.axis.z > 0.6, "{:?}", cone.axis);
            let (mut inside, mut drawable) = (0, 0);
            for (j, v) in vpls.list.iter().enumerate() {
                let w = (v.p - x.si.p).normalize();
                drawable += (lobe.pdf(j) > 0.0) as usize;
                if cone.contains(w) && vpls.flux[j] > 0.0 {
                    inside += 1;
                    assert!(lobe.pdf(j) > 0.0, "VPL {j} lies in the cone but G cannot draw it");
                }
            }
            assert!(inside > 0, "the cone holds some of the lamp");
            assert!(drawable < vpls.len() / 2, "G draws from {drawable} of {} VPLs", vpls.len());
        });
    }

    #[test]
    fn lobes_outside_its_range_of_widths_leave_g_inactive() {
        with_lobe(|vpls, _, x| {
            assert!(Clusters::new(vpls, 10f32.to_radians(), 20f32.to_radians()).at(x).is_none(), "24° > 20°");
            assert!(Clusters::new(vpls, 30f32.to_radians(), 45f32.to_radians()).at(x).is_none(), "24° < 30°");
            assert!(Clusters::new(vpls, 0.0, 0.0).at(x).is_none(), "off");
        });
    }
}
