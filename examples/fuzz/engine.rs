//! The fuzz loop: pick an input from the corpus, mutate it, write it to `<out>/current.bin`, run the target
//! under `catch_unwind` with a watchdog and the counting allocator, and record what went wrong.
//!
//! Findings go to `<out>/findings/`: `panic-*.bin` (with a `.txt` giving the message; the loop goes on),
//! `hang-*.bin` and `memory-*.bin` (the process exits with status 3 after saving them). An input whose
//! error message is of a kind not seen before (digits, quoted text and paths blanked) joins the corpus: a
//! cheap stand-in for coverage feedback on stable Rust.

use std::collections::{HashMap, HashSet};
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering::Relaxed};
use std::sync::{Mutex, OnceLock};
use std::time::{Duration, Instant};

use super::alloc;
use super::mutate::{Mutator, Rng};
use super::targets::{Seed, Target};

/// How to run.
#[derive(Clone, Debug)]
pub struct Config {
    /// The reader under test.
    pub target: Target,
    /// Stop after this long.
    pub seconds: f64,
    /// Stop after this many inputs (if given).
    pub max_inputs: Option<u64>,
    /// Seed of the mutation stream.
    pub seed: u64,
    /// Where `current.bin`, `findings/` and the scratch folder's name go.
    pub out: PathBuf,
    /// An input running longer than this is a hang.
    pub timeout: Duration,
    /// An input whose allocations would bring the heap this far above where it started is a finding.
    pub mem_limit: usize,
    /// Seeds that take longer than this to run once are left out.
    pub slow_seed: Duration,
    /// Seeds whose heap grows by more than this many bytes while they run are left out. Unlike
    /// `slow_seed`, this picks the same seeds on every machine (allocations do not depend on its speed).
    pub big_seed: usize,
    /// Progress lines every this many seconds (0: none).
    pub progress_every: f64,
}

/// What a run found.
#[derive(Debug, Default)]
pub struct Report {
    /// Inputs executed (seeds included).
    pub inputs: u64,
    /// Seconds spent.
    pub secs: f64,
    /// Seeds used, and left out as slow.
    pub seeds: usize,
    /// Seeds left out because they were slow or big.
    pub slow_seeds: usize,
    /// Corpus size at the end.
    pub corpus: usize,
    /// Distinct outcome kinds seen.
    pub outcome_kinds: usize,
    /// Inputs that returned `Ok`.
    pub ok: u64,
    /// Panics: one entry per distinct location (the saved file and the message).
    pub panics: Vec<(PathBuf, String)>,
    /// Panics in total (duplicates included).
    pub panic_count: u64,
    /// The largest heap growth of one input, bytes.
    pub max_peak: usize,
    /// The longest time one input took.
    pub slowest: Duration,
    /// The heap growth of the input that ran last, bytes.
    pub last_peak: usize,
}

static STARTED_MS: AtomicU64 = AtomicU64::new(0);
static EXECUTED: AtomicU64 = AtomicU64::new(0);
/// The running target's `out` folder (a process may run several targets one after another).
static OUT: Mutex<Option<PathBuf>> = Mutex::new(None);
static PANIC_MSG: Mutex<Option<String>> = Mutex::new(None);

fn clock() -> &'static Instant {
    static T0: OnceLock<Instant> = OnceLock::new();
    T0.get_or_init(Instant::now)
}

fn now_ms() -> u64 {
    clock().elapsed().as_millis() as u64 + 1
}

/// Copies `<out>/current.bin` to `<out>/findings/<kind>-<n>.bin`, writes `why` next to it, and exits.
fn fatal(kind: &str, why: &str) -> ! {
    let n = EXECUTED.load(Relaxed);
    let out = OUT.lock().ok().and_then(|o| o.clone());
    if let Some(out) = out {
        let dir = out.join("findings");
        let _ = std::fs::create_dir_all(&dir);
        let dest = dir.join(format!("{kind}-{n}.bin"));
        let _ = std::fs::copy(out.join("current.bin"), &dest);
        let _ = std::fs::write(dest.with_extension("txt"), why);
        eprintln!("FINDING {kind}: {why}; input saved as {}", dest.display());
    } else {
        eprintln!("FINDING {kind}: {why}");
    }
    eprintln!("fuzz: stopped after {n} inputs");
    std::process::exit(3);
}

fn on_over_limit(size: usize, total: usize) {
    fatal("memory", &format!("an allocation of {size} bytes would bring the heap to {total} bytes, over the limit"));
}

/// Starts the watchdog thread (once per process); it reads the timeout from `TIMEOUT_MS`.
static TIMEOUT_MS: AtomicU64 = AtomicU64::new(5000);

