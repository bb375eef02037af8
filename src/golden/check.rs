//! Rendering a golden entry and comparing it with its image: `check` (re-render and compare every entry)
//! and `update` (re-render and rewrite entries, saying what moved), plus `add` for a user's own goldens.
//!
//! Depends on `job` (rendering an entry), `integrator` (its settings), `image` and `metrics`.

use std::path::Path;
use std::time::Instant;

use crate::error::{Error, Result, Warnings};
use crate::image::Image;
use crate::integrator::RenderSettings;
use crate::integrator::cache::{CacheOverrides, Placement};
use crate::job::RenderJob;
use crate::metrics::{Metric, compare};
use crate::scene::LoadOptions;

use super::manifest::{Entry, Manifest, Recorded, Spec, file_name, resolve};
use super::provenance::{self, Provenance};
use super::{FLIP_TOLERANCE, REL_RMSE_TOLERANCE, Rule, machine_kind, matches, matrix, platform, rule};

/// A rendered spec.
#[derive(Clone, Debug)]
pub struct Rendered {
    /// The image.
    pub image: Image,
    /// Wall seconds of loading and rendering.
    pub secs: f64,
    /// Every resolved setting (see [`Recorded::settings`]).
    pub settings: serde_json::Map<String, serde_json::Value>,
}

/// Renders `spec` (scene paths relative to `dir`) as `cachert render` would, with `threads` workers
/// (default: all cores; the image does not depend on it). Warnings are dropped: a golden checks images.
pub fn render_spec(dir: &Path, spec: &Spec, threads: Option<usize>) -> Result<Rendered> {
    let start = Instant::now();
    let placement = spec.placement.as_deref().map(Placement::parse).transpose()?;
    let job = RenderJob {
        scene: resolve(dir, &spec.scene),
        load: LoadOptions { resolution: spec.resolution, ..LoadOptions::default() },
        settings: RenderSettings {
            seed: spec.seed,
            spp: spec.spp,
            threads,
            progress: false,
            quick: false,
            integrator: Some(spec.integrator.clone()),
            set: spec.set.iter().map(|(k, v)| (k.clone(), v.clone())).collect(),
            cache: CacheOverrides { placement, caches: spec.caches, subpixels: None, target_error: None },
        },
        outputs: Default::default(),
    };
    let out = job.render(&mut Warnings::default())?;
    let settings = match &out.cache {
        Some(c) => c.settings.clone(),
        None => [("spp".to_string(), serde_json::Value::from(out.spp))].into_iter().collect(),
    };
    Ok(Rendered { image: out.image, secs: start.elapsed().as_secs_f64(), settings })
}

/// How a re-render compares with its golden.
#[derive(Clone, Debug, PartialEq)]
pub enum Verdict {
    /// The same bits.
    Identical,
    /// Not the same bits, within the tolerances (only under [`Rule::Tolerance`]).
    Within,
    /// Neither; the reason.
    Failed(String),
}

impl Verdict {
    /// Whether the entry passed.
    pub fn passed(&self) -> bool {
        !matches!(self, Verdict::Failed(_))
    }
}

/// The result of checking one entry.
#[derive(Clone, Debug)]
pub struct Outcome {
    /// The entry's name.
    pub name: String,
    /// Pass or fail.
    pub verdict: Verdict,
    /// The rule it was judged by.
    pub rule: Rule,
    /// RMSE against the golden (NaN when not compared).
    pub rmse: f64,
    /// The same relative to the golden's mean.
    pub rel_rmse: f64,
    /// Mean HDR-FLIP against the golden (NaN when not compared).
    pub flip: f64,
    /// Seconds the re-render took.
    pub secs: f64,
}

impl Outcome {
    /// One line of the report: verdict, the rule (`bits` or `tol.`), time, errors, name, and the reason of
    /// a failure or of a tolerance.
    pub fn line(&self) -> String {
        let (tag, why) = match &self.verdict {
            Verdict::Identical => ("PASS identical", String::new()),
            Verdict::Within => ("PASS within   ", String::new()),
            Verdict::Failed(r) => ("FAIL          ", format!(": {r}")),
        };
        let (rule, lenience) = match &self.rule {
            Rule::Bits => ("bits", String::new()),
            r => ("tol.", format!(" [judged {}]", r.describe())),
        };
        format!(
            "{tag} {rule} {:>7.2} s  RMSE {:<9.3e} rel. {:<9.3e} FLIP {:<9.3e} {}{why}{lenience}",
            self.secs, self.rmse, self.rel_rmse, self.flip, self.name
        )
    }
}

