//! STAGE 4's question to importance caching (beyond the paper; experiments/notes/refine.md): how well the
//! distributions of a cache's neighbours would sample the light at the cache's own site — the leave-one-out
//! prediction refine's error estimate asks of every application ([`super::Application::predict`]).
//!
//! The estimator is unbiased wherever the conservative technique C draws, so the neighbours do not miss the
//! cache's value: they sample it with more or less noise. At the site, the contribution of VPL j is taken to
//! be the cache's own F value f_j (the luminance of its contribution with visibility, split VPLs left out).
//! Its expectation drawing from the neighbours is Σ f_j over the VPLs some technique can draw ([`sampled`]: a
//! VPL no technique reaches, without C, is lost), and one sample's variance with independent draws, for the
//! balance heuristic with n_t draws of technique t (density p_t, the mixture over the neighbours'
//! distributions, uniform or weighted as shading mixes them: [`super::mixture`]), is
//!
//! Var = Σ_j f_j² / D_j − Σ_t n_t μ_t²,  D_j = Σ_t n_t p_t(j),  μ_t = Σ_j p_t(j) f_j / D_j
//!
//! (Veach's multi-sample MIS). Its sums over j are estimated from [`DRAWS`] VPLs drawn from the cache's own F
//! at stratified positions: F's density is f_j / Σf, so each sum is Σf times a mean over the draws, and the
//! cost does not grow with the VPL count. Shading stratifies a pixel's draws across its sub-pixel samples,
//! which lowers its variance far below one sample's over their count (2.6× in RMSE on sibenik at 320×180
//! with a cache at every pixel), so where it does, the pixel's variance is measured instead
//! ([`pixel_variance`]): the driver's own mixture, draws and MIS weights, run [`REPLICAS`] times with the
//! pixel's stratified positions, f_j in place of the traced contribution.
//!
//! What this leaves out: the B distributions, which are made only once placement is over, are stood in
//! for by U (B is U bounded over the cache's region); the lobe technique G, which draws at glossy shading
//! points only; in [`sampled`], the α-max heuristic, whose variance is taken to be the balance heuristic's;
//! and that a pixel's sub-pixel samples sit at different points.
//!
//! Depends on the record's distributions, the mixture and the sampling streams only.

use super::distribution::Quantised;
use super::mixture::{Blend, CONSERVATIVE, Mis, Mixture, TECHNIQUES};
use crate::sampling::{Rng, Stratum};

/// VPLs drawn from a cache's own F to estimate the sums over every VPL.
const DRAWS: u32 = 64;

/// Runs of a pixel's estimator behind [`pixel_variance`].
const REPLICAS: u64 = 8;

/// Stream tag of [`pixel_variance`]'s runs.
const STAGE_REPLICA: u64 = 0x6c6f_6f72;

/// What one sample of the estimator at a cache's site would give, drawing independently from its neighbours'
/// mixture.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Sampled {
    /// The cache's own light, Σ_j f_j (luminance).
    pub total: f32,
    /// The estimator's expectation: the total less the VPLs no technique can draw.
    pub expected: f32,
    /// The variance of one sample's estimate.
    pub variance: f32,
}

/// The estimator at the site of a cache whose F is `own`, drawing `draws[t]` samples of each technique t from
/// the mixtures (by `blend`, each neighbour with its weight) of `near`'s distributions (F, U, B; B stood in
/// for by U where it is not made yet) and C uniformly over `vpls` VPLs (module doc); G draws nothing here.
pub(super) fn sampled<'a>(
    own: &Quantised,
    blend: Blend,
    near: impl Iterator<Item = (&'a [Option<Quantised>; 3], f32)> + Clone,
    draws: [u32; TECHNIQUES],
    vpls: usize,
) -> Sampled {
    // Each stored technique's distributions among the neighbours (B: U where B is not made yet), with their
    // weights in the mixture.
    let weighted = blend == Blend::Weighted;
    let stored = |t: usize| {
        near.clone().filter_map(move |(d, w)| {
            let q = d[t].as_ref().or(if t == 2 { d[1].as_ref() } else { None })?;
            let w = if weighted { w as f64 } else { 1.0 };
            (w > 0.0).then_some((q, w))
        })
    };
    let counts: [usize; 3] = std::array::from_fn(|t| stored(t).count());
    let sums: [f64; 3] = std::array::from_fn(|t| stored(t).map(|(_, w)| w).sum());
    // n_t of the techniques that can draw: F, U and B where a neighbour has the distribution, C always.
    let n: [f64; 4] = std::array::from_fn(|t| {
        let can = if t == CONSERVATIVE { vpls > 0 } else { counts[t] > 0 };
        if can { draws[t] as f64 } else { 0.0 }
    });
    let total = own.value_sum() as f64;
    let (mut s, mut mu, mut lost) = (0f64, [0f64; 4], 0f64);
    for k in 0..DRAWS {
        // The middle of stratum k of DRAWS, as 64 bits.
        let u = (((2 * k + 1) as u128) << 64) / (2 * DRAWS) as u128;
        let j = own.sample(u as u64);
        let p: [f64; 4] = std::array::from_fn(|t| match t {
            CONSERVATIVE => 1.0 / vpls.max(1) as f64,
            _ if counts[t] == 0 => 0.0,
            _ => stored(t).map(|(q, w)| w * q.pdf(j) as f64).sum::<f64>() / sums[t],
        });
        let d: f64 = (0..4).map(|t| n[t] * p[t]).sum();
        if d <= 0.0 {
            lost += 1.0;
            continue;
        }
        // Drawn with density f_j / total: f_j² / D_j over it is total · f_j / D_j, and so on.
        s += own.value(j) as f64 / d;
        for t in 0..4 {
            mu[t] += p[t] / d;
        }
    }
    let m = DRAWS as f64;
    let (s, lost) = (total * s / m, total * lost / m);
    let spread: f64 = (0..4).map(|t| n[t] * (total * mu[t] / m).powi(2)).sum();
    Sampled { total: total as f32, expected: (total - lost) as f32, variance: (s - spread).max(0.0) as f32 }
}

