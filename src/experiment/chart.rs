//! The experiment's charts (SVG, one per scene), RMSE and mean HDR-FLIP against the reference on log–log
//! axes, one line per placement through its cache budgets (means over seeds, error bars from the smallest
//! to the largest seed):
//! - over wall seconds ([`XAxis::Seconds`], the speed–accuracy chart), with one more line for the per-pixel
//!   baseline through its sample counts: the method that reaches a given error first is the leftmost line;
//! - over the number of caches ([`XAxis::Caches`], the paper's Fig. 7).
//!
//! Reads only the sweep's rows; draws with plotters' SVG backend. Depends on nothing else of the crate.

use std::path::Path;

use plotters::prelude::*;

use super::Row;
use crate::error::{Error, Result};

/// Colours of the series, in order of first appearance (the charts of `cli` use them too).
pub const PALETTE: [RGBColor; 10] = [
    RGBColor(0, 0, 0),
    RGBColor(213, 94, 0),
    RGBColor(0, 114, 178),
    RGBColor(0, 158, 115),
    RGBColor(204, 121, 167),
    RGBColor(230, 159, 0),
    RGBColor(86, 180, 233),
    RGBColor(120, 120, 120),
    RGBColor(160, 40, 40),
    RGBColor(40, 40, 160),
];

/// What a chart's horizontal axis shows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum XAxis {
    /// Mean wall seconds of a run.
    Seconds,
    /// The cache budget (per-pixel baselines, which have none, are left out).
    Caches,
}

/// One point of a series: mean seconds, budget, and for each metric (mean, min, max) over seeds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Point {
    /// Mean wall seconds.
    pub secs: f64,
    /// Cache budget (0 for a per-pixel baseline).
    pub caches: usize,
    /// RMSE mean, smallest, largest.
    pub rmse: (f64, f64, f64),
    /// HDR-FLIP mean, smallest, largest.
    pub flip: (f64, f64, f64),
}

/// The series of `scene`'s rows: per placement (or baseline label), its points ordered by time. The
/// reference row (`none`) is left out.
pub fn series(rows: &[Row], scene: &str) -> Vec<(String, Vec<Point>)> {
    let mut out: Vec<(String, Vec<Point>)> = Vec::new();
    let mine: Vec<&Row> = rows.iter().filter(|r| r.scene == scene && r.placement != "none").collect();
    for r in &mine {
        // Baseline rows `LABEL:N` form one series over N.
        let name = match r.placement.split_once(':') {
            Some((label, n)) if n.parse::<u32>().is_ok() => label.to_string(),
            _ => r.placement.clone(),
        };
        if !out.iter().any(|(n, _)| *n == name) {
            out.push((name, Vec::new()));
        }
    }
    for (name, points) in &mut out {
        let same = |r: &&&Row| {
            r.placement == *name
                || r.placement.split_once(':').is_some_and(|(l, n)| l == name && n.parse::<u32>().is_ok())
        };
        let mut keys: Vec<(usize, String)> =
            mine.iter().filter(same).map(|r| (r.caches, r.placement.clone())).collect();
        keys.sort();
        keys.dedup();
        for (caches, placement) in keys {
            let sel: Vec<&Row> =
                mine.iter().filter(|r| r.caches == caches && r.placement == placement).copied().collect();
            let n = sel.len() as f64;
            let stat = |f: fn(&Row) -> f64| {
                let v: Vec<f64> = sel.iter().map(|r| f(r)).collect();
                (
                    v.iter().sum::<f64>() / n,
                    v.iter().copied().fold(f64::INFINITY, f64::min),
                    v.iter().copied().fold(0.0, f64::max),
                )
            };
            points.push(Point {
                secs: sel.iter().map(|r| r.stats.times.total).sum::<f64>() / n,
                caches,
                rmse: stat(|r| r.rmse),
                flip: stat(|r| r.flip),
            });
        }
        points.sort_by(|a, b| a.secs.total_cmp(&b.secs));
    }
    out
}

/// Writes the speed–accuracy chart of `scene`'s rows to `path`.
pub fn write(rows: &[Row], scene: &str, path: &Path) -> Result<()> {
    write_over(rows, scene, path, XAxis::Seconds)
}

