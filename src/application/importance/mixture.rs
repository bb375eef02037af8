//! STAGE 5 (application, importance caching): how a shading point draws VPLs from its caches
//! (ALGORITHMS.md §6.3, "bilateral MIS") — the four techniques F (full, with visibility), U (unoccluded),
//! B (bounded over the cache's region) and C (conservative: uniform over all VPLs), each of F, U and B the
//! mixture of its distribution over the selected caches whose distribution is not all zero, n_t draws of
//! technique t (one each by default), combined by the balance heuristic over the draw counts (Veach's multi-sample MIS: a
//! draw of VPL j counts I_j / Σ_t n_t·p_t(j)) or Georgiev's α-max heuristic (α = 1: the technique with the
//! largest n_t·p_t(j) takes the draw, weighted 1 / (n_t·p_t(j))).
//!
//! The mixture over the caches is uniform (ALGORITHMS.md §6.3) or, by default, weighted: each cache by a
//! weight the caller gives, the interpolation weight 1/Dist of Eq. 5 to the power `mixweight`
//! (experiments/notes/importance-tried.md, "The caches mixed by their weights"). A draw then chooses cache k
//! with probability w_k / Σw and the technique's density is Σ_k w_k p_k(j) / Σw, so the estimator stays
//! unbiased; a cache across a shadow's edge from the shading point, three cache spacings away, no longer has
//! the say of the one at the point.
//!
//! A fifth technique, G ([`super::lobe`]), joins the combination at shading points whose glossy lobe is in
//! its range: it draws among the VPLs in the lobe's cone, by flux times the lobe's falloff over clamped
//! squared distance.
//!
//! A technique none of the selected caches can draw from (every one of its distributions is 0), or G where
//! the shading point has no lobe for it, draws no sample and has density 0 in the combination
//! (multi-sample MIS with n_t = 0). C is never empty, so every VPL that contributes has a positive density
//! in the combination and the estimator is unbiased.
//!
//! Depends on the record's distributions and the shading point's lobe only.

use super::distribution::Quantised;
use super::lobe::Lobe;
use crate::sampling::Rng;

/// The techniques, in the order the combination and the parameter's letters use.
pub const LETTERS: [char; TECHNIQUES] = ['f', 'u', 'b', 'c', 'g'];

/// How many techniques there are.
pub const TECHNIQUES: usize = 5;

/// The conservative technique's index.
pub const CONSERVATIVE: usize = 3;

/// The lobe technique's index.
pub const LOBE: usize = 4;

/// How the techniques' samples are combined.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mis {
    /// Balance heuristic: a sample of VPL j counts I_j / Σ_t n_t·p_t(j).
    Balance,
    /// α-max with α = 1: a sample counts I_j / (n_t·p_t(j)) when its technique t has the largest n_t·p_t(j)
    /// (the earliest of equals), else 0.
    AlphaMax,
}

/// How a technique's draw chooses among the selected caches.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Blend {
    /// Each cache alike (ALGORITHMS.md §6.3): the caches' weights are ignored.
    Uniform,
    /// Each cache in proportion to its weight.
    Weighted,
}

/// A cache's weight in a mixture blended by `blend`, `w` the weight its caller gave it.
#[inline]
fn blended(blend: Blend, w: f32) -> f32 {
    if blend == Blend::Weighted { w } else { 1.0 }
}

/// The stored distributions (F, U, B) of the selected caches, and the shading point's lobe, as the shading
/// point sees them.
pub struct Mixture<'l, I> {
    /// The caches' distributions, each with its weight in the mixture.
    caches: I,
    /// Selected caches whose distribution of each stored technique is not all zero (and whose weight is
    /// not 0).
    counts: [u32; 3],
    /// The sum of those caches' weights (their count when the blend is uniform).
    sums: [f32; 3],
    blend: Blend,
    draws: [u32; TECHNIQUES],
    vpls: usize,
    lobe: Option<Lobe<'l>>,
}