/// The variance of a pixel's value (the mean of its `samples` sub-pixel samples) at the site of a cache whose
/// F is `own`, each sample shading from the distributions `near` (F, U, B; B stood in for by U where it is
/// not made yet; each with its weight in the mixture by `blend`) with `draws[t]` draws of technique t,
/// stratified across the samples as shading stratifies them, combined by `mis`: the sample variance of
/// [`REPLICAS`] runs of the estimator (module doc), their random streams keyed by `key`.
#[allow(clippy::too_many_arguments)]
pub(super) fn pixel_variance(
    key: u64,
    own: &Quantised,
    blend: Blend,
    near: &[(&[Option<Quantised>; 3], f32)],
    draws: [u32; TECHNIQUES],
    vpls: usize,
    mis: Mis,
    samples: u32,
) -> f32 {
    // B where it is made, else U (cloned: the mixture reads the three distributions of a record together).
    let dists: Vec<[Option<Quantised>; 3]> =
        near.iter().map(|(d, _)| [d[0].clone(), d[1].clone(), d[2].clone().or_else(|| d[1].clone())]).collect();
    let mix = Mixture::new(dists.iter().zip(near.iter().map(|&(_, w)| w)), blend, draws, vpls, None);
    let samples = samples.max(1);
    let runs: Vec<f64> = (0..REPLICAS)
        .map(|r| {
            let mut rng = Rng::keyed(key, STAGE_REPLICA, r);
            let mut sum = 0f64;
            for i in 0..samples {
                let stratum = Stratum::new(key, STAGE_REPLICA ^ r, i, samples);
                for t in 0..TECHNIQUES {
                    let m = mix.draws(t);
                    for d in 0..m {
                        let Some(j) = mix.sample(t, d, Some(stratum.draw(t as u64, d, m)), &mut rng) else { continue };
                        sum += (own.value(j) * mix.factor(t, j, mis)) as f64;
                    }
                }
            }
            sum / samples as f64
        })
        .collect();
    let mean = runs.iter().sum::<f64>() / REPLICAS as f64;
    (runs.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (REPLICAS - 1) as f64) as f32
}

#[cfg(test)]
mod tests {
    use super::super::mixture::{Blend, Mis, Mixture};
    use super::*;
    use crate::sampling::Rng;

    fn q(w: &[f32]) -> Option<Quantised> {
        Quantised::new(w)
    }

    /// The brute-force answer: the estimator run many times (the driver's own mixture, draws and balance
    /// weights), its mean and variance.
    fn simulated(
        f: &[f32],
        near: &'static [[Option<Quantised>; 3]],
        weights: &[f32],
        blend: Blend,
        draws: [u32; TECHNIQUES],
        runs: usize,
    ) -> (f64, f64) {
        let m = Mixture::new(near.iter().zip(weights.iter().copied()), blend, draws, f.len(), None);
        let mut rng = Rng::new(7);
        let (mut sum, mut sum2) = (0f64, 0f64);
        for _ in 0..runs {
            let mut y = 0f64;
            for t in 0..TECHNIQUES {
                for d in 0..m.draws(t) {
                    let Some(j) = m.sample(t, d, None, &mut rng) else { continue };
                    y += (f[j] * m.factor(t, j, Mis::Balance)) as f64;
                }
            }
            sum += y;
            sum2 += y * y;
        }
        let mean = sum / runs as f64;
        (mean, sum2 / runs as f64 - mean * mean)
    }

