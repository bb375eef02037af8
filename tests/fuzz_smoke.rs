//! A short run of the fuzz harness (`examples/fuzz`) over every reader, with a fixed seed: no panic, hang or
//! memory blow-up may show up. A hang or an allocation over the limit ends the test process (status 3)
//! with the input saved under `target/fuzz-smoke/<target>/findings/`.
#![allow(dead_code)]

#[path = "../examples/fuzz/alloc.rs"]
mod alloc;
#[path = "../examples/fuzz/engine.rs"]
mod engine;
#[path = "../examples/fuzz/mutate.rs"]
mod mutate;
#[path = "../examples/fuzz/targets.rs"]
mod targets;

use std::path::PathBuf;
use std::time::Duration;

#[global_allocator]
static ALLOC: alloc::Counting = alloc::Counting;

/// Seconds per target: five targets, well under a minute in all.
const SECONDS: f64 = 6.0;

#[test]
fn every_reader_survives_a_short_fuzz_run() {
    let root = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("fuzz-smoke");
    let mut problems = Vec::new();
    for target in targets::ALL {
        let out = root.join(target.name());
        let _ = std::fs::remove_dir_all(&out);
        let cfg = engine::Config {
            target,
            seconds: SECONDS,
            max_inputs: Some(20_000),
            seed: 7,
            out: out.clone(),
            timeout: Duration::from_secs(10),
            mem_limit: 1 << 30,
            slow_seed: Duration::from_millis(500),
            progress_every: 0.0,
        };
        let r = engine::run(&cfg).unwrap_or_else(|e| panic!("{}: {e}", out.display()));
        eprintln!(
            "{}: {} inputs in {:.1} s from {} seeds, {} outcome kinds, largest heap growth {:.1} MiB",
            target.name(),
            r.inputs,
            r.secs,
            r.seeds,
            r.outcome_kinds,
            r.max_peak as f64 / (1 << 20) as f64
        );
        assert!(r.seeds > 0, "{}: no seeds", target.name());
        assert!(r.inputs > r.seeds as u64, "{}: no mutated input ran", target.name());
        for (file, msg) in &r.panics {
            problems.push(format!("{}: panic {msg} (input: {})", target.name(), file.display()));
        }
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

#[test]
fn the_signature_of_an_error_is_its_template() {
    let a = engine::signature(&Err("/a/b.pbrt:3:7: unknown shape type \"cone\"; expected one of x".into()));
    let b = engine::signature(&Err("/c.pbrt:1:1: unknown shape type \"ball\"; expected one of x".into()));
    assert_eq!(a, b);
    assert_eq!(engine::signature(&Ok(())), "ok");
}
