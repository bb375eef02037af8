//! A sweep described in a TOML file (`cachert experiment SPEC.toml`): scenes × applications × placements ×
//! cache budgets × parameter values × seeds at one resolution, expanded into independent [`Job`]s. The flag
//! form (`cachert experiment --scene … --caches …`) builds the same [`SpecFile`] from its flags and runs it
//! the same way: one set of jobs, one `results.csv` schema, one table writer.
//!
//! ```toml
//! resolution = [160, 90]         # optional: default each scene's own (then caches, not density)
//! seeds = 3
//!
//! [[scene]]
//! file = "../../shared/scenes/mcguire-sibenik-geometry/sibenik.pbrt"   # relative to this file
//! name = "sibenik"                                                      # optional
//!
//! [[application]]
//! name = "…"                   # a cache-based integrator of the application registry
//! placements = ["im", "sd", "sd+as", "vgc", "vgc+dgs"]
//! density = [0.5, 1, 2]          # × the paper's density for the application; or caches = [417, 833]
//! set = { maxdistance = 0.5 }    # parameters of every run (and of the reference)
//! vary = { sdminsize = [1, 10, 100] }   # swept: every combination, with every placement
//! scenes = ["sibenik"]           # optional: only these scenes (default: all)
//! per_pixel = [1, 2, 4]          # optional: the application's own estimator per pixel at these counts
//! baselines = [4, 16, 64]        # optional: the application's per-pixel baselines (see below)
//! ```
//!
//! `baselines` (the flag form's `--baseline-samples`) renders, once per reference and at seed 0, each of the
//! application's per-pixel baselines (`Application::baselines`: pbrt-v3's `ambientocclusion` for AO, power
//! and uniform VPL sampling for importance caching) at N rays (or draws) per pixel sample × 4 pixel samples,
//! box-filtered — rows `ao:N`, `power:N`, `uniform:N` — and the first baseline converged (64 × 64, row
//! `converged`). Every baseline row and every seed-0 run is also measured against that converged image
//! (columns `rmse_converged`, `flip_converged`). These jobs render in the sweep's own process only (not
//! with `--emit-jobs`). `per_pixel`, by contrast, runs the application's own estimator, so it converges to
//! the reference by construction.
//!
//! Depends on the application and placement registries (names, paper budgets) and on `toml`; it renders
//! nothing.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde::Deserialize;

use crate::application::{PerSample, registry};
use crate::error::{Error, Result, SourceLoc};
use crate::integrator::cache::Placement;
use crate::integrator::cache::settings::PAPER_PIXELS;

/// A parameter value as written: a string, a number or a boolean (passed on as `--set KEY=VALUE`).
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(untagged)]
pub enum Value {
    /// `"cone"`.
    Text(String),
    /// `10`.
    Int(i64),
    /// `0.5`.
    Float(f64),
    /// `true`.
    Bool(bool),
}

impl Value {
    /// The value as `--set` takes it.
    pub fn text(&self) -> String {
        match self {
            Value::Text(s) => s.clone(),
            Value::Int(i) => i.to_string(),
            Value::Float(f) => f.to_string(),
            Value::Bool(b) => b.to_string(),
        }
    }
}

/// One `[[scene]]`.
#[derive(Clone, Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneSpec {
    /// The scene file, relative to the spec's folder (or absolute).
    pub file: String,
    /// Its name in tables and charts (default: the folder and the file stem, `dir-stem`).
    pub name: Option<String>,
}

/// One `[[application]]`.
#[derive(Clone, Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AppSpec {
    /// A cache-based integrator of the application registry.
    pub name: String,
    /// Placement names (never `none`: every sweep has the reference).
    pub placements: Vec<String>,
    /// Budgets (or `density`).
    pub caches: Option<Vec<usize>>,
    /// Factors of the paper's density (or `caches`).
    pub density: Option<Vec<f64>>,
    /// Parameters of every run and of the reference.
    #[serde(default)]
    pub set: BTreeMap<String, Value>,
    /// Parameters swept: every combination, with every placement.
    #[serde(default)]
    pub vary: BTreeMap<String, Vec<Value>>,
    /// Only these scenes (default: all).
    pub scenes: Option<Vec<String>>,
    /// The application's own estimator per pixel at these counts, every seed.
    #[serde(default)]
    pub per_pixel: Vec<u32>,
    /// The application's per-pixel baselines at these ray (or draw) counts per pixel sample, seed 0, and
    /// their converged image.
    #[serde(default)]
    pub baselines: Vec<u32>,
}

