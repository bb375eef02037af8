//! The subcommands of the `cachert` binary, as library functions returning the text to print, so tests
//! can call them; `main.rs` only parses flags, prints and maps errors to exit status 2.

pub mod compare;
pub mod convert;
pub mod experiment;
pub mod golden;
pub mod info;
pub mod render;

/// `cachert` — render pbrt-v3 scenes with cache-based algorithms.
#[derive(clap::Parser, Debug)]
#[command(name = "cachert", version, about)]
pub struct Cli {
    /// What to do.
    #[command(subcommand)]
    pub command: Command,
}

/// The subcommands.
#[derive(clap::Subcommand, Debug)]
pub enum Command {
    /// Render a pbrt-v3 scene file.
    Render(render::RenderArgs),
    /// Show what a scene file loads to, or describe an image (.exr, .pfm, .png).
    Info(info::InfoArgs),
    /// Convert an image between EXR, PFM and PNG, optionally scaled by 2^STOPS (`--exposure`).
    Convert(convert::ConvertArgs),
    /// Compare an image with a reference (RMSE, relMSE, HDR-FLIP, LDR-FLIP).
    Compare(compare::CompareArgs),
    /// Time the pbrt-v3 reference scenes against pbrt-v3's own CPU times (`bench micro`: single stages).
    Bench(crate::experiment::bench::BenchArgs),
    /// Sweep placements × budgets × seeds against the per-sample reference (RMSE, HDR-FLIP).
    Experiment(experiment::ExperimentArgs),
    /// Golden-image regression: check, update or add goldens (a folder with a MANIFEST.json).
    Golden(golden::GoldenArgs),
}

/// What a command printed, and whether it succeeded (a failed `golden check` exits with status 1).
#[derive(Debug)]
pub struct Done {
    /// Text for standard output.
    pub text: String,
    /// False for a check that found failures.
    pub passed: bool,
}

impl From<String> for Done {
    fn from(text: String) -> Self {
        Done { text, passed: true }
    }
}

/// Runs a parsed command line; returns what to print on stdout and whether it passed.
pub fn run(cli: &Cli) -> crate::Result<Done> {
    match &cli.command {
        Command::Render(a) => render::run(a).map(Done::from),
        Command::Info(a) => info::run(a).map(Done::from),
        Command::Convert(a) => convert::run(a).map(Done::from),
        Command::Compare(a) => compare::run(a).map(Done::from),
        Command::Bench(a) => crate::experiment::bench::run(a).map(Done::from),
        Command::Experiment(a) => experiment::run(a).map(Done::from),
        Command::Golden(a) => golden::run(a),
    }
}

/// A cache budget from the command line: a whole number of at least 1 (a negative one reaches here, not
/// clap's "use -- to pass -5" tip, which would make it the scene's name).
pub fn parse_caches(s: &str) -> std::result::Result<usize, String> {
    match s.trim().parse::<i128>() {
        Ok(n) if n >= 1 => usize::try_from(n).map_err(|_| format!("{n} caches is more than this machine can address")),
        Ok(n) => Err(format!("the cache budget must be at least 1, got {n}")),
        Err(_) => Err(format!("expected a whole number of caches, got \"{s}\"")),
    }
}

/// Parses a `--target-error E` value: a positive finite relative RMSE, for clap.
pub fn parse_target_error(s: &str) -> std::result::Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(e) if e > 0.0 && e.is_finite() => Ok(e),
        _ => Err(format!("expected a positive relative RMSE such as 0.05, got \"{s}\"")),
    }
}

/// Parses a `--resolution WxH` value (positive integers), for clap.
pub fn parse_resolution(s: &str) -> std::result::Result<[u32; 2], String> {
    let p = |v: &str| v.trim().parse::<u32>().ok().filter(|&v| v > 0);
    match s.split_once(['x', 'X']).map(|(w, h)| (p(w), p(h))) {
        Some((Some(w), Some(h))) => Ok([w, h]),
        _ => Err(format!("expected WxH with positive integers (e.g. 640x360), found \"{s}\"")),
    }
}

/// Parses a `--set KEY=VALUE` value (key and value trimmed; the key not empty), for clap.
pub fn parse_key_value(s: &str) -> std::result::Result<(String, String), String> {
    match s.split_once('=') {
        Some((k, v)) if !k.trim().is_empty() => Ok((k.trim().to_string(), v.trim().to_string())),
        _ => Err(format!("expected KEY=VALUE, found \"{s}\"")),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cache_budgets_are_whole_numbers_of_at_least_one() {
        assert_eq!(parse_caches("700"), Ok(700));
        assert_eq!(parse_caches(" 1 "), Ok(1));
        assert!(parse_caches("-5").unwrap_err().contains("at least 1, got -5"));
        assert!(parse_caches("0").unwrap_err().contains("at least 1"));
        assert!(parse_caches("7.5").unwrap_err().contains("whole number"));
    }
}