/// RMSE, the same relative to the reference's mean over all channels, and mean HDR-FLIP.
fn errors(test: &Image, golden: &Image) -> Result<Errors> {
    let v = compare(test, golden, &[Metric::Rmse, Metric::Flip])?;
    let m = golden.mean();
    let mean = (m[0] + m[1] + m[2]) / 3.0;
    Ok(Errors { rmse: v[0].1, rel_rmse: v[0].1 / mean.abs().max(1e-12), flip: v[1].1 })
}

/// Errors of a re-render against its golden.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Errors {
    /// RMSE.
    pub rmse: f64,
    /// RMSE over the golden's mean.
    pub rel_rmse: f64,
    /// Mean HDR-FLIP.
    pub flip: f64,
}

impl Errors {
    const ZERO: Errors = Errors { rmse: 0.0, rel_rmse: 0.0, flip: 0.0 };
    const NAN: Errors = Errors { rmse: f64::NAN, rel_rmse: f64::NAN, flip: f64::NAN };
}

/// Compares a re-render with its golden. Bit-identical passes; otherwise under [`Rule::Bits`] it fails, and
/// under [`Rule::Tolerance`] it passes within [`REL_RMSE_TOLERANCE`] and [`FLIP_TOLERANCE`].
pub fn judge(test: &Image, golden: &Image, rule: &Rule) -> (Verdict, Errors) {
    if (test.width, test.height) != (golden.width, golden.height) {
        let why =
            format!("the render is {}×{}, the golden {}×{}", test.width, test.height, golden.width, golden.height);
        return (Verdict::Failed(why), Errors::NAN);
    }
    let same_bits = test.pixels.iter().zip(&golden.pixels).all(|(a, b)| a.map(f32::to_bits) == b.map(f32::to_bits));
    if same_bits {
        return (Verdict::Identical, Errors::ZERO);
    }
    let e = match errors(test, golden) {
        Ok(e) => e,
        Err(err) => return (Verdict::Failed(err.to_string()), Errors::NAN),
    };
    let (rel, flip) = (e.rel_rmse, e.flip);
    let verdict = if *rule == Rule::Bits {
        Verdict::Failed("not bit-identical on the platform the golden was made on".into())
    } else if !(rel <= REL_RMSE_TOLERANCE && flip <= FLIP_TOLERANCE) {
        Verdict::Failed(format!("beyond the tolerance (relative RMSE {REL_RMSE_TOLERANCE:e}, FLIP {FLIP_TOLERANCE})"))
    } else {
        Verdict::Within
    };
    (verdict, e)
}

/// The entries of `m` whose names match `filter`; an error when a filter matches none.
fn select<'m>(m: &'m Manifest, filter: Option<&str>, dir: &Path) -> Result<Vec<&'m Entry>> {
    let chosen: Vec<&Entry> = m.entries.iter().filter(|e| filter.is_none_or(|f| matches(&e.name, f))).collect();
    if chosen.is_empty() {
        return Err(Error::usage(match filter {
            Some(f) => format!("no golden in {} matches \"{f}\"", dir.display()),
            None => format!("{} lists no goldens", dir.join(super::MANIFEST).display()),
        }));
    }
    Ok(chosen)
}

/// Re-renders every entry of `dir`'s manifest matching `filter` and compares it with its golden by the
/// entry's [`rule`] (`tolerance`: every entry by the tolerance, on purpose), calling `log` with each outcome
/// as it comes. A render or read failure is a failed outcome, not an error; errors are for a missing or
/// malformed manifest and a filter that matches nothing.
pub fn check(
    dir: &Path,
    filter: Option<&str>,
    threads: Option<usize>,
    tolerance: bool,
    log: &mut dyn FnMut(&Outcome),
) -> Result<Vec<Outcome>> {
    let m = Manifest::read(dir, false)?;
    let here = platform();
    let mut out = Vec::new();
    for e in select(&m, filter, dir)? {
        let rule = rule(&e.recorded.platform, &here, tolerance);
        let golden = crate::image::read(&resolve(dir, &e.file));
        let outcome = match (render_spec(dir, &e.spec, threads), golden) {
            (Err(err), _) => failed(e, rule, format!("cannot render: {err}"), 0.0),
            (Ok(r), Err(err)) => failed(e, rule, format!("cannot read the golden: {err}"), r.secs),
            (Ok(r), Ok(g)) => {
                let (verdict, err) = judge(&r.image, &g, &rule);
                let Errors { rmse, rel_rmse, flip } = err;
                Outcome { name: e.name.clone(), verdict, rule, rmse, rel_rmse, flip, secs: r.secs }
            }
        };
        log(&outcome);
        out.push(outcome);
    }
    Ok(out)
}

