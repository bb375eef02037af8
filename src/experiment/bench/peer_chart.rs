//! The error-versus-CPU-time chart of `cachert bench --integrator irradiancecache` (SVG): two panels, RMSE
//! over the whole image and off the light, against CPU seconds on a log axis, one line per series
//! (pbrt-v2's `minweight` and `nsamples` sweeps, one per cachert placement over cache budgets; with
//! `--seeds` a cachert point is the mean over the seeds).
//!
//! Reads only the rows the bench measured; draws with plotters' SVG backend.

use std::path::Path;

use plotters::prelude::*;

use crate::error::{Error, Result};

use super::irc_peer::{PeerRow, V2_DEFAULTS, series_names};
use crate::experiment::chart::{PALETTE, tick};

/// Writes the chart of `rows` to `path`.
pub fn write(rows: &[PeerRow], path: &Path) -> Result<()> {
    let fail = |e: String| Error::file(path, format!("cannot draw the chart: {e}"));
    crate::experiment::chart::font()?;
    let root = SVGBackend::new(path, (1100, 480)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| fail(e.to_string()))?;
    let panels = root.split_evenly((1, 2));
    let series = series_names(rows.iter());
    let (cpu_lo, cpu_hi) = rows.iter().fold((f64::INFINITY, 0.0f64), |(a, b), r| (a.min(r.cpu_s), b.max(r.cpu_s)));
    type Metric = fn(&PeerRow) -> f64;
    let metrics: [(&str, Metric); 2] =
        [("RMSE, whole image", |r| r.rmse), ("RMSE, off the light", |r| r.rmse_off_light)];
    // The target: at most half of pbrt-v2's CPU time at its defaults, at or below its error there.
    let v2_default = rows.iter().find(|r| r.renderer == "pbrt-v2" && r.setting == V2_DEFAULTS);
    for (panel, (title, metric)) in panels.iter().zip(metrics) {
        let hi = rows.iter().map(metric).fold(0.0f64, f64::max) * 1.1;
        let lo = rows.iter().map(metric).fold(f64::INFINITY, f64::min) * 0.9;
        let mut chart = ChartBuilder::on(panel)
            .caption(format!("Cornell box 256x256 vs path-ref: {title}"), ("sans-serif", 16))
            .margin(10)
            .x_label_area_size(40)
            .y_label_area_size(60)
            .build_cartesian_2d((cpu_lo * 0.8..cpu_hi * 1.25).log_scale(), lo.min(hi * 0.5)..hi.max(1e-6))
            .map_err(|e| fail(e.to_string()))?;
        chart
            .configure_mesh()
            .x_desc("CPU seconds (log)")
            .y_desc("RMSE")
            .x_label_formatter(&|v| tick(*v))
            .y_label_formatter(&|v| tick(*v))
            .draw()
            .map_err(|e| fail(e.to_string()))?;
        for (i, name) in series.iter().enumerate() {
            let colour = PALETTE[i % PALETTE.len()];
            let mut pts: Vec<(f64, f64)> =
                rows.iter().filter(|r| r.series == *name).map(|r| (r.cpu_s, metric(r))).collect();
            pts.sort_by(|a, b| a.0.total_cmp(&b.0));
            chart
                .draw_series(LineSeries::new(pts.clone(), colour.stroke_width(2)))
                .map_err(|e| fail(e.to_string()))?
                .label(*name)
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], colour.stroke_width(2)));
            chart
                .draw_series(pts.into_iter().map(|p| Circle::new(p, 3, colour.filled())))
                .map_err(|e| fail(e.to_string()))?;
        }
        if let Some(d) = v2_default {
            let (x, y) = (d.cpu_s / 2.0, metric(d));
            let dashed = RGBColor(200, 0, 0).stroke_width(1);
            chart
                .draw_series(DashedLineSeries::new(vec![(x, lo), (x, y), (cpu_lo * 0.8, y)], 6, 4, dashed))
                .map_err(|e| fail(e.to_string()))?
                .label("target: <= pbrt-v2 default error at <= half its CPU")
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], dashed));
        }
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .draw()
            .map_err(|e| fail(e.to_string()))?;
    }
    root.present().map_err(|e| fail(e.to_string()))?;
    Ok(())
}
