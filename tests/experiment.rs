//! Behaviour of the flag form of `cachert experiment`: it builds a spec and runs it as the spec form does,
//! so it writes the one `results.csv` schema and the one set of tables; the error falls with the budget;
//! the per-pixel baselines are measured against the converged image; the reference is reused on a second
//! run and not with other parameters; `--replot` rebuilds the tables and charts from results.csv alone; an
//! importance-caching sweep times both of its many-light baselines; bad flags are usage errors.

mod common;

use std::path::Path;
use std::process::{Command, Output};

use cachert::experiment::jobs::Record;
use cachert::experiment::results::read_csv;

fn cachert(args: &[&str], out: &Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_cachert")).arg("experiment").args(args).arg("--out").arg(out).output().unwrap()
}

fn spheres() -> String {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/spheres.pbrt").display().to_string()
}

/// The flag form's sweep on the spheres: 2 budgets × 2 placements × 2 seeds, with baselines `extra`.
fn sweep(out: &Path, extra: &[&str]) -> Output {
    let scene = spheres();
    let mut args = vec![
        "--scene",
        &scene,
        "--integrator",
        "cacheao",
        "--resolution",
        "48x32",
        "--caches",
        "40,320",
        "--placements",
        "im,vgc+dgs",
        "--seeds",
        "2",
        "--nthreads",
        "2",
    ];
    args.extend_from_slice(extra);
    let o = cachert(&args, out);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    o
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

#[test]
fn the_flag_form_writes_the_one_schema_and_its_tables_and_reuses_the_reference() {
    let dir = common::TempDir::new("experiment");
    let first = sweep(&dir.0, &["--baseline-samples", "1,16"]);
    assert!(stderr(&first).contains("scenes-spheres-cacheao-none:"), "{}", stderr(&first));
    let rows: Vec<Record> = read_csv(&dir.path("results.csv")).unwrap();
    // 2 budgets × 2 placements × 2 seeds, the converged image and two `ao:N` rows.
    assert_eq!(rows.len(), 11, "{rows:#?}");
    let header = std::fs::read_to_string(dir.path("results.csv")).unwrap();
    assert!(header.starts_with("id,status,error,scene,application,placement,method,samples,caches,seed,"), "{header}");
    assert!(rows.iter().all(|r| r.status == "ok" && r.resolution == Some([48, 32])), "{rows:#?}");
    for p in ["im", "vgc+dgs"] {
        let err = |c: usize| rows.iter().filter(|r| r.placement == p && r.caches == c).map(|r| r.rmse).sum::<f64>();
        assert!(err(320) < err(40), "{p}: the error must fall as caches grow");
    }
    // Seed-0 renders and the baselines are also measured against the converged image; more rays, less
    // error.
    for r in &rows {
        assert_eq!(r.rmse_converged.is_some(), r.seed == 0 && r.method != "converged", "{r:#?}");
    }
    let conv = |m: &str| rows.iter().find(|r| r.method == m).and_then(|r| r.rmse_converged).unwrap();
    assert!(conv("ao:16") < conv("ao:1"));
    assert!(dir.path("results.json").is_file() && dir.path("report.html").is_file());
    let tables = std::fs::read_to_string(dir.path("tables.md")).unwrap();
    for t in ["## Which method wins", "## Ratios to IM", "## At equal time", "## Against the converged", "| vgc+dgs |"]
    {
        assert!(tables.contains(t), "{t}: {tables}");
    }

    // `--replot` rebuilds the same tables from results.csv alone, and the charts.
    let svgs: Vec<String> = dir.entries().into_iter().filter(|n| n.ends_with(".svg")).collect();
    assert_eq!(svgs.len(), 2, "{:?}", dir.entries());
    std::fs::remove_file(dir.path("tables.md")).unwrap();
    std::fs::remove_file(dir.path(&svgs[0])).unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_cachert")).args(["experiment", "--replot"]).arg(&dir.0).output().unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(std::fs::read_to_string(dir.path("tables.md")).unwrap(), tables);
    assert!(dir.path(&svgs[0]).is_file());

    // A second sweep reuses the stored reference and converged image.
    let again = sweep(&dir.0, &["--baseline-samples", "1"]);
    assert!(stderr(&again).contains("0 to run"), "{}", stderr(&again));

    // Other parameters (here the ray length) make their own reference and converged image.
    let other = sweep(&dir.0, &["--baseline-samples", "1", "--set", "maxdistance=0.3"]);
    let log = stderr(&other);
    assert!(log.contains("-none-") && log.contains("-converged-"), "{log}");
}

#[test]
fn an_importance_caching_sweep_times_both_many_light_baselines() {
    let dir = common::TempDir::new("experiment-imc");
    let room = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/room.pbrt").display().to_string();
    let args = [
        "--scene",
        &room,
        "--integrator",
        "importancecache",
        "--resolution",
        "24x18",
        "--caches",
        "16",
        "--placements",
        "vgc+dgs",
        "--seeds",
        "1",
        "--set",
        "vpls=64",
        "--baseline-samples",
        "1,8",
    ];
    let o = cachert(&args, &dir.0);
    assert!(o.status.success(), "{}", stderr(&o));
    let rows = read_csv(&dir.path("results.csv")).unwrap();
    let names: Vec<&str> = rows.iter().map(|r| r.method.as_str()).collect();
    assert_eq!(names, ["converged", "power:1", "uniform:1", "power:8", "uniform:8", "vgc+dgs"], "{rows:#?}");
    // Both estimate the reference's sum: more draws, less error against it.
    let err = |m: &str| rows.iter().find(|r| r.method == m).unwrap().rmse;
    assert!(err("power:8") < err("power:1") && err("uniform:8") < err("uniform:1"), "{rows:#?}");
}

#[test]
fn bad_flags_are_usage_errors_and_render_nothing() {
    let dir = common::TempDir::new("experiment-bad");
    let scene = spheres();
    for (args, want) in [
        (vec!["--scene", &scene, "--placements", "im,vgc+foo"], "vgc+foo"),
        (vec!["--scene", &scene, "--placements", "none"], "reference"),
        (vec!["--scene", &scene, "--caches", "0"], "--caches"),
        (vec!["--scene", &scene, "--seeds", "0"], "seeds"),
        (vec!["--scene", &scene, "--integrator", "path"], "not a cache-based integrator"),
        (vec!["--scene", &scene, "--baseline-samples", "x"], "--baseline-samples"),
    ] {
        let o = cachert(&args, &dir.path("out"));
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", stderr(&o));
        assert!(stderr(&o).contains(want) && !stderr(&o).contains("panicked"), "{args:?}: {}", stderr(&o));
    }
    assert!(!dir.path("out").join("runs").exists() || dir.path("out").join("runs").read_dir().unwrap().count() == 0);
}

#[test]
fn replot_refuses_a_bad_results_file_with_its_line_and_column_and_writes_nothing() {
    let dir = common::TempDir::new("replot-bad");
    let head = "id,status,scene,application,placement,method,caches,seed,rmse,flip,total_s";
    dir.write("results.csv", format!("{head}\na,ok,box,cacheao,vgc,vgc,100,0,0.1,zero,2.0\n"));
    let out =
        Command::new(env!("CARGO_BIN_EXE_cachert")).args(["experiment", "--replot"]).arg(&dir.0).output().unwrap();
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("results.csv:2:36: expected flip (a number), found \"zero\""), "{err}");
    assert_eq!(dir.entries(), ["results.csv"], "nothing drawn");
}

