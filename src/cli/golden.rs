//! `cachert golden check | update | add`: golden-image regression over a folder with a `MANIFEST.json`
//! (the repository's `golden/` by default, or a user's own with `--dir`).

use std::collections::BTreeMap;
use std::path::PathBuf;

use crate::error::{Error, Result};
use crate::golden::{self, Spec};

use super::Done;

/// Flags of `cachert golden`.
#[derive(clap::Args, Debug, Clone)]
pub struct GoldenArgs {
    /// What to do.
    #[command(subcommand)]
    pub action: Action,
}

/// The folder and the selection, shared by every action.
#[derive(clap::Args, Debug, Clone)]
pub struct Common {
    /// The golden folder (its MANIFEST.json lists the goldens).
    #[arg(long, default_value = "golden")]
    pub dir: PathBuf,
    /// Only the goldens whose name contains PATTERN (with `*`: matches the whole name, `*` any text).
    #[arg(long, value_name = "PATTERN")]
    pub filter: Option<String>,
    /// Worker threads per render (the images do not depend on it).
    #[arg(long)]
    pub nthreads: Option<usize>,
}

/// `golden` actions.
#[derive(clap::Subcommand, Debug, Clone)]
pub enum Action {
    /// Re-render every golden and compare: bit for bit on the platform it was made on (architecture and
    /// system, e.g. x86_64-linux, whatever the CPU model), else within relative RMSE 1e-4 and HDR-FLIP
    /// 0.005; each line names its rule. Exit status 1 when any fails.
    Check {
        /// Folder, filter, threads.
        #[command(flatten)]
        common: Common,
        /// Judge every golden by the tolerance, even one made on this platform (e.g. for a build with other
        /// compiler flags); each line says so.
        #[arg(long)]
        tolerance: bool,
    },
    /// Re-render goldens and rewrite them and the manifest, printing what moved (refused when CI is set,
    /// and when src/, Cargo.toml or Cargo.lock have uncommitted changes unless --allow-dirty).
    Update {
        /// Folder, filter, threads.
        #[command(flatten)]
        common: Common,
        /// Also add the entries of the project's matrix (every placement × application × shipped scene, and
        /// the per-pixel integrators) missing from the manifest; for the repository's golden/ folder.
        #[arg(long)]
        matrix: bool,
        /// Record even from code with uncommitted changes (warned about; the commit is marked -dirty).
        #[arg(long)]
        allow_dirty: bool,
    },
    /// Render a scene and add it as a new golden (refused when CI is set).
    Add(AddArgs),
}

/// Flags of `golden add`: the golden's name and the render, as `cachert render` takes them.
#[derive(clap::Args, Debug, Clone)]
pub struct AddArgs {
    /// The golden folder (created if missing).
    #[arg(long, default_value = "golden")]
    pub dir: PathBuf,
    /// The golden's name (default: the scene's file stem, the integrator and the placement).
    #[arg(long)]
    pub name: Option<String>,
    /// The scene file (stored relative to the golden folder when it is relative).
    pub scene: PathBuf,
    /// The integrator (default: the scene's).
    #[arg(long)]
    pub integrator: Option<String>,
    /// Placement of a cache-based integrator.
    #[arg(long)]
    pub placement: Option<String>,
    /// Cache budget of a cache-based integrator.
    #[arg(long, allow_negative_numbers = true, value_parser = super::parse_caches)]
    pub caches: Option<usize>,
    /// Film resolution WxH.
    #[arg(long, value_parser = super::parse_resolution)]
    pub resolution: Option<[u32; 2]>,
    /// Samples per pixel.
    #[arg(long)]
    pub spp: Option<u32>,
    /// Seed.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Integrator parameter (repeatable), KEY=VALUE.
    #[arg(long = "set", value_name = "KEY=VALUE", value_parser = super::parse_key_value)]
    pub set: Vec<(String, String)>,
    /// Worker threads.
    #[arg(long)]
    pub nthreads: Option<usize>,
    /// Record even from code with uncommitted changes (warned about; the commit is marked -dirty).
    #[arg(long)]
    pub allow_dirty: bool,
}

