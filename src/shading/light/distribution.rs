//! STAGE 5 (shading): piecewise-constant 1D and 2D distributions (pbrt-v3's `Distribution1D` and
//! `Distribution2D`), used to pick a light by power and a direction from an environment map.
//!
//! Built once per scene; sampling and pdf lookups never allocate. Depends on nothing else in the crate.

/// A piecewise-constant density on [0, 1) with `n` equal steps of heights `func` (pbrt-v3 `Distribution1D`).
/// Negative or non-finite heights count as 0.
#[derive(Clone, Debug, PartialEq)]
pub struct Distribution1D {
    func: Vec<f32>,
    cdf: Vec<f32>,
    func_int: f32,
}

impl Distribution1D {
    /// The distribution of the step heights `f` (at least one).
    pub fn new(f: &[f32]) -> Self {
        let n = f.len().max(1);
        let func: Vec<f32> = if f.is_empty() {
            vec![0.0]
        } else {
            f.iter().map(|&x| if x.is_finite() { x.max(0.0) } else { 0.0 }).collect()
        };
        let mut cdf = vec![0.0f32; n + 1];
        // Accumulate in f64 so long rows keep their small entries.
        let mut acc = 0.0f64;
        let mut sums = vec![0.0f64; n + 1];
        for i in 0..n {
            acc += func[i] as f64 / n as f64;
            sums[i + 1] = acc;
        }
        let func_int = acc as f32;
        for i in 1..=n {
            cdf[i] = if acc > 0.0 { (sums[i] / acc) as f32 } else { i as f32 / n as f32 };
        }
        cdf[n] = 1.0;
        Distribution1D { func, cdf, func_int }
    }

    /// Number of steps.
    pub fn count(&self) -> usize {
        self.func.len()
    }

    /// ∫ f over [0, 1] (the mean step height).
    pub fn integral(&self) -> f32 {
        self.func_int
    }

    /// Height of step `i`.
    pub fn func(&self, i: usize) -> f32 {
        self.func[i]
    }

    /// The step whose cdf interval holds `u` (pbrt-v3 `FindInterval`: clamped to a valid step).
    #[inline]
    fn find(&self, u: f32) -> usize {
        // First index with cdf > u, minus one.
        let first = self.cdf.partition_point(|&c| c <= u);
        first.saturating_sub(1).min(self.func.len() - 1)
    }

    /// The step boundaries' cumulative probabilities: `count() + 1` values from 0 to 1.
    pub fn cdf(&self) -> &[f32] {
        &self.cdf
    }

    /// A point x in [0, 1) for `u` in [0, 1), its density and its step (pbrt-v3 `SampleContinuous`).
    #[inline]
    pub fn sample_continuous(&self, u: f32) -> (f32, f32, usize) {
        let o = self.find(u);
        let mut du = u - self.cdf[o];
        let w = self.cdf[o + 1] - self.cdf[o];
        if w > 0.0 {
            du /= w;
        }
        let pdf = if self.func_int > 0.0 { self.func[o] / self.func_int } else { 0.0 };
        let x = ((o as f32 + du) / self.count() as f32).min(1.0 - f32::EPSILON / 2.0);
        (x, pdf, o)
    }

    /// A step chosen with probability ∝ its height, and that probability (pbrt-v3 `SampleDiscrete`).
    #[inline]
    pub fn sample_discrete(&self, u: f32) -> (usize, f32) {
        let o = self.find(u);
        (o, self.discrete_pdf(o))
    }

    /// The probability [`Distribution1D::sample_discrete`] picks step `i` (uniform when all are 0).
    #[inline]
    pub fn discrete_pdf(&self, i: usize) -> f32 {
        if self.func_int > 0.0 {
            self.func[i] / (self.func_int * self.count() as f32)
        } else {
            self.cdf[i + 1] - self.cdf[i]
        }
    }
}

/// A piecewise-constant density on [0, 1)² from an `nu`×`nv` grid (row `v` holds `nu` values), sampled as
/// a marginal over rows then a conditional within the row (pbrt-v3 `Distribution2D`).
#[derive(Clone, Debug, PartialEq)]
pub struct Distribution2D {
    conditional: Vec<Distribution1D>,
    marginal: Distribution1D,
}

impl Distribution2D {
    /// The distribution of `f` (row-major, `nv` rows of `nu`).
    pub fn new(f: &[f32], nu: usize, nv: usize) -> Self {
        let (nu, nv) = (nu.max(1), nv.max(1));
        let conditional: Vec<Distribution1D> =
            (0..nv).map(|v| Distribution1D::new(f.get(v * nu..(v + 1) * nu).unwrap_or(&[]))).collect();
        let rows: Vec<f32> = conditional.iter().map(|c| c.integral()).collect();
        Distribution2D { conditional, marginal: Distribution1D::new(&rows) }
    }