fn start_watchdog() {
    static STARTED: OnceLock<()> = OnceLock::new();
    STARTED.get_or_init(|| {
        std::thread::Builder::new()
            .name("fuzz-watchdog".into())
            .spawn(|| {
                loop {
                    std::thread::sleep(Duration::from_millis(50));
                    let start = STARTED_MS.load(Relaxed);
                    let limit = TIMEOUT_MS.load(Relaxed);
                    if start != 0 && now_ms().saturating_sub(start) > limit {
                        fatal("hang", &format!("an input ran longer than {limit} ms"));
                    }
                }
            })
            .map(drop)
            .unwrap_or_else(|e| eprintln!("fuzz: no watchdog thread: {e}"));
    });
}

/// The kind of an outcome: the error message as a template. Words made only of letters (and a few
/// punctuation marks) are kept; numbers, quoted names, paths and anything else become `_`.
pub fn signature(outcome: &Result<(), String>) -> String {
    let Err(msg) = outcome else { return "ok".into() };
    let mut words: Vec<&str> = Vec::new();
    for word in msg.split_whitespace() {
        let plain = word.len() <= 24
            && word.chars().all(|c| c.is_ascii_alphabetic() || matches!(c, ':' | ',' | ';' | '(' | ')' | '-'));
        let w = if plain { word } else { "_" };
        if !(w == "_" && words.last() == Some(&"_")) {
            words.push(w);
        }
        if words.len() >= 16 {
            break;
        }
    }
    words.join(" ")
}

