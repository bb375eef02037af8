//! `cachert bench micro [NAME…]`: benchmarks of single stages on fixed inputs, the figures the
//! `#[ignore]`d timing tests used to print. Each prints rows from one run — wall seconds, CPU seconds and a
//! figure of its own (throughput, counts, what a search found) — and asserts nothing about time: the
//! machine is shared and noisy.
//!
//! | name | workload |
//! |---|---|
//! | `flip` | HDR-FLIP of a 1920×1080 generated pattern against a noisy copy |
//! | `ply` | every PLY of `bitterli-bathroom/models` in the scenes folder, read three times (page cache warmed first) |
//! | `placement` | every strategy on the synthetic room at 1920×1080 with 120K caches (DGS and AS with mock masks) |
//! | `selection` | cache selection for 200 rows of the room at 1920×1080, 1 cache per 17 valid pixels: per pixel and in tiles of 2–16 |
//! | `parse` | tokenizing and parsing a generated 20 MB `trianglemesh` |
//!
//! `--quick` shrinks each workload (the PLY files are what the folder holds) so that all of them run in
//! about a second: the smoke test's check that the code paths still run, not a measurement.

use std::fmt::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;

use glam::Vec3A;

use crate::cache::{CacheIndex, LookupParams};
use crate::error::{Error, Result, Warnings};
use crate::metrics::flip;
use crate::metrics::pattern::pattern;
use crate::os::process_cpu_secs;
use crate::placement::synthetic::{MaskOracle, room};
use crate::placement::{AdaptivePlacement, AdaptiveSampling, Discontinuity, ImageUniform, InitialPlacement};
use crate::placement::{PlacementParams, SpatialDirectional, ViewGuided};

/// Flags of `cachert bench micro`.
#[derive(clap::Args, Debug, Clone)]
pub struct MicroArgs {
    /// The benchmarks to run, in this order (default: all).
    #[arg(value_enum)]
    pub names: Vec<Micro>,
    /// Folder holding the shared scenes (`ply` reads `bitterli-bathroom/models/*.ply` there).
    #[arg(long, default_value = "../shared/scenes")]
    pub scenes: PathBuf,
    /// Worker threads of the pool every benchmark runs in (0: all cores).
    #[arg(long, default_value_t = 2)]
    pub nthreads: usize,
    /// Tiny workloads, about a second in all: shows that each benchmark runs; its figures mean nothing.
    #[arg(long)]
    pub quick: bool,
}

/// One micro-benchmark.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum Micro {
    /// HDR-FLIP at 1920×1080.
    Flip,
    /// Reading the bathroom's PLY meshes.
    Ply,
    /// Every placement strategy at 1920×1080 with 120K caches.
    Placement,
    /// Cache selection per pixel and in tiles.
    Selection,
    /// Parsing a 20 MB `trianglemesh`.
    Parse,
}

const ALL: [Micro; 5] = [Micro::Flip, Micro::Ply, Micro::Placement, Micro::Selection, Micro::Parse];

/// One printed row.
#[derive(Clone, Debug)]
struct Row {
    bench: &'static str,
    case: String,
    wall_s: f64,
    cpu_s: f64,
    figure: String,
}

/// Collects rows, printing each to stderr as it is measured (a long run shows progress).
struct Rows(Vec<Row>);

impl Rows {
    /// Runs `f`; returns its result and a row with its wall and CPU seconds, to be completed and pushed.
    fn time<T>(bench: &'static str, case: impl Into<String>, f: impl FnOnce() -> T) -> (T, Row) {
        let (cpu0, t0) = (process_cpu_secs(), Instant::now());
        let out = f();
        let wall_s = t0.elapsed().as_secs_f64();
        let cpu_s = match (cpu0, process_cpu_secs()) {
            (Some(a), Some(b)) => b - a,
            _ => f64::NAN,
        };
        (out, Row { bench, case: case.into(), wall_s, cpu_s, figure: String::new() })
    }

    fn push(&mut self, row: Row, figure: impl Into<String>) {
        let row = Row { figure: figure.into(), ..row };
        eprintln!("{}", format_row(&row));
        self.0.push(row);
    }
}

/// Runs the chosen benchmarks in a pool of `--nthreads` threads and returns their table.
pub fn run(args: &MicroArgs) -> Result<String> {
    let names = if args.names.is_empty() { ALL.to_vec() } else { args.names.clone() };
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(args.nthreads)
        .build()
        .map_err(|e| Error::usage(format!("--nthreads {}: {e}", args.nthreads)))?;
    let threads = pool.current_num_threads();
    let mut rows = Rows(Vec::new());
    pool.install(|| {
        names.iter().try_for_each(|name| match name {
            Micro::Flip => flip_bench(args.quick, &mut rows),
            Micro::Ply => ply_bench(&args.scenes, &mut rows),
            Micro::Placement => placement_bench(args.quick, &mut rows),
            Micro::Selection => {
                selection_bench(args.quick, &mut rows);
                Ok(())
            }
            Micro::Parse => parse_bench(args.quick, &mut rows),
        })
    })?;
    Ok(table(&rows.0, threads, args.quick))
}

