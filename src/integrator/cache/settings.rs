//! STAGE 7 (integrator): the generic parameters of every cache-based integrator (ALGORITHMS.md §7) — placement,
//! budget, lookup, sub-pixel samples, seed — with the paper's defaults, read once into typed
//! [`CacheSettings`]. Each application reads its own parameters beside these (`Application::from_params`).
//!
//! Depends on `placement` (strategy names, placement parameters) and the parameter reader; never on an
//! application.

use std::fmt;

use crate::error::{Error, Result};
use crate::gbuffer::scale::SceneScale;
use crate::placement::{AngularMode, PlacementParams, TargetError, registry};
use crate::scene::Scene;

use crate::parse::integrator::{Choice, IntegratorParams, ParamDef, Parameter, Valid, json_f32};

/// `placement`: where the caches go.
pub const PLACEMENT: ParamDef<String> = ParamDef::text(
    "placement",
    "vgc+dgs",
    "`none` (per-sample reference), `im`, `sd`, `sd+as`, `vgc`, `vgc+dgs`, `refine`, `vgc+as`, `vgc+dgs:diff`, `vgc+dgs:geom`",
);
/// `caches`: the budget N_c (default from the application's default budget at 1920×1080 and the image's
/// pixels).
pub const CACHES: ParamDef<i64> = ParamDef::computed(
    "caches",
    "B × pixels / (1920×1080)",
    "total cache budget N_c; B is the application's default budget at 1920×1080, the paper's or a measured better one (on its page in docs/integrators/)",
)
.valid(Valid::AtLeast { lo: 1.0, finite: true });
/// `ratio`: R.
pub const RATIO: ParamDef<f64> = ParamDef::float("ratio", 0.15, "stage-2 share R of two-stage strategies")
    .valid(Valid::Below { lo: 0.0, below: 1.0 });
/// `refineshare`: refine's share of the budget added in rounds.
pub const REFINE_SHARE: ParamDef<f64> =
    ParamDef::float("refineshare", 0.8, "refine: share of the budget added in rounds after its uniform first stage")
        .valid(Valid::Below { lo: 0.0, below: 1.0 });
/// `refinerounds`: refine's rounds.
pub const REFINE_ROUNDS: ParamDef<i64> =
    ParamDef::int("refinerounds", 3, "refine: rounds of insertion, each from a fresh map").between(1, 64);
/// `refinefloor`: refine's uniform floor.
pub const REFINE_FLOOR: ParamDef<f64> = ParamDef::float(
    "refinefloor",
    0.1,
    "refine: uniform floor added to each round's map, as a fraction of the map's mean",
)
.valid(Valid::AtLeast { lo: 0.0, finite: true });
/// `targeterror`: refine's target relative RMSE.
pub const TARGET_ERROR: ParamDef<f64> = ParamDef::computed(
    "targeterror",
    "none",
    "refine: place caches until its own estimate of the relative RMSE against `none` is this (`caches` becomes a ceiling); importance caching draws fewer lights when its first caches already beat it",
)
.valid(Valid::Positive { finite: true });
/// `sigma_a`: VGC's σ_a (default from the cache density, chosen by the strategy).
pub const SIGMA_A: ParamDef<f64> = ParamDef::computed(
    "sigma_a",
    "from the cache density (25° at ≤40K … 15° at ≥120K caches per 1920×1080 pixels)",
    "VGC angular threshold, degrees",
)
.valid(Valid::Positive { finite: true });
/// `gamma`: Γ.
pub const GAMMA: ParamDef<f64> = ParamDef::float("gamma", 0.2, "Γ: threshold growth with depth, per metre");
/// `meters_per_unit`.
pub const METERS_PER_UNIT: ParamDef<f64> =
    ParamDef::float("meters_per_unit", 1.0, "metres per scene unit").valid(Valid::Positive { finite: true });
/// `lambda`: λ (default from the scene's size, chosen by the strategy).
pub const LAMBDA: ParamDef<f64> = ParamDef::computed("lambda", "0.5 / L", "normal weight of Eq. 2 and Eq. 5")
    .valid(Valid::AtLeast { lo: 0.0, finite: true });
/// `N`: kNN candidates.
pub const CANDIDATES: ParamDef<i64> = ParamDef::int("N", 20, "kNN candidates").between(1, 1024);
/// `theta_max`: the normal filter.
pub const THETA_MAX: ParamDef<f64> =
    ParamDef::float("theta_max", 30.0, "normal filter, degrees").between(0.0, 180.0, "degrees");
/// `M`: caches blended per sample.
pub const KEEP: ParamDef<i64> = ParamDef::int("M", 6, "caches blended per sample").between(1, 1024);
/// `subpixels` (`--spp` or `--quick` give the default when set).
pub const SUBPIXELS: ParamDef<i64> = ParamDef::int("subpixels", 4, "sub-pixel samples per pixel").between(1, 1024);
/// `sdminsize`: S_min.
pub const SD_MIN_SIZE: ParamDef<i64> =
    ParamDef::int("sdminsize", 10, "SD minimum cluster size S_min").between(1, 1 << 30);
