//! The experiment's outputs (issue 14): a small spec sweep writes the tables of the paper (Table 2 ablation,
//! a swept parameter with defaults and best values, Table 4 timings, the claims), charts as SVG and PNG
//! (error over time with the per-pixel estimator, over caches, over the swept value), and `report.html`,
//! which headless Chromium loads with every picture decoded and no script error. A page with a broken
//! picture is caught by the same check. The report opens with which method wins where (computed from the
//! results) and the charts, then the tables; a table that would be all "—" is left out (issue 42).

mod common;

use std::path::{Path, PathBuf};
use std::process::Command;

use cachert::experiment::report;
use cachert::experiment::results::{parse_csv, write_tables};
use cachert::experiment::spec::Spec;
use cachert::experiment::tables::Table;
use common::TempDir;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn cachert(args: &[&str]) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_cachert")).args(args).output().unwrap();
    let s = |b: &[u8]| String::from_utf8_lossy(b).into_owned();
    (out.status.code().unwrap_or(-1), s(&out.stdout), s(&out.stderr))
}

/// Chromium (or Chrome) from the PATH, or `None` after [`common::unavailable`] (a failure under CI). The test
/// installs nothing: the set-up does (`scripts/install-report-tools.sh`, which `.ci/run` runs first).
fn chromium() -> Option<PathBuf> {
    let found = ["chromium", "chromium-browser", "google-chrome"].iter().find_map(|name| {
        let out = Command::new("sh").arg("-c").arg(format!("command -v {name}")).output().ok()?;
        let path = String::from_utf8_lossy(&out.stdout).trim().to_string();
        (out.status.success() && !path.is_empty()).then(|| PathBuf::from(path))
    });
    if found.is_none() {
        common::unavailable(&format!(
            "the browser check: no chromium, chromium-browser or google-chrome on the PATH (run {} once)",
            root().join("scripts/install-report-tools.sh").display()
        ));
    }
    found
}

/// The page's self-check after headless Chromium has loaded it: the body's `data-check` attribute.
fn browser_check(browser: &Path, page: &Path) -> String {
    let out = Command::new("timeout")
        .args(["120", browser.to_str().unwrap()])
        .args(["--headless", "--no-sandbox", "--disable-gpu", "--virtual-time-budget=10000", "--dump-dom"])
        .arg(format!("file://{}", page.display()))
        .output()
        .unwrap();
    let dom = String::from_utf8_lossy(&out.stdout);
    let at = dom.find("data-check=\"").unwrap_or_else(|| {
        panic!("no data-check in the DOM (status {:?}): {}", out.status, String::from_utf8_lossy(&out.stderr))
    });
    let rest = &dom[at + "data-check=\"".len()..];
    rest[..rest.find('"').unwrap()].to_string()
}

