//! The experiment's charts, each written as SVG and PNG: RMSE and mean HDR-FLIP against the reference, one
//! line per method (means over seeds, error bars from the smallest to the largest seed):
//! - over wall seconds ([`XAxis::Seconds`], the speed–accuracy chart), with the per-pixel baseline through its
//!   sample counts on the same axes: the method that reaches a given error first is the leftmost line;
//! - over the number of caches ([`XAxis::Caches`], the paper's Fig. 7);
//! - over the value of a swept parameter ([`Plot`] built by the caller: the paper's Fig. 8 and Table 3).
//!
//! A method has one colour in every chart, a function of its name ([`super::palette`]); log axes label
//! every decade they span ([`super::ticks`]). Text needs a TrueType font ([`font`]). Reads only the rows it
//! is given; draws with plotters' SVG and bitmap backends. Depends on nothing else of the crate but `image`
//! (to write the PNG).

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use plotters::coord::Shift;
use plotters::prelude::*;

use super::palette::colour_of;
use super::ticks::log_ticks;
pub(crate) use super::ticks::tick;
use crate::error::{Error, Result};

/// One measured run as a chart draws it: a point of a series before the mean over seeds.
#[derive(Clone, Debug, PartialEq)]
pub struct Row {
    /// The chart's name (the scene, or scene and application).
    pub scene: String,
    /// The series: a placement, or a per-pixel method `LABEL:N` (one series over N).
    pub placement: String,
    /// Budget (0 for a per-pixel run).
    pub caches: usize,
    /// Seed.
    pub seed: u64,
    /// RMSE against the reference.
    pub rmse: f64,
    /// Mean HDR-FLIP against the reference.
    pub flip: f64,
    /// Wall seconds of the run.
    pub secs: f64,
}

/// Colours by position, for charts whose series are not methods (the pbrt comparison's, `bench`); the
/// experiment's charts colour a method by its name ([`colour_of`]).
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

/// Where [`font`] looks for a sans-serif TrueType font, after `$CACHERT_FONT` (Debian's fonts-dejavu-core,
/// fonts-liberation, fonts-noto-core, fonts-freefont-ttf).
const FONTS: [&str; 5] = [
    "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf",
    "/usr/share/fonts/truetype/liberation/LiberationSans-Regular.ttf",
    "/usr/share/fonts/truetype/liberation2/LiberationSans-Regular.ttf",
    "/usr/share/fonts/truetype/noto/NotoSans-Regular.ttf",
    "/usr/share/fonts/truetype/freefont/FreeSans.ttf",
];

/// Registers the charts' font once: the file named by `$CACHERT_FONT`, else the first of `FONTS` that
/// loads. Charts (their labels are text) need it; the error says how to get one.
pub fn font() -> Result<()> {
    static FONT: OnceLock<std::result::Result<(), String>> = OnceLock::new();
    FONT.get_or_init(|| {
        let wanted = std::env::var_os("CACHERT_FONT").map(PathBuf::from);
        let candidates: Vec<PathBuf> = wanted.into_iter().chain(FONTS.iter().map(PathBuf::from)).collect();
        for path in &candidates {
            let Ok(bytes) = std::fs::read(path) else { continue };
            let bytes: &'static [u8] = Box::leak(bytes.into_boxed_slice());
            if plotters::style::register_font("sans-serif", FontStyle::Normal, bytes).is_ok() {
                return Ok(());
            }
        }
        Err(format!(
            "charts need a TrueType font and none loads (tried $CACHERT_FONT and {}); install fonts-dejavu-core \
             or set CACHERT_FONT to a .ttf file",
            FONTS.join(", ")
        ))
    })
    .clone()
    .map_err(Error::usage)
}

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

impl Point {
    /// The point of `values` (one (rmse, flip, seconds) per seed; not empty) at budget `caches`.
    pub fn of(caches: usize, values: &[(f64, f64, f64)]) -> Point {
        let n = values.len() as f64;
        let stat = |f: fn(&(f64, f64, f64)) -> f64| {
            let v: Vec<f64> = values.iter().map(f).collect();
            (
                v.iter().sum::<f64>() / n,
                v.iter().copied().fold(f64::INFINITY, f64::min),
                v.iter().copied().fold(f64::NEG_INFINITY, f64::max),
            )
        };
        Point { secs: values.iter().map(|v| v.2).sum::<f64>() / n, caches, rmse: stat(|v| v.0), flip: stat(|v| v.1) }
    }
}

