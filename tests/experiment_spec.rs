//! `cachert experiment SPEC.toml` (issue 14): a sweep from a TOML spec runs every job once, resumes after an
//! interruption without redoing finished runs, records failed runs with their message and carries on,
//! refuses a folder another sweep holds, and gives the same results when its jobs are emitted as command
//! lines, run by a shell (as GNU parallel or a Slurm array would), and collected.

mod common;

use std::path::{Path, PathBuf};
use std::process::Command;

use common::TempDir;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// A spec over the shipped scenes at 40×30: cache AO with two placements and two budgets, irradiance
/// caching with a varied SD minimum size, 2 seeds; `extra` is appended (another scene, say).
fn spec(dir: &TempDir, extra: &str) -> PathBuf {
    let text = format!(
        "resolution = [40, 30]\nseeds = 2\n\
         [[scene]]\nfile = \"{spheres}\"\nname = \"spheres\"\n\
         [[scene]]\nfile = \"{room}\"\nname = \"room\"\n{extra}\
         [[application]]\nname = \"cacheao\"\nplacements = [\"im\", \"vgc+dgs\"]\ncaches = [30, 90]\n\
         [[application]]\nname = \"irradiancecache\"\nplacements = [\"sd\"]\ndensity = [2]\n\
         set = {{ gather = 8 }}\nvary = {{ sdminsize = [5, 50] }}\n",
        spheres = root().join("scenes/spheres.pbrt").display(),
        room = root().join("scenes/room.pbrt").display(),
    );
    dir.write("spec.toml", text)
}

fn cachert(args: &[&str]) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_cachert")).args(args).output().unwrap();
    let s = |b: &[u8]| String::from_utf8_lossy(b).into_owned();
    (out.status.code().unwrap_or(-1), s(&out.stdout), s(&out.stderr))
}

/// The rows of a results.csv as (id → the whole line's fields by column name).
fn rows(path: &Path) -> Vec<std::collections::BTreeMap<String, String>> {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let head: Vec<String> = lines.next().unwrap().split(',').map(str::to_string).collect();
    lines
        .map(|l| {
            // No field of these runs holds a comma (errors are checked separately).
            head.iter().cloned().zip(l.split(',').map(str::to_string)).collect()
        })
        .collect()
}

#[test]
fn a_spec_sweep_runs_resumes_and_matches_its_emitted_jobs() {
    let dir = TempDir::new("spec");
    let spec = spec(&dir, "");
    let (s, out) = (spec.to_str().unwrap(), dir.path("out"));
    let o = out.to_str().unwrap();
    let (code, stdout, stderr) = cachert(&["experiment", s, "--out", o, "--nthreads", "2"]);
    assert_eq!(code, 0, "{stderr}");
    // 4 references (2 scenes × 2 applications; sdminsize only moves caches) and 2·2·2·2 + 2·1·2·2 runs.
    assert!(stderr.contains("28 jobs, 0 done, 28 to run"), "{stderr}");
    let first = rows(&out.join("results.csv"));
    assert_eq!(first.len(), 24);
    assert!(first.iter().all(|r| r["status"] == "ok" && r["rmse"].parse::<f64>().unwrap() > 0.0), "{first:?}");
    let r = first.iter().find(|r| r["application"] == "irradiancecache").unwrap();
    assert!(r["varied"].starts_with("sdminsize=") && r["set"].contains("gather=8"), "{r:?}");
    assert!(r["total_s"].parse::<f64>().unwrap() > 0.0 && r["stage1"].parse::<u64>().unwrap() > 0, "{r:?}");
    for f in [
        "results.json",
        "tables.md",
        "report.html",
        "spheres-cacheao-error-vs-time.svg",
        "spheres-cacheao-error-vs-caches.png",
    ] {
        assert!(out.join(f).is_file(), "{f}");
    }
    assert!(stdout.contains("## Which method wins"), "{stdout}");
    let tables = std::fs::read_to_string(out.join("tables.md")).unwrap();
    assert!(tables.contains("| vgc+dgs | 90 | 2 |"), "{tables}");

    // Run again: nothing to do. Interrupted (one run's files gone): only it runs, to the same numbers.
    let (_, _, stderr) = cachert(&["experiment", s, "--out", o]);
    assert!(stderr.contains("28 jobs, 28 done, 0 to run"), "{stderr}");
    let gone = &first[3]["id"];
    std::fs::remove_file(out.join(format!("runs/{gone}.json"))).unwrap();
    let (code, _, stderr) = cachert(&["experiment", s, "--out", o]);
    assert!(code == 0 && stderr.contains("27 done, 1 to run") && stderr.contains(gone.as_str()), "{stderr}");
    // Same images, so the same errors (the times are the new run's).
    let key = |r: &std::collections::BTreeMap<String, String>| (r["id"].clone(), r["rmse"].clone(), r["flip"].clone());
    let keys = |rs: &[std::collections::BTreeMap<String, String>]| rs.iter().map(key).collect::<Vec<_>>();
    assert_eq!(keys(&rows(&out.join("results.csv"))), keys(&first));

    // Emitted as command lines, run by a shell one after another, collected: the same measurements.
    let (out2, jobs) = (dir.path("out2"), dir.path("jobs.txt"));
    let o2 = out2.to_str().unwrap();
    let (code, stdout, _) = cachert(&["experiment", s, "--out", o2, "--emit-jobs", jobs.to_str().unwrap()]);
    assert!(code == 0 && stdout.contains("wrote 28 jobs"), "{stdout}");
    let lines = std::fs::read_to_string(&jobs).unwrap();
    assert_eq!(lines.lines().count(), 28);
    assert!(lines.lines().all(|l| l.contains(" render ") && l.contains("--stats") && l.contains(" 2> ")), "{lines}");
    let status = Command::new("sh").arg(&jobs).status().unwrap();
    assert!(status.success());
    let (code, _, stderr) = cachert(&["experiment", s, "--out", o2, "--collect"]);
    assert_eq!(code, 0, "{stderr}");
    assert_eq!(keys(&rows(&out2.join("results.csv"))), keys(&first));
    // Jobs already done are not emitted again.
    let (_, stdout, _) = cachert(&["experiment", s, "--out", o2, "--emit-jobs", jobs.to_str().unwrap()]);
    assert!(stdout.contains("wrote 0 jobs of 28"), "{stdout}");
}