/// HDR-FLIP of a noisy pattern against the clean one.
fn flip_bench(quick: bool, rows: &mut Rows) -> Result<()> {
    let (w, h) = if quick { (192, 108) } else { (1920, 1080) };
    let (reference, test) = (pattern(w, h, 1, 0.0), pattern(w, h, 2, 0.2));
    let (hdr, row) =
        Rows::time("flip", format!("HDR-FLIP {w}×{h}"), || flip::hdr_flip_map(&test, &reference, flip::DEFAULT_PPD));
    let hdr = hdr?;
    let e = &hdr.exposures;
    let figure = format!("{} exposures ({:.3} to {:.3}), mean {:.6}", e.count, e.start, e.stop, hdr.map.mean());
    rows.push(row, figure);
    Ok(())
}

/// The `.ply` files of `dir`, sorted.
fn plys_in(dir: &Path) -> Result<Vec<PathBuf>> {
    let entries = std::fs::read_dir(dir)
        .map_err(|e| Error::file(dir, format!("{e} (the ply benchmark reads the bathroom's meshes; pass --scenes)")))?;
    let mut files = Vec::new();
    for entry in entries {
        let path = entry.map_err(|e| Error::file(dir, e.to_string()))?.path();
        if path.extension().is_some_and(|e| e == "ply") {
            files.push(path);
        }
    }
    files.sort();
    Ok(files)
}

/// Reads every PLY of the bathroom three times, after reading the bytes once to warm the page cache.
fn ply_bench(scenes: &Path, rows: &mut Rows) -> Result<()> {
    let files = plys_in(&scenes.join("bitterli-bathroom/models"))?;
    let mut bytes = 0;
    for f in &files {
        bytes += std::fs::read(f).map_err(|e| Error::file(f, e.to_string()))?.len();
    }
    for pass in 1..=3 {
        let (triangles, row) = Rows::time("ply", format!("bathroom models, pass {pass}"), || {
            files.iter().map(|f| Ok(read_ply_quietly(f)?.triangle_count())).sum::<Result<usize>>()
        });
        let figure = format!(
            "{} files, {:.1} MB, {} triangles: {:.1} MB/s",
            files.len(),
            bytes as f64 / 1e6,
            triangles?,
            bytes as f64 / 1e6 / row.wall_s
        );
        rows.push(row, figure);
    }
    Ok(())
}

fn read_ply_quietly(f: &Path) -> Result<crate::scene::shapes::mesh_data::MeshData> {
    crate::scene::shapes::ply::read_ply(f, &mut Warnings::default())
}

/// A cache count as the rows name it: 120K, or the count itself below 10 000.
fn count(n: usize) -> String {
    if n >= 10_000 { format!("{}K", n / 1000) } else { n.to_string() }
}

/// Every strategy on the synthetic room: the three first stages at the whole budget, then VGC at the
/// two-stage share followed by DGS and by AS with the rest (mock visibility masks as their records).
fn placement_bench(quick: bool, rows: &mut Rows) -> Result<()> {
    let ((w, h), total) = if quick { ((192, 108), 1200) } else { ((1920, 1080), 120_000) };
    let (g, row) = Rows::time("placement", format!("G-buffer (synthetic room {w}×{h})"), || room(w, h));
    let (lo, hi) = g.depth_range;
    rows.push(row, format!("{} valid pixels, depth {lo:.2}–{hi:.2} m", g.valid_count));
    let p = PlacementParams::default();
    let n1 = ((1.0 - p.ratio as f64) * total as f64).round() as usize;
    let (n, n2) = (count(total), count(total - n1));

    let (im, row) = Rows::time("placement", format!("IM {n}"), || ImageUniform.place(&g, total, &p, 1));
    rows.push(row, format!("{} sites", im?.sites.len()));
    let (sd, row) =
        Rows::time("placement", format!("SD {n} (T search)"), || SpatialDirectional.place(&g, total, &p, 1));
    let i = sd?.info;
    let figure =
        format!("T = {:?}, {} iterations, {} clusters found", i.sd_threshold, i.search_iterations, i.clusters_found);
    rows.push(row, figure);
    let (vgc, row) =
        Rows::time("placement", format!("VGC {n} (σ_s search)"), || ViewGuided::default().place(&g, total, &p, 1));
    let i = vgc?.info;
    let figure = format!(
        "σ_s = {:?}, σ_a = {:?}, {} iterations, {} clusters found",
        i.sigma_s, i.sigma_a_deg, i.search_iterations, i.clusters_found
    );
    rows.push(row, figure);
    let (vgc1, row) = Rows::time("placement", format!("VGC {} (two-stage share)", count(n1)), || {
        ViewGuided { two_stage: true }.place(&g, n1, &p, 1)
    });
    let vgc1 = vgc1?;
    rows.push(row, format!("{} sites", vgc1.sites.len()));
    let mut oracle = MaskOracle::new(&g, &vgc1.sites);
    let (dgs, row) = Rows::time("placement", format!("DGS {n2} (map + draws, mock masks)"), || {
        Discontinuity::default().place(&g, &vgc1, &mut oracle, total - n1, &p, 1)
    });
    rows.push(row, format!("{} added", dgs?.added));
    let mut oracle = MaskOracle::new(&g, &vgc1.sites);
    let (adaptive, row) = Rows::time("placement", format!("AS {n2} after VGC (mock masks)"), || {
        AdaptiveSampling.place(&g, &vgc1, &mut oracle, total - n1, &p, 1)
    });
    let adaptive = adaptive?;
    rows.push(row, format!("{} added, {} rounds", adaptive.added, adaptive.rounds));
    Ok(())
}

