//! The comparison tables of a sweep: each cache method's error as a ratio to IM's (what
//! `experiments/summarise.py` printed), each per-pixel estimator's error at the cache method's wall time as
//! a ratio to the cache method's (what the retired `equal_time.py` printed; its two-file form, baselines from
//! another sweep, is `--replot DIR --baselines DIR2`), and every run measured against the converged
//! per-pixel image (the flag form's second table), and the settings whose error spreads over the seeds by more
//! than 10 % of its mean (what the retired `results/stability/aggregate.py` flagged).
//!
//! Depends only on the records of `jobs`, [`super::summary`] and [`super::tables::Table`]; it reads no file.

use std::collections::BTreeMap;

use super::jobs::Record;
use super::spec::CONVERGED;
use super::summary::{self, Summary, errors, is_cache_run, ok, pairs, total};
use super::tables::Table;

/// The order of the ratio table's columns: the paper's methods and refine; any other placement follows by name.
const METHODS: [&str; 8] = ["sd", "sd+as", "vgc", "vgc+as", "vgc+dgs", "refine", "vgc+dgs:diff", "vgc+dgs:geom"];

/// Per scene, application and budget: IM's mean RMSE and HDR-FLIP, and each other plain cache method's as a
/// ratio to them, marked `+` (clearly lower than IM) or `-` (clearly higher) by the two-standard-error rule.
pub fn to_im(records: &[Record]) -> Vec<Table> {
    let mut methods: Vec<String> = Vec::new();
    let mut rows = Vec::new();
    let plain = |r: &&Record| is_cache_run(r) && r.varied.is_empty() && r.placement != "im";
    for p in ok(records).filter(plain).map(|r| r.placement.clone()) {
        if !methods.contains(&p) {
            methods.push(p);
        }
    }
    methods.sort_by_key(|m| (METHODS.iter().position(|k| k == m).unwrap_or(METHODS.len()), m.clone()));
    for (scene, app) in pairs(records) {
        for caches in summary::budgets(records, &scene, &app) {
            let at = summary::methods_at(records, &scene, &app, caches);
            let Some((im_r, im_f)) = at.get("im").and_then(|rs| errors(rs)) else { continue };
            let mut row =
                vec![format!("{scene} {app}"), caches.to_string(), format!("{:.5} / {:.5}", im_r.mean, im_f.mean)];
            for m in &methods {
                row.push(match at.get(m).and_then(|rs| errors(rs)) {
                    None => "—".into(),
                    Some((r, f)) => format!("{} / {}", ratio(&r, &im_r), ratio(&f, &im_f)),
                });
            }
            rows.push(row);
        }
    }
    if rows.is_empty() {
        return Vec::new();
    }
    let mut header = vec!["scene, application".to_string(), "caches".into(), "IM RMSE / FLIP".into()];
    header.extend(methods.iter().cloned());
    vec![Table {
        title: "Ratios to IM".into(),
        note: "Each plain cache method's mean RMSE / mean HDR-FLIP over seeds as a ratio to IM's at the same \
               budget; `+`: clearly lower than IM, `-`: clearly higher (the difference of the means exceeds two \
               standard errors of the difference)."
            .into(),
        header,
        rows,
    }]
}

/// `a.mean / im.mean` with two decimals, marked `+`/`-` when clearly lower/higher.
fn ratio(a: &Summary, im: &Summary) -> String {
    let mark = if a.clearly_below(im) {
        "+"
    } else if im.clearly_below(a) {
        "-"
    } else {
        ""
    };
    format!("{:.2}{mark}", a.mean / im.mean)
}

/// One point of a per-pixel estimator: (seconds, RMSE, HDR-FLIP), means over its seeds.
type Point = (f64, f64, f64);

