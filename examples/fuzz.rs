//! Fuzz harness for cachert's input readers, on stable Rust (see `examples/fuzz/README.md`).
//!
//! ```text
//! cargo run --release --example fuzz -- --target parse|scene|ply|obj|image --seconds N --seed S --out DIR
//! cargo run --release --example fuzz -- --target ply --replay FILE...
//! ```

#[path = "fuzz/alloc.rs"]
mod alloc;
#[path = "fuzz/engine.rs"]
mod engine;
#[path = "fuzz/mutate.rs"]
mod mutate;
#[path = "fuzz/targets.rs"]
mod targets;

use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Duration;

use targets::Target;

#[global_allocator]
static ALLOC: alloc::Counting = alloc::Counting;

const USAGE: &str = "usage: fuzz --target parse|scene|ply|obj|image [--seconds N] [--inputs N] [--seed S] \
[--out DIR] [--timeout-ms MS] [--mem-limit-mib MIB] [--slow-seed-ms MS] [--replay FILE... [--as PATH]]";

fn main() -> ExitCode {
    match real_main() {
        Ok(code) => code,
        Err(msg) => {
            eprintln!("fuzz: {msg}\n{USAGE}");
            ExitCode::from(2)
        }
    }
}

fn real_main() -> Result<ExitCode, String> {
    let mut args = std::env::args().skip(1);
    let mut target = None;
    let mut cfg_seconds = 60.0;
    let mut max_inputs = None;
    let mut seed = 1u64;
    let mut out = None;
    let mut timeout_ms = 20_000u64;
    let mut mem_mib = 2048usize;
    let mut slow_seed_ms = 500u64;
    let mut replay: Option<Vec<PathBuf>> = None;
    let mut replay_as = None;
    while let Some(a) = args.next() {
        let mut value = |name: &str| args.next().ok_or_else(|| format!("{name} needs a value"));
        let num = |name: &str, v: String| v.parse::<f64>().map_err(|_| format!("{name}: not a number: {v}"));
        match a.as_str() {
            "--target" => {
                let v = value("--target")?;
                target = Some(Target::from_name(&v).ok_or_else(|| format!("unknown target \"{v}\""))?);
            }
            "--seconds" => cfg_seconds = num("--seconds", value("--seconds")?)?,
            "--inputs" => max_inputs = Some(num("--inputs", value("--inputs")?)? as u64),
            "--seed" => seed = num("--seed", value("--seed")?)? as u64,
            "--out" => out = Some(PathBuf::from(value("--out")?)),
            "--timeout-ms" => timeout_ms = num("--timeout-ms", value("--timeout-ms")?)? as u64,
            "--mem-limit-mib" => mem_mib = num("--mem-limit-mib", value("--mem-limit-mib")?)? as usize,
            "--slow-seed-ms" => slow_seed_ms = num("--slow-seed-ms", value("--slow-seed-ms")?)? as u64,
            "--as" => replay_as = Some(PathBuf::from(value("--as")?)),
            "--replay" => replay = Some(Vec::new()),
            "-h" | "--help" => {
                println!("{USAGE}");
                return Ok(ExitCode::SUCCESS);
            }
            other if replay.is_some() && !other.starts_with("--") => {
                if let Some(r) = replay.as_mut() {
                    r.push(PathBuf::from(other));
                }
            }
            other => return Err(format!("unknown argument \"{other}\"")),
        }
    }
    let target = target.ok_or("--target is required")?;
    if let Some(files) = replay {
        engine::replay(target, &files, replay_as.as_deref()).map_err(|e| e.to_string())?;
        return Ok(ExitCode::SUCCESS);
    }
    let out = out.unwrap_or_else(|| PathBuf::from(format!("target/fuzz-out/{}", target.name())));
    let cfg = engine::Config {
        target,
        seconds: cfg_seconds,
        max_inputs,
        seed,
        out,
        timeout: Duration::from_millis(timeout_ms),
        mem_limit: mem_mib << 20,
        slow_seed: Duration::from_millis(slow_seed_ms),
        big_seed: usize::MAX,
        progress_every: 60.0,
    };
    let r = engine::run(&cfg).map_err(|e| format!("{}: {e}", cfg.out.display()))?;
    println!(
        "SUMMARY target={} seed={} seconds={:.0} inputs={} inputs_per_s={:.0} ok={} seeds={} slow_seeds_skipped={} \
         corpus={} outcome_kinds={} panics={} distinct_panics={} max_heap_growth_mib={:.1} slowest_ms={:.0} out={}",
        target.name(),
        seed,
        r.secs,
        r.inputs,
        r.inputs as f64 / r.secs.max(1e-9),
        r.ok,
        r.seeds,
        r.slow_seeds,
        r.corpus,
        r.outcome_kinds,
        r.panic_count,
        r.panics.len(),
        r.max_peak as f64 / (1 << 20) as f64,
        r.slowest.as_secs_f64() * 1e3,
        cfg.out.display()
    );
    Ok(if r.panics.is_empty() { ExitCode::SUCCESS } else { ExitCode::from(1) })
}
