//! The experiment's tables, each as Markdown (`tables.md`) and HTML (the report): every run's setting with
//! RMSE and HDR-FLIP over seeds; the paper's Table 2 (the DGS ablation), its Table 3 and Fig. 8 (a swept
//! parameter, with each method at its default and at its best value), its Table 4 (per-stage times, median
//! of the seeds, with the placement's share with and without the G-buffer); and the claims table (which
//! method is best in each setting, whether clearly, and whether the per-pixel integrator reaches its error
//! in less time). The ratio tables (to IM, at equal time, against the converged image) are in
//! [`super::ratios`]; [`all`] gathers every table of `tables.md`.
//!
//! Depends only on the records of `jobs` and on [`super::summary`]; it reads no file.

use std::collections::BTreeMap;
use std::fmt::Write as _;

use super::jobs::Record;
use super::summary::{self, Summary, errors, middle_budget, ok, pairs, total, varied_one};

/// A table with a title and a note under it. A cell may hold `**bold**` text.
#[derive(Clone, Debug, PartialEq)]
pub struct Table {
    /// The heading.
    pub title: String,
    /// What it shows (one paragraph).
    pub note: String,
    /// Column names.
    pub header: Vec<String>,
    /// Cells, row by row.
    pub rows: Vec<Vec<String>>,
}

impl Table {
    /// Whether the table shows any measurement: some cell outside its label columns ([`LABELS`]: scene,
    /// application, method, budget) that is neither "—" nor empty. A table that would be all "—" is left
    /// out of `tables.md` and the report.
    pub fn has_data(&self) -> bool {
        let data: Vec<usize> =
            (0..self.header.len()).filter(|&i| !LABELS.contains(&self.header[i].to_lowercase().as_str())).collect();
        self.rows.iter().any(|row| {
            row.iter().enumerate().any(|(i, c)| (data.contains(&i) || i >= self.header.len()) && !no_data(c))
        })
    }

    /// As Markdown: a `##` heading, the note, the table.
    pub fn markdown(&self) -> String {
        let mut t = format!("## {}\n\n", self.title);
        if !self.note.is_empty() {
            let _ = writeln!(t, "{}\n", self.note);
        }
        let _ = writeln!(t, "| {} |", self.header.join(" | "));
        let _ = writeln!(t, "|{}", "---|".repeat(self.header.len()));
        for r in &self.rows {
            let _ = writeln!(t, "| {} |", r.join(" | "));
        }
        t.push('\n');
        t
    }

    /// As HTML: an `h3`, the note, the table (text escaped, `**x**` in bold).
    pub fn html(&self) -> String {
        let mut t = format!("<h3>{}</h3>\n", escape(&self.title));
        if !self.note.is_empty() {
            let _ = writeln!(t, "<p class=\"note\">{}</p>", escape(&self.note));
        }
        t.push_str("<table>\n<tr>");
        for h in &self.header {
            let _ = write!(t, "<th>{}</th>", escape(h));
        }
        t.push_str("</tr>\n");
        for r in &self.rows {
            t.push_str("<tr>");
            for c in r {
                let _ = write!(t, "<td>{}</td>", bold(&escape(c)));
            }
            t.push_str("</tr>\n");
        }
        t.push_str("</table>\n");
        t
    }
}

/// The column names that label a row rather than measure something (see [`Table::has_data`]).
pub const LABELS: [&str; 6] = ["scene", "application", "scene, application", "method", "caches", "placement"];

/// Whether a cell holds no measurement: "—", empty, or only "—" and separators ("— / —").
fn no_data(cell: &str) -> bool {
    cell.chars().all(|c| c == '—' || c == '/' || c == '*' || c.is_whitespace())
}

/// `s` with `&`, `<`, `>` and `"` escaped for HTML.
pub fn escape(s: &str) -> String {
    s.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;").replace('"', "&quot;")
}

/// `**x**` → `<b>x</b>`.
fn bold(s: &str) -> String {
    let mut out = String::new();
    for (i, part) in s.split("**").enumerate() {
        if i % 2 == 1 {
            let _ = write!(out, "<b>{part}</b>");
        } else {
            out.push_str(part);
        }
    }
    out
}

/// `m ± sd` with 5 decimals.
fn pm(s: &Summary) -> String {
    format!("{:.5} ± {:.5}", s.mean, s.sd)
}