/// Cache selection over the first rows of the room, one query per valid pixel and then in square tiles
/// (`select_group`); each figure is µs per pixel of those rows, with the count of neighbours returned.
fn selection_bench(quick: bool, rows: &mut Rows) {
    let ((w, h), nrows) = if quick { ((192, 108), 16) } else { ((1920, 1080), 200) };
    let g = room(w, h);
    let valid: Vec<(Vec3A, Vec3A)> = g.points.iter().flatten().map(|sp| (sp.p, sp.n)).collect();
    let caches: Vec<(Vec3A, Vec3A)> = valid.iter().step_by(17).copied().collect();
    let (index, row) = Rows::time("selection", format!("index (1 in 17 valid pixels, {w}×{h})"), || {
        CacheIndex::new(&caches, LookupParams::default(), 0.5 / 24.0)
    });
    rows.push(row, format!("{} caches", index.len()));
    let per_px = |secs: f64| secs * 1e6 / (nrows * w) as f64;

    let (sum, row) = Rows::time("selection", format!("single, {nrows} rows"), || {
        let (mut out, mut sum) = (Vec::new(), 0usize);
        for sp in g.points[..nrows * w].iter().flatten() {
            index.select(sp.p, sp.n, &mut out);
            sum += out.len();
        }
        sum
    });
    let figure = format!("{:.3} µs/px ({sum} neighbours)", per_px(row.wall_s));
    rows.push(row, figure);
    for tile in [2usize, 4, 8, 16] {
        let (sum, row) = Rows::time("selection", format!("tile {tile}×{tile}, {nrows} rows"), || {
            let (mut q, mut sum) = (Vec::new(), 0usize);
            for ty in (0..nrows).step_by(tile) {
                for tx in (0..w).step_by(tile) {
                    q.clear();
                    for y in ty..ty + tile {
                        q.extend(g.points[y * w + tx..y * w + tx + tile].iter().flatten().map(|sp| (sp.p, sp.n)));
                    }
                    index.select_group(&q, |_, o| sum += o.len());
                }
            }
            sum
        });
        let figure = format!("{:.3} µs/px ({sum} neighbours)", per_px(row.wall_s));
        rows.push(row, figure);
    }
}

/// A `trianglemesh` whose text is `points_bytes` of `point3 P` and then indices up to `total_bytes`.
fn mesh_text(points_bytes: usize, total_bytes: usize) -> String {
    let mut text = String::from("WorldBegin\nShape \"trianglemesh\"\n  \"point3 P\" [\n");
    let mut i = 0u64;
    while text.len() < points_bytes {
        let v = |k: u64| (k.wrapping_mul(2654435761) % 200_000) as f64 / 1000.0 - 100.0;
        let _ = writeln!(text, "    {:.6} {:.6} {:.6}", v(i), v(i + 1), v(i + 2));
        i += 3;
    }
    text.push_str("  ]\n  \"integer indices\" [\n");
    let n = i / 3;
    let mut k = 0;
    while text.len() < total_bytes {
        let _ = writeln!(text, "    {} {} {}", k % n, (k + 1) % n, (k + 2) % n);
        k += 1;
    }
    text.push_str("  ]\nWorldEnd\n");
    text
}

/// Parses a generated 20 MB `trianglemesh` (14 MB of points, the rest indices).
fn parse_bench(quick: bool, rows: &mut Rows) -> Result<()> {
    let text = if quick { mesh_text(140_000, 200_000) } else { mesh_text(14_000_000, 20_000_000) };
    let mb = text.len() as f64 / 1e6;
    let (ds, row) = Rows::time("parse", format!("trianglemesh, {mb:.1} MB"), || {
        crate::parse::parse_str(&text, Path::new("speed.pbrt"))
    });
    let figure = format!("{} directives: {:.1} MB/s", ds?.len(), mb / row.wall_s);
    rows.push(row, figure);
    Ok(())
}

fn format_row(r: &Row) -> String {
    format!("{:<10} {:<40} {:>8.3} {:>8.2}  {}", r.bench, r.case, r.wall_s, r.cpu_s, r.figure)
}

fn table(rows: &[Row], threads: usize, quick: bool) -> String {
    let mut out = format!("{:<10} {:<40} {:>8} {:>8}  figure\n", "bench", "case", "wall s", "cpu s");
    for r in rows {
        let _ = writeln!(out, "{}", format_row(r));
    }
    let _ = write!(out, "one run of each row on a pool of {threads} threads; nothing is asserted about time");
    if quick {
        out.push_str("; --quick: tiny workloads, the figures mean nothing");
    }
    out
}