#[test]
fn a_sweep_writes_the_papers_tables_charts_and_a_report_that_loads_in_chromium() {
    let dir = TempDir::new("report");
    let spec = dir.write(
        "spec.toml",
        format!(
            "resolution = [48, 32]\nseeds = 2\n\
             [[scene]]\nfile = \"{}\"\nname = \"spheres\"\n\
             [[application]]\nname = \"cacheao\"\n\
             placements = [\"im\", \"vgc\", \"vgc+as\", \"vgc+dgs\", \"vgc+dgs:diff\", \"vgc+dgs:geom\"]\n\
             caches = [40, 80, 160]\nset = {{ gather = 8 }}\nper_pixel = [1, 2]\n\
             [[application]]\nname = \"cacheao\"\nplacements = [\"vgc+dgs\"]\ncaches = [80]\n\
             set = {{ gather = 8 }}\nvary = {{ ratio = [0, 0.2] }}\n",
            root().join("scenes/spheres.pbrt").display()
        ),
    );
    let out = dir.path("out");
    let (code, stdout, stderr) =
        cachert(&["experiment", spec.to_str().unwrap(), "--out", out.to_str().unwrap(), "--nthreads", "2"]);
    assert_eq!(code, 0, "{stdout}\n{stderr}");
    assert!(stdout.contains("Which method wins"), "{stdout}");

    // The tables.
    let tables = std::fs::read_to_string(out.join("tables.md")).unwrap();
    for needle in [
        "## Which method wins",
        "## DGS ablation (the paper's Table 2): cacheao",
        "| spheres | 80 |",
        "## ratio swept: cacheao, 80 caches",
        "ratio=0 | ratio=0.2 | default | best ratio (RMSE)",
        "## Stage times (the paper's Table 4): spheres, cacheao, 80 caches",
        "placement share | … without G-buffer",
        "| per-pixel:2 | — | 2 |",
    ] {
        assert!(tables.contains(needle), "tables.md lacks {needle:?}:\n{tables}");
    }
    // Per-pixel runs of the same estimator are rows with their sample count and no budget.
    let csv = std::fs::read_to_string(out.join("results.csv")).unwrap();
    let head: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    let col = |name: &str| head.iter().position(|h| *h == name).unwrap();
    let pp: Vec<Vec<&str>> =
        csv.lines().skip(1).map(|l| l.split(',').collect::<Vec<_>>()).filter(|f| f[col("samples")] == "2").collect();
    assert_eq!(pp.len(), 2, "{csv}");
    assert!(
        pp.iter().all(|f| f[col("method")] == "per-pixel:2" && f[col("caches")] == "0" && f[col("status")] == "ok")
    );
    // The per-pixel estimator is the reference's own: more samples, closer to it.
    let rmse = |n: &str| -> f64 {
        csv.lines()
            .skip(1)
            .map(|l| l.split(',').collect::<Vec<_>>())
            .filter(|f| f[col("samples")] == n)
            .map(|f| f[col("rmse")].parse::<f64>().unwrap())
            .sum()
    };
    assert!(rmse("2") < rmse("1") && rmse("2") > 0.0, "per-pixel:1 {} per-pixel:2 {}", rmse("1"), rmse("2"));

    // The charts, as SVG and PNG.
    for stem in
        ["spheres-cacheao-error-vs-time", "spheres-cacheao-error-vs-caches", "spheres-cacheao-80-error-vs-ratio"]
    {
        let svg = std::fs::read_to_string(out.join(format!("{stem}.svg"))).unwrap();
        assert!(svg.contains("<svg"), "{stem}");
        let png = std::fs::read(out.join(format!("{stem}.png"))).unwrap();
        assert!(png.starts_with(b"\x89PNG"), "{stem}");
    }
    let time = std::fs::read_to_string(out.join("spheres-cacheao-error-vs-time.svg")).unwrap();
    assert!(time.contains("per-pixel") && time.contains("vgc+dgs"));

    // The report: self-contained, with every table, chart and group of images.
    let page = out.join("report.html");
    let html = std::fs::read_to_string(&page).unwrap();
    assert!(!html.contains("http://") && !html.contains("https://"), "the page must not reach the network");
    for needle in ["Which method wins", "DGS ablation", "Stage times", "error-vs-ratio", "Images: spheres, cacheao"] {
        assert!(html.contains(needle), "report lacks {needle}");
    }
    assert!(html.contains("HDR-FLIP maps") && html.contains("Cache overlays") && html.contains("Largest errors"));
    // The page opens with who wins and the charts; the tables and images follow.
    let at = |needle: &str| html.find(needle).unwrap_or_else(|| panic!("report lacks {needle}"));
    assert!(at("id=\"summary\"") < at("id=\"charts\"") && at("id=\"charts\"") < at("id=\"tables\""));
    assert!(at("id=\"tables\"") < at("id=\"g0\""));
    // The summary names the method with the lowest mean RMSE at each budget, computed here from results.csv.
    for caches in ["40", "80", "160"] {
        let mut means: Vec<(String, f64)> = Vec::new();
        for f in csv.lines().skip(1).map(|l| l.split(',').collect::<Vec<_>>()) {
            if f[col("caches")] != caches || f[col("placement")] == "none" || !f[col("varied")].is_empty() {
                continue;
            }
            let rmse: f64 = f[col("rmse")].parse().unwrap();
            match means.iter_mut().find(|(m, _)| m == f[col("method")]) {
                Some((_, sum)) => *sum += rmse,
                None => means.push((f[col("method")].to_string(), rmse)),
            }
        }
        let best = means.iter().min_by(|a, b| a.1.total_cmp(&b.1)).unwrap();
        let line = format!("spheres, {caches} caches: lowest RMSE <b>{}</b>", best.0);
        assert!(html[..at("id=\"charts\"")].contains(&line), "the summary lacks {line:?}");
    }
    let images = html.matches("<img").count();
    // 3 charts + the comparer's 2 + reference + 6 × (image, map, overlay) + 2 windows × 7 crops.
    assert_eq!(images, 3 + 2 + 1 + 6 * 3 + 2 * 7, "pictures in the page");

    let Some(browser) = chromium() else { return };
    let check = browser_check(&browser, &page);
    assert_eq!(check, format!("ok images={images} broken= errors="), "the page's own check in Chromium");

    // The check can fail: a picture that does not decode is named.
    let first = html.find("data:image/png;base64,").unwrap() + "data:image/png;base64,".len();
    let mut broken = html.clone();
    broken.replace_range(first..first + 40, &"A".repeat(40));
    let bad = dir.write("broken.html", broken);
    let check = browser_check(&browser, &bad);
    assert!(check.starts_with("fail") && check.contains("reference"), "{check}");
}