/// The scratch folder for this process (on tmpfs when there is one).
pub fn scratch_dir(tag: &str) -> PathBuf {
    let base = if Path::new("/dev/shm").is_dir() { PathBuf::from("/dev/shm") } else { std::env::temp_dir() };
    let dir = base.join(format!("cachert-fuzz-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let _ = std::fs::create_dir_all(&dir);
    dir
}

struct Entry {
    data: Vec<u8>,
    seed: usize,
}

/// Runs the fuzz loop as configured.
pub fn run(cfg: &Config) -> std::io::Result<Report> {
    std::fs::create_dir_all(cfg.out.join("findings"))?;
    if let Ok(mut o) = OUT.lock() {
        *o = Some(cfg.out.clone());
    }
    clock();
    TIMEOUT_MS.store(cfg.timeout.as_millis() as u64, Relaxed);
    // A current.bin left by a run that died (a crash the harness could not catch: stack overflow, abort).
    let current = cfg.out.join("current.bin");
    if current.exists() {
        let dest = cfg.out.join("findings").join(format!("died-{}.bin", std::process::id()));
        std::fs::rename(&current, &dest)?;
        eprintln!("fuzz: the previous run died on an input; it is kept as {}", dest.display());
    }
    std::panic::set_hook(Box::new(|info| {
        let loc = info.location().map(|l| format!("{}:{}", l.file(), l.line())).unwrap_or_default();
        let msg = info
            .payload()
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| info.payload().downcast_ref::<String>().cloned())
            .unwrap_or_default();
        if let Ok(mut m) = PANIC_MSG.lock() {
            *m = Some(format!("{loc}\t{msg}"));
        }
    }));
    alloc::set_over_limit_hook(on_over_limit);
    start_watchdog();

    let scratch = scratch_dir(cfg.target.name());
    let all_seeds = cfg.target.seeds(&scratch);
    let mut report = Report::default();
    let mut seeds: Vec<Seed> = Vec::new();
    let mut kinds: HashSet<String> = HashSet::new();
    let mut panic_sites: HashMap<String, u64> = HashMap::new();
    let t0 = Instant::now();

    // Every seed runs once first (findings in seeds count too); slow ones are left out afterwards.
    let mut exec = |input: &[u8], seed: &Seed, report: &mut Report| -> Option<String> {
        if let Err(e) = std::fs::write(&current, input) {
            eprintln!("fuzz: cannot write {}: {e}", current.display());
        }
        if let Ok(mut m) = PANIC_MSG.lock() {
            *m = None;
        }
        let base = alloc::live();
        alloc::set_limit(base.saturating_add(cfg.mem_limit));
        alloc::reset_peak();
        let start = Instant::now();
        STARTED_MS.store(now_ms(), Relaxed);
        let outcome = catch_unwind(AssertUnwindSafe(|| cfg.target.run(input, seed, &scratch)));
        STARTED_MS.store(0, Relaxed);
        let took = start.elapsed();
        alloc::set_limit(usize::MAX);
        report.last_peak = alloc::peak().saturating_sub(base);
        report.max_peak = report.max_peak.max(report.last_peak);
        report.slowest = report.slowest.max(took);
        report.inputs += 1;
        EXECUTED.store(report.inputs, Relaxed);
        match outcome {
            Ok(r) => {
                report.ok += u64::from(r.is_ok());
                Some(signature(&r))
            }
            Err(_) => {
                report.panic_count += 1;
                let msg = PANIC_MSG.lock().ok().and_then(|mut m| m.take()).unwrap_or_default();
                let site = msg.split('\t').next().unwrap_or("").to_string();
                let count = panic_sites.entry(site.clone()).or_default();
                *count += 1;
                if *count == 1 {
                    let n = report.panics.len();
                    let dest = cfg.out.join("findings").join(format!("panic-{n}.bin"));
                    let _ = std::fs::write(&dest, input);
                    let _ = std::fs::write(dest.with_extension("txt"), format!("{msg}\nseed: {}\n", seed.name));
                    eprintln!("FINDING panic at {site}: {msg}; input saved as {}", dest.display());
                    report.panics.push((dest, msg));
                }
                None
            }
        }
    };

    for seed in all_seeds {
        let start = Instant::now();
        let sig = exec(&seed.data, &seed, &mut report);
        if start.elapsed() > cfg.slow_seed || report.last_peak > cfg.big_seed {
            report.slow_seeds += 1;
            continue;
        }
        if let Some(s) = sig {
            kinds.insert(s);
        }
        seeds.push(seed);
    }
    report.seeds = seeds.len();
    if seeds.is_empty() {
        let _ = std::fs::remove_file(&current);
        let _ = std::fs::remove_dir_all(&scratch);
        return Ok(report);
    }
    let mut corpus: Vec<Entry> =
        seeds.iter().enumerate().map(|(i, s)| Entry { data: s.data.clone(), seed: i }).collect();
    let seed_bytes: Vec<&[u8]> = seeds.iter().map(|s| s.data.as_slice()).collect();
    let dict: Vec<&[u8]> = cfg.target.dict().iter().map(|s| s.as_bytes()).collect();
    let mutator = Mutator { others: &seed_bytes, dict: &dict, max_len: cfg.target.max_len() };
    let mut rng = Rng::new(cfg.seed);
    let mut next_progress = cfg.progress_every;
    const MAX_CORPUS: usize = 4000;

    loop {
        let secs = t0.elapsed().as_secs_f64();
        if secs >= cfg.seconds || cfg.max_inputs.is_some_and(|m| report.inputs >= m) {
            break;
        }
        // `touch <out>/STOP` ends a run early, with its summary.
        if report.inputs % 512 == 0 && cfg.out.join("STOP").exists() {
            let _ = std::fs::remove_file(cfg.out.join("STOP"));
            break;
        }
        if cfg.progress_every > 0.0 && secs >= next_progress {
            next_progress += cfg.progress_every;
            eprintln!(
                "[{secs:7.0} s] {}: {} inputs ({:.0}/s), corpus {}, kinds {}, panics {}, \
                 max heap growth {:.1} MiB, slowest {:.0} ms",
                cfg.target.name(),
                report.inputs,
                report.inputs as f64 / secs,
                corpus.len(),
                kinds.len(),
                report.panic_count,
                report.max_peak as f64 / (1 << 20) as f64,
                report.slowest.as_secs_f64() * 1e3
            );
        }
        let pick = rng.below(corpus.len());
        let mut data = corpus[pick].data.clone();
        let origin = corpus[pick].seed;
        mutator.mutate(&mut rng, &mut data);
        if let Some(sig) = exec(&data, &seeds[origin], &mut report)
            && !kinds.contains(&sig)
        {
            kinds.insert(sig);
            if corpus.len() < MAX_CORPUS && data.len() <= 64 << 10 {
                corpus.push(Entry { data, seed: origin });
            }
        }
    }
    report.secs = t0.elapsed().as_secs_f64();
    report.corpus = corpus.len();
    report.outcome_kinds = kinds.len();
    let mut sorted: Vec<&String> = kinds.iter().collect();
    sorted.sort();
    let listing: String = sorted.iter().map(|k| format!("{k}\n")).collect();
    let _ = std::fs::write(cfg.out.join("outcome-kinds.txt"), listing);
    let _ = std::fs::remove_file(&current);
    let _ = std::fs::remove_dir_all(&scratch);
    Ok(report)
}

/// Runs each file in `inputs` through the target once and prints the outcome (for reproducing findings).
pub fn replay(target: Target, inputs: &[PathBuf], seed_path: Option<&Path>) -> std::io::Result<()> {
    let scratch = scratch_dir(&format!("replay-{}", target.name()));
    for file in inputs {
        let data = std::fs::read(file)?;
        let ext = match target {
            Target::Parse | Target::Scene => seed_path.map_or_else(|| file.clone(), Path::to_path_buf),
            Target::Ply => "ply".into(),
            Target::Obj => "obj".into(),
            Target::Image => {
                let is_exr = data.starts_with(&[0x76, 0x2f, 0x31, 0x01]);
                (if is_exr { "exr" } else { "pfm" }).into()
            }
        };
        let seed = Seed { name: file.display().to_string(), path: ext, data: Vec::new() };
        let start = Instant::now();
        let r = target.run(&data, &seed, &scratch);
        println!("{}: {:.3} s: {:?}", file.display(), start.elapsed().as_secs_f64(), r);
    }
    let _ = std::fs::remove_dir_all(&scratch);
    Ok(())
}
