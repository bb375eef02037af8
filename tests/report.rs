//! The experiment's outputs (issue 14): a small spec sweep writes the tables of the paper (Table 2 ablation,
//! a swept parameter with defaults and best values, Table 4 timings, the claims), charts as SVG and PNG
//! (error over time with the per-pixel estimator, over caches, over the swept value), and `report.html`,
//! which headless Chromium loads with every picture decoded and no script error. A page with a broken
//! picture is caught by the same check.

mod common;

use std::path::{Path, PathBuf};
use std::process::Command;

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