/// The page without rendering: records from a results.csv, no run images (so no image sections).
fn page_of(csv: &str, extra: Vec<Table>) -> (String, String) {
    let dir = TempDir::new("report-page");
    let records = parse_csv(Path::new("results.csv"), csv).unwrap();
    let mut tables = cachert::experiment::tables::all(&records);
    tables.extend(extra);
    let spec = Spec { path: PathBuf::from("spec.toml"), jobs: Vec::new() };
    let page = report::write(&spec, &records, &tables, &[], &dir.0).unwrap();
    write_tables(&tables, &dir.path("tables.md")).unwrap();
    (std::fs::read_to_string(page).unwrap(), std::fs::read_to_string(dir.path("tables.md")).unwrap())
}

#[test]
fn the_report_opens_with_the_winners_and_leaves_out_tables_without_data() {
    let mut csv = String::from("id,status,scene,application,placement,method,caches,seed,rmse,flip,total_s\n");
    // At 10 caches vgc has the lower RMSE and im the lower FLIP; at 20 vgc both.
    for (p, caches, rmse, flip) in
        [("im", 10, 0.30, 0.010), ("vgc", 10, 0.20, 0.020), ("im", 20, 0.15, 0.009), ("vgc", 20, 0.10, 0.008)]
    {
        for seed in 0..2 {
            csv += &format!("{p}-{caches}-{seed},ok,room,app,{p},{p},{caches},{seed},{rmse},{flip},1.5\n");
        }
    }
    let dashes = Table {
        title: "Nothing measured here".into(),
        note: String::new(),
        header: vec!["scene".into(), "caches".into(), "IM".into(), "VGC".into()],
        rows: vec![vec!["room".into(), "10".into(), "—".into(), "—".into()]],
    };
    let (html, md) = page_of(&csv, vec![dashes]);
    assert!(html.contains("room, 10 caches: lowest RMSE <b>vgc</b> (0.20000), lowest HDR-FLIP <b>im</b> (0.01000)"));
    assert!(html.contains("room, 20 caches: lowest RMSE <b>vgc</b> (0.10000), lowest HDR-FLIP <b>vgc</b>"));
    assert!(html.contains("lowest RMSE: vgc in 2 of 2 settings; lowest HDR-FLIP: im in 1 of 2 settings, vgc in 1"));
    let at = |needle: &str| html.find(needle).unwrap_or_else(|| panic!("report lacks {needle}"));
    assert!(at("id=\"summary\"") < at("id=\"charts\"") && at("id=\"charts\"") < at("id=\"tables\""));
    // The table of dashes is in neither the report nor tables.md; the measured ones are.
    assert!(!html.contains("Nothing measured here") && !md.contains("Nothing measured here"));
    assert!(html.contains("All runs") && md.contains("## All runs"));
}
