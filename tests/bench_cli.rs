//! `cachert bench` (src/cli/bench.rs) on a scenes folder of its own: `--repeat` times each row that many
//! times and keeps the least CPU time, listing every run; the irradiance-caching comparison refuses it, and
//! `--seeds` (its own) is refused elsewhere.
//! (The comparisons with pbrt-v3 and pbrt-v2 themselves are benchmarks, run by hand: see results/bench.)

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