fn failed(e: &Entry, rule: Rule, why: String, secs: f64) -> Outcome {
    let Errors { rmse, rel_rmse, flip } = Errors::NAN;
    Outcome { name: e.name.clone(), verdict: Verdict::Failed(why), rule, rmse, rel_rmse, flip, secs }
}

/// Refuses under continuous integration: goldens move only by an explicit command on a developer's
/// machine, never as a side effect of a CI run.
fn refuse_under_ci(what: &str) -> Result<()> {
    if std::env::var_os("CI").is_some() {
        return Err(Error::usage(format!(
            "golden {what} refuses to run when the environment variable CI is set: goldens are made only by an \
             explicit command on a developer's machine, and the commit that moves one says why"
        )));
    }
    Ok(())
}

/// The commit to record for goldens made now: refused when the code this binary was built from has
/// uncommitted changes, unless `allow_dirty` (then a loud warning, and the commit ends in `-dirty`).
fn recorded_commit(allow_dirty: bool, what: &str, log: &mut dyn FnMut(&str)) -> Result<String> {
    let p = provenance::of_this_build();
    if let Provenance::Dirty(commit, files) = &p {
        let list = files.iter().take(8).map(|f| format!("\n  {f}")).collect::<String>();
        let more = if files.len() > 8 { format!("\n  … and {} more", files.len() - 8) } else { String::new() };
        if !allow_dirty {
            return Err(Error::usage(format!(
                "golden {what} refuses to record from code with uncommitted changes (commit {commit}, {}):{list}{more}\n\
                 commit them first, so that each golden names code that can be checked out, or pass \
                 --allow-dirty to record them marked \"{commit}-dirty\"",
                provenance::CODE_PATHS.join(", ")
            )));
        }
        log(&format!(
            "WARNING: recording goldens from code with uncommitted changes; they are marked \"{}\" and no \
             one can check out the code that made them:{list}{more}",
            p.commit()
        ));
    }
    Ok(p.commit())
}

/// Renders `spec`, writes its image to `dir/file` and returns what to record.
fn make(dir: &Path, file: &str, spec: &Spec, threads: Option<usize>, commit: &str) -> Result<(Recorded, Image)> {
    let r = render_spec(dir, spec, threads)?;
    if let Some((x, y, c, v)) = r.image.first_non_finite() {
        return Err(Error::usage(format!("the render has a non-finite value {v} at pixel ({x}, {y}), channel {c}")));
    }
    crate::image::write(&r.image, &resolve(dir, file))?;
    let recorded = Recorded {
        commit: commit.to_string(),
        platform: platform(),
        machine: machine_kind(),
        mean: r.image.mean(),
        secs: r.secs,
        settings: r.settings,
    };
    Ok((recorded, r.image))
}

