//! The charts of a spec sweep, from its records: per scene and application the error against wall time
//! (cache methods over their budgets, the per-pixel estimator over its sample counts) and against the number
//! of caches (the paper's Fig. 7); per swept parameter the error against its value at each budget (Fig. 8,
//! Table 3). Each is written as SVG and PNG; returns the SVG paths, which the report shows.
//!
//! Depends on the records of `jobs`, [`super::summary`] and the chart writer.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use super::chart::{self, Plot, Point, Row, XAxis};
use super::jobs::Record;
use super::spec::CONVERGED;
use super::summary::{ok, pairs, total, varied_one};
use crate::error::Result;

/// A chart's file and what it shows.
#[derive(Clone, Debug, PartialEq)]
pub struct Figure {
    /// The SVG (a PNG with the same stem is beside it).
    pub svg: PathBuf,
    /// Scene and application.
    pub scene: String,
    /// The application.
    pub application: String,
    /// One line saying what it shows.
    pub caption: String,
}

/// Writes every chart of `records` into `out`. Without a font for their text there are none; `log` says why.
pub fn write(records: &[Record], out: &Path, log: &mut dyn FnMut(&str)) -> Result<Vec<Figure>> {
    let mut figures = Vec::new();
    if let Err(e) = chart::font() {
        log(&format!("no charts: {e}"));
        return Ok(figures);
    }
    for (scene, app) in pairs(records) {
        let label = format!("{scene}-{app}");
        let rows: Vec<Row> = ok(records)
            // The converged per-pixel image (64 × 64 samples) is a second reference, not a method.
            .filter(|r| r.scene == scene && r.application == app && r.varied.is_empty() && r.method != CONVERGED)
            .map(|r| Row {
                scene: label.clone(),
                placement: r.method.clone(),
                caches: r.caches,
                seed: r.seed,
                rmse: r.rmse,
                flip: r.flip,
                secs: total(r),
            })
            .collect();
        let figure =
            |svg: PathBuf, caption: String| Figure { svg, scene: scene.clone(), application: app.clone(), caption };
        if !rows.is_empty() {
            let time = out.join(format!("{label}-error-vs-time.svg"));
            chart::write_over(&rows, &label, &time, XAxis::Seconds)?;
            figures.push(figure(time, "error against wall time: cache methods over their budgets, the per-pixel estimator over its sample counts".into()));
            let caches = out.join(format!("{label}-error-vs-caches.svg"));
            chart::write_over(&rows, &label, &caches, XAxis::Caches)?;
            figures.push(figure(caches, "error against the number of caches (the paper's Fig. 7)".into()));
        }
        // key → budget → placement → value → (rmse, flip, seconds) per seed.
        type Runs = Vec<(f64, f64, f64)>;
        let mut swept: BTreeMap<(String, usize), BTreeMap<String, BTreeMap<String, Runs>>> = BTreeMap::new();
        for r in ok(records).filter(|r| r.scene == scene && r.application == app) {
            if let Some((k, v)) = varied_one(r) {
                swept
                    .entry((k.to_string(), r.caches))
                    .or_default()
                    .entry(r.placement.clone())
                    .or_default()
                    .entry(v.to_string())
                    .or_default()
                    .push((r.rmse, r.flip, total(r)));
            }
        }
        for ((key, caches), lines) in swept {
            let series: Vec<(String, Vec<(f64, Point)>)> = lines
                .into_iter()
                .map(|(placement, values)| {
                    let mut pts: Vec<(f64, Point)> = values
                        .iter()
                        .filter_map(|(v, runs)| Some((v.parse::<f64>().ok()?, Point::of(caches, runs))))
                        .collect();
                    pts.sort_by(|a, b| a.0.total_cmp(&b.0));
                    (placement, pts)
                })
                .collect();
            let xs: Vec<f64> = series.iter().flat_map(|(_, p)| p.iter().map(|q| q.0)).collect();
            let (lo, hi) = xs.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| (a.min(x), b.max(x)));
            let log_x = lo > 0.0 && hi / lo >= 20.0;
            let plot = Plot {
                title: format!("{label}, {caches} caches"),
                x_desc: if log_x { format!("{key} (log)") } else { key.clone() },
                log_x,
                series,
            };
            let svg = out.join(format!("{label}-{caches}-error-vs-{key}.svg"));
            chart::save(&plot, &svg)?;
            figures.push(figure(svg, format!("error against {key} at {caches} caches (the paper's Fig. 8 / Table 3)")));
        }
    }
    Ok(figures)
}
