//! The target-error study (issue 43): for runs that swept refine's `targeterror` (`vary = { targeterror =
//! [...] }`), the relative RMSE each achieved — its RMSE over the reference's mean — against the target it
//! was given, as a table (per scene, application and target: caches placed, refine's own last estimate, the
//! achieved error over seeds and its ratio to the target, marked when outside the band the issue asks for)
//! and as a log–log chart per application (target on x, achieved on y, one line per scene, the diagonal and
//! the band drawn).
//!
//! Depends only on the records of `jobs`, [`super::summary`], [`super::tables::Table`] and plotters.

use std::collections::BTreeMap;
use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::*;

use super::chart::{Drawing, PALETTE, font, save_drawing, tick};
use super::figures::Figure;
use super::jobs::Record;
use super::summary::{Summary, ok};
use super::tables::Table;
use super::ticks::log_ticks;
use crate::error::Result;

/// The parameter swept.
const PARAM: &str = "targeterror";

/// The band the achieved error must fall in, as a multiple of the target (issue 43).
pub const BAND: (f64, f64) = (0.67, 1.5);

/// The target of a run that swept it, and the relative RMSE it achieved.
fn target_of(r: &Record) -> Option<(f64, f64)> {
    let value = r.varied.split(';').find_map(|p| p.split_once('=').filter(|(k, _)| *k == PARAM).map(|(_, v)| v))?;
    let target = value.parse::<f64>().ok()?;
    let achieved = r.rmse / r.reference_mean;
    (target > 0.0 && achieved.is_finite()).then_some((target, achieved))
}

/// The runs per (application, scene, target in millionths), in that order.
type Cells<'a> = BTreeMap<(String, String, u64), Vec<&'a Record>>;

fn cells(records: &[Record]) -> Cells<'_> {
    let mut out: Cells = BTreeMap::new();
    for r in ok(records) {
        if let Some((t, _)) = target_of(r) {
            let key = (r.application.clone(), r.scene.clone(), (t * 1e6).round() as u64);
            out.entry(key).or_default().push(r);
        }
    }
    out
}

/// The table of targets and what was achieved; `None` when no run swept a target.
pub fn table(records: &[Record]) -> Option<Table> {
    let cells = cells(records);
    if cells.is_empty() {
        return None;
    }
    let (mut rows, mut inside) = (Vec::new(), 0);
    for ((app, scene, t), rs) in &cells {
        let target = *t as f64 / 1e6;
        let achieved = Summary::of(rs.iter().filter_map(|r| target_of(r)).map(|(_, a)| a))?;
        let placed = Summary::of(rs.iter().map(|r| (r.caches_placed[0] + r.caches_placed[1]) as f64))?;
        let estimate = Summary::of(rs.iter().filter_map(|r| r.estimate));
        let ratio = achieved.mean / target;
        let ok = (BAND.0..=BAND.1).contains(&ratio);
        inside += usize::from(ok);
        rows.push(vec![
            format!("{scene} {app}"),
            format!("{target}"),
            format!("{:.0}", placed.mean),
            estimate.map_or("—".into(), |e| format!("{:.4}", e.mean)),
            format!("{:.4} ± {:.4}", achieved.mean, achieved.sd),
            if ok { format!("{ratio:.3}") } else { format!("**{ratio:.3}**") },
        ]);
    }
    rows.push(vec![
        "within the band".into(),
        String::new(),
        String::new(),
        String::new(),
        String::new(),
        format!("{inside} of {}", cells.len()),
    ]);
    Some(Table {
        title: "Target error: asked and achieved".into(),
        note: format!(
            "refine with `targeterror` swept: the caches it placed (mean over seeds), its own last estimate of the \
             relative RMSE (made without the reference), the relative RMSE achieved (RMSE over the reference's \
             mean; mean ± sd over seeds) and achieved / target, in bold when outside [{}, {}].",
            BAND.0, BAND.1
        ),
        header: ["scene", "target", "caches", "estimate", "achieved", "achieved / target"].map(String::from).to_vec(),
        rows,
    })
}

/// Writes one chart per application whose runs swept a target into `out`.
pub fn figures(records: &[Record], out: &Path) -> Result<Vec<Figure>> {
    let cells = cells(records);
    let mut apps: Vec<&String> = cells.keys().map(|k| &k.0).collect();
    apps.dedup();
    if apps.is_empty() {
        return Ok(Vec::new());
    }
    font()?;
    let mut figures = Vec::new();
    for app in apps {
        // Per scene: (target, mean, min, max achieved).
        let mut lines: BTreeMap<&str, Vec<(f64, f64, f64, f64)>> = BTreeMap::new();
        for ((a, scene, t), rs) in &cells {
            let Some(s) = Summary::of(rs.iter().filter_map(|r| target_of(r)).map(|(_, x)| x)) else { continue };
            if a == app {
                lines.entry(scene.as_str()).or_default().push((*t as f64 / 1e6, s.mean, s.min, s.max));
            }
        }
        let svg = out.join(format!("{app}-target-vs-achieved.svg"));
        save_drawing(&TargetChart { app, lines }, (700, 600), &svg)?;
        figures.push(Figure {
            svg,
            scene: "all scenes".into(),
            application: app.clone(),
            caption: format!(
                "{app}: refine's target relative RMSE against the one achieved (mean over seeds, bars from the \
                 smallest to the largest); the diagonal and the band [{}, {}] × target",
                BAND.0, BAND.1
            ),
        });
    }
    Ok(figures)
}