/// A chart: its series of (x, point), drawn as RMSE and HDR-FLIP panels side by side.
#[derive(Clone, Debug, PartialEq)]
pub struct Plot {
    /// The title's first part (the panels add the metric).
    pub title: String,
    /// The horizontal axis' label.
    pub x_desc: String,
    /// Whether the horizontal axis is logarithmic (every x must then be positive).
    pub log_x: bool,
    /// Named series of (x, point), in drawing order.
    pub series: Vec<(String, Vec<(f64, Point)>)>,
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
            let values: Vec<(f64, f64, f64)> = mine
                .iter()
                .filter(|r| r.caches == caches && r.placement == placement)
                .map(|r| (r.rmse, r.flip, r.secs))
                .collect();
            points.push(Point::of(caches, &values));
        }
        points.sort_by(|a, b| a.secs.total_cmp(&b.secs));
    }
    out
}

/// Writes the speed–accuracy chart of `scene`'s rows to `path` (SVG) and beside it as PNG.
pub fn write(rows: &[Row], scene: &str, path: &Path) -> Result<()> {
    write_over(rows, scene, path, XAxis::Seconds)
}

/// Writes the chart of `scene`'s rows over `x` to `path` (SVG) and beside it as PNG.
pub fn write_over(rows: &[Row], scene: &str, path: &Path, x: XAxis) -> Result<()> {
    let mut all = series(rows, scene);
    if x == XAxis::Caches {
        all.retain_mut(|(_, points)| {
            points.retain(|p| p.caches > 0);
            points.sort_by_key(|p| p.caches);
            !points.is_empty()
        });
    }
    let plot = Plot {
        title: scene.to_string(),
        x_desc: match x {
            XAxis::Seconds => "wall seconds (log)",
            XAxis::Caches => "caches (log)",
        }
        .into(),
        log_x: true,
        series: all
            .into_iter()
            .map(|(name, points)| {
                let xs = points.into_iter().map(|p| (if x == XAxis::Seconds { p.secs } else { p.caches as f64 }, p));
                (name, xs.collect())
            })
            .collect(),
    };
    save(&plot, path)
}

/// Writes `plot` to `path` as SVG and to the same path with `.png` as PNG; nothing when it has no point.
pub fn save(plot: &Plot, path: &Path) -> Result<()> {
    if plot.series.iter().all(|(_, p)| p.is_empty()) {
        return Ok(());
    }
    font()?;
    save_drawing(plot, (1200, 500), path)
}

/// A figure that can draw itself on any plotters backend (the SVG and the PNG of [`save_drawing`]).
pub trait Drawing {
    /// Draws the figure on `root`.
    fn draw_on<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> std::result::Result<(), String>;
}

impl Drawing for Plot {
    fn draw_on<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> std::result::Result<(), String> {
        draw(self, root)
    }
}

/// Writes `figure` at `size` pixels to `path` as SVG and to the same path with `.png` as PNG (the font must be
/// registered: [`font`]).
pub fn save_drawing(figure: &impl Drawing, size: (u32, u32), path: &Path) -> Result<()> {
    let fail = |e: String| Error::file(path, format!("cannot draw the chart: {e}"));
    {
        let root = SVGBackend::new(path, size).into_drawing_area();
        figure.draw_on(&root).map_err(fail)?;
        root.present().map_err(|e| fail(e.to_string()))?;
    }
    let png = path.with_extension("png");
    let mut buf = vec![0u8; (size.0 * size.1 * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut buf, size).into_drawing_area();
        figure.draw_on(&root).map_err(fail)?;
        root.present().map_err(|e| fail(e.to_string()))?;
    }
    let rgb: Vec<[u8; 3]> = buf.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
    crate::image::write_rgb8_png(size.0 as usize, size.1 as usize, &rgb, &png)
}