/// A spec as data: what a spec file holds, or what the flag form of `cachert experiment` builds.
#[derive(Clone, Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SpecFile {
    /// Film resolution of every run; `None`: each scene's own.
    pub resolution: Option<[u32; 2]>,
    /// Seeds 0..seeds.
    #[serde(default = "one")]
    pub seeds: u64,
    /// The scenes.
    pub scene: Vec<SceneSpec>,
    /// The applications with their sweeps.
    pub application: Vec<AppSpec>,
}

fn one() -> u64 {
    1
}

/// What a per-pixel baseline job renders (`baselines = [...]`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BaselineRun {
    /// The first baseline converged (64 pixel samples × 64 rays), once per reference: the second
    /// reference the seed-0 runs are measured against (columns `rmse_converged`, `flip_converged`).
    Converged,
    /// Every baseline of the application at N rays (or draws) per pixel sample × 4 pixel samples.
    Rays(u32),
}

/// What one job renders: the arguments of one `cachert render` run.
#[derive(Clone, Debug, PartialEq)]
pub struct Job {
    /// Unique, file-safe id: the stem of its files under `runs/`.
    pub id: String,
    /// Scene name (for tables and charts).
    pub scene: String,
    /// Scene file.
    pub file: PathBuf,
    /// The cache-based integrator.
    pub application: String,
    /// `none` for the reference job.
    pub placement: String,
    /// Budget (1 for the reference).
    pub caches: usize,
    /// Seed.
    pub seed: u64,
    /// Film resolution (`None`: the scene's own).
    pub resolution: Option<[u32; 2]>,
    /// Every `--set` pair: the application's fixed ones, then the varied ones.
    pub set: Vec<(String, String)>,
    /// The varied pairs alone, `k=v;…` (empty without `vary`).
    pub varied: String,
    /// The id of the reference job this run is measured against (its own id for a reference).
    pub reference: String,
    /// For a per-pixel run of the application's own estimator (placement `none`): its sample count.
    pub samples: Option<u32>,
    /// For a run of the application's per-pixel baselines (placement `none`): which.
    pub baseline: Option<BaselineRun>,
}

impl Job {
    /// Whether this is a reference job.
    pub fn is_reference(&self) -> bool {
        self.id == self.reference
    }

    /// The label of its method in tables and charts: the placement and the varied parameters, or
    /// `per-pixel:N` for a per-pixel run.
    pub fn method(&self) -> String {
        match (self.baseline, self.samples) {
            (Some(BaselineRun::Converged), _) => CONVERGED.to_string(),
            (Some(BaselineRun::Rays(n)), _) => format!("{BASELINES}:{n}"),
            (None, Some(n)) => format!("{PER_PIXEL}:{n}"),
            (None, None) if self.varied.is_empty() => self.placement.clone(),
            (None, None) => format!("{} {}", self.placement, self.varied.replace(';', " ")),
        }
    }
}

/// The method label of per-pixel runs (`per-pixel:N`).
pub const PER_PIXEL: &str = "per-pixel";

/// The method label of a baseline job before it ran (`baselines:N`); each of its records is labelled by
/// its baseline (`ao:N`, `power:N`, `uniform:N`).
pub const BASELINES: &str = "baselines";

/// The method label of the converged per-pixel image.
pub const CONVERGED: &str = "converged";

/// A parsed spec: its jobs, references first.
#[derive(Clone, Debug)]
pub struct Spec {
    /// The spec file.
    pub path: PathBuf,
    /// Every job: the references, then the runs in sweep order.
    pub jobs: Vec<Job>,
}

/// Reads and expands a spec file. Errors carry the file and, for malformed TOML or a bad value, the line
/// and column.
pub fn read(path: &Path) -> Result<Spec> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::file(path, format!("cannot read: {e}")))?;
    parse(&text, path)
}

/// The location of byte `offset` of `text` in `path`.
fn at(path: &Path, text: &str, offset: usize) -> SourceLoc {
    SourceLoc::from_offset(path.into(), text, offset)
}