/// The error of a per-pixel estimator (points ordered by time) at `t` seconds: `k` 1 for RMSE, 2 for
/// HDR-FLIP; interpolated linearly in log-time/log-error between the two nearest points, extrapolated as
/// error ∝ t^-1/2 outside them.
fn at_time(points: &[Point], t: f64, k: usize) -> f64 {
    let e = |p: &Point| if k == 1 { p.1 } else { p.2 };
    let (Some(first), Some(last)) = (points.first(), points.last()) else { return f64::NAN };
    if t <= first.0 {
        return e(first) * (first.0 / t).sqrt();
    }
    if t >= last.0 {
        return e(last) * (last.0 / t).sqrt();
    }
    for w in points.windows(2) {
        let (a, b) = (&w[0], &w[1]);
        if a.0 <= t && t <= b.0 {
            let f = (t / a.0).ln() / (b.0 / a.0).ln();
            return (e(a).ln() * (1.0 - f) + e(b).ln() * f).exp();
        }
    }
    f64::NAN
}

/// The per-pixel estimators of `scene` and `app` by label (`ao`, `power`, `per-pixel`, …): each sample
/// count's point, ordered by time.
fn per_pixel_points(records: &[Record], scene: &str, app: &str) -> BTreeMap<String, Vec<Point>> {
    let mut runs: BTreeMap<(String, u32), Vec<&Record>> = BTreeMap::new();
    for r in ok(records).filter(|r| r.scene == scene && r.application == app) {
        if let (Some(n), Some((label, _))) = (r.samples, r.method.split_once(':')) {
            runs.entry((label.to_string(), n)).or_default().push(r);
        }
    }
    let mut out: BTreeMap<String, Vec<Point>> = BTreeMap::new();
    for ((label, _), rs) in runs {
        let mean = |f: &dyn Fn(&Record) -> f64| rs.iter().map(|r| f(r)).sum::<f64>() / rs.len() as f64;
        out.entry(label).or_default().push((mean(&total), mean(&|r| r.rmse), mean(&|r| r.flip)));
    }
    for points in out.values_mut() {
        points.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)).then(a.2.total_cmp(&b.2)));
    }
    out
}

/// Per scene and application with per-pixel runs: every plain cache setting's mean error and time over the
/// seeds, each per-pixel estimator's error at that time, and the ratio estimator / cache (> 1: the caches
/// ahead).
pub fn equal_time(records: &[Record]) -> Vec<Table> {
    equal_time_against(records, records, "")
}

/// [`equal_time`] with the per-pixel runs taken from `baselines` (another sweep's records, say one without
/// a parameter that changes the estimators, measured against the same reference); `from` names where they
/// came from in each table's title (empty: the same sweep).
pub fn equal_time_against(records: &[Record], baselines: &[Record], from: &str) -> Vec<Table> {
    let mut out = Vec::new();
    for (scene, app) in pairs(records) {
        let bases = per_pixel_points(baselines, &scene, &app);
        if bases.is_empty() {
            continue;
        }
        let mut groups: BTreeMap<(usize, String), Vec<&Record>> = BTreeMap::new();
        for r in ok(records).filter(|r| r.scene == scene && r.application == app && is_cache_run(r)) {
            groups.entry((r.caches, r.method.clone())).or_default().push(r);
        }
        let mut rows = Vec::new();
        for ((caches, method), g) in &groups {
            let n = g.len() as f64;
            let t = g.iter().map(|r| total(r)).sum::<f64>() / n;
            let e: Vec<f64> = g.iter().map(|r| r.rmse).collect();
            let f: Vec<f64> = g.iter().map(|r| r.flip).collect();
            let (me, mf) = (e.iter().sum::<f64>() / n, f.iter().sum::<f64>() / n);
            let lo_hi =
                |v: &[f64]| v.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| (a.min(x), b.max(x)));
            let ((e0, e1), (f0, f1)) = (lo_hi(&e), lo_hi(&f));
            let mut row =
                vec![caches.to_string(), method.clone(), format!("{t:.2}"), format!("{me:.5} ({e0:.5}–{e1:.5})")];
            for b in bases.values() {
                let pe = at_time(b, t, 1);
                row.extend([format!("{pe:.5}"), format!("{:.2}", pe / me)]);
            }
            row.push(format!("{mf:.4} ({f0:.4}–{f1:.4})"));
            for b in bases.values() {
                let pf = at_time(b, t, 2);
                row.extend([format!("{pf:.4}"), format!("{:.2}", pf / mf)]);
            }
            rows.push(row);
        }
        let mut header = ["caches", "placement", "s", "RMSE (min–max)"].map(String::from).to_vec();
        for l in bases.keys() {
            header.extend([format!("{l} RMSE"), "ratio".into()]);
        }
        header.push("FLIP (min–max)".into());
        for l in bases.keys() {
            header.extend([format!("{l} FLIP"), "ratio".into()]);
        }
        let points: Vec<String> = bases
            .iter()
            .map(|(l, b)| {
                let p: Vec<String> = b.iter().map(|(t, e, f)| format!("{t:.2} s: RMSE {e:.5} FLIP {f:.4}")).collect();
                format!("{l}: {}", p.join(", "))
            })
            .collect();
        out.push(Table {
            title: if from.is_empty() {
                format!("At equal time: {scene}, {app}")
            } else {
                format!("At equal time: {scene}, {app}, per-pixel runs from {from}")
            },
            note: format!(
                "Each cache setting's mean wall seconds, RMSE and HDR-FLIP over seeds (min–max over seeds); each \
                 per-pixel estimator's error at that time, interpolated linearly in log-time/log-error between \
                 its two nearest sample counts and extrapolated as error ∝ t^-1/2 outside them, and the ratio \
                 estimator / cache (> 1: the caches ahead). The per-pixel points (means over seeds): {}.",
                points.join("; ")
            ),
            header,
            rows,
        });
    }
    out
}