/// Re-renders and rewrites the entries of `dir` matching `filter`, writing the manifest after each, and
/// returns one line per entry saying what moved and by how much. With `matrix`, entries of the project's
/// matrix ([`matrix::entries`]) missing from the manifest are added first (those matching `filter`).
/// Refuses when the environment variable `CI` is set, and when the code has uncommitted changes unless
/// `allow_dirty` (see [`provenance`]).
pub fn update(
    dir: &Path,
    filter: Option<&str>,
    with_matrix: bool,
    threads: Option<usize>,
    allow_dirty: bool,
    log: &mut dyn FnMut(&str),
) -> Result<Vec<String>> {
    refuse_under_ci("update")?;
    let commit = recorded_commit(allow_dirty, "update", log)?;
    let mut m = Manifest::read(dir, with_matrix)?;
    if with_matrix {
        for (name, spec) in matrix::entries() {
            if m.get(&name).is_none() && filter.is_none_or(|f| matches(&name, f)) {
                let recorded = Recorded {
                    commit: String::new(),
                    platform: String::new(),
                    machine: String::new(),
                    mean: [0.0; 3],
                    secs: 0.0,
                    settings: Default::default(),
                };
                m.entries.push(Entry { file: file_name(&name), name, spec, recorded });
            }
        }
    }
    std::fs::create_dir_all(dir).map_err(|e| Error::file(dir, format!("cannot create the golden folder: {e}")))?;
    let names: Vec<String> = select(&m, filter, dir)?.iter().map(|e| e.name.clone()).collect();
    let mut lines = Vec::new();
    for name in names {
        let i = m.entries.iter().position(|e| e.name == name).expect("selected from this manifest");
        let e = &m.entries[i];
        let old = crate::image::read(&resolve(dir, &e.file)).ok();
        let (recorded, image) = make(dir, &e.file, &e.spec, threads, &commit).map_err(|err| in_entry(&name, err))?;
        let what = match old {
            None => "new".to_string(),
            Some(old) => match judge(&image, &old, &Rule::Bits) {
                (Verdict::Identical, _) => "unchanged (identical)".to_string(),
                (_, Errors { rmse, rel_rmse, flip }) => format!(
                    "moved: RMSE {rmse:.3e} (relative {rel_rmse:.3e}), FLIP {flip:.3e}, mean {:.6} → {:.6}",
                    mean3(e.recorded.mean),
                    mean3(recorded.mean)
                ),
            },
        };
        let line = format!("{name}: {what} ({:.2} s)", recorded.secs);
        log(&line);
        lines.push(line);
        m.entries[i].recorded = recorded;
        m.write(dir)?;
    }
    Ok(lines)
}

/// Adds a golden named `name` rendered from `spec` to `dir` (creating the folder and manifest), refusing a
/// name already there, refusing under `CI`, and refusing code with uncommitted changes unless
/// `allow_dirty` (the warning goes to `log`). Returns the entry.
pub fn add(
    dir: &Path,
    name: &str,
    spec: Spec,
    threads: Option<usize>,
    allow_dirty: bool,
    log: &mut dyn FnMut(&str),
) -> Result<Entry> {
    refuse_under_ci("add")?;
    let mut m = Manifest::read(dir, true)?;
    if name.is_empty() || m.get(name).is_some() {
        return Err(Error::usage(format!(
            "a golden named \"{name}\" is already in {} (use golden update to re-render it)",
            dir.display()
        )));
    }
    std::fs::create_dir_all(dir).map_err(|e| Error::file(dir, format!("cannot create the golden folder: {e}")))?;
    let commit = recorded_commit(allow_dirty, "add", log)?;
    let file = file_name(name);
    let (recorded, _) = make(dir, &file, &spec, threads, &commit).map_err(|err| in_entry(name, err))?;
    let entry = Entry { name: name.to_string(), file, spec, recorded };
    m.entries.push(entry.clone());
    m.write(dir)?;
    Ok(entry)
}

fn mean3(m: [f64; 3]) -> f64 {
    (m[0] + m[1] + m[2]) / 3.0
}

/// Prefixes an error with the golden it happened in (location errors keep their location first).
fn in_entry(name: &str, err: Error) -> Error {
    match err {
        Error::Usage(msg) => Error::usage(format!("golden \"{name}\": {msg}")),
        other => other,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn image(v: f32) -> Image {
        Image::from_pixels(4, 3, vec![[v, v, v]; 12]).unwrap()
    }

    #[test]
    fn judging_asks_for_identical_bits_by_the_bit_rule_and_the_tolerance_otherwise() {
        let g = image(1.0);
        let tol = Rule::Tolerance(super::super::Lenience::Asked);
        assert_eq!(judge(&g, &g, &Rule::Bits).0, Verdict::Identical);
        let mut near = g.clone();
        near.pixels[0][0] = f32::from_bits(1.0f32.to_bits() + 1);
        assert!(matches!(judge(&near, &g, &Rule::Bits).0, Verdict::Failed(_)));
        let (v, e) = judge(&near, &g, &tol);
        assert_eq!(v, Verdict::Within, "{e:?}");
        let (v, e) = judge(&image(1.01), &g, &tol);
        assert!(matches!(v, Verdict::Failed(_)) && (e.rel_rmse - 0.01).abs() < 1e-4, "{v:?} {e:?}");
        let small = Image::from_pixels(2, 2, vec![[1.0; 3]; 4]).unwrap();
        assert!(matches!(judge(&small, &g, &tol).0, Verdict::Failed(ref r) if r.contains("4×3")));
        let mut nan = g.clone();
        nan.pixels[3][1] = f32::NAN;
        assert!(!judge(&nan, &g, &tol).0.passed());
    }
}