/// Parses spec text (paths relative to `path`'s folder).
pub fn parse(text: &str, path: &Path) -> Result<Spec> {
    let file: SpecFile = toml::from_str(text).map_err(|e| {
        let offset = e.span().map_or(0, |s| s.start);
        Error::at(&at(path, text, offset), format!("experiment spec: {}", e.message()))
    })?;
    // Errors about a value: located at its first mention in the file.
    let near = |needle: &str, msg: String| {
        let offset = text.find(needle).unwrap_or(0);
        Error::at(&at(path, text, offset), format!("experiment spec: {msg}"))
    };
    expand(&file, path, &near)
}

/// Expands a spec into its jobs: scene paths relative to `path`'s folder; `near(needle, message)` makes
/// the error of a bad value (located at `needle` in a spec file; a usage error for the flag form).
pub fn expand(file: &SpecFile, path: &Path, near: &dyn Fn(&str, String) -> Error) -> Result<Spec> {
    if file.resolution.is_some_and(|r| r.contains(&0)) {
        return Err(near("resolution", "resolution must be two positive integers".into()));
    }
    if file.seeds == 0 {
        return Err(near("seeds", "seeds must be at least 1".into()));
    }
    if file.scene.is_empty() || file.application.is_empty() {
        return Err(near("", "needs at least one [[scene]] and one [[application]]".into()));
    }
    let scenes = scenes_of(file, path, near)?;
    let mut refs = Vec::new();
    let mut runs = Vec::new();
    for a in &file.application {
        let plan = Plan::of(file, a, &scenes, near)?;
        for (scene, file_path) in &scenes {
            if a.scenes.as_ref().is_some_and(|names| !names.contains(scene)) {
                continue;
            }
            // The reference depends on the application and the parameters of every run that are not
            // placement-only; a varied parameter that changes the reference gets one reference per value.
            for combo in &plan.combos {
                let mut set = plan.fixed.clone();
                set.extend(combo.iter().cloned());
                let ref_set = ref_set_of(&set);
                let ref_id = format!("{scene}-{}-none{}", a.name, super::variant(&ref_set));
                // The reference; every other job of this scene and combination starts from it.
                let reference = Job {
                    id: ref_id.clone(),
                    scene: scene.clone(),
                    file: file_path.clone(),
                    application: a.name.clone(),
                    placement: Placement::REFERENCE.to_string(),
                    caches: 1,
                    seed: 0,
                    resolution: file.resolution,
                    set: ref_set,
                    varied: String::new(),
                    reference: ref_id.clone(),
                    samples: None,
                    baseline: None,
                };
                if !refs.iter().any(|j: &Job| j.id == ref_id) {
                    runs.extend(per_pixel_jobs(a, &plan, &reference, file.seeds));
                    refs.push(reference.clone());
                }
                let varied: String = combo.iter().map(|(k, v)| format!("{k}={v};")).collect();
                for &caches in &plan.budgets {
                    for p in &plan.placements {
                        for seed in 0..file.seeds {
                            let tag = p.replace([':', '+'], "_");
                            let vary_tag = if combo.is_empty() {
                                String::new()
                            } else {
                                super::tag(&combo.iter().collect::<Vec<_>>())
                            };
                            runs.push(Job {
                                id: format!("{scene}-{}-{tag}-{caches}{vary_tag}-s{seed}", a.name),
                                placement: p.clone(),
                                caches,
                                seed,
                                set: set.clone(),
                                varied: varied.trim_end_matches(';').to_string(),
                                ..reference.clone()
                            });
                        }
                    }
                }
            }
        }
    }
    let mut jobs = refs;
    jobs.extend(runs);
    let mut ids = std::collections::HashSet::new();
    if let Some(dup) = jobs.iter().find(|j| !ids.insert(j.id.as_str())) {
        return Err(near("", format!("two runs have the id \"{}\" (repeated values?)", dup.id)));
    }
    Ok(Spec { path: path.to_path_buf(), jobs })
}

/// The spec's scenes as (name, file), files relative to the spec's folder; names checked and unique.
fn scenes_of(file: &SpecFile, path: &Path, near: &dyn Fn(&str, String) -> Error) -> Result<Vec<(String, PathBuf)>> {
    let dir = path.parent().unwrap_or(Path::new("."));
    let mut scenes: Vec<(String, PathBuf)> = Vec::new();
    for s in &file.scene {
        let p = Path::new(&s.file);
        let full = if p.is_absolute() { p.to_path_buf() } else { dir.join(p) };
        let name = s.name.clone().unwrap_or_else(|| super::name_of(&full));
        if name.is_empty() || !name.chars().all(|c| c.is_ascii_alphanumeric() || "-_.".contains(c)) {
            return Err(near(&s.file, format!("scene name \"{name}\" must be letters, digits, - _ .")));
        }
        if scenes.iter().any(|(n, _)| *n == name) {
            return Err(near(&s.file, format!("two scenes are named \"{name}\" (set name = …)")));
        }
        scenes.push((name, full));
    }
    Ok(scenes)
}

