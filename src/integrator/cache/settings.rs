//! STAGE 7 (integrator): the generic parameters of every cache-based integrator (ALGORITHMS.md §7) — placement,
//! budget, lookup, sub-pixel samples, seed — with the paper's defaults, read once into typed
//! [`CacheSettings`]. Each application reads its own parameters beside these (`Application::from_params`).
//!
//! Depends on `placement` (strategy names, placement parameters) and the parameter reader; never on an
//! application.

use std::fmt;

use crate::error::{Error, Result};
use crate::placement::{AngularMode, PlacementParams, registry};
use crate::scene::Scene;

use crate::parse::integrator::{IntegratorParams, Parameter, json_f32};

/// The generic parameters of every cache-based integrator: name, pbrt type, default, meaning.
pub const PARAMETERS: &[Parameter] = &[
    Parameter::new(
        "placement",
        "string",
        "`vgc+dgs`",
        "`none` (per-sample reference), `im`, `sd`, `sd+as`, `vgc`, `vgc+dgs`, `vgc+as`, `vgc+dgs:diff`, `vgc+dgs:geom`",
    ),
    Parameter::new(
        "caches",
        "integer",
        "B × pixels / (1920×1080)",
        "total cache budget N_c; B is the paper's budget for the application at 1920×1080 (in its README section)",
    ),
    Parameter::new("ratio", "float", "0.15", "stage-2 share R of two-stage strategies"),
    Parameter::new(
        "sigma_a",
        "float",
        "from the cache density (25° at ≤40K … 15° at ≥120K caches per 1920×1080 pixels)",
        "VGC angular threshold, degrees",
    ),
    Parameter::new("gamma", "float", "0.2", "Γ: threshold growth with depth, per metre"),
    Parameter::new("meters_per_unit", "float", "1", "metres per scene unit"),
    Parameter::new("lambda", "float", "0.5 / L", "normal weight of Eq. 2 and Eq. 5"),
    Parameter::new("N", "integer", "20", "kNN candidates"),
    Parameter::new("theta_max", "float", "30", "normal filter, degrees"),
    Parameter::new("M", "integer", "6", "caches blended per sample"),
    Parameter::new("subpixels", "integer", "4", "sub-pixel samples per pixel"),
    Parameter::new("sdminsize", "integer", "10", "SD minimum cluster size S_min"),
    Parameter::new("jitter", "float", "0.2", "VGC representative jitter (fraction of the cluster extent)"),
    Parameter::new(
        "angular",
        "string",
        "`cone`",
        "VGC angular split: `cone` or `spherical` (the paper's literal φ/θ box)",
    ),
    Parameter::new("seed", "integer", "`--seed`", "seed of placement and evaluation"),
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

    /// Parses a placement name; an unknown one is an error listing every valid name.
    pub fn parse(name: &str) -> Result<Self> {
        if name == Self::REFERENCE {
            return Ok(Placement::Reference);
        }
        match registry::NAMES.iter().find(|&&n| n == name) {
            Some(&n) => Ok(Placement::Strategy(n)),
            None => Err(Error::usage(format!(
                "unknown placement \"{name}\"; expected one of: {}, {}",
                Self::REFERENCE,
                registry::NAMES.join(", ")
            ))),
        }
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
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct CacheOverrides {
    /// The placement (`--placement`).
    pub placement: Option<Placement>,
    /// The cache budget (`--caches`).
    pub caches: Option<usize>,
    /// The sub-pixel count when the parameter `subpixels` is not written (`--spp`, `--quick`).
    pub subpixels: Option<u32>,
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
}

impl CacheSettings {
    /// Reads the parameters of [`PARAMETERS`] for `scene` (messages name `integrator`, whose paper budget at
    /// 1920×1080 is `paper_caches`); `o` wins over them.
    pub fn from_params(
        p: &IntegratorParams<'_>,
        o: &CacheOverrides,
        scene: &Scene,
        (integrator, paper_caches): (&str, usize),
        seed: u64,
        progress: bool,
    ) -> Result<Self> {
        let [w, h] = scene.film.cropped_bounds().size();
        let default_caches = ((w * h) as f64 * paper_caches as f64 / PAPER_PIXELS).round().max(1.0) as i64;
        let bad = |name: &str, what: &str| Error::usage(format!("{}{integrator}: \"{name}\" {what}", p.at(name)));
        // Read even when overridden, so a written value counts as read (the override wins silently).
        let caches = p.int_or("caches", default_caches)?;
        let caches = match o.caches {
            Some(c) => c as i64,
            None => caches,
        };
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
            return Err(Error::usage(format!("{integrator}: M ({keep}) cannot exceed N ({candidates})")));
        }
        let subpixels = count("subpixels", o.subpixels.map_or(4, i64::from), 1024)? as u32;
        let theta_max = p.float_or("theta_max", 30.0)?;
        if !(0.0..=180.0).contains(&theta_max) {
            return Err(bad("theta_max", &format!("must be in [0, 180] degrees, got {theta_max}")));
        }
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
        let written = p.string_or("placement", "vgc+dgs")?;
        let placement = match o.placement {
            Some(pl) => pl,
            None => Placement::parse(&written)?,
        };
        let seed = p.int_or("seed", seed as i64)? as u64;
        Ok(CacheSettings { placement, caches: caches as usize, params, subpixels, seed, progress })
    }

    /// The resolved settings as JSON (the `--stats` report): every parameter of [`PARAMETERS`] with its
    /// default filled in where the driver knows it (σ_a's and λ's automatic values are `null`).
    pub fn to_json(&self) -> serde_json::Map<String, serde_json::Value> {
        let p = &self.params;
        let angular = match p.angular {
            AngularMode::Cone => "cone",
            AngularMode::SphericalAngles => "spherical",
        };
        let pairs: [(&str, serde_json::Value); 15] = [
            ("placement", self.placement.name().into()),
            ("caches", self.caches.into()),
            ("ratio", json_f32(p.ratio)),
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
