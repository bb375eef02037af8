//! The labels of the charts' axes: [`tick`] prints a value without float noise, and [`log_ticks`] chooses
//! the labelled values and grid lines of a logarithmic axis so that every decade the axis spans is labelled
//! (plotters' own log axis labels only the powers of ten inside the range, which left wall times under
//! 1 s and budgets under 1000 with no label at all). Pure functions; depends on nothing of the crate.

/// An axis label: `v` to six significant digits without trailing zeros (plotters' own labels print a log
/// axis' ticks in full, e.g. 0.30000000000000004).
pub fn tick(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    let decimals = (5 - v.abs().log10().floor() as i32).clamp(0, 15) as usize;
    let s = format!("{v:.decimals$}");
    if s.contains('.') { s.trim_end_matches('0').trim_end_matches('.').to_string() } else { s }
}

/// Ticks of a logarithmic axis over [lo, hi]: the labelled values and the grid lines (every multiple 1–9 of
/// a power of ten in the range). Labelled are:
/// - over more than three decades, every power of ten in the range;
/// - else 1, 2 and 5 times each power of ten; when fewer than four of those fall in the range, 1, 2, 3
///   and 5 times (0.03, 0.05, 0.1, 0.2 over 0.026–0.28); when still fewer than four (less than a decade),
///   every multiple 1–9 (0.3, 0.4, …);
/// - when even that gives fewer than two (a range inside one step, 0.31–0.38), the two ends rounded inwards
///   to two significant digits.
///
/// Empty for a range that is not positive and increasing.
pub fn log_ticks(lo: f64, hi: f64) -> (Vec<f64>, Vec<f64>) {
    let (mut labelled, mut grid, mut decades, mut steps) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    if !(lo > 0.0 && hi > lo && hi.is_finite()) {
        return (labelled, grid);
    }
    let mut e = lo.log10().floor() as i32;
    while 10f64.powi(e) <= hi {
        for m in 1..=9 {
            // m × 10^e, computed so that 0.3 is 0.3 and not 0.30000000000000004.
            let v = if e < 0 { m as f64 / 10f64.powi(-e) } else { m as f64 * 10f64.powi(e) };
            if (lo..=hi).contains(&v) {
                grid.push(v);
                if m == 1 {
                    decades.push(v);
                }
                if matches!(m, 1 | 2 | 5) {
                    labelled.push(v);
                }
                if matches!(m, 1 | 2 | 3 | 5) {
                    steps.push(v);
                }
            }
        }
        e += 1;
    }
    if (hi / lo).log10() > 3.0 {
        labelled = decades;
    } else if labelled.len() < 4 && steps.len() >= 4 {
        labelled = steps;
    } else if labelled.len() < 4 {
        labelled = grid.clone();
    }
    if labelled.len() < 2 {
        labelled = vec![round_to(lo, 2, f64::ceil), round_to(hi, 2, f64::floor)];
        labelled.dedup();
    }
    (labelled, grid)
}

/// `v` (positive) rounded to `digits` significant digits by `round` (`ceil` or `floor`).
fn round_to(v: f64, digits: i32, round: fn(f64) -> f64) -> f64 {
    let e = v.log10().floor() as i32 - digits + 1;
    if e < 0 {
        let k = 10f64.powi(-e);
        round(v * k) / k
    } else {
        let k = 10f64.powi(e);
        round(v / k) * k
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn labels(lo: f64, hi: f64) -> Vec<String> {
        log_ticks(lo, hi).0.iter().map(|&v| tick(v)).collect()
    }

    #[test]
    fn log_axes_label_every_decade_they_span() {
        // Wall seconds from 0.3 to 40: 1 and 10 labelled, with the 1–2–5 steps between.
        assert_eq!(labels(0.3, 40.0), ["0.5", "1", "2", "5", "10", "20"]);
        // Times under 1 s (the cache methods of a small sweep) are labelled, not left bare.
        assert_eq!(labels(0.016, 0.3), ["0.02", "0.05", "0.1", "0.2"]);
        // A decade with too few of 1, 2, 5: 3 joins them (every multiple would crowd the axis).
        assert_eq!(labels(0.0255, 0.28), ["0.03", "0.05", "0.1", "0.2"]);
        // Budgets under 1000, 833 to 1667 × the padding: every multiple, 1000 among them.
        assert_eq!(labels(666.0, 2084.0), ["700", "800", "900", "1000", "2000"]);
        // 0.04–1.2: 0.05 and 0.1, 0.2, 0.5, 1 labelled; the grid has every multiple.
        let (labelled, grid) = log_ticks(0.04, 1.2);
        assert_eq!(labelled.iter().map(|&v| tick(v)).collect::<Vec<_>>(), ["0.05", "0.1", "0.2", "0.5", "1"]);
        assert_eq!(grid.len(), 6 + 9 + 1);
        // Inside one decade too few of 1, 2, 5 fall in the range: every multiple is labelled.
        assert_eq!(labels(0.0018, 0.0065), ["0.002", "0.003", "0.004", "0.005", "0.006"]);
        // Over more than three decades, each power of ten.
        assert_eq!(labels(0.02, 3000.0), ["0.1", "1", "10", "100", "1000"]);
        // Between two multiples: the two ends, rounded inwards.
        assert_eq!(labels(0.312, 0.387), ["0.32", "0.38"]);
        // Every decade spanned has a label, whatever the range.
        for (lo, hi) in [(0.3, 40.0), (0.0021, 0.9), (5.0, 20000.0), (120.0, 9000.0), (0.07, 0.7)] {
            let l = log_ticks(lo, hi).0;
            let mut e = lo.log10().ceil() as i32;
            while 10f64.powi(e) <= hi {
                let p = 10f64.powi(e);
                assert!(l.iter().any(|v| (v / p - 1.0).abs() < 1e-9), "{lo}–{hi}: no label at {p}: {l:?}");
                e += 1;
            }
            assert!(l.len() >= 2, "{lo}–{hi}: {l:?}");
        }
        assert!(log_ticks(0.0, 1.0).0.is_empty());
        assert!(log_ticks(2.0, 1.0).0.is_empty());
    }

    #[test]
    fn tick_labels_have_six_significant_digits_and_no_float_noise() {
        assert_eq!(tick(0.30000000000000004), "0.3");
        assert_eq!(tick(0.6000000000000001), "0.6");
        assert_eq!(tick(0.00195), "0.00195");
        assert_eq!(tick(1234.5), "1234.5");
        assert_eq!(tick(20.0), "20");
        assert_eq!(tick(-0.125), "-0.125");
        assert_eq!(tick(1e-7), "0.0000001");
        assert_eq!(tick(0.0), "0");
    }
}