    /// A point (u, v) for the sample `u`, with its density (0 when the whole grid is 0).
    #[inline]
    pub fn sample(&self, u: [f32; 2]) -> ([f32; 2], f32) {
        let (v, pdf1, row) = self.marginal.sample_continuous(u[1]);
        let (s, pdf0, _) = self.conditional[row].sample_continuous(u[0]);
        ([s, v], pdf0 * pdf1)
    }

    /// The density at point `p` of [0, 1)² (pbrt-v3 `Distribution2D::Pdf`).
    #[inline]
    pub fn pdf(&self, p: [f32; 2]) -> f32 {
        let nu = self.conditional[0].count();
        let nv = self.marginal.count();
        let iu = ((p[0] * nu as f32) as isize).clamp(0, nu as isize - 1) as usize;
        let iv = ((p[1] * nv as f32) as isize).clamp(0, nv as isize - 1) as usize;
        let total = self.marginal.integral();
        if total > 0.0 { self.conditional[iv].func(iu) / total } else { 0.0 }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn discrete_probabilities_follow_the_heights() {
        let d = Distribution1D::new(&[1.0, 0.0, 3.0]);
        assert!((d.discrete_pdf(0) - 0.25).abs() < 1e-6);
        assert_eq!(d.discrete_pdf(1), 0.0);
        assert!((d.discrete_pdf(2) - 0.75).abs() < 1e-6);
        // Inverting the cdf: u below 1/4 picks step 0, above picks step 2, never the empty one.
        assert_eq!(d.sample_discrete(0.1).0, 0);
        assert_eq!(d.sample_discrete(0.25).0, 2);
        assert_eq!(d.sample_discrete(0.999_999_9).0, 2);
        for i in 0..1000 {
            assert_ne!(d.sample_discrete(i as f32 / 1000.0).0, 1);
        }
    }

    #[test]
    fn all_zero_heights_become_uniform() {
        let d = Distribution1D::new(&[0.0, 0.0, 0.0, 0.0]);
        assert!((d.discrete_pdf(2) - 0.25).abs() < 1e-6);
        let (x, pdf, _) = d.sample_continuous(0.6);
        assert!((x - 0.6).abs() < 1e-6 && pdf == 0.0);
        let d = Distribution1D::new(&[f32::NAN, -1.0]);
        assert_eq!(d.integral(), 0.0);
    }

    #[test]
    fn continuous_samples_have_the_stated_density() {
        // Histogram of x against the step heights: each step gets func/Σfunc of the samples, and the
        // returned pdf equals func/∫f in that step.
        let f = [0.5, 2.0, 0.0, 1.5];
        let d = Distribution1D::new(&f);
        let n = 40_000;
        let mut hist = [0usize; 4];
        for i in 0..n {
            let (x, pdf, o) = d.sample_continuous((i as f32 + 0.5) / n as f32);
            let step = (x * 4.0) as usize;
            assert_eq!(step, o);
            assert!((pdf - f[o] / 1.0).abs() < 1e-5, "pdf {pdf} in step {o}");
            hist[step] += 1;
        }
        for k in 0..4 {
            assert!((hist[k] as f32 / n as f32 - f[k] / 4.0).abs() < 1e-3, "{hist:?}");
        }
    }

    #[test]
    fn the_2d_density_integrates_to_one_and_matches_its_samples() {
        let (nu, nv) = (5, 3);
        let f: Vec<f32> = (0..nu * nv).map(|i| ((i * 7) % 5) as f32 + 0.25 * (i % 2) as f32).collect();
        let d = Distribution2D::new(&f, nu, nv);
        // ∫ pdf over the unit square by the midpoint rule on a fine grid (exact for a step function).
        let m = 60;
        let mut int = 0.0f64;
        for j in 0..m {
            for i in 0..m {
                int += d.pdf([(i as f32 + 0.5) / m as f32, (j as f32 + 0.5) / m as f32]) as f64;
            }
        }
        assert!((int / (m * m) as f64 - 1.0).abs() < 1e-4, "{int}");
        // The pdf returned by sample equals pdf() at the sample, and the cell frequencies follow f/Σf.
        let total: f32 = f.iter().sum();
        let k = 200;
        let mut hist = vec![0usize; nu * nv];
        for j in 0..k {
            for i in 0..k {
                let u = [(i as f32 + 0.5) / k as f32, (j as f32 + 0.5) / k as f32];
                let (p, pdf) = d.sample(u);
                assert!((pdf - d.pdf(p)).abs() < 1e-4 * pdf.max(1.0), "{pdf} vs {}", d.pdf(p));
                hist[(p[1] * nv as f32) as usize * nu + (p[0] * nu as f32) as usize] += 1;
            }
        }
        for c in 0..nu * nv {
            let want = f[c] / total;
            assert!((hist[c] as f32 / (k * k) as f32 - want).abs() < 0.01, "cell {c}: {hist:?}");
        }
    }
}