#[test]
fn a_failed_run_is_a_row_with_its_message_and_the_sweep_goes_on() {
    let dir = TempDir::new("spec-fail");
    let bad = dir.write("bad.pbrt", "WorldBegin\nShape \"spher\"\nWorldEnd\n");
    let spec = spec(&dir, &format!("[[scene]]\nfile = \"{}\"\nname = \"bad\"\n", bad.display()));
    let out = dir.path("out");
    let (code, _, stderr) = cachert(&["experiment", spec.to_str().unwrap(), "--out", out.to_str().unwrap()]);
    assert_eq!(code, 0, "{stderr}");
    let text = std::fs::read_to_string(out.join("results.csv")).unwrap();
    let failed: Vec<&str> = text.lines().filter(|l| l.contains(",failed,")).collect();
    assert_eq!(failed.len(), 12, "{text}");
    assert!(
        failed.iter().all(|l| l.starts_with("bad-") && l.contains("bad.pbrt:2:7") && l.contains("spher")),
        "{failed:?}"
    );
    assert_eq!(text.lines().filter(|l| l.contains(",ok,")).count(), 24);
    let table = std::fs::read_to_string(out.join("tables.md")).unwrap();
    assert!(
        table.contains("## All runs: bad, cacheao") && table.contains("| im | 30 | 0 | — | — | — | — | 2 |"),
        "{table}"
    );
}

#[test]
fn a_folder_another_sweep_holds_is_refused_a_stale_lock_is_taken_over_and_bad_specs_name_their_line() {
    let dir = TempDir::new("spec-lock");
    let spec = spec(&dir, "");
    let out = dir.path("out");
    std::fs::create_dir_all(&out).unwrap();
    // Held by a running process (this test's own): refused.
    let me = std::process::id().to_string();
    std::fs::write(out.join(".cachert-experiment.lock"), format!("{me}\n")).unwrap();
    let (code, _, stderr) = cachert(&["experiment", spec.to_str().unwrap(), "--out", out.to_str().unwrap()]);
    assert!(code == 2 && stderr.contains("another experiment") && stderr.contains(&me), "{stderr}");
    assert!(!out.join("results.csv").exists());
    // Left by a sweep that was killed (its process is gone): taken over, and the sweep resumes.
    std::fs::write(out.join(".cachert-experiment.lock"), "4000000000\n").unwrap();
    let (code, _, stderr) = cachert(&["experiment", spec.to_str().unwrap(), "--out", out.to_str().unwrap()]);
    assert!(code == 0 && out.join("results.csv").is_file(), "{stderr}");
    assert!(!out.join(".cachert-experiment.lock").exists());
    let bad = dir.write("bad.toml", "resolution = [40, 30]\nseeds = 2\n[[scene]]\nfile = \"x.pbrt\"\nfiel = 1\n");
    let (code, _, stderr) = cachert(&["experiment", bad.to_str().unwrap(), "--out", out.to_str().unwrap()]);
    assert!(code == 2 && stderr.contains("bad.toml:5:") && stderr.contains("fiel"), "{stderr}");
    // A flag the spec already answers is refused, not silently ignored.
    for flag in [
        &["--scene", "x.pbrt"][..],
        &["--caches", "10"],
        &["--seeds", "1"],
        &["--set", "a=1"],
        &["--resolution", "8x8"],
    ] {
        let mut args = vec!["experiment", spec.to_str().unwrap()];
        args.extend_from_slice(flag);
        let (code, _, stderr) = cachert(&args);
        assert!(code == 2 && stderr.contains(flag[0]), "{flag:?}: {stderr}");
    }
}