/// Per scene and application with a converged per-pixel image (a spec's `baselines`): the seed-0 runs and
/// the baselines measured against it, and the per-sample reference's own gap to it.
pub fn converged(records: &[Record]) -> Vec<Table> {
    let mut out = Vec::new();
    for (scene, app) in pairs(records) {
        let mine = || ok(records).filter(|r| r.scene == scene && r.application == app);
        let Some(conv) = mine().find(|r| r.method == CONVERGED) else { continue };
        let mut rows = vec![vec![
            "per-sample reference".to_string(),
            "—".into(),
            format!("{:.5}", conv.rmse),
            format!("{:.5}", conv.flip),
            format!("{:.2}", conv.reference_s),
        ]];
        for r in mine() {
            let (Some(rmse), Some(flip)) = (r.rmse_converged, r.flip_converged) else { continue };
            let budget = if r.caches == 0 { "—".to_string() } else { r.caches.to_string() };
            rows.push(vec![
                r.method.clone(),
                budget,
                format!("{rmse:.5}"),
                format!("{flip:.5}"),
                format!("{:.2}", total(r)),
            ]);
        }
        out.push(Table {
            title: format!("Against the converged per-pixel image: {scene}, {app}"),
            note: "Seed 0 of every run and the per-pixel baselines (`LABEL:N`: N rays or draws per pixel sample × 4 \
                   pixel samples) against the first baseline converged (64 × 64). Two references: the other tables \
                   measure against the per-sample reference, this one against the baseline's converged image, \
                   which need not estimate the same quantity (for ambient occlusion pbrt-v3's hemisphere about the \
                   geometric normal, while the caches and the per-sample reference gather about the shading \
                   normal): the first row is the gap between the two. A spec's `per_pixel` runs the \
                   application's own estimator instead, so they agree by construction."
                .into(),
            header: ["render", "caches", "RMSE", "HDR-FLIP", "total s"].map(String::from).to_vec(),
            rows,
        });
    }
    out
}

/// A setting whose error spreads over its seeds by more than this share of its mean is listed by [`seed_spread`].
const SPREAD: f64 = 0.10;

