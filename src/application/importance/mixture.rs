//! STAGE 5 (application, importance caching): how a shading point draws VPLs from its caches
//! (ALGORITHMS.md §6.3, "bilateral MIS") — the four techniques F (full, with visibility), U (unoccluded),
//! B (bounded over the cache's region) and C (conservative: uniform over all VPLs), each the uniform mixture
//! of its distribution over the selected caches whose distribution is not all zero, n_t draws of technique t
//! (one each by default), combined by the balance heuristic over the draw counts (Veach's multi-sample MIS: a
//! draw of VPL j counts I_j / Σ_t n_t·p_t(j)) or Georgiev's α-max heuristic (α = 1: the technique with the
//! largest n_t·p_t(j) takes the draw, weighted 1 / (n_t·p_t(j))).
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

/// The stored distributions (F, U, B) of the selected caches, and the shading point's lobe, as the shading
/// point sees them.
pub struct Mixture<'l, I> {
    caches: I,
    /// Selected caches whose distribution of each stored technique is not all zero.
    counts: [u32; 3],
    draws: [u32; TECHNIQUES],
    vpls: usize,
    lobe: Option<Lobe<'l>>,
}

impl<'a, 'l, I> Mixture<'l, I>
where
    I: Iterator<Item = &'a [Option<Quantised>; 3]> + Clone,
{
    /// The mixture over `caches` (their F, U, B distributions) and the shading point's `lobe` of the
    /// techniques, technique t drawing `draws[t]` samples (0: not used), over `vpls` VPLs.
    pub fn new(caches: I, draws: [u32; TECHNIQUES], vpls: usize, lobe: Option<Lobe<'l>>) -> Self {
        let mut counts = [0u32; 3];
        for d in caches.clone() {
            for (t, c) in counts.iter_mut().enumerate() {
                *c += d[t].is_some() as u32;
            }
        }
        Mixture { caches, counts, draws, vpls, lobe }
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
        let sum: f32 = self.caches.clone().filter_map(|d| d[t].as_ref()).map(|q| q.pdf(j)).sum();
        sum / self.counts[t] as f32
    }

    /// Draw `d` of technique `t`: a cache chosen uniformly among those that can draw (with `rng`), then a
    /// VPL from its distribution at 64 uniform bits `u` (C: the VPL at `u` directly), or, when `u` is
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
        let k = rng.below(self.counts[t]) as usize;
        let q = self.caches.clone().filter_map(|d| d[t].as_ref()).nth(k)?;
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

    fn caches() -> Vec<[Option<Quantised>; 3]> {
        // Three caches over 6 VPLs: VPL 4 has zero F density at every cache (occluded at the caches), VPL 5
        // is zero in every stored distribution, and one cache's F is all zero.
        let q = |w: &[f32]| Quantised::new(w);
        vec![
            [
                q(&[1.0, 2.0, 0.0, 4.0, 0.0, 0.0]),
                q(&[1.0, 2.0, 3.0, 4.0, 5.0, 0.0]),
                q(&[2.0, 2.0, 3.0, 4.0, 9.0, 0.0]),
            ],
            [None, q(&[0.0, 0.0, 3.0, 1.0, 1.0, 0.0]), q(&[1.0, 1.0, 3.0, 1.0, 1.0, 0.0])],
            [q(&[0.0, 5.0, 1.0, 0.0, 0.0, 0.0]), None, q(&[1.0; 6])],
        ]
    }

    /// The exact expectation of the estimator for contributions `i`: Σ_t n_t Σ_j p_t(j)·factor_t(j)·I_j.
    fn expectation(
        m: &Mixture<'_, impl Iterator<Item = &'static [Option<Quantised>; 3]> + Clone>,
        i: &[f32],
        mis: Mis,
    ) -> f32 {
        (0..TECHNIQUES)
            .map(|t| m.draws(t) as f32 * (0..i.len()).map(|j| m.pdf(t, j) * m.factor(t, j, mis) * i[j]).sum::<f32>())
            .sum()
    }

    #[test]
    fn every_combination_with_c_is_unbiased_for_vpls_no_stored_distribution_reaches() {
        let c: &'static [[Option<Quantised>; 3]] = Box::leak(caches().into_boxed_slice());
        let i = [0.5, 1.0, 2.0, 0.25, 3.0, 7.0];
        let exact: f32 = i.iter().sum();
        // Every technique drawing 0, 1 or 2 samples (3⁴ combinations), C at least once (G has no lobe here).
        for code in 0..81u32 {
            let draws: [u32; TECHNIQUES] =
                std::array::from_fn(|k| if k == LOBE { 1 } else { code / 3u32.pow(k as u32) % 3 });
            if draws[CONSERVATIVE] == 0 {
                continue;
            }
            for mis in [Mis::Balance, Mis::AlphaMax] {
                let m = Mixture::new(c.iter(), draws, i.len(), None);
                let e = expectation(&m, &i, mis);
                assert!((e - exact).abs() < 1e-4 * exact, "{draws:?} {mis:?}: {e} vs {exact}");
            }
        }
    }

    #[test]
    fn without_c_a_vpl_no_distribution_reaches_is_lost() {
        let c: &'static [[Option<Quantised>; 3]] = Box::leak(caches().into_boxed_slice());
        let m = Mixture::new(c.iter(), [1, 0, 0, 0, 0], 6, None);
        let i = [0.0, 0.0, 0.0, 0.0, 3.0, 0.0];
        assert_eq!(expectation(&m, &i, Mis::Balance), 0.0, "F alone never draws VPL 4");
        let pdf_sum: f32 = (0..6).map(|j| m.pdf(0, j)).sum();
        assert!((pdf_sum - 1.0).abs() < 1e-5);
    }

    #[test]
    fn draws_follow_the_mixture_density() {
        let c: &'static [[Option<Quantised>; 3]] = Box::leak(caches().into_boxed_slice());
        let m = Mixture::new(c.iter(), [1; TECHNIQUES], 6, None);
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
                assert!((h as f64 / n as f64 - p).abs() <= 5.0 * sd + 1e-9, "t {t} j {j}");
            }
        }
    }

    #[test]
    fn a_technique_no_cache_can_draw_from_is_inactive() {
        let only: &'static [[Option<Quantised>; 3]] =
            Box::leak(vec![[None, None, Quantised::new(&[1.0, 1.0])]].into_boxed_slice());
        let m = Mixture::new(only.iter(), [1; TECHNIQUES], 2, None);
        assert!(!m.active(0) && !m.active(1) && m.active(2) && m.active(3));
        assert_eq!(m.sample(0, 0, None, &mut Rng::new(1)), None);
        assert_eq!(m.pdf(1, 0), 0.0);
    }
}