/// One `[[application]]` checked and resolved: what its jobs are made of.
struct Plan {
    /// Its placements, as written (`none` refused: every sweep has the reference).
    placements: Vec<String>,
    /// Its budgets: `caches`, or `density` × the paper's budget scaled to the resolution.
    budgets: Vec<usize>,
    /// The parameters of every run (`set`).
    fixed: Vec<(String, String)>,
    /// Every combination of the `vary` values (one empty combination without `vary`).
    combos: Vec<Vec<(String, String)>>,
    /// The application's own estimator per pixel, when `per_pixel` asks for it.
    per_sample: Option<PerSample>,
}

impl Plan {
    fn of(
        file: &SpecFile,
        a: &AppSpec,
        scenes: &[(String, PathBuf)],
        near: &dyn Fn(&str, String) -> Error,
    ) -> Result<Plan> {
        let entry = registry::entry(&a.name).ok_or_else(|| {
            near(&a.name, format!("\"{}\" is not a cache-based integrator (one of: {})", a.name, registry::names()))
        })?;
        let placements = a
            .placements
            .iter()
            .map(|p| match Placement::parse(p) {
                Ok(Placement::Reference) => Err(near(p, "\"none\" is the reference; every sweep has it".into())),
                Ok(_) => Ok(p.clone()),
                Err(e) => Err(near(p, format!("{e}"))),
            })
            .collect::<Result<Vec<_>>>()?;
        let budgets: Vec<usize> = match (&a.caches, &a.density) {
            (Some(c), None) if !c.is_empty() && c.iter().all(|&n| n > 0) => c.clone(),
            (None, Some(_)) if file.resolution.is_none() => {
                return Err(near("density", "density needs the resolution (the paper's density is per pixel)".into()));
            }
            (None, Some(d)) if !d.is_empty() && d.iter().all(|&x| x > 0.0 && x.is_finite()) => d
                .iter()
                .map(|&x| {
                    let [w, h] = file.resolution.unwrap_or([1, 1]);
                    ((x * entry.paper_caches as f64 * (w as f64 * h as f64) / PAPER_PIXELS).round() as usize).max(1)
                })
                .collect(),
            _ => {
                return Err(near(
                    &a.name,
                    format!(
                        "application \"{}\" needs either caches = [positive counts] or density = [positive factors]",
                        a.name
                    ),
                ));
            }
        };
        let fixed: Vec<(String, String)> = a.set.iter().map(|(k, v)| (k.clone(), v.text())).collect();
        for (k, vs) in &a.vary {
            if vs.is_empty() {
                return Err(near(k, format!("vary.{k} lists no values")));
            }
            if a.set.contains_key(k) {
                return Err(near(k, format!("{k} is both set and varied")));
            }
        }
        if let Some(names) = &a.scenes
            && let Some(bad) = names.iter().find(|n| !scenes.iter().any(|(s, _)| s == *n))
        {
            return Err(near(bad, format!("application \"{}\" names scene \"{bad}\", which no [[scene]] has", a.name)));
        }
        let per_sample = match (entry.per_sample, a.per_pixel.is_empty()) {
            (_, true) => None,
            (Some(p), false) if a.per_pixel.iter().all(|&n| n > 0) => Some(p),
            (Some(_), false) => {
                return Err(near("per_pixel", "per_pixel counts must be positive".into()));
            }
            (None, false) => {
                return Err(near("per_pixel", format!("\"{}\" has no per-pixel form", a.name)));
            }
        };
        if let Some(p) = per_sample
            && a.vary.contains_key(p.count)
        {
            return Err(near(p.count, format!("per_pixel sets {} itself; it cannot be varied beside it", p.count)));
        }
        if a.baselines.contains(&0) {
            return Err(near("baselines", "baselines counts must be positive".into()));
        }
        Ok(Plan { placements, budgets, fixed, combos: combinations(&a.vary), per_sample })
    }
}