/// Every table of the sweep, in the order of `tables.md`.
pub fn all(records: &[Record]) -> Vec<Table> {
    let mut t = claims(records);
    t.extend(super::ratios::to_im(records));
    t.extend(super::beyond::against_the_paper(records));
    t.extend(super::target::table(records));
    t.extend(super::ratios::seed_spread(records));
    t.extend(super::ratios::equal_time(records));
    t.extend(super::ratios::converged(records));
    t.extend(ablation(records));
    t.extend(swept(records));
    t.extend(timings(records));
    t.extend(results(records));
    t
}

/// Per scene and application: each method and budget's RMSE and FLIP (mean ± sd over seeds), median time,
/// σ_a, and failures.
fn results(records: &[Record]) -> Vec<Table> {
    // (scene, application) → (method, budget) → runs.
    type Methods<'a> = BTreeMap<(String, usize), Vec<&'a Record>>;
    let mut groups: BTreeMap<(String, String), Methods> = BTreeMap::new();
    for r in records {
        groups
            .entry((r.scene.clone(), r.application.clone()))
            .or_default()
            .entry((r.method.clone(), r.caches))
            .or_default()
            .push(r);
    }
    let mut out = Vec::new();
    for ((scene, app), methods) in groups {
        let mut rows = Vec::new();
        for ((m, caches), rs) in methods {
            let good: Vec<&Record> = rs.iter().filter(|r| r.status == "ok").copied().collect();
            let failed = rs.len() - good.len();
            let budget = if caches == 0 { "—".to_string() } else { caches.to_string() };
            let Some((rm, fl)) = errors(&good) else {
                rows.push(vec![
                    m,
                    budget,
                    "0".into(),
                    "—".into(),
                    "—".into(),
                    "—".into(),
                    "—".into(),
                    failed.to_string(),
                ]);
                continue;
            };
            let secs = Summary::of(good.iter().map(|r| total(r))).map_or(f64::NAN, |s| s.median);
            let sigma = good.iter().find_map(|r| r.sigma_a_deg).map_or("—".into(), |s| format!("{s:.1}°"));
            rows.push(vec![
                m,
                budget,
                rm.n.to_string(),
                pm(&rm),
                pm(&fl),
                format!("{secs:.2}"),
                sigma,
                failed.to_string(),
            ]);
        }
        out.push(Table {
            title: format!("All runs: {scene}, {app}"),
            note: "Means ± sample standard deviations over seeds, against the per-sample reference; seconds are \
                   medians; σ_a is VGC's angular threshold as used."
                .into(),
            header: ["method", "caches", "runs", "RMSE", "HDR-FLIP", "total s", "σ_a", "failed"]
                .map(String::from)
                .to_vec(),
            rows,
        });
    }
    out
}

/// Cells `RMSE / FLIP` (means) for `methods` with the smallest of each metric in bold.
fn best_cells(cells: &[Option<(Summary, Summary)>]) -> Vec<String> {
    let best = |f: fn(&(Summary, Summary)) -> f64| cells.iter().flatten().map(f).fold(f64::INFINITY, f64::min);
    let (br, bf) = (best(|c| c.0.mean), best(|c| c.1.mean));
    cells
        .iter()
        .map(|c| match c {
            None => "—".into(),
            Some((r, f)) => {
                let r = if r.mean == br { format!("**{:.5}**", r.mean) } else { format!("{:.5}", r.mean) };
                let f = if f.mean == bf { format!("**{:.5}**", f.mean) } else { format!("{:.5}", f.mean) };
                format!("{r} / {f}")
            }
        })
        .collect()
}

