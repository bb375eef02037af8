//! STAGE 6 (render): the `cacheao` integrator — cache-based ambient occlusion with a switchable placement
//! strategy. Reads every parameter of ALGORITHMS.md §7 that applies, with the paper's defaults, and runs the
//! generic cache driver with the AO application.
//!
//! The parameters, their types and defaults are [`PARAMETERS`] (shown by `cachert render --help`).
//!
//! The image holds AO in [0, 1] (Σ V cos θ / Σ cos θ), not pbrt-v3's π-scaled value.

use crate::application::ambient_occlusion::CacheAo;
use crate::error::{Error, Result};
use crate::placement::{AngularMode, PlacementParams};
use crate::scene::Scene;

use super::cached::CacheSettings;
use super::params::IntegratorParams;

/// Every `cacheao` parameter: name, pbrt type, default, meaning. The one list behind `render --help` and
/// the README's table.
pub const PARAMETERS: &[(&str, &str, &str, &str)] = &[
    (
        "placement",
        "string",
        "`vgc+dgs`",
        "`none` (per-sample reference), `im`, `sd`, `sd+as`, `vgc`, `vgc+dgs`, `vgc+as`, `vgc+dgs:diff`, `vgc+dgs:geom`",
    ),
    ("caches", "integer", "120000 × pixels / (1920×1080)", "total cache budget N_c (the paper's density)"),
    ("ratio", "float", "0.15", "stage-2 share R of two-stage strategies"),
    ("sigma_a", "float", "from the budget (25° at ≤40K … 15° at ≥120K)", "VGC angular threshold, degrees"),
    ("gamma", "float", "0.2", "Γ: threshold growth with depth, per metre"),
    ("meters_per_unit", "float", "1", "metres per scene unit"),
    ("lambda", "float", "0.5 / L", "normal weight of Eq. 2 and Eq. 5"),
    ("N", "integer", "20", "kNN candidates"),
    ("theta_max", "float", "30", "normal filter, degrees"),
    ("M", "integer", "6", "caches blended per sample"),
    ("gather", "integer", "32", "gathering grid side: gather² rays per cache"),
    ("maxdistance", "float", "0.1 · L", "occlusion ray length"),
    ("subpixels", "integer", "4", "sub-pixel samples per pixel"),
    ("sdminsize", "integer", "10", "SD minimum cluster size S_min"),
    ("jitter", "float", "0.2", "VGC representative jitter (fraction of the cluster extent)"),
    ("angular", "string", "`cone`", "VGC angular split: `cone` or `spherical` (the paper's literal φ/θ box)"),
    ("seed", "integer", "`--seed`", "seed of placement and evaluation"),
];

/// The parameter table as plain text for `cachert render --help`.
pub fn help() -> String {
    let mut out = String::from("cacheao parameters (in the scene's Integrator line, or --set NAME=VALUE):\n");
    let width = PARAMETERS.iter().map(|p| p.0.len() + p.1.len() + 3).max().unwrap_or(0);
    for (name, ty, default, meaning) in PARAMETERS {
        let head = format!("{name} ({ty})");
        out.push_str(&format!(
            "  {head:<width$}  {}; default {}\n",
            meaning.replace('`', ""),
            default.replace('`', "")
        ));
    }
    out.push_str("  (L is the diagonal of the scene's bounding box.)\n");
    out
}

/// The paper's cache density: 120K caches at 1920×1080.
pub const PAPER_CACHES_PER_PIXEL: f64 = 120_000.0 / (1920.0 * 1080.0);

/// Resolves the `cacheao` parameters for `scene`.
pub fn settings(
    p: &IntegratorParams<'_>,
    scene: &Scene,
    seed: u64,
    progress: bool,
) -> Result<(CacheAo, CacheSettings)> {
    let l = scene.diagonal();
    let [w, h] = scene.film.cropped_bounds().size();
    let default_caches = ((w * h) as f64 * PAPER_CACHES_PER_PIXEL).round().max(1.0) as i64;
    let bad = |name: &str, what: &str| Error::usage(format!("{}cacheao: \"{name}\" {what}", p.at(name)));
    let caches = p.int_or("caches", default_caches)?;
    if caches < 1 {
        return Err(bad("caches", &format!("must be at least 1, got {caches}")));
    }
    let ratio = p.float_or("ratio", 0.15)?;
    if !(0.0..1.0).contains(&ratio) {
        return Err(bad("ratio", &format!("must be in [0, 1), got {ratio}")));
    }
    let positive = |name: &'static str, v: f64| {
        if v > 0.0 && v.is_finite() { Ok(v) } else { Err(bad(name, &format!("must be positive, got {v}"))) }
    };
    let sigma_a = p.float("sigma_a")?.map(|v| positive("sigma_a", v)).transpose()?;
    let lambda = p
        .float("lambda")?
        .map(|v| if v >= 0.0 && v.is_finite() { Ok(v) } else { Err(bad("lambda", "must be ≥ 0")) })
        .transpose()?;
    let count = |name: &'static str, default: i64, max: i64| -> Result<usize> {
        let v = p.int_or(name, default)?;
        if !(1..=max).contains(&v) {
            return Err(bad(name, &format!("must be between 1 and {max}, got {v}")));
        }
        Ok(v as usize)
    };
    let candidates = count("N", 20, 1024)?;
    let keep = count("M", 6, 1024)?;
    if keep > candidates {
        return Err(Error::usage(format!("cacheao: M ({keep}) cannot exceed N ({candidates})")));
    }
    let gather = count("gather", 32, 256)?;
    let subpixels = count("subpixels", 4, 1024)? as u32;
    let theta_max = p.float_or("theta_max", 30.0)?;
    if !(0.0..=180.0).contains(&theta_max) {
        return Err(bad("theta_max", &format!("must be in [0, 180] degrees, got {theta_max}")));
    }
    let max_distance = match p.float("maxdistance")? {
        Some(v) => positive("maxdistance", v)? as f32,
        None if l > 0.0 => 0.1 * l,
        None => f32::INFINITY,
    };
    let angular = match p.string_or("angular", "cone")?.as_str() {
        "cone" => AngularMode::Cone,
        "spherical" => AngularMode::SphericalAngles,
        other => return Err(bad("angular", &format!("must be \"cone\" or \"spherical\", got \"{other}\""))),
    };
    let mut params = PlacementParams {
        ratio: ratio as f32,
        sigma_a_deg: sigma_a.map(|v| v as f32),
        gamma: p.float_or("gamma", 0.2)? as f32,
        meters_per_unit: positive("meters_per_unit", p.float_or("meters_per_unit", 1.0)?)? as f32,
        lambda: lambda.map(|v| v as f32),
        jitter: p.float_or("jitter", 0.2)? as f32,
        angular,
        sd_min_size: count("sdminsize", 10, 1 << 30)?,
        ..Default::default()
    };
    params.lookup.candidates = candidates;
    params.lookup.keep = keep;
    params.lookup.theta_max_deg = theta_max as f32;
    let placement = p.string_or("placement", "vgc+dgs")?;
    if placement != "none" {
        crate::placement::registry::strategy(&placement)?;
    }
    let seed = p.int_or("seed", seed as i64)? as u64;
    let app = CacheAo::new(gather, max_distance);
    Ok((app, CacheSettings { placement, caches: caches as usize, params, subpixels, seed, progress }))
}