/// Runs a `golden` action, printing progress lines to stderr.
pub fn run(a: &GoldenArgs) -> Result<Done> {
    match &a.action {
        Action::Check { common: c, tolerance } => {
            let log = &mut |o: &golden::Outcome| eprintln!("{}", o.line());
            let outcomes = golden::check(&c.dir, c.filter.as_deref(), c.nthreads, *tolerance, log)?;
            Ok(summary(&outcomes))
        }
        Action::Update { common: c, matrix, allow_dirty } => {
            let log = &mut |l: &str| eprintln!("{l}");
            let lines = golden::update(&c.dir, c.filter.as_deref(), *matrix, c.nthreads, *allow_dirty, log)?;
            let moved = lines.iter().filter(|l| l.contains(": moved") || l.contains(": new")).count();
            Ok(Done {
                text: format!("updated {} goldens in {} ({moved} new or moved)", lines.len(), c.dir.display()),
                passed: true,
            })
        }
        Action::Add(a) => add(a),
    }
}

/// The report's last lines: counts, and the failures by name.
fn summary(outcomes: &[golden::Outcome]) -> Done {
    let failed: Vec<&golden::Outcome> = outcomes.iter().filter(|o| !o.verdict.passed()).collect();
    let identical = outcomes.iter().filter(|o| o.verdict == golden::Verdict::Identical).count();
    let secs: f64 = outcomes.iter().map(|o| o.secs).sum();
    let bits = outcomes.iter().filter(|o| o.rule == golden::Rule::Bits).count();
    let mut text = format!(
        "{} goldens: {} passed ({identical} identical), {} failed, {secs:.1} s; {bits} judged bit for bit on {}, \
         {} within the tolerance",
        outcomes.len(),
        outcomes.len() - failed.len(),
        failed.len(),
        golden::platform(),
        outcomes.len() - bits
    );
    if !failed.is_empty() {
        text.push_str("\nfailed:");
        for o in &failed {
            text.push_str(&format!("\n  {}", o.line()));
        }
    }
    Done { text, passed: failed.is_empty() }
}

fn add(a: &AddArgs) -> Result<Done> {
    let set: BTreeMap<String, String> = a.set.iter().cloned().collect();
    // The scene as the manifest will resolve it: relative to the golden folder.
    let scene = if a.scene.is_absolute() {
        a.scene.clone()
    } else {
        let cwd = std::env::current_dir().map_err(|e| Error::usage(format!("cannot read the current folder: {e}")))?;
        relative_to(&cwd.join(&a.scene), &cwd.join(&a.dir))
    };
    let integrator = match &a.integrator {
        Some(i) => i.clone(),
        None => crate::scene::load(&a.scene, Default::default())?.integrator.map_or("path".to_string(), |n| n.name),
    };
    let stem = a.scene.file_stem().map_or("scene".into(), |s| s.to_string_lossy().to_string());
    let name = a.name.clone().unwrap_or_else(|| golden::matrix::name(&stem, &integrator, a.placement.as_deref()));
    let spec = Spec {
        scene: scene.to_string_lossy().to_string(),
        integrator,
        placement: a.placement.clone(),
        caches: a.caches,
        resolution: a.resolution,
        spp: a.spp,
        seed: a.seed,
        set,
    };
    let e = golden::check::add(&a.dir, &name, spec, a.nthreads, a.allow_dirty, &mut |l| eprintln!("{l}"))?;
    Ok(Done {
        text: format!("added golden \"{}\" ({}, {:.2} s) to {}", e.name, e.file, e.recorded.secs, a.dir.display()),
        passed: true,
    })
}

/// `path` relative to the folder `base` (both absolute), through `..` where needed.
fn relative_to(path: &std::path::Path, base: &std::path::Path) -> PathBuf {
    fn norm(p: &std::path::Path) -> Vec<std::path::Component<'_>> {
        let mut out = Vec::new();
        for c in p.components() {
            match c {
                std::path::Component::ParentDir => {
                    out.pop();
                }
                std::path::Component::CurDir => {}
                c => out.push(c),
            }
        }
        out
    }
    let (p, b) = (norm(path), norm(base));
    let common = p.iter().zip(&b).take_while(|(x, y)| x == y).count();
    let mut rel = PathBuf::new();
    for _ in common..b.len() {
        rel.push("..");
    }
    for c in &p[common..] {
        rel.push(c.as_os_str());
    }
    rel
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    #[test]
    fn relative_paths_climb_out_of_the_golden_folder() {
        let r = relative_to(Path::new("/a/scenes/s.pbrt"), Path::new("/a/golden"));
        assert_eq!(r, Path::new("../scenes/s.pbrt"));
        let r = relative_to(Path::new("/a/./golden/s.pbrt"), Path::new("/a/golden/"));
        assert_eq!(r, Path::new("s.pbrt"));
        let r = relative_to(Path::new("/a/b/../s.pbrt"), Path::new("/a/g/h"));
        assert_eq!(r, Path::new("../../s.pbrt"));
    }
}