impl<'a, 'l, I> Mixture<'l, I>
where
    I: Iterator<Item = (&'a [Option<Quantised>; 3], f32)> + Clone,
{
    /// The mixture over `caches` (their F, U, B distributions, each with its weight, finite and ≥ 0, read
    /// only when `blend` is [`Blend::Weighted`]; a cache of weight 0 takes no part) and the shading point's `lobe` of the techniques, technique
    /// t drawing `draws[t]` samples (0: not used), over `vpls` VPLs.
    pub fn new(caches: I, blend: Blend, draws: [u32; TECHNIQUES], vpls: usize, lobe: Option<Lobe<'l>>) -> Self {
        let mut counts = [0u32; 3];
        let mut sums = [0f32; 3];
        for (d, w) in caches.clone() {
            let w = blended(blend, w);
            for t in 0..3 {
                if d[t].is_some() && w > 0.0 {
                    counts[t] += 1;
                    sums[t] += w;
                }
            }
        }
        Mixture { caches, counts, sums, blend, draws, vpls, lobe }
    }

    /// Whether technique `t` draws samples.
    #[inline]
    pub fn active(&self, t: usize) -> bool {
        self.draws[t] > 0
            && self.vpls > 0
            && match t {
                CONSERVATIVE => true,
                LOBE => self.lobe.is_some(),
                _ => self.counts[t] > 0,
            }
    }

    /// How many samples technique `t` draws (0 when it is not active).
    #[inline]
    pub fn draws(&self, t: usize) -> u32 {
        if self.active(t) { self.draws[t] } else { 0 }
    }

    /// p_t(j): the probability that technique `t` draws VPL `j` (0 for an inactive technique).
    #[inline]
    pub fn pdf(&self, t: usize, j: usize) -> f32 {
        if !self.active(t) {
            return 0.0;
        }
        if t == CONSERVATIVE {
            return 1.0 / self.vpls as f32;
        }
        if let (LOBE, Some(lobe)) = (t, &self.lobe) {
            return lobe.pdf(j);
        }
        // With a uniform blend every weight is 1 and the sum is the count: the products are exact.
        let sum: f32 =
            self.caches.clone().filter_map(|(d, w)| Some(blended(self.blend, w) * d[t].as_ref()?.pdf(j))).sum();
        sum / self.sums[t]
    }

    /// Draw `d` of technique `t`: a cache chosen among those that can draw (with `rng`: uniformly, or by
    /// weight), then a VPL from its distribution at 64 uniform bits `u` (C: the VPL at `u` directly), or, when `u` is
    /// `None`, at bits drawn from `rng`; for G the VPL its draw `d` chose when the lobe was made (from the
    /// bits it was given); `None` for an inactive technique.
    #[inline]
    pub fn sample(&self, t: usize, d: u32, u: Option<u64>, rng: &mut Rng) -> Option<usize> {
        if !self.active(t) {
            return None;
        }
        if t == CONSERVATIVE {
            return Some(match u {
                Some(u) => ((u as u128 * self.vpls as u128) >> 64) as usize,
                None => rng.below(self.vpls as u32) as usize,
            });
        }
        if let (LOBE, Some(lobe)) = (t, &self.lobe) {
            return Some(lobe.pick(d));
        }
        let q = match self.blend {
            Blend::Uniform => {
                let k = rng.below(self.counts[t]) as usize;
                self.caches.clone().filter_map(|(d, _)| d[t].as_ref()).nth(k)?
            }
            Blend::Weighted => {
                // 24 bits of a uniform number, scaled to the sum; the last cache takes what rounding leaves.
                let mut target = (rng.next_u64() >> 40) as f32 * (1.0 / (1u32 << 24) as f32) * self.sums[t];
                let mut chosen = None;
                for (q, w) in self.caches.clone().filter_map(|(d, w)| Some((d[t].as_ref()?, w))) {
                    if w <= 0.0 {
                        continue;
                    }
                    chosen = Some(q);
                    if target < w {
                        break;
                    }
                    target -= w;
                }
                chosen?
            }
        };
        Some(q.sample(u.unwrap_or_else(|| rng.next_u64())))
    }

    /// What a sample of VPL `j` drawn by technique `t` is multiplied by (its contribution I_j times this
    /// is the sample's share of the estimate): the MIS weight over the density.
    #[inline]
    pub fn factor(&self, t: usize, j: usize, mis: Mis) -> f32 {
        let p: [f32; TECHNIQUES] = std::array::from_fn(|k| self.draws(k) as f32 * self.pdf(k, j));
        match mis {
            Mis::Balance => {
                let sum: f32 = p.iter().sum();
                if sum > 0.0 { 1.0 / sum } else { 0.0 }
            }
            Mis::AlphaMax => {
                // The winner: the first technique with the largest density.
                let best = (0..TECHNIQUES).fold(0, |b, k| if p[k] > p[b] { k } else { b });
                if best == t && p[t] > 0.0 { 1.0 / p[t] } else { 0.0 }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    type Cache = (&'static [Option<Quantised>; 3], f32);

    /// Three caches over 6 VPLs, weighted 1, 4 and 0.5: VPL 4 has zero F density at every cache (occluded at
    /// the caches), VPL 5 is zero in every stored distribution, and one cache's F is all zero.
    fn caches() -> &'static [Cache] {
        let q = |w: &[f32]| Quantised::new(w);
        let d: &'static [[Option<Quantised>; 3]] = Box::leak(
            vec![
                [
                    q(&[1.0, 2.0, 0.0, 4.0, 0.0, 0.0]),
                    q(&[1.0, 2.0, 3.0, 4.0, 5.0, 0.0]),
                    q(&[2.0, 2.0, 3.0, 4.0, 9.0, 0.0]),
                ],
                [None, q(&[0.0, 0.0, 3.0, 1.0, 1.0, 0.0]), q(&[1.0, 1.0, 3.0, 1.0, 1.0, 0.0])],
                [q(&[0.0, 5.0, 1.0, 0.0, 0.0, 0.0]), None, q(&[1.0; 6])],
            ]
            .into_boxed_slice(),
        );
        Box::leak(d.iter().zip([1.0, 4.0, 0.5]).collect::<Vec<_>>().into_boxed_slice())
    }

    const BLENDS: [Blend; 2] = [Blend::Uniform, Blend::Weighted];

    /// The exact expectation of the estimator for contributions `i`: Σ_t n_t Σ_j p_t(j)·factor_t(j)·I_j.
    fn expectation(m: &Mixture<'_, impl Iterator<Item = Cache> + Clone>, i: &[f32], mis: Mis) -> f32 {
        (0..TECHNIQUES)
            .map(|t| m.draws(t) as f32 * (0..i.len()).map(|j| m.pdf(t, j) * m.factor(t, j, mis) * i[j]).sum::<f32>())
            .sum()
    }

    #[test]
    fn every_combination_with_c_is_unbiased_for_vpls_no_stored_distribution_reaches() {
        let c = caches();
        let i = [0.5, 1.0, 2.0, 0.25, 3.0, 7.0];
        let exact: f32 = i.iter().sum();
        // Every technique drawing 0, 1 or 2 samples (3⁴ combinations), C at least once (G has no lobe here).
        for code in 0..81u32 {
            let draws: [u32; TECHNIQUES] =
                std::array::from_fn(|k| if k == LOBE { 1 } else { code / 3u32.pow(k as u32) % 3 });
            if draws[CONSERVATIVE] == 0 {
                continue;
            }
            for (mis, blend) in [Mis::Balance, Mis::AlphaMax].into_iter().flat_map(|m| BLENDS.map(|b| (m, b))) {
                let m = Mixture::new(c.iter().copied(), blend, draws, i.len(), None);
                let e = expectation(&m, &i, mis);
                assert!((e - exact).abs() < 1e-4 * exact, "{draws:?} {mis:?} {blend:?}: {e} vs {exact}");
            }
        }
    }

    #[test]
    fn without_c_a_vpl_no_distribution_reaches_is_lost() {
        for blend in BLENDS {
            let m = Mixture::new(caches().iter().copied(), blend, [1, 0, 0, 0, 0], 6, None);
            let i = [0.0, 0.0, 0.0, 0.0, 3.0, 0.0];
            assert_eq!(expectation(&m, &i, Mis::Balance), 0.0, "F alone never draws VPL 4");
            let pdf_sum: f32 = (0..6).map(|j| m.pdf(0, j)).sum();
            assert!((pdf_sum - 1.0).abs() < 1e-5);
        }
    }

    #[test]
    fn the_weighted_density_is_the_weighted_mean_of_the_caches() {
        let c = caches();
        let (uniform, weighted) = BLENDS.map(|b| Mixture::new(c.iter().copied(), b, [1; TECHNIQUES], 6, None)).into();
        // U: caches 0 (weight 1) and 1 (weight 4) have it.
        let (u0, u1) = (c[0].0[1].as_ref().unwrap(), c[1].0[1].as_ref().unwrap());
        for j in 0..6 {
            let by_weight = (u0.pdf(j) + 4.0 * u1.pdf(j)) / 5.0;
            assert!((weighted.pdf(1, j) - by_weight).abs() < 1e-6, "j {j}");
            assert!((uniform.pdf(1, j) - (u0.pdf(j) + u1.pdf(j)) / 2.0).abs() < 1e-6, "j {j}");
        }
        assert!(weighted.pdf(1, 0) < uniform.pdf(1, 0), "VPL 0 is only in the lighter cache's U");
    }

    #[test]
    fn draws_follow_the_mixture_density() {
        for blend in BLENDS {
            let m = Mixture::new(caches().iter().copied(), blend, [1; TECHNIQUES], 6, None);
            let mut rng = Rng::new(11);
            for t in 0..CONSERVATIVE + 1 {
                let n = 200_000;
                let mut hits = [0u32; 6];
                for _ in 0..n {
                    hits[m.sample(t, 0, None, &mut rng).unwrap()] += 1;
                }
                for (j, &h) in hits.iter().enumerate() {
                    let p = m.pdf(t, j) as f64;
                    let sd = (p * (1.0 - p) / n as f64).sqrt();
                    assert!((h as f64 / n as f64 - p).abs() <= 5.0 * sd + 1e-9, "{blend:?} t {t} j {j}");
                }
            }
        }
    }

    #[test]
    fn a_technique_no_cache_can_draw_from_is_inactive() {
        let only: &'static [[Option<Quantised>; 3]] =
            Box::leak(vec![[None, None, Quantised::new(&[1.0, 1.0])]].into_boxed_slice());
        for blend in BLENDS {
            let m = Mixture::new(only.iter().map(|d| (d, 2.0)), blend, [1; TECHNIQUES], 2, None);
            assert!(!m.active(0) && !m.active(1) && m.active(2) && m.active(3));
            assert_eq!(m.sample(0, 0, None, &mut Rng::new(1)), None);
            assert_eq!(m.pdf(1, 0), 0.0);
        }
    }

    #[test]
    fn a_cache_of_weight_zero_takes_no_part() {
        // Cache 0 weighs nothing (its weight underflowed); only it has an F: F draws nothing and no density is
        // NaN. U is cache 1's alone.
        let q = |w: &[f32]| Quantised::new(w);
        let d: &'static [[Option<Quantised>; 3]] =
            Box::leak(vec![[q(&[1.0, 0.0]), q(&[1.0, 0.0]), None], [None, q(&[0.0, 1.0]), None]].into_boxed_slice());
        let m = Mixture::new(d.iter().zip([0.0, 2.0]), Blend::Weighted, [1; TECHNIQUES], 2, None);
        assert!(!m.active(0) && m.active(1));
        assert_eq!((m.pdf(1, 0), m.pdf(1, 1)), (0.0, 1.0));
        let mut rng = Rng::new(5);
        assert!((0..1000).all(|_| m.sample(1, 0, None, &mut rng) == Some(1)));
        assert!((0..2).all(|j| (0..TECHNIQUES).all(|t| m.factor(t, j, Mis::Balance).is_finite())));
    }
}