type Lines<'a> = BTreeMap<&'a str, Vec<(f64, f64, f64, f64)>>;

/// One application's chart: its name and its lines.
struct TargetChart<'a> {
    app: &'a str,
    lines: Lines<'a>,
}

impl Drawing for TargetChart<'_> {
    fn draw_on<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> std::result::Result<(), String> {
        draw(self.app, &self.lines, root)
    }
}

fn draw<DB: DrawingBackend>(
    app: &str,
    lines: &Lines<'_>,
    root: &DrawingArea<DB, Shift>,
) -> std::result::Result<(), String> {
    let e = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
    root.fill(&WHITE).map_err(e)?;
    let all = lines.values().flatten();
    let lo = all.clone().flat_map(|p| [p.0, p.2]).fold(f64::INFINITY, f64::min).max(1e-6) * 0.7;
    let hi = all.flat_map(|p| [p.0, p.3]).fold(0.0f64, f64::max).max(lo * 2.0) * 1.4;
    // Labelled at 1, 2 and 5 of every decade.
    let (labelled, grid) = log_ticks(lo, hi);
    let mut chart = ChartBuilder::on(root)
        .caption(format!("{app}: target against achieved relative RMSE"), ("sans-serif", 16))
        .margin(10)
        .x_label_area_size(40)
        .y_label_area_size(60)
        .build_cartesian_2d(
            (lo..hi).log_scale().with_key_points(labelled.clone()).with_light_points(grid.clone()),
            (lo..hi).log_scale().with_key_points(labelled).with_light_points(grid),
        )
        .map_err(e)?;
    chart
        .configure_mesh()
        .x_desc("target (log)")
        .y_desc("achieved relative RMSE (log)")
        .x_label_formatter(&|v| tick(*v))
        .y_label_formatter(&|v| tick(*v))
        .draw()
        .map_err(e)?;
    let grey = RGBColor(150, 150, 150);
    for (k, style) in [(1.0, grey.stroke_width(2)), (BAND.0, grey.stroke_width(1)), (BAND.1, grey.stroke_width(1))] {
        chart.draw_series(LineSeries::new([(lo, lo * k), (hi, hi * k)], style)).map_err(e)?;
    }
    for (i, (scene, pts)) in lines.iter().enumerate() {
        let colour = PALETTE[(i + 1) % PALETTE.len()];
        chart
            .draw_series(LineSeries::new(pts.iter().map(|p| (p.0, p.1)), colour.stroke_width(2)).point_size(3))
            .map_err(e)?
            .label(*scene)
            .legend(move |(x, y)| PathElement::new([(x, y), (x + 16, y)], colour.stroke_width(2)));
        chart
            .draw_series(pts.iter().map(|p| PathElement::new(vec![(p.0, p.2), (p.0, p.3)], colour.stroke_width(1))))
            .map_err(e)?;
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperLeft)
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .draw()
        .map_err(e)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run(scene: &str, target: f64, rmse: f64, seed: u64) -> Record {
        Record {
            status: "ok".into(),
            scene: scene.into(),
            application: "someapp".into(),
            placement: "refine".into(),
            method: "refine".into(),
            caches: 1000,
            seed,
            varied: format!("targeterror={target}"),
            rmse,
            flip: 0.1,
            reference_mean: 0.5,
            estimate: Some(target * 0.9),
            caches_placed: [10, 90],
            ..Default::default()
        }
    }

    #[test]
    fn the_table_divides_by_the_reference_mean_and_marks_what_misses_the_band() {
        let records =
            vec![run("a", 0.1, 0.05, 0), run("a", 0.1, 0.05, 1), run("a", 0.02, 0.02, 0), run("b", 0.1, 0.04, 0)];
        let t = table(&records).unwrap();
        // a at 0.02: achieved 0.04 = 2 × the target (bold); a at 0.1: 0.1 (1.000); b at 0.1: 0.08 (0.800).
        assert_eq!(t.rows[0][0], "a someapp");
        assert_eq!(t.rows[0][1], "0.02");
        assert_eq!(t.rows[0][5], "**2.000**");
        assert_eq!(t.rows[1][4], "0.1000 ± 0.0000");
        assert_eq!(t.rows[1][5], "1.000");
        assert_eq!(t.rows[1][2], "100");
        assert_eq!(t.rows[2][5], "0.800");
        assert_eq!(t.rows.last().unwrap()[5], "2 of 3");
        assert!(table(&[Record { varied: String::new(), ..run("a", 0.1, 0.05, 0) }]).is_none());
    }
}