#[test]
fn replot_of_a_spec_sweep_draws_one_line_per_application_and_method() {
    // Issue 42: a results folder of a sweep over three applications (each with its own budgets), with a
    // second reference for one of them (a varied parameter of the estimator). Each application gets its
    // own charts with one line per method; the per-pixel runs of the other reference get a chart of
    // their own instead of joining the first reference's line.
    let dir = common::TempDir::new("replot-sweep");
    let mut csv =
        String::from("id,status,scene,application,placement,method,samples,caches,seed,varied,set,rmse,flip,total_s\n");
    let apps = [
        ("cacheao", [10, 20], "", "gather"),
        ("irradiancecache", [30, 60], "gather=16", "gather"),
        ("importancecache", [100, 200], "vpls=64", "draws"),
    ];
    for (app, budgets, set, count) in apps {
        let extra = if app == "importancecache" { "sampling=power;" } else { "" };
        let base = set.split(';').filter(|p| !p.is_empty() && !p.starts_with("gather=")).collect::<Vec<_>>();
        let prefix = if base.is_empty() { String::new() } else { format!("{};", base.join(";")) };
        for seed in 0..2 {
            for n in [1, 2] {
                let pp_set = format!("{prefix}{extra}{count}={n}");
                csv += &format!(
                    "{app}-pp{n}-s{seed},ok,s,{app},none,per-pixel:{n},{n},0,{seed},,{pp_set},0.{n},0.0{n},0.{n}\n"
                );
            }
            for (i, p) in ["im", "vgc"].iter().enumerate() {
                for (j, c) in budgets.iter().enumerate() {
                    let (rmse, secs) = (0.05 + 0.01 * (i + j) as f64, 0.3 + j as f64);
                    csv +=
                        &format!("{app}-{p}-{c}-s{seed},ok,s,{app},{p},{p},,{c},{seed},,{set},{rmse},{rmse},{secs}\n");
                }
            }
        }
    }
    // The second reference of cacheao: per-pixel runs (varied empty, as the sweep writes them) and a swept run.
    csv += "cacheao-pp4-x-s0,ok,s,cacheao,none,per-pixel:4,4,0,0,,maxdistance=0.5;gather=4,0.01,0.001,2.0\n";
    csv += "cacheao-im-10-x-s0,ok,s,cacheao,im,im maxdistance=0.5,,10,0,maxdistance=0.5,maxdistance=0.5,0.2,0.02,0.4\n";
    dir.write("results.csv", &csv);
    let o = Command::new(env!("CARGO_BIN_EXE_cachert")).args(["experiment", "--replot"]).arg(&dir.0).output().unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    let svg = |name: &str| {
        std::fs::read_to_string(dir.path(name)).unwrap_or_else(|_| panic!("no {name} in {:?}", dir.entries()))
    };
    for (app, _, _, _) in apps {
        // Per-pixel (2 counts), im and vgc (2 budgets each): 6 points in each of the two panels, so
        // neither another application's runs nor the other reference's per-pixel run joined a line.
        let time = svg(&format!("s-{app}-error-vs-time.svg"));
        assert_eq!(time.matches("<circle").count(), 12, "{app}");
        let texts: Vec<&str> = time.lines().map(str::trim).collect();
        for label in ["per-pixel", "im", "vgc"] {
            assert_eq!(texts.iter().filter(|t| **t == label).count(), 2, "{app}: {label} in each panel's legend");
        }
        let caches = svg(&format!("s-{app}-error-vs-caches.svg"));
        assert_eq!(caches.matches("<circle").count(), 8, "{app}");
    }
    // The other reference's per-pixel run: its own time chart, named by its setting.
    let other = svg("s-cacheao-maxdistance-0.5-error-vs-time.svg");
    assert_eq!(other.matches("<circle").count(), 2);
    assert!(other.contains("maxdistance-0.5"));
    assert!(dir.path("s-cacheao-10-error-vs-maxdistance.svg").is_file(), "{:?}", dir.entries());
}