/// The paper's Table 2: VGC, VGC+AS and DGS from the record differences, the geometry, and both, per
/// application and scene at the middle budget.
fn ablation(records: &[Record]) -> Vec<Table> {
    const COLUMNS: [(&str, &str); 5] = [
        ("vgc", "VGC"),
        ("vgc+as", "VGC+AS"),
        ("vgc+dgs:diff", "DGS (diff)"),
        ("vgc+dgs:geom", "DGS (geom)"),
        ("vgc+dgs", "VGC+DGS (the application's default terms)"),
    ];
    let mut by_app: BTreeMap<String, Vec<Vec<String>>> = BTreeMap::new();
    for (scene, app) in pairs(records) {
        let Some(caches) = middle_budget(records, &scene, &app) else { continue };
        let methods = summary::methods_at(records, &scene, &app, caches);
        let cells: Vec<Option<(Summary, Summary)>> =
            COLUMNS.iter().map(|(p, _)| methods.get(*p).and_then(|rs| errors(rs))).collect();
        if cells.iter().filter(|c| c.is_some()).count() < 2 {
            continue;
        }
        let mut row = vec![scene.clone(), caches.to_string()];
        row.extend(best_cells(&cells));
        by_app.entry(app).or_default().push(row);
    }
    by_app
        .into_iter()
        .map(|(app, rows)| {
            let mut header = vec!["scene".to_string(), "caches".into()];
            header.extend(COLUMNS.iter().map(|(_, h)| h.to_string()));
            Table {
                title: format!("DGS ablation (the paper's Table 2): {app}"),
                note: "RMSE / HDR-FLIP, means over seeds at the middle budget; the best of each metric in bold. \
                       DGS (diff) builds the discontinuity map from record differences, DGS (geom) from the \
                       geometry term; the default uses both except where the application drops the geometry \
                       term (importance caching)."
                    .into(),
                header,
                rows,
            }
        })
        .collect()
}

/// The paper's Table 3 and Fig. 8: per application, swept parameter and budget, each method's error at every
/// value, at its default (the plain run) and at its best value.
fn swept(records: &[Record]) -> Vec<Table> {
    // (application, key, budget) → (scene, placement) → value → runs.
    type Values<'a> = BTreeMap<String, Vec<&'a Record>>;
    type Lines<'a> = BTreeMap<(String, String), Values<'a>>;
    let mut groups: BTreeMap<(String, String, usize), Lines> = BTreeMap::new();
    for r in ok(records) {
        if let Some((k, v)) = varied_one(r) {
            groups
                .entry((r.application.clone(), k.to_string(), r.caches))
                .or_default()
                .entry((r.scene.clone(), r.placement.clone()))
                .or_default()
                .entry(v.to_string())
                .or_default()
                .push(r);
        }
    }
    let mut out = Vec::new();
    for ((app, key, caches), lines) in groups {
        let mut values: Vec<String> = lines.values().flat_map(|v| v.keys().cloned()).collect();
        values.sort_by(|a, b| {
            a.parse::<f64>().unwrap_or(f64::NAN).total_cmp(&b.parse::<f64>().unwrap_or(f64::NAN)).then(a.cmp(b))
        });
        values.dedup();
        let mut rows = Vec::new();
        for ((scene, placement), by_value) in &lines {
            let mut cells: Vec<Option<(Summary, Summary)>> =
                values.iter().map(|v| by_value.get(v).and_then(|rs| errors(rs))).collect();
            let default = summary::methods_at(records, scene, &app, caches).get(placement).and_then(|rs| errors(rs));
            cells.push(default);
            let best_value = values
                .iter()
                .zip(&cells)
                .filter_map(|(v, c)| c.map(|c| (v, c.0.mean)))
                .min_by(|a, b| a.1.total_cmp(&b.1))
                .map_or("—".to_string(), |(v, _)| v.clone());
            let mut row = vec![scene.clone(), placement.clone()];
            row.extend(best_cells(&cells));
            row.push(best_value);
            rows.push(row);
        }
        let mut header = vec!["scene".to_string(), "method".into()];
        header.extend(values.iter().map(|v| format!("{key}={v}")));
        header.push("default".into());
        header.push(format!("best {key} (RMSE)"));
        out.push(Table {
            title: format!("{key} swept: {app}, {caches} caches"),
            note: format!(
                "RMSE / HDR-FLIP, means over seeds, at each value of {key}; \"default\" is the run without {key} \
                 set (the default value). The smallest of each metric in a row is in bold. (The paper's Table 3 \
                 sweeps the DGS ratio; its Fig. 8 sweeps SD's minimum cluster size and VGC's σ_a.)"
            ),
            header,
            rows,
        });
    }
    out
}

/// The stages of a timing table: the `--stats` names and the column headings.
const STAGES: [(&str, &str); 10] = [
    ("prepare", "prepare"),
    ("shading_points", "G-buffer"),
    ("initial_generation", "initial gen"),
    ("initial_computation", "initial comp"),
    ("adaptive_generation", "adaptive gen"),
    ("adaptive_computation", "adaptive comp"),
    ("kd_tree", "kd-tree"),
    ("finish_records", "finish records"),
    ("render", "render"),
    ("per_pixel_term", "per-pixel term"),
];