/// `jitter`.
pub const JITTER: ParamDef<f64> =
    ParamDef::float("jitter", 0.2, "VGC representative jitter (fraction of the cluster extent)");
/// `angular`: VGC's angular split.
pub const ANGULAR: Choice<AngularMode> = Choice::new(
    "angular",
    "cone",
    &[("cone", AngularMode::Cone), ("spherical", AngularMode::SphericalAngles)],
    "VGC angular split: `cone` or `spherical` (the paper's literal φ/θ box)",
);
/// `seed` (default `--seed`).
pub const SEED: ParamDef<i64> = ParamDef::computed("seed", "`--seed`", "seed of placement and evaluation");

/// The generic parameters of every cache-based integrator: name, pbrt type, default, meaning.
pub const PARAMETERS: &[Parameter] = &[
    PLACEMENT.row,
    CACHES.row,
    RATIO.row,
    REFINE_SHARE.row,
    REFINE_ROUNDS.row,
    REFINE_FLOOR.row,
    TARGET_ERROR.row,
    SIGMA_A.row,
    GAMMA.row,
    METERS_PER_UNIT.row,
    LAMBDA.row,
    CANDIDATES.row,
    THETA_MAX.row,
    KEEP.row,
    SUBPIXELS.row,
    SD_MIN_SIZE.row,
    JITTER.row,
    ANGULAR.row,
    SEED.row,
];

/// Pixels of the paper's images (1920×1080), to which `Application::PAPER_CACHES` refers.
pub use crate::placement::PAPER_PIXELS;

/// Where the caches go: nowhere (the per-sample reference) or a strategy of the placement registry.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Placement {
    /// `none`: no caches; the application's brute-force answer at every sub-pixel sample.
    Reference,
    /// A strategy name known to `placement::registry` (`vgc+dgs`, …).
    Strategy(&'static str),
}

impl Placement {
    /// The name `none` that selects [`Placement::Reference`].
    pub const REFERENCE: &'static str = "none";

    /// Parses a placement name, ignoring case (the paper writes `VGC+DGS`); an unknown one is an error
    /// naming the nearest and listing every valid name.
    pub fn parse(name: &str) -> Result<Self> {
        Self::parse_or_why(name).map_err(Error::usage)
    }

    /// [`Placement::parse`] with the reason as text, for callers that locate it (a scene parameter).
    pub fn parse_or_why(name: &str) -> std::result::Result<Self, String> {
        let lower = name.to_ascii_lowercase();
        if lower == Self::REFERENCE {
            return Ok(Placement::Reference);
        }
        if let Some(&n) = registry::NAMES.iter().find(|&&n| n == lower) {
            return Ok(Placement::Strategy(n));
        }
        let all = std::iter::once(Self::REFERENCE).chain(registry::NAMES.iter().copied());
        let near =
            crate::parse::closest(&lower, all.clone()).map(|n| format!(" (did you mean \"{n}\"?)")).unwrap_or_default();
        Err(format!("unknown placement \"{name}\"{near}; expected one of: {}", all.collect::<Vec<_>>().join(", ")))
    }

    /// The name as typed.
    pub fn name(&self) -> &'static str {
        match self {
            Placement::Reference => Self::REFERENCE,
            Placement::Strategy(n) => n,
        }
    }
}

impl fmt::Display for Placement {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// Typed command-line settings of a cache-based render that win over the scene's and `--set`'s
/// (`--placement`, `--caches`, `--spp`; `experiment`'s sweep).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CacheOverrides {
    /// The placement (`--placement`).
    pub placement: Option<Placement>,
    /// The cache budget (`--caches`).
    pub caches: Option<usize>,
    /// The sub-pixel count when the parameter `subpixels` is not written (`--spp`, `--quick`).
    pub subpixels: Option<u32>,
    /// refine's target relative RMSE (`--target-error`).
    pub target_error: Option<f64>,
}

/// How a cache-based render is set up: the generic parameters, resolved.
#[derive(Clone, Debug, PartialEq)]
pub struct CacheSettings {
    /// The strategy, or the per-sample reference.
    pub placement: Placement,
    /// Total cache budget N_c.
    pub caches: usize,
    /// Placement parameters.
    pub params: PlacementParams,
    /// Sub-pixel samples per pixel (the same positions for every method and the reference).
    pub subpixels: u32,
    /// Seed of every random decision of placement and evaluation.
    pub seed: u64,
    /// Show progress bars.
    pub progress: bool,
    /// The scene's length scale L (the G-buffer carries it to placement; λ's default is 0.5/L).
    pub scale: SceneScale,
}