/// The jobs rendered once per reference beside it: the application's own estimator per pixel at each
/// `per_pixel` count and every seed, then its per-pixel baselines at seed 0 (their converged image, then
/// every baseline at each `baselines` count).
fn per_pixel_jobs(a: &AppSpec, plan: &Plan, reference: &Job, seeds: u64) -> Vec<Job> {
    let mut jobs = Vec::new();
    let (scene, ref_set) = (&reference.scene, &reference.set);
    for (p, &n) in plan.per_sample.iter().flat_map(|p| a.per_pixel.iter().map(move |n| (p, n))) {
        // The reference's settings with the count replaced.
        let mut pp_set: Vec<(String, String)> = ref_set.iter().filter(|(k, _)| k != p.count).cloned().collect();
        pp_set.extend(p.set.iter().map(|(k, v)| (k.to_string(), v.to_string())));
        pp_set.push((p.count.to_string(), n.to_string()));
        for seed in 0..seeds {
            jobs.push(Job {
                id: format!("{scene}-{}-pp{n}{}-s{seed}", a.name, super::variant(ref_set)),
                seed,
                set: pp_set.clone(),
                samples: Some(n),
                ..reference.clone()
            });
        }
    }
    let kinds = a.baselines.first().map(|_| BaselineRun::Converged).into_iter();
    for kind in kinds.chain(a.baselines.iter().map(|&n| BaselineRun::Rays(n))) {
        let (what, samples) = match kind {
            BaselineRun::Converged => (CONVERGED.to_string(), None),
            BaselineRun::Rays(n) => (format!("bl{n}"), Some(n)),
        };
        jobs.push(Job {
            id: format!("{scene}-{}-{what}{}", a.name, super::variant(ref_set)),
            samples,
            baseline: Some(kind),
            ..reference.clone()
        });
    }
    jobs
}

/// The pairs of `set` that change the reference (those that are not placement-only).
fn ref_set_of(set: &[(String, String)]) -> Vec<(String, String)> {
    set.iter().filter(|(k, _)| !super::placement_only(k)).cloned().collect()
}