/// The paper's Table 4: per scene and application at the middle budget, each method's stage times (median
/// over seeds), the spread of its total, and the share of placement (both generation steps) in the total
/// with and without the G-buffer.
fn timings(records: &[Record]) -> Vec<Table> {
    let mut out = Vec::new();
    for (scene, app) in pairs(records) {
        let Some(caches) = middle_budget(records, &scene, &app) else { continue };
        let mut rows = Vec::new();
        for (placement, rs) in summary::methods_at(records, &scene, &app, caches) {
            let median = |k: &str| {
                Summary::of(rs.iter().map(|r| r.times.get(k).copied().unwrap_or(0.0))).map_or(f64::NAN, |s| s.median)
            };
            let mut row = vec![placement.clone(), rs.len().to_string()];
            row.extend(STAGES.iter().map(|(k, _)| format!("{:.3}", median(k))));
            let totals = Summary::of(rs.iter().map(|r| total(r)));
            let (t, spread) =
                totals.map_or((f64::NAN, String::from("—")), |s| (s.median, format!("{:.3}–{:.3}", s.min, s.max)));
            row.push(format!("{t:.3}"));
            row.push(spread);
            // Shares per run, then the median: the placement's fraction of the run.
            let share = |without_gbuffer: bool| {
                Summary::of(rs.iter().map(|r| {
                    let g = |k: &str| r.times.get(k).copied().unwrap_or(0.0);
                    let placement = g("initial_generation") + g("adaptive_generation");
                    let whole = total(r) - if without_gbuffer { g("shading_points") } else { 0.0 };
                    100.0 * placement / whole
                }))
                .map_or("—".into(), |s| format!("{:.1} %", s.median))
            };
            row.push(share(false));
            row.push(share(true));
            rows.push(row);
        }
        let mut header = vec!["method".to_string(), "runs".into()];
        header.extend(STAGES.iter().map(|(_, h)| format!("{h} s")));
        header.extend(["total s", "total min–max", "placement share", "… without G-buffer"].map(String::from));
        out.push(Table {
            title: format!("Stage times (the paper's Table 4): {scene}, {app}, {caches} caches"),
            note: "Medians over the seeds (the runs column) of each stage's wall seconds; the placement share is \
                   the two generation steps over the total, with the G-buffer stage counted and left out. One \
                   process per run on a shared machine: differences under ~10 % are noise."
                .into(),
            header,
            rows,
        });
    }
    out
}

/// Per scene, application and budget: the best cache method by each metric, whether it is below the
/// runner-up by more than two standard errors, and whether the per-pixel integrator reaches the best
/// method's RMSE in no more time.
fn claims(records: &[Record]) -> Vec<Table> {
    let mut rows = Vec::new();
    for (scene, app) in pairs(records) {
        let per_pixel: Vec<(&str, Summary, Summary)> = {
            let mut m: BTreeMap<&str, Vec<&Record>> = BTreeMap::new();
            for r in ok(records).filter(|r| r.scene == scene && r.application == app && r.samples.is_some()) {
                m.entry(r.method.as_str()).or_default().push(r);
            }
            m.into_iter()
                .filter_map(|(k, rs)| {
                    Some((k, Summary::of(rs.iter().map(|r| r.rmse))?, Summary::of(rs.iter().map(|r| total(r)))?))
                })
                .collect()
        };
        for caches in summary::budgets(records, &scene, &app) {
            let methods = summary::methods_at(records, &scene, &app, caches);
            let stats: Vec<MethodStats<'_>> = methods
                .iter()
                .filter_map(|(m, rs)| {
                    let (r, f) = errors(rs)?;
                    Some((m, r, f, Summary::of(rs.iter().map(|r| total(r)))?.median))
                })
                .collect();
            if stats.is_empty() {
                continue;
            }
            rows.push(claim_row(&scene, &app, caches, &stats, &per_pixel));
        }
    }
    if rows.is_empty() {
        return Vec::new();
    }
    vec![Table {
        title: "Which method wins".into(),
        note: "Per setting, the cache method with the lowest mean RMSE and HDR-FLIP; \"clearly\" when it is \
               below the runner-up by more than two standard errors of the difference (with few seeds, a rough test). \
               \"Better than IM\": clearly lower in both metrics; \"worse than IM\": clearly higher in either. The \
               last column says whether a per-pixel run of the same estimator reached the best method's RMSE in \
               no more wall time."
            .into(),
        header: [
            "scene",
            "application",
            "caches",
            "best RMSE",
            "best HDR-FLIP",
            "better than IM",
            "worse than IM",
            "per-pixel reaches it as fast?",
        ]
        .map(String::from)
        .to_vec(),
        rows,
    }]
}

