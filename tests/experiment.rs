//! Behaviour of `cachert experiment`: the sweep's rows, files and table on a shipped scene, the error
//! falling with the budget, the per-pixel comparison against the converged image, and the reference being
//! reused on a second run; `--replot` redraws a finished sweep's charts from its results.csv; an
//! importance-caching sweep times both of its many-light baselines.

mod common;

use std::path::Path;

use cachert::experiment::{Sweep, run};
use cachert::integrator::cache::Placement;

fn sweep(out: &Path, baseline_samples: Vec<u32>) -> Sweep {
    Sweep {
        scenes: vec![Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/spheres.pbrt")],
        resolution: Some([48, 32]),
        caches: vec![40, 320],
        integrator: "cacheao".into(),
        placements: vec![Placement::parse("im").unwrap(), Placement::parse("vgc+dgs").unwrap()],
        seeds: 2,
        set: vec![],
        out: out.to_path_buf(),
        threads: Some(2),
        baseline_samples,
    }
}

#[test]
fn a_sweep_writes_every_row_and_its_files_and_reuses_the_reference() {
    let dir = common::TempDir::new("experiment");
    let mut log = Vec::new();
    let (rows, table) = run(&sweep(&dir.0, vec![1, 16]), &mut |l| log.push(l.to_string())).unwrap();
    // 2 budgets × 2 placements × 2 seeds, plus `none` and two `ao:N` rows.
    assert_eq!(rows.len(), 11, "{rows:#?}");
    assert!(log.iter().any(|l| l.contains("reference in")), "{log:?}");
    for p in ["im", "vgc+dgs"] {
        let err = |c: usize| rows.iter().filter(|r| r.placement == p && r.caches == c).map(|r| r.rmse).sum::<f64>();
        assert!(err(320) < err(40), "{p}: the error must fall as caches grow");
    }
    // Seed-0 renders and the per-pixel ones are also measured against the converged image; more rays, less
    // error.
    assert!(rows.iter().all(|r| r.converged.is_some() == (r.seed == 0)), "{rows:#?}");
    let conv = |p: &str| rows.iter().find(|r| r.placement == p).and_then(|r| r.converged).unwrap().0;
    assert!(conv("ao:16") < conv("ao:1"));
    let csv = std::fs::read_to_string(dir.path("results.csv")).unwrap();
    assert_eq!(csv.lines().count(), 12);
    assert!(dir.path("results.json").is_file() && dir.path("scenes-spheres-cacheao-converged.exr").is_file());
    assert!(table.contains("| vgc+dgs |") && table.contains("converged"), "{table}");

    // `--replot` draws the same chart again from results.csv alone (its numbers are rounded there, so the
    // drawing may move by a pixel: the series and the axes are compared, not the bytes).
    let svgs: Vec<String> = dir.entries().into_iter().filter(|n| n.ends_with("-error-vs-time.svg")).collect();
    assert_eq!(svgs.len(), 1, "{:?}", dir.entries());
    let drawn = std::fs::read_to_string(dir.path(&svgs[0])).unwrap();
    std::fs::remove_file(dir.path(&svgs[0])).unwrap();
    let written = cachert::experiment::replot::replot(&dir.0).unwrap();
    assert_eq!(written, vec![dir.path(&svgs[0])]);
    let redrawn = std::fs::read_to_string(&written[0]).unwrap();
    let texts = |svg: &str| -> Vec<String> {
        svg.split("<text")
            .skip(1)
            .map(|t| t.split_once('>').unwrap().1.split('<').next().unwrap().trim().to_string())
            .collect()
    };
    assert_eq!(texts(&drawn), texts(&redrawn), "the same series, ticks and labels");
    let labels = texts(&redrawn);
    assert!(["ao", "im", "vgc+dgs", "wall seconds (log)"].iter().all(|w| labels.iter().any(|t| t == w)), "{labels:?}");

    // A second sweep reuses the stored reference and converged image.
    let mut log = Vec::new();
    run(&sweep(&dir.0, vec![1]), &mut |l| log.push(l.to_string())).unwrap();
    assert!(!log.iter().any(|l| l.contains("reference in") || l.contains("converged per-pixel image")), "{log:?}");

    // Other parameters (here the ray length) make their own reference instead of reusing that one.
    let mut other = sweep(&dir.0, vec![1]);
    other.set = vec![("maxdistance".into(), "0.3".into())];
    let mut log = Vec::new();
    run(&other, &mut |l| log.push(l.to_string())).unwrap();
    assert!(log.iter().any(|l| l.contains("reference in")), "{log:?}");
    assert!(log.iter().any(|l| l.contains("converged per-pixel image")), "{log:?}");
}

#[test]
fn an_importance_caching_sweep_times_both_many_light_baselines() {
    let dir = common::TempDir::new("experiment-imc");
    let s = Sweep {
        scenes: vec![Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/room.pbrt")],
        resolution: Some([24, 18]),
        caches: vec![16],
        integrator: "importancecache".into(),
        placements: vec![Placement::parse("vgc+dgs").unwrap()],
        seeds: 1,
        set: vec![("vpls".into(), "64".into())],
        ..sweep(&dir.0, vec![1, 8])
    };
    let (rows, _) = run(&s, &mut |_| {}).unwrap();
    let names: Vec<&str> = rows.iter().map(|r| r.placement.as_str()).collect();
    assert_eq!(names, ["none", "power:1", "power:8", "uniform:1", "uniform:8", "vgc+dgs"], "{rows:#?}");
    // Both estimate the reference's sum: more draws, less error against it.
    let err = |p: &str| rows.iter().find(|r| r.placement == p).unwrap().rmse;
    assert!(err("power:8") < err("power:1") && err("uniform:8") < err("uniform:1"), "{rows:#?}");
}

#[test]
fn replot_refuses_a_bad_results_file_with_its_line_and_column_and_writes_nothing() {
    let dir = common::TempDir::new("replot-bad");
    dir.write("results.csv", "scene,placement,caches,seed,rmse,flip,total_s\nbox,vgc,100,0,0.1,zero,2.0\n");
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_cachert"))
        .args(["experiment", "--replot"])
        .arg(&dir.0)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("results.csv:2:19: expected the HDR-FLIP (a finite number), found \"zero\""), "{err}");
    assert_eq!(dir.entries(), ["results.csv"], "nothing drawn");
}