/// Every combination of the varied values (one empty combination when nothing varies), keys in order.
fn combinations(vary: &BTreeMap<String, Vec<Value>>) -> Vec<Vec<(String, String)>> {
    let mut out: Vec<Vec<(String, String)>> = vec![Vec::new()];
    for (k, vs) in vary {
        out = out
            .into_iter()
            .flat_map(|c| {
                vs.iter().map(move |v| {
                    let mut c = c.clone();
                    c.push((k.clone(), v.text()));
                    c
                })
            })
            .collect();
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn first_app() -> &'static str {
        registry::APPLICATIONS[0].name
    }

    fn spec(body: &str) -> Result<Spec> {
        let text = format!(
            "resolution = [32, 24]\nseeds = 2\n[[scene]]\nfile = \"a/s.pbrt\"\n[[application]]\nname = \"{}\"\n{body}",
            first_app()
        );
        parse(&text, Path::new("/x/spec.toml"))
    }

    #[test]
    fn a_spec_expands_into_references_then_runs() {
        let s = spec("placements = [\"im\", \"vgc+dgs\"]\ncaches = [10, 20]\nvary = { sdminsize = [1, 5] }\n").unwrap();
        // Placement-only parameters share one reference.
        let refs: Vec<&Job> = s.jobs.iter().filter(|j| j.is_reference()).collect();
        assert_eq!(refs.len(), 1);
        assert_eq!(s.jobs.len(), 1 + 2 * 2 * 2 * 2);
        assert!(s.jobs[0].is_reference() && s.jobs[0].placement == "none");
        assert_eq!(s.jobs[0].file, Path::new("/x/a/s.pbrt"));
        let r = &s.jobs[1];
        assert_eq!((r.caches, r.seed, r.varied.as_str()), (10, 0, "sdminsize=1"));
        assert!(r.set.contains(&("sdminsize".into(), "1".into())));
        assert_eq!(r.reference, s.jobs[0].id);
    }

    #[test]
    fn a_varied_parameter_of_the_estimator_gets_its_own_reference() {
        let s =
            spec("placements = [\"im\"]\ncaches = [10]\nset = { subpixels = 2 }\nvary = { seed = [1, 2] }\n").unwrap();
        assert_eq!(s.jobs.iter().filter(|j| j.is_reference()).count(), 2);
    }

    #[test]
    fn per_pixel_runs_use_the_reference_settings_with_the_count_replaced_and_scenes_filter() {
        let s = spec("placements = [\"im\"]\ncaches = [10]\nset = { gather = 8 }\nper_pixel = [2, 4]\n").unwrap();
        let pp: Vec<&Job> = s.jobs.iter().filter(|j| j.samples.is_some()).collect();
        assert_eq!(pp.len(), 2 * 2, "two counts × two seeds");
        let count = registry::APPLICATIONS[0].per_sample.unwrap().count;
        for j in &pp {
            assert_eq!(j.placement, "none");
            assert_eq!(j.set.iter().filter(|(k, _)| k == count).count(), 1, "{:?}", j.set);
            assert_eq!(j.method(), format!("per-pixel:{}", j.samples.unwrap()));
            assert_eq!(j.reference, s.jobs[0].id);
        }
        let e = spec("placements = [\"im\"]\ncaches = [10]\nscenes = [\"nope\"]\n").unwrap_err().to_string();
        assert!(e.contains("nope") && e.contains("[[scene]]"), "{e}");
        let s = spec("placements = [\"im\"]\ncaches = [10]\nscenes = [\"a-s\"]\n").unwrap();
        assert_eq!(s.jobs.len(), 1 + 2);
    }

    #[test]
    fn baselines_add_a_converged_job_and_one_job_per_count_at_seed_0() {
        let s = spec("placements = [\"im\"]\ncaches = [10]\nbaselines = [1, 4]\n").unwrap();
        let b: Vec<&Job> = s.jobs.iter().filter(|j| j.baseline.is_some()).collect();
        assert_eq!(b.len(), 3, "{b:#?}");
        assert_eq!(b[0].baseline, Some(BaselineRun::Converged));
        assert_eq!(b[0].method(), CONVERGED);
        assert_eq!((b[2].baseline, b[2].seed, b[2].method().as_str()), (Some(BaselineRun::Rays(4)), 0, "baselines:4"));
        assert!(b.iter().all(|j| j.reference == s.jobs[0].id && j.placement == "none"));
        let e = spec("placements = [\"im\"]\ncaches = [10]\nbaselines = [0]\n").unwrap_err().to_string();
        assert!(e.contains("baselines"), "{e}");
    }

    #[test]
    fn without_a_resolution_the_scene_keeps_its_own_and_density_is_refused() {
        let text = format!(
            "[[scene]]\nfile = \"s.pbrt\"\n[[application]]\nname = \"{}\"\nplacements = [\"im\"]\n",
            first_app()
        );
        let s = parse(&format!("{text}caches = [5]\n"), Path::new("x.toml")).unwrap();
        assert!(s.jobs.iter().all(|j| j.resolution.is_none()));
        let e = parse(&format!("{text}density = [1]\n"), Path::new("x.toml")).unwrap_err().to_string();
        assert!(e.contains("density needs the resolution"), "{e}");
    }

    #[test]
    fn density_scales_the_paper_budget_to_the_pixels() {
        let s = spec("placements = [\"im\"]\ndensity = [1]\n").unwrap();
        let paper = registry::APPLICATIONS[0].paper_caches as f64;
        let expected = (paper * 32.0 * 24.0 / PAPER_PIXELS).round().max(1.0) as usize;
        assert_eq!(s.jobs[1].caches, expected);
    }

    #[test]
    fn bad_specs_name_the_line_and_what_was_expected() {
        let e = spec("placements = [\"im\"]\ncaches = [10]\nfoo = 1\n").unwrap_err().to_string();
        assert!(e.starts_with("/x/spec.toml:") && e.contains("foo"), "{e}");
        let e = spec("placements = [\"im\", \"vgc+foo\"]\ncaches = [10]\n").unwrap_err().to_string();
        assert!(e.starts_with("/x/spec.toml:7:") && e.contains("vgc+foo"), "{e}");
        let e = spec("placements = [\"im\"]\n").unwrap_err().to_string();
        assert!(e.contains("caches") && e.contains("density"), "{e}");
        let e = spec("placements = [\"none\"]\ncaches = [1]\n").unwrap_err().to_string();
        assert!(e.contains("reference"), "{e}");
        let e = parse("resolution = [32, 24\n", Path::new("s.toml")).unwrap_err().to_string();
        assert!(e.starts_with("s.toml:"), "{e}");
        let e = spec("placements = [\"im\"]\ncaches = [10]\nset = { sdminsize = 1 }\nvary = { sdminsize = [2] }\n")
            .unwrap_err()
            .to_string();
        assert!(e.contains("both set and varied"), "{e}");
    }
}