/// The cache runs whose RMSE or HDR-FLIP has a sample standard deviation over the seeds above 10 % of its mean,
/// per scene, application, budget, method and varied setting; no table when none is. Its note gives, per
/// application, the largest RMSE spread of all settings with two or more seeds.
pub fn seed_spread(records: &[Record]) -> Vec<Table> {
    type Key = (String, String, usize, String, String);
    let mut groups: BTreeMap<Key, Vec<&Record>> = BTreeMap::new();
    for r in ok(records).filter(|r| is_cache_run(r)) {
        let key = (r.scene.clone(), r.application.clone(), r.caches, r.placement.clone(), r.varied.clone());
        groups.entry(key).or_default().push(r);
    }
    let mut rows = Vec::new();
    let mut largest: BTreeMap<String, (f64, String)> = BTreeMap::new();
    for ((scene, app, caches, placement, varied), rs) in &groups {
        let Some((r, f)) = errors(rs) else { continue };
        if r.n < 2 {
            continue;
        }
        let (r_cv, f_cv) = (r.sd / r.mean, f.sd / f.mean);
        let method = if varied.is_empty() { placement.clone() } else { format!("{placement} {varied}") };
        let at = format!("{scene}, {caches} caches, {method}");
        let entry = largest.entry(app.clone()).or_insert((f64::NEG_INFINITY, String::new()));
        if r_cv > entry.0 {
            *entry = (r_cv, at);
        }
        if r_cv > SPREAD || f_cv > SPREAD {
            rows.push(vec![
                format!("{scene} {app}"),
                caches.to_string(),
                method,
                r.n.to_string(),
                format!("{:.5} ± {:.5} ({:.0} %)", r.mean, r.sd, 100.0 * r_cv),
                format!("{:.5} ± {:.5} ({:.0} %)", f.mean, f.sd, 100.0 * f_cv),
            ]);
        }
    }
    if rows.is_empty() {
        return Vec::new();
    }
    let most: Vec<String> = largest.iter().map(|(app, (cv, at))| format!("{app} {:.1} % ({at})", 100.0 * cv)).collect();
    vec![Table {
        title: "Seed spread above 10 %".into(),
        note: format!(
            "Cache runs whose RMSE or HDR-FLIP has a standard deviation over the seeds above 10 % of its mean \
             (in parentheses: the standard deviation as a share of the mean); every other setting spreads less. \
             Largest RMSE spread per application: {}.",
            most.join("; ")
        ),
        header: ["scene, application", "caches", "method", "seeds", "RMSE mean ± sd", "HDR-FLIP mean ± sd"]
            .map(String::from)
            .to_vec(),
        rows,
    }]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn equal_time_interpolates_in_log_log_and_extrapolates_by_the_square_root() {
        let pts = [(1.0, 0.1, 0.4), (4.0, 0.05, 0.2)];
        assert!((at_time(&pts, 1.0, 1) - 0.1).abs() < 1e-12);
        assert!((at_time(&pts, 2.0, 1) - (0.1f64.ln() * 0.5 + 0.05f64.ln() * 0.5).exp()).abs() < 1e-12);
        assert!((at_time(&pts, 0.25, 2) - 0.8).abs() < 1e-12);
        assert!((at_time(&pts, 16.0, 1) - 0.025).abs() < 1e-12);
    }

    #[test]
    fn seed_spread_lists_the_settings_above_ten_percent() {
        let head = "id,status,scene,application,placement,method,caches,seed,varied,rmse,flip,total_s\n";
        let mut text = head.to_string();
        for (seed, (a, b)) in [(0.10, 0.20), (0.10, 0.20), (0.10, 0.30)].iter().enumerate() {
            text += &format!("im-{seed},ok,s,app,im,im,100,{seed},,{a},0.5,1\n");
            text += &format!("sd-{seed},ok,s,app,sd,sd,100,{seed},,{b},0.5,1\n");
        }
        let records = super::super::results::parse_csv(std::path::Path::new("x.csv"), &text).unwrap();
        let t = seed_spread(&records);
        assert_eq!(t.len(), 1);
        assert_eq!(t[0].rows.len(), 1, "{:?}", t[0].rows);
        assert_eq!(t[0].rows[0][2], "sd");
        assert!(t[0].rows[0][4].ends_with("(25 %)"), "{}", t[0].rows[0][4]);
        assert!(t[0].note.contains("app 24.7 % (s, 100 caches, sd)"), "{}", t[0].note);
        let calm: Vec<Record> = records.into_iter().filter(|r| r.placement == "im").collect();
        assert!(seed_spread(&calm).is_empty());
    }
}
