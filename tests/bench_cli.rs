//! `cachert bench` (src/experiment/bench/) on a scenes folder of its own: `--repeat` times each row that many
//! times and keeps the least CPU time, listing every run; the irradiance-caching comparison refuses it, and
//! `--seeds` (its own) is refused elsewhere; `cachert bench micro --quick` runs every micro-benchmark on tiny
//! inputs and prints its rows (what it prints about time is not checked).
//! (The comparisons with pbrt-v3 and pbrt-v2 themselves are benchmarks, run by hand: see experiments/notes/bench.md and experiments/results/bench.)

mod common;

use std::process::Command;

use common::{TempDir, header};

#[test]
fn repeat_keeps_the_least_cpu_time_of_every_run_and_lists_them() {
    let dir = TempDir::new("bench-repeat");
    // A lit scene under the name the shading rows look for; its Integrator line is replaced by the bench.
    let scene = format!(
        "{}WorldBegin\nAttributeBegin\nAreaLightSource \"diffuse\" \"rgb L\" [4 4 4]\nShape \"sphere\" \"float radius\" 0.3\n\
         AttributeEnd\nShape \"trianglemesh\" \"point P\" [-5 -5 -1  5 -5 -1  5 5 -1  -5 5 -1] \"integer indices\" [0 1 2 0 2 3]\n\
         WorldEnd\n",
        header(16, 16, 1)
    );
    dir.write("bitterli-cornell-box-v3/ao-ref.pbrt", scene);
    let json = dir.path("rows.json");
    let out = Command::new(env!("CARGO_BIN_EXE_cachert"))
        .args(["bench", "--integrator", "path", "--spp", "2", "--repeat", "3", "--only", "cornell", "--scenes"])
        .arg(&dir.0)
        .arg("--json")
        .arg(&json)
        .output()
        .expect("the binary runs");
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert!(String::from_utf8_lossy(&out.stdout).contains("least of 3 runs"));
    let rows: serde_json::Value = serde_json::from_slice(&std::fs::read(&json).unwrap()).unwrap();
    let row = &rows.as_array().unwrap()[0];
    let runs: Vec<f64> = row["cpu_s_runs"].as_array().unwrap().iter().map(|v| v.as_f64().unwrap()).collect();
    assert_eq!(runs.len(), 3);
    assert_eq!(row["cpu_s"].as_f64().unwrap(), runs.iter().copied().fold(f64::INFINITY, f64::min));
    assert!(row["pbrt_cpu_s_runs"].as_array().unwrap().is_empty() && row["pbrt_cpu_s"].is_null());
}

#[test]
fn the_irradiance_caching_comparison_refuses_repeat() {
    // A scenes folder of its own, so that the refusal, not a missing folder, is what stops it (CI's clone has
    // no ../shared).
    let dir = TempDir::new("bench-repeat-irc");
    let out = Command::new(env!("CARGO_BIN_EXE_cachert"))
        .args(["bench", "--integrator", "irradiancecache", "--pbrt-v2", "/bin/true", "--repeat", "2", "--scenes"])
        .arg(&dir.0)
        .output()
        .expect("the binary runs");
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("--repeat"));
}

#[test]
fn seeds_apply_to_the_irradiance_caching_comparison_only() {
    let dir = TempDir::new("bench-seeds");
    let out = Command::new(env!("CARGO_BIN_EXE_cachert"))
        .args(["bench", "--integrator", "path", "--seeds", "3", "--scenes"])
        .arg(&dir.0)
        .output()
        .expect("the binary runs");
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("--seeds applies to the irradiance-caching comparison"));
}

/// A square of two triangles, as `bitterli-bathroom/models` would hold many.
const QUAD_PLY: &str = "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n\
                        element face 1\nproperty list uchar int vertex_indices\nend_header\n\
                        0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n";

/// `cachert bench micro ARGS… --quick` on a scenes folder holding one tiny bathroom mesh: its stdout.
fn micro(args: &[&str]) -> std::process::Output {
    let dir = TempDir::new("bench-micro");
    dir.write("bitterli-bathroom/models/quad.ply", QUAD_PLY);
    Command::new(env!("CARGO_BIN_EXE_cachert"))
        .args(["bench", "micro"])
        .args(args)
        .args(["--quick", "--scenes"])
        .arg(&dir.0)
        .output()
        .expect("the binary runs")
}

/// The rows of `stdout` that belong to benchmark `name`.
fn rows<'a>(stdout: &'a str, name: &str) -> Vec<&'a str> {
    stdout.lines().filter(|l| l.split_whitespace().next() == Some(name)).collect()
}

#[test]
fn every_micro_benchmark_runs_and_prints_its_rows() {
    let out = micro(&[]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let stdout = String::from_utf8_lossy(&out.stdout);
    for (name, count, figure) in [
        ("flip", 1, "exposures"),
        ("ply", 3, "1 files, 0.0 MB, 2 triangles"),
        ("placement", 7, "added"),
        ("selection", 6, "µs/px"),
        ("parse", 1, "3 directives"),
    ] {
        let rows = rows(&stdout, name);
        assert_eq!(rows.len(), count, "{name}:\n{stdout}");
        assert!(rows.iter().any(|r| r.contains(figure)), "{name}: no \"{figure}\"\n{stdout}");
    }
    assert!(stdout.contains("--quick: tiny workloads"), "{stdout}");
}

#[test]
fn micro_benchmarks_run_only_those_named_and_refuse_unknown_names() {
    let out = micro(&["parse", "flip"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let stdout = String::from_utf8_lossy(&out.stdout);
    let names: Vec<&str> = stdout.lines().skip(1).filter_map(|l| l.split_whitespace().next()).collect();
    assert_eq!(names[..2], ["parse", "flip"], "{stdout}");
    assert!(rows(&stdout, "placement").is_empty() && rows(&stdout, "ply").is_empty(), "{stdout}");

    let out = micro(&["bvh"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("selection"), "the valid names are listed");
}
