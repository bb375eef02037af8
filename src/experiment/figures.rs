//! The charts of a spec sweep, from its records: per scene and application the error against wall time
//! (cache methods over their budgets, the per-pixel estimator over its sample counts) and against the number
//! of caches (the paper's Fig. 7); per swept parameter the error against its value at each budget (Fig. 8,
//! Table 3). Each is written as SVG and PNG; returns the SVG paths, which the report shows.
//!
//! A chart holds the runs of one scene, one application and one setting ([`setting`]: the fixed
//! parameters that change the reference), one line per method: runs of different applications, or measured
//! against different references (a `vary` over a parameter of the estimator, two `[[application]]` blocks
//! with other `set`s), are never drawn as one line. A scene and application with one setting keeps the plain
//! file names (`<scene>-<application>-error-vs-time.svg`); with several, each setting's charts add it to the
//! name (`<scene>-<application>-<k>-<v>-error-vs-time.svg`).
//!
//! Depends on the records of `jobs`, [`super::summary`], the application registry (which parameter is a
//! per-pixel run's sample count) and the chart writer.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use super::chart::{self, Plot, Point, Row, XAxis};
use super::jobs::Record;
use super::spec::CONVERGED;
use super::summary::{is_cache_run, ok, pairs, total, varied_one};
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

/// `k=v` pairs.
type Pairs = Vec<(String, String)>;

/// The pairs of a `k=v;…` field (a results.csv `set` or `varied`).
fn split_pairs(field: &str) -> Pairs {
    field.split(';').filter_map(|p| p.split_once('=')).map(|(k, v)| (k.to_string(), v.to_string())).collect()
}

/// The setting that decides a run's chart: its parameters less the varied ones (a swept chart's x) and the
/// placement-only ones (σ_a, `ratio`, …: they set where caches go, not what the reference is), sorted.
pub fn setting(r: &Record) -> Pairs {
    let varied: Vec<String> = split_pairs(&r.varied).into_iter().map(|(k, _)| k).collect();
    let mut s: Pairs =
        split_pairs(&r.set).into_iter().filter(|(k, _)| !varied.contains(k) && !super::placement_only(k)).collect();
    s.sort();
    s
}

/// `set` less what makes a run of `app` per-pixel (its sample count and the settings beside it): what a
/// per-pixel run shares with the cache runs measured against the same reference.
fn shared(app: &str, set: &[(String, String)]) -> Pairs {
    let per = crate::application::registry::entry(app).and_then(|e| e.per_sample);
    set.iter()
        .filter(|(k, _)| per.is_none_or(|p| k != p.count && !p.set.iter().any(|(s, _)| s == k)))
        .cloned()
        .collect()
}

/// The runs each time and budget chart of one scene and application draws, per setting: the plain cache
/// runs with that setting and the per-pixel runs (and baselines) that share it; per-pixel runs that share
/// no cache run's setting form a chart of their own.
fn charts_of<'a>(drawn: &[&'a Record], app: &str) -> Vec<(Pairs, Vec<&'a Record>)> {
    let mut keys: Vec<Pairs> = drawn.iter().filter(|r| is_cache_run(r)).map(|r| setting(r)).collect();
    keys.sort();
    keys.dedup();
    // Every key has cache runs: the groups of per-pixel runs alone come after them.
    let cached = keys.len();
    let mut out: Vec<(Pairs, Vec<&Record>)> = keys
        .into_iter()
        .map(|k| {
            let runs = drawn.iter().filter(|r| is_cache_run(r) && setting(r) == k).copied().collect();
            (k, runs)
        })
        .collect();
    for r in drawn.iter().filter(|r| !is_cache_run(r)) {
        let mine = shared(app, &setting(r));
        let mut placed = false;
        for g in out[..cached].iter_mut().filter(|g| shared(app, &g.0) == mine) {
            g.1.push(r);
            placed = true;
        }
        if !placed {
            match out[cached..].iter_mut().find(|g| g.0 == mine) {
                Some(g) => g.1.push(r),
                None => out.push((mine, vec![*r])),
            }
        }
    }
    out
}

/// The label (file-name stem and title) of the charts of `scene` and `app` with `setting`: `scene-app`,
/// and the setting's pairs as `k-v` when the pair has charts of several settings (`tagged`).
fn label_of(scene: &str, app: &str, setting: &[(String, String)], tagged: bool) -> String {
    let mut label = format!("{scene}-{app}");
    if tagged && !setting.is_empty() {
        let text: Vec<String> = setting.iter().map(|(k, v)| format!("{k}-{v}")).collect();
        let safe: String = text
            .join("_")
            .chars()
            .map(|c| if c.is_ascii_alphanumeric() || "-_.".contains(c) { c } else { '_' })
            .collect();
        label = format!("{label}-{safe}");
    }
    label
}

/// Writes every chart of `records` into `out`. Without a font for their text there are none; `log` says why.
pub fn write(records: &[Record], out: &Path, log: &mut dyn FnMut(&str)) -> Result<Vec<Figure>> {
    let mut figures = Vec::new();
    if let Err(e) = chart::font() {
        log(&format!("no charts: {e}"));
        return Ok(figures);
    }
    for (scene, app) in pairs(records) {
        let figure =
            |svg: PathBuf, caption: String| Figure { svg, scene: scene.clone(), application: app.clone(), caption };
        let drawn: Vec<&Record> = ok(records)
            // The converged per-pixel image (64 × 64 samples) is a second reference, not a method.
            .filter(|r| r.scene == scene && r.application == app && r.varied.is_empty() && r.method != CONVERGED)
            .collect();
        let charts = charts_of(&drawn, &app);
        let tagged = charts.len() > 1;
        for (key, runs) in &charts {
            let label = label_of(&scene, &app, key, tagged);
            let rows: Vec<Row> = runs
                .iter()
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
            let time = out.join(format!("{label}-error-vs-time.svg"));
            chart::write_over(&rows, &label, &time, XAxis::Seconds)?;
            figures.push(figure(time, "error against wall time: cache methods over their budgets, the per-pixel estimator over its sample counts".into()));
            if runs.iter().any(|r| is_cache_run(r)) {
                let caches = out.join(format!("{label}-error-vs-caches.svg"));
                chart::write_over(&rows, &label, &caches, XAxis::Caches)?;
                figures.push(figure(caches, "error against the number of caches (the paper's Fig. 7)".into()));
            }
        }
        // (setting, key, budget) → placement → value → (rmse, flip, seconds) per seed.
        type Runs = Vec<(f64, f64, f64)>;
        type Lines = BTreeMap<String, BTreeMap<String, Runs>>;
        let mut swept: BTreeMap<(Pairs, String, usize), Lines> = BTreeMap::new();
        for r in ok(records).filter(|r| r.scene == scene && r.application == app) {
            if let Some((k, v)) = varied_one(r) {
                swept
                    .entry((setting(r), k.to_string(), r.caches))
                    .or_default()
                    .entry(r.placement.clone())
                    .or_default()
                    .entry(v.to_string())
                    .or_default()
                    .push((r.rmse, r.flip, total(r)));
            }
        }
        let mut settings: Vec<&Pairs> = swept.keys().map(|k| &k.0).collect();
        settings.dedup();
        let tagged = settings.len() > 1;
        for ((set, key, caches), lines) in swept {
            let label = label_of(&scene, &app, &set, tagged);
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
    figures.extend(super::target::figures(records, out)?);
    Ok(figures)
}