    #[test]
    fn the_variance_is_the_simulated_estimators() {
        // 256 VPLs; the cache's light is on the first quarter, its neighbours' F sees half of it (an edge
        // of a shadow between them) and their U all of it.
        let n = 256;
        let f: Vec<f32> = (0..n).map(|j| if j < 64 { 1.0 + (j % 7) as f32 } else { 0.0 }).collect();
        let own = Quantised::new(&f).unwrap();
        let fq: Vec<f32> = (0..n).map(|j| own.value(j)).collect();
        let half: Vec<f32> = (0..n).map(|j| if j < 32 { fq[j] } else { 0.0 }).collect();
        let wide: Vec<f32> = (0..n).map(|j| if j < 128 { 1.0 } else { 0.0 }).collect();
        let near: &'static [[Option<Quantised>; 3]] =
            Box::leak(vec![[q(&half), q(&wide), None], [q(&fq), q(&wide), None]].into_boxed_slice());
        let draws = [2, 1, 0, 1, 0];
        // Uniform, and weighted toward the neighbour that sees the cache's light whole, and away from it.
        let mut variances = vec![];
        for (weights, blend) in
            [([1.0, 1.0], Blend::Uniform), ([1.0, 3.0], Blend::Weighted), ([3.0, 1.0], Blend::Weighted)]
        {
            let got = sampled(&own, blend, near.iter().zip(weights), draws, n);
            let (mean, var) = simulated(&fq, near, &weights, blend, draws, 400_000);
            assert!((got.expected as f64 - mean).abs() < 0.01 * mean, "{weights:?}: {got:?} vs mean {mean}");
            assert!((got.variance as f64 / var - 1.0).abs() < 0.08, "{weights:?}: {got:?} vs variance {var}");
            variances.push(got.variance);
        }
        assert!(variances[1] < variances[0] && variances[0] < variances[2], "{variances:?}");
        let got = sampled(&own, Blend::Uniform, near.iter().map(|d| (d, 1.0)), draws, n);
        // From its own F (and the same U) the variance is less than half the neighbours'.
        let alone: &'static [[Option<Quantised>; 3]] = Box::leak(vec![[q(&fq), q(&wide), None]].into_boxed_slice());
        let own_var = sampled(&own, Blend::Uniform, alone.iter().map(|d| (d, 1.0)), draws, n).variance;
        let (_, simulated_own) = simulated(&fq, alone, &[1.0], Blend::Uniform, draws, 400_000);
        assert!((own_var as f64 / simulated_own - 1.0).abs() < 0.08, "{own_var} vs {simulated_own}");
        assert!(own_var < 0.5 * got.variance, "{own_var} vs {}", got.variance);
    }

    #[test]
    fn the_pixel_variance_is_the_analytic_one_without_strata_and_lower_with_them() {
        let n = 256;
        let f: Vec<f32> = (0..n).map(|j| if j < 64 { 1.0 + (j % 7) as f32 } else { 0.0 }).collect();
        let own = Quantised::new(&f).unwrap();
        let half: Vec<f32> = (0..n).map(|j| if j < 32 { own.value(j) } else { 0.0 }).collect();
        let wide: Vec<f32> = (0..n).map(|j| if j < 128 { 1.0 } else { 0.0 }).collect();
        let near = [[q(&half), q(&wide), None], [q(&f), q(&wide), None]];
        let refs: Vec<(&[Option<Quantised>; 3], f32)> = near.iter().map(|d| (d, 1.0)).collect();
        // The mean over many keys of the runs' sample variance is the variance (it is unbiased).
        let mean_over_keys = |draws: [u32; TECHNIQUES], samples: u32| {
            (0..2000u64)
                .map(|k| pixel_variance(k, &own, Blend::Uniform, &refs, draws, n, Mis::Balance, samples) as f64)
                .sum::<f64>()
                / 2000.0
        };
        // One sample, one draw per technique (B stood in for by U): nothing to stratify.
        let one = [1, 1, 1, 1, 0];
        let analytic = sampled(&own, Blend::Uniform, refs.iter().copied(), one, n).variance as f64;
        let simulated = mean_over_keys(one, 1);
        assert!((simulated / analytic - 1.0).abs() < 0.1, "{simulated} vs {analytic}");
        // Four samples of eight draws each: the strata take much of the variance of independent draws.
        let eight = [8, 8, 8, 8, 0];
        let independent = sampled(&own, Blend::Uniform, refs.iter().copied(), eight, n).variance as f64 / 4.0;
        let stratified = mean_over_keys(eight, 4);
        assert!(stratified < 0.5 * independent, "{stratified} vs {independent}");
    }

    #[test]
    fn without_c_the_vpls_no_neighbour_draws_are_missed() {
        let f = [1.0, 1.0, 2.0, 0.0];
        let own = Quantised::new(&f).unwrap();
        let near: &'static [[Option<Quantised>; 3]] =
            Box::leak(vec![[q(&[1.0, 1.0, 0.0, 0.0]), None, None]].into_boxed_slice());
        let got = sampled(&own, Blend::Weighted, near.iter().map(|d| (d, 0.5)), [1, 0, 0, 0, 0], 4);
        assert!((got.total - 4.0).abs() < 0.05 && (got.expected - 2.0).abs() < 0.05, "{got:?}");
        let (mean, _) = simulated(&f, near, &[0.5], Blend::Weighted, [1, 0, 0, 0, 0], 10_000);
        assert!((mean - got.expected as f64).abs() < 0.05, "{mean}");
    }
}