/// Writes the chart of `scene`'s rows over `x` to `path`.
pub fn write_over(rows: &[Row], scene: &str, path: &Path, x: XAxis) -> Result<()> {
    let fail = |e: String| Error::file(path, format!("cannot draw the chart: {e}"));
    let xof = move |p: &Point| match x {
        XAxis::Seconds => p.secs,
        XAxis::Caches => p.caches as f64,
    };
    let mut all = series(rows, scene);
    if x == XAxis::Caches {
        all.retain_mut(|(_, points)| {
            points.retain(|p| p.caches > 0);
            points.sort_by_key(|p| p.caches);
            !points.is_empty()
        });
    }
    let pts: Vec<&Point> = all.iter().flat_map(|(_, p)| p).collect();
    if pts.is_empty() {
        return Ok(());
    }
    let root = SVGBackend::new(path, (1200, 500)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| fail(e.to_string()))?;
    let panels = root.split_evenly((1, 2));
    let (t_lo, t_hi) = pts.iter().fold((f64::INFINITY, 0.0f64), |(a, b), p| (a.min(xof(p)), b.max(xof(p))));
    let x_desc = match x {
        XAxis::Seconds => "wall seconds (log)",
        XAxis::Caches => "caches (log)",
    };
    type Metric = fn(&Point) -> (f64, f64, f64);
    let metrics: [(&str, Metric); 2] = [("RMSE", |p| p.rmse), ("HDR-FLIP", |p| p.flip)];
    for (panel, (title, metric)) in panels.iter().zip(metrics) {
        let hi = pts.iter().map(|p| metric(p).2).fold(0.0f64, f64::max).max(1e-9) * 1.2;
        let lo = pts.iter().map(|p| metric(p).1).filter(|v| *v > 0.0).fold(f64::INFINITY, f64::min).min(hi) * 0.8;
        let mut chart = ChartBuilder::on(panel)
            .caption(format!("{scene}: {title} against the reference"), ("sans-serif", 16))
            .margin(10)
            .x_label_area_size(40)
            .y_label_area_size(60)
            .build_cartesian_2d((t_lo.max(1e-3) * 0.8..t_hi * 1.25).log_scale(), (lo..hi).log_scale())
            .map_err(|e| fail(e.to_string()))?;
        chart
            .configure_mesh()
            .x_desc(x_desc)
            .y_desc(format!("{title} (log)"))
            .draw()
            .map_err(|e| fail(e.to_string()))?;
        for (i, (name, points)) in all.iter().enumerate() {
            let colour = PALETTE[i % PALETTE.len()];
            let line: Vec<(f64, f64)> = points.iter().map(|p| (xof(p), metric(p).0)).collect();
            chart
                .draw_series(LineSeries::new(line.clone(), colour.stroke_width(2)))
                .map_err(|e| fail(e.to_string()))?
                .label(name.as_str())
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], colour.stroke_width(2)));
            chart
                .draw_series(line.iter().map(|&p| Circle::new(p, 3, colour.filled())))
                .map_err(|e| fail(e.to_string()))?;
            let bars = points.iter().filter(|p| metric(p).1 < metric(p).2).map(|p| {
                let (_, a, b) = metric(p);
                PathElement::new(vec![(xof(p), a.max(lo)), (xof(p), b)], colour.stroke_width(1))
            });
            chart.draw_series(bars).map_err(|e| fail(e.to_string()))?;
        }
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperRight)
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .draw()
            .map_err(|e| fail(e.to_string()))?;
    }
    root.present().map_err(|e| fail(e.to_string()))?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::cache_driver::stats::{CacheStats, StageTimes};

    fn row(placement: &str, caches: usize, seed: u64, rmse: f64, secs: f64) -> Row {
        let times = StageTimes { total: secs, ..Default::default() };
        Row {
            scene: "s".into(),
            placement: placement.into(),
            caches,
            seed,
            rmse,
            flip: rmse / 10.0,
            converged: None,
            stats: CacheStats { times, ..Default::default() },
        }
    }

    #[test]
    fn series_average_seeds_and_gather_baseline_counts() {
        let rows = vec![
            row("none", 0, 0, 0.0, 50.0),
            row("vgc", 100, 0, 0.2, 1.0),
            row("vgc", 100, 1, 0.4, 3.0),
            row("vgc", 50, 0, 0.5, 0.5),
            row("power:16", 0, 0, 0.3, 4.0),
            row("power:4", 0, 0, 0.6, 1.0),
        ];
        let s = series(&rows, "s");
        assert_eq!(s.iter().map(|(n, _)| n.as_str()).collect::<Vec<_>>(), ["vgc", "power"]);
        let vgc = &s[0].1;
        assert_eq!(vgc.len(), 2);
        assert_eq!(vgc[1].secs, 2.0);
        assert!((vgc[1].rmse.0 - 0.3).abs() < 1e-12 && vgc[1].rmse.1 == 0.2 && vgc[1].rmse.2 == 0.4);
        assert_eq!(s[1].1.iter().map(|p| p.secs).collect::<Vec<_>>(), [1.0, 4.0]);
        let dir = std::env::temp_dir().join(format!("cachert-chart-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("c.svg");
        write(&rows, "s", &path).unwrap();
        let svg = std::fs::read_to_string(&path).unwrap();
        assert!(svg.contains("<svg") && svg.contains("power") && svg.contains("vgc"));
        // Over caches the baseline, which has no budget, is left out.
        write_over(&rows, "s", &path, XAxis::Caches).unwrap();
        let svg = std::fs::read_to_string(&path).unwrap();
        assert!(svg.contains("caches (log)") && svg.contains("vgc") && !svg.contains("power"));
        std::fs::remove_dir_all(&dir).ok();
    }
}