/// One method's figures at one setting: its name, RMSE and HDR-FLIP over seeds, median wall seconds.
type MethodStats<'a> = (&'a String, Summary, Summary, f64);

/// The row of "Which method wins" for one scene, application and budget: the verdicts in RMSE and HDR-FLIP,
/// the methods clearly better and worse than IM, and whether a per-pixel run (name, RMSE, seconds) reached
/// the best RMSE in no more time.
fn claim_row(
    scene: &str,
    app: &str,
    caches: usize,
    stats: &[MethodStats<'_>],
    per_pixel: &[(&str, Summary, Summary)],
) -> Vec<String> {
    let verdict = |metric: fn(&MethodStats<'_>) -> Summary| {
        let mut order: Vec<&MethodStats<'_>> = stats.iter().collect();
        order.sort_by(|a, b| metric(a).mean.total_cmp(&metric(b).mean));
        let best = order[0];
        match order.get(1) {
            Some(second) if metric(best).clearly_below(&metric(second)) => {
                format!("**{}** (clearly, next {})", best.0, second.0)
            }
            Some(second) => format!("{} (within noise of {})", best.0, second.0),
            None => best.0.to_string(),
        }
    };
    let best_rmse = stats.iter().min_by(|a, b| a.1.mean.total_cmp(&b.1.mean)).map(|s| (s.1.mean, s.3));
    let im = stats.iter().find(|s| s.0 == "im");
    let beat_im: Vec<&str> = stats
        .iter()
        .filter(|s| im.is_some_and(|im| s.1.clearly_below(&im.1) && s.2.clearly_below(&im.2)))
        .map(|s| s.0.as_str())
        .collect();
    let lose_im: Vec<&str> = stats
        .iter()
        .filter(|s| im.is_some_and(|im| im.1.clearly_below(&s.1) || im.2.clearly_below(&s.2)))
        .map(|s| s.0.as_str())
        .collect();
    let faster = match best_rmse {
        Some((err, secs)) if !per_pixel.is_empty() => per_pixel
            .iter()
            .filter(|(_, r, t)| r.mean <= err && t.median <= secs)
            .min_by(|a, b| a.2.median.total_cmp(&b.2.median))
            .map_or("no".to_string(), |(m, r, t)| {
                format!("**yes**: {m} ({:.5} in {:.2} s vs {err:.5} in {secs:.2} s)", r.mean, t.median)
            }),
        _ => "not run".into(),
    };
    vec![
        scene.to_string(),
        app.to_string(),
        caches.to_string(),
        verdict(|s| s.1),
        verdict(|s| s.2),
        if beat_im.is_empty() { "—".into() } else { beat_im.join(", ") },
        if lose_im.is_empty() { "—".into() } else { lose_im.join(", ") },
        faster,
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tables_render_as_markdown_and_escaped_html() {
        let t = Table {
            title: "A <b>".into(),
            note: String::new(),
            header: vec!["x".into(), "y".into()],
            rows: vec![vec!["**1**".into(), "a&b".into()]],
        };
        assert_eq!(t.markdown(), "## A <b>\n\n| x | y |\n|---|---|\n| **1** | a&b |\n\n");
        let h = t.html();
        assert!(h.contains("<h3>A &lt;b&gt;</h3>") && h.contains("<td><b>1</b></td><td>a&amp;b</td>"), "{h}");
    }

    #[test]
    fn a_table_of_dashes_has_no_data() {
        let t = |rows: Vec<Vec<&str>>| Table {
            title: "t".into(),
            note: String::new(),
            header: vec!["scene".into(), "caches".into(), "IM".into(), "VGC".into()],
            rows: rows.into_iter().map(|r| r.into_iter().map(String::from).collect()).collect(),
        };
        // Labels alone are no data: the scene and the budget are there, every measurement is "—".
        assert!(!t(vec![vec!["s", "100", "—", "— / —"], vec!["s", "200", "—", ""]]).has_data());
        assert!(!t(vec![]).has_data());
        assert!(t(vec![vec!["s", "100", "—", "**0.1**"]]).has_data());
    }
}
