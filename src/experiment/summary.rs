//! Statistics over the seeds of one setting, and the groupings of a sweep's records that the tables, charts
//! and report share (which budget is "the paper's", which runs vary a parameter).
//!
//! Depends only on the records of `jobs`; it reads no file.

use std::collections::BTreeMap;

use super::jobs::Record;

/// Mean, sample standard deviation, extremes and median of some values.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Summary {
    /// How many values.
    pub n: usize,
    /// Their mean.
    pub mean: f64,
    /// Their sample standard deviation (0 for one value).
    pub sd: f64,
    /// The smallest.
    pub min: f64,
    /// The largest.
    pub max: f64,
    /// The median (the mean of the middle two for an even count).
    pub median: f64,
}

impl Summary {
    /// The summary of `values` without NaNs; `None` when none is left.
    pub fn of(values: impl IntoIterator<Item = f64>) -> Option<Summary> {
        let mut v: Vec<f64> = values.into_iter().filter(|x| !x.is_nan()).collect();
        if v.is_empty() {
            return None;
        }
        v.sort_by(f64::total_cmp);
        let n = v.len();
        let mean = v.iter().sum::<f64>() / n as f64;
        let sd = if n > 1 { (v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1) as f64).sqrt() } else { 0.0 };
        let median = if n % 2 == 1 { v[n / 2] } else { 0.5 * (v[n / 2 - 1] + v[n / 2]) };
        Some(Summary { n, mean, sd, min: v[0], max: v[n - 1], median })
    }

    /// The standard error of the mean.
    pub fn se(&self) -> f64 {
        self.sd / (self.n as f64).sqrt()
    }

    /// Whether this mean is below `other`'s by more than two standard errors of the difference — the
    /// criterion by which the results call one method better than another (with 3 seeds, a rough one).
    pub fn clearly_below(&self, other: &Summary) -> bool {
        let se = (self.se().powi(2) + other.se().powi(2)).sqrt();
        other.mean - self.mean > 2.0 * se
    }
}

/// The records that measured something.
pub fn ok(records: &[Record]) -> impl Iterator<Item = &Record> {
    records.iter().filter(|r| r.status == "ok")
}

/// Whether a record is a cache run (not a per-pixel run, a baseline or the converged image, whose
/// placement is `none`).
pub fn is_cache_run(r: &Record) -> bool {
    r.placement != crate::integrator::cache::Placement::REFERENCE
}

/// (scene, application) pairs in order.
pub fn pairs(records: &[Record]) -> Vec<(String, String)> {
    let mut keys: Vec<(String, String)> = ok(records).map(|r| (r.scene.clone(), r.application.clone())).collect();
    keys.sort();
    keys.dedup();
    keys
}

/// The budgets of the plain cache runs (no varied parameter) of `scene` and `app`, ascending.
pub fn budgets(records: &[Record], scene: &str, app: &str) -> Vec<usize> {
    let mut b: Vec<usize> = ok(records)
        .filter(|r| r.scene == scene && r.application == app && r.varied.is_empty() && is_cache_run(r))
        .map(|r| r.caches)
        .collect();
    b.sort();
    b.dedup();
    b
}

/// The middle one of [`budgets`] (the paper's density in a sweep over ½, 1 and 2 × it), if any.
pub fn middle_budget(records: &[Record], scene: &str, app: &str) -> Option<usize> {
    let b = budgets(records, scene, app);
    b.get(b.len() / 2).copied()
}

/// The runs of one setting, grouped: method → its records, for `scene`, `app` and budget `caches`, plain
/// cache runs only (no varied parameter, no per-pixel run).
pub fn methods_at<'a>(
    records: &'a [Record],
    scene: &str,
    app: &str,
    caches: usize,
) -> BTreeMap<String, Vec<&'a Record>> {
    let mut m: BTreeMap<String, Vec<&Record>> = BTreeMap::new();
    for r in ok(records).filter(|r| {
        r.scene == scene && r.application == app && r.caches == caches && r.varied.is_empty() && is_cache_run(r)
    }) {
        m.entry(r.placement.clone()).or_default().push(r);
    }
    m
}

/// A record's total seconds.
pub fn total(r: &Record) -> f64 {
    r.times.get("total").copied().unwrap_or(f64::NAN)
}

/// RMSE and HDR-FLIP summaries of some runs.
pub fn errors(rs: &[&Record]) -> Option<(Summary, Summary)> {
    Some((Summary::of(rs.iter().map(|r| r.rmse))?, Summary::of(rs.iter().map(|r| r.flip))?))
}

/// The one varied parameter of a record, as (key, value), when exactly one is varied.
pub fn varied_one(r: &Record) -> Option<(&str, &str)> {
    if r.varied.contains(';') {
        return None;
    }
    r.varied.split_once('=')
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn summaries_and_the_two_standard_error_rule() {
        let s = Summary::of([3.0, 1.0, 2.0, f64::NAN]).unwrap();
        assert_eq!((s.n, s.mean, s.sd, s.min, s.max, s.median), (3, 2.0, 1.0, 1.0, 3.0, 2.0));
        assert_eq!(Summary::of([4.0, 1.0]).unwrap().median, 2.5);
        assert!(Summary::of([f64::NAN]).is_none());
        let a = Summary::of([1.0, 1.1, 0.9]).unwrap();
        let b = Summary::of([2.0, 2.1, 1.9]).unwrap();
        let c = Summary::of([1.05, 1.2, 0.95]).unwrap();
        assert!(a.clearly_below(&b) && !b.clearly_below(&a) && !a.clearly_below(&c));
    }
}
