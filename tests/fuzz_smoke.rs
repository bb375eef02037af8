//! A short run of the fuzz harness (`examples/fuzz`) over every reader, with a fixed seed and input count:
//! no panic, hang or memory blow-up may show up. A hang or an allocation over the limit ends the test process
//! (status 3) with the input saved under `target/tmp/fuzz-smoke/<target>/findings/`.
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

/// Inputs per target. The run is bounded by a count, not by time, so that every machine tries the same
/// inputs (the mutation stream is fixed by the seed) and a finding here is a finding everywhere: about
/// 15–22 s for the five targets on the 2-core CI machine.
const INPUTS: u64 = 20_000;

/// The heap one input may grow by, and how long it may run. A few bytes of scene text can legitimately
/// ask for a large mesh: a `loopsubdiv` at its cap (`MAX_SUBDIVIDED_TRIANGLES`, 4M triangles) loads and
/// builds its BVH in 1.34 GB and 6.4 s on the CI machine (an input the time-bounded smoke run of stop 63
/// met; the limit was 1 GiB then). Both limits sit above that worst case; 2 GiB is libFuzzer's default.
const MEM_LIMIT: usize = 2 << 30;
const TIMEOUT_SECONDS: u64 = 30;

/// A safety stop per target on a machine far slower than the CI's; it only shortens the same sequence.
const MAX_SECONDS: f64 = 60.0;

#[test]
fn every_reader_survives_a_short_fuzz_run() {
    let root = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("fuzz-smoke");
    let mut problems = Vec::new();
    for target in targets::ALL {
        let out = root.join(target.name());
        let _ = std::fs::remove_dir_all(&out);
        let cfg = engine::Config {
            target,
            seconds: MAX_SECONDS,
            max_inputs: Some(INPUTS),
            seed: 7,
            out: out.clone(),
            timeout: Duration::from_secs(TIMEOUT_SECONDS),
            mem_limit: MEM_LIMIT,
            // Seeds are left out by heap, not time: the big scenes (sibenik, staircase, buddha; 16–44 MiB
            // each, against under 2 MiB for every other seed) took 0.1–0.6 s per input, near any time limit.
            slow_seed: Duration::from_secs(3600),
            big_seed: 8 << 20,
            progress_every: 0.0,
        };
        let r = engine::run(&cfg).unwrap_or_else(|e| panic!("{}: {e}", out.display()));
        eprintln!(
            "{}: {} inputs in {:.1} s from {} seeds, {} outcome kinds, largest heap growth {:.1} MiB, \
             slowest input {:.0} ms",
            target.name(),
            r.inputs,
            r.secs,
            r.seeds,
            r.outcome_kinds,
            r.max_peak as f64 / (1 << 20) as f64,
            r.slowest.as_secs_f64() * 1e3
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