/// Draws the two panels of `plot` on `root`.
fn draw<DB: DrawingBackend>(plot: &Plot, root: &DrawingArea<DB, Shift>) -> std::result::Result<(), String> {
    let e = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
    root.fill(&WHITE).map_err(e)?;
    let xs: Vec<f64> = plot.series.iter().flat_map(|(_, p)| p.iter().map(|q| q.0)).collect();
    let pts: Vec<&Point> = plot.series.iter().flat_map(|(_, p)| p.iter().map(|q| &q.1)).collect();
    let (x_lo, x_hi) = xs.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| (a.min(x), b.max(x)));
    type Metric = fn(&Point) -> (f64, f64, f64);
    let metrics: [(&str, Metric); 2] = [("RMSE", |p| p.rmse), ("HDR-FLIP", |p| p.flip)];
    for (panel, (title, metric)) in root.split_evenly((1, 2)).iter().zip(metrics) {
        let hi = pts.iter().map(|p| metric(p).2).fold(0.0f64, f64::max).max(1e-9) * 1.2;
        let lo = pts.iter().map(|p| metric(p).1).filter(|v| *v > 0.0).fold(f64::INFINITY, f64::min).min(hi) * 0.8;
        let mut builder = ChartBuilder::on(panel);
        builder
            .caption(format!("{}: {title} against the reference", plot.title), ("sans-serif", 16))
            .margin(10)
            .x_label_area_size(40)
            .y_label_area_size(60);
        // The two axis kinds have different coordinate types: one body, instantiated twice.
        macro_rules! body {
            ($chart:expr) => {{
                let mut chart = $chart.map_err(e)?;
                chart
                    .configure_mesh()
                    .x_desc(plot.x_desc.as_str())
                    .y_desc(format!("{title} (log)"))
                    .x_label_formatter(&|v| tick(*v))
                    .y_label_formatter(&|v| tick(*v))
                    .draw()
                    .map_err(e)?;
                for (name, points) in &plot.series {
                    // By name, so that a method has one colour in every chart of a report.
                    let colour = colour_of(name);
                    let line: Vec<(f64, f64)> = points.iter().map(|(x, p)| (*x, metric(p).0)).collect();
                    chart
                        .draw_series(LineSeries::new(line.clone(), colour.stroke_width(2)))
                        .map_err(e)?
                        .label(name.as_str())
                        .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], colour.stroke_width(2)));
                    chart.draw_series(line.iter().map(|&p| Circle::new(p, 3, colour.filled()))).map_err(e)?;
                    let bars = points.iter().filter(|(_, p)| metric(p).1 < metric(p).2).map(|(x, p)| {
                        let (_, a, b) = metric(p);
                        PathElement::new(vec![(*x, a.max(lo)), (*x, b)], colour.stroke_width(1))
                    });
                    chart.draw_series(bars).map_err(e)?;
                }
                chart
                    .configure_series_labels()
                    .position(SeriesLabelPosition::UpperRight)
                    .background_style(WHITE.mix(0.8))
                    .border_style(BLACK)
                    .draw()
                    .map_err(e)?;
            }};
        }
        let (labelled, grid) = log_ticks(lo, hi);
        let y = (lo..hi).log_scale().with_key_points(labelled).with_light_points(grid);
        if plot.log_x {
            let (x_lo, x_hi) = (x_lo.max(1e-3) * 0.8, x_hi * 1.25);
            let (labelled, grid) = log_ticks(x_lo, x_hi);
            let x = (x_lo..x_hi).log_scale().with_key_points(labelled).with_light_points(grid);
            body!(builder.build_cartesian_2d(x, y));
        } else {
            let pad = ((x_hi - x_lo) * 0.05).max(1e-6);
            body!(builder.build_cartesian_2d(x_lo - pad..x_hi + pad, y));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(placement: &str, caches: usize, seed: u64, rmse: f64, secs: f64) -> Row {
        Row { scene: "s".into(), placement: placement.into(), caches, seed, rmse, flip: rmse / 10.0, secs }
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
        if let Err(e) = font() {
            eprintln!("skipping the drawing half: {e}");
            return;
        }
        let dir = std::env::temp_dir().join(format!("cachert-chart-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("c.svg");
        write(&rows, "s", &path).unwrap();
        let svg = std::fs::read_to_string(&path).unwrap();
        assert!(svg.contains("<svg") && svg.contains("power") && svg.contains("vgc"));
        let png = crate::image::read(&dir.join("c.png")).unwrap();
        assert_eq!((png.width, png.height), (1200, 500));
        // Not blank: the lines and text darken some pixels.
        assert!(png.pixels.iter().filter(|p| p[0] < 0.5).count() > 1000);
        // Over caches the baseline, which has no budget, is left out.
        write_over(&rows, "s", &path, XAxis::Caches).unwrap();
        let svg = std::fs::read_to_string(&path).unwrap();
        assert!(svg.contains("caches (log)") && svg.contains("vgc") && !svg.contains("power"));
        // A linear axis takes zero (the DGS ratio sweep).
        let p = |r: f64| Point::of(10, &[(r, r / 10.0, 1.0)]);
        let plot = Plot {
            title: "t".into(),
            x_desc: "ratio".into(),
            log_x: false,
            series: vec![("vgc+dgs".into(), vec![(0.0, p(0.3)), (0.15, p(0.2)), (0.5, p(0.25))])],
        };
        save(&plot, &path).unwrap();
        assert!(std::fs::read_to_string(&path).unwrap().contains("ratio"));
        std::fs::remove_dir_all(&dir).ok();
    }
}