impl CacheSettings {
    /// Reads the parameters of [`PARAMETERS`] for `scene`, whose length scale is `scale` (the application's
    /// default budget at 1920×1080 is `default_caches_1080p`); `o` wins over them.
    pub fn from_params(
        p: &IntegratorParams<'_>,
        o: &CacheOverrides,
        scene: &Scene,
        scale: SceneScale,
        default_caches_1080p: usize,
        seed: u64,
        progress: bool,
    ) -> Result<Self> {
        let [w, h] = scene.film.cropped_bounds().size();
        let default_caches = ((w * h) as f64 * default_caches_1080p as f64 / PAPER_PIXELS).round().max(1.0) as i64;
        // Read even when overridden, so a written value counts as read (the override wins silently).
        let written = p.written_or(&CACHES, default_caches)?;
        let caches = p.check(&CACHES, o.caches.map_or(written, |c| c as i64))?;
        let ratio = p.get(&RATIO)?;
        let sigma_a = p.get_opt(&SIGMA_A)?;
        let lambda = p.get_opt(&LAMBDA)?;
        let candidates = p.get(&CANDIDATES)? as usize;
        let keep = p.get(&KEEP)? as usize;
        if keep > candidates {
            return Err(Error::usage(format!("{}: M ({keep}) cannot exceed N ({candidates})", p.integrator())));
        }
        let subpixels = match o.subpixels {
            Some(n) => p.get_or(&SUBPIXELS, i64::from(n))?,
            None => p.get(&SUBPIXELS)?,
        } as u32;
        let theta_max = p.get(&THETA_MAX)?;
        let angular = p.choice(&ANGULAR)?;
        let mut params = PlacementParams {
            ratio: ratio as f32,
            sigma_a_deg: sigma_a.map(|v| v as f32),
            gamma: p.get(&GAMMA)? as f32,
            meters_per_unit: p.get(&METERS_PER_UNIT)? as f32,
            lambda: lambda.map(|v| v as f32),
            jitter: p.get(&JITTER)? as f32,
            angular,
            sd_min_size: p.get(&SD_MIN_SIZE)? as usize,
            refine_share: p.get(&REFINE_SHARE)? as f32,
            refine_rounds: p.get(&REFINE_ROUNDS)? as u32,
            refine_floor: p.get(&REFINE_FLOOR)? as f32,
            ..Default::default()
        };
        params.lookup.candidates = candidates;
        params.lookup.keep = keep;
        params.lookup.theta_max_deg = theta_max as f32;
        let written = p.get(&PLACEMENT)?;
        let placement = match o.placement {
            Some(pl) => pl,
            None => Placement::parse_or_why(&written).map_err(|why| p.invalid(&PLACEMENT.row, why))?,
        };
        // Read even when overridden, as `caches` is.
        let written_target = p.get_opt(&TARGET_ERROR)?;
        let target = match (o.target_error, written_target) {
            (Some(t), _) if !(t > 0.0 && t.is_finite()) => {
                return Err(Error::usage(format!("--target-error must be a positive number, got {t}")));
            }
            (Some(t), _) => Some(t),
            (None, t) => t,
        };
        if let Some(t) = target {
            match placement {
                Placement::Strategy("refine") => {
                    params.target = Some(TargetError { relative: t as f32, added_mean: 0.0 });
                }
                // The per-sample reference places no caches: a target has nothing to steer.
                Placement::Reference => {}
                Placement::Strategy(other) => {
                    let why = format!("needs placement \"refine\" (the placement is \"{other}\")");
                    return Err(match (o.target_error, written_target) {
                        (None, Some(_)) => p.invalid(&TARGET_ERROR.row, why),
                        _ => Error::usage(format!("--target-error {why}")),
                    });
                }
            }
        }
        let seed = p.get_or(&SEED, seed as i64)? as u64;
        Ok(CacheSettings { placement, caches: caches as usize, params, subpixels, seed, progress, scale })
    }

    /// The resolved settings as JSON (the `--stats` report): every parameter of [`PARAMETERS`] with its
    /// default filled in where the driver knows it (σ_a's and λ's automatic values are `null`).
    pub fn to_json(&self) -> serde_json::Map<String, serde_json::Value> {
        let p = &self.params;
        let angular = match p.angular {
            AngularMode::Cone => "cone",
            AngularMode::SphericalAngles => "spherical",
        };
        let pairs: [(&str, serde_json::Value); 19] = [
            ("placement", self.placement.name().into()),
            ("caches", self.caches.into()),
            ("ratio", json_f32(p.ratio)),
            ("refineshare", json_f32(p.refine_share)),
            ("refinerounds", p.refine_rounds.into()),
            ("refinefloor", json_f32(p.refine_floor)),
            ("targeterror", p.target.map(|t| json_f32(t.relative)).into()),
            ("sigma_a", p.sigma_a_deg.map(json_f32).into()),
            ("gamma", json_f32(p.gamma)),
            ("meters_per_unit", json_f32(p.meters_per_unit)),
            ("lambda", p.lambda.map(json_f32).into()),
            ("N", p.lookup.candidates.into()),
            ("theta_max", json_f32(p.lookup.theta_max_deg)),
            ("M", p.lookup.keep.into()),
            ("subpixels", self.subpixels.into()),
            ("sdminsize", p.sd_min_size.into()),
            ("jitter", json_f32(p.jitter)),
            ("angular", angular.into()),
            ("seed", self.seed.into()),
        ];
        pairs.into_iter().map(|(k, v)| (k.to_string(), v)).collect()
    }
}