#[test]
fn pool_judges_refine_over_the_cells_of_several_sweeps_and_a_later_sweep_replaces_a_cell() {
    // Issue 43's "mean over the cells" spans sweeps of different sizes: --pool reads each folder's
    // results.csv, keeps cells of different sizes apart, and takes a cell measured again from the later folder.
    let dir = common::TempDir::new("pool");
    let head = "id,status,scene,application,placement,method,caches,seed,width,height,rmse,flip,total_s\n";
    let sweep = |name: &str, size: (u32, u32), app: &str, refine: f64| {
        let mut csv = String::from(head);
        for seed in 0..3 {
            let j = seed as f64 * 1e-4;
            for (p, r) in [("im", 1.0), ("sd", 1.1), ("sd+as", 1.2), ("vgc", 1.0), ("vgc+dgs", 1.0), ("refine", refine)]
            {
                let (w, h) = size;
                csv += &format!("{p}-{seed},ok,s,{app},{p},{p},100,{seed},{w},{h},{},{},1.0\n", r + j, r + j);
            }
        }
        std::fs::create_dir_all(dir.path(name)).unwrap();
        std::fs::write(dir.path(name).join("results.csv"), csv).unwrap();
    };
    sweep("a", (160, 90), "cacheao", 0.8);
    sweep("b", (320, 180), "cacheao", 0.7);
    sweep("c", (160, 90), "cacheao", 0.9);
    let run = |dirs: &[&str]| {
        let mut c = Command::new(env!("CARGO_BIN_EXE_cachert"));
        c.arg("experiment");
        for d in dirs {
            c.arg("--pool").arg(dir.path(d));
        }
        c.output().unwrap()
    };
    let o = run(&["a", "b", "c"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let md = String::from_utf8_lossy(&o.stdout);
    assert!(md.contains("| c | s 160x90 cacheao | 100 | im 1.00010 | 0.900+ | 0.900+ | 0.900+ |"), "{md}");
    assert!(md.contains("| b | s 320x180 cacheao | 100 |"), "{md}");
    assert!(!md.contains("| a |"), "a's cell is replaced by c's: {md}");
    assert!(md.contains("| **every cell: 2** | loses 0, wins 2 | 0.800 | 0.800 (loses 0) |"), "{md}");
    // A folder without results is a clear error, and nothing is printed as if pooled.
    let o = run(&["a", "missing"]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("missing") && o.stdout.is_empty(), "{}", stderr(&o));
}
