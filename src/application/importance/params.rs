//! Importance caching's parameters (the table of docs/integrators/importancecache.md): each declared once with
//! its default and range, read into [`ImportanceCache`], reported back for `--stats`, and copied into the
//! per-pixel baselines' settings.
//!
//! Depends on the parameter reader `parse::integrator` and its parent's settings type.

use crate::error::Result;
use crate::parse::integrator::{Choice, IntegratorParams, ParamDef, Parameter, Valid};

use super::mixture::{LETTERS, LOBE, Mis, TECHNIQUES};
use super::vpl::Vpls;
use super::{DEFAULT_LIGHT_SAMPLES, ImportanceCache, MAX_SHARE_LEVEL, MAX_TECHNIQUE_DRAWS, Sampling, ShareLevel};
use crate::application::Application;
use crate::application::Baseline;

/// Most VPLs a render may ask for (beyond the memory check).
const MAX_VPLS: i64 = 1 << 26;

/// `vpls`.
pub const VPLS: ParamDef<i64> =
    ParamDef::int("vpls", 8192, "virtual point lights (direct and indirect light)").between(1, MAX_VPLS);
/// `vpldepth`.
pub const VPLDEPTH: ParamDef<i64> = ParamDef::int(
    "vpldepth",
    4,
    "most surface vertices of a light path beyond the receiver (pbrt-v3 path maxdepth − 1)",
)
.between(0, 64);
/// `vplseed`.
pub const VPLSEED: ParamDef<i64> =
    ParamDef::int("vplseed", 0, "seed of the VPLs (fixed across --seed, so seeds share one reference)");
/// `clamp`: d_c / L.
pub const CLAMP: ParamDef<f64> =
    ParamDef::float("clamp", 0.025, "distance clamp d_c as a fraction of L (estimator and reference alike)")
        .valid(Valid::AtLeast { lo: 0.0, finite: true });
/// `compensate`: VPLs drawn where the clamp's loss is put back (0: the clamped sum alone).
pub const COMPENSATE: ParamDef<i64> = ParamDef::int(
    "compensate",
    4,
    "the light the clamp removes is put back: one ray of length d_c from the shading point, and this many VPLs \
     drawn by flux at the surface it finds (estimator and reference alike; 0: the clamped sum alone)",
)
.between(0, MAX_TECHNIQUE_DRAWS as i64);
/// Default of `distributions`: every technique once, each drawing `lightsamples` VPLs per sample (before
/// `learnshares` moves draws to F).
pub const DEFAULT_DISTRIBUTIONS: &str = "fubcg";
/// `distributions`: the letters of the techniques that draw.
pub const DISTRIBUTIONS: ParamDef<String> = ParamDef::text(
    "distributions",
    DEFAULT_DISTRIBUTIONS,
    "techniques that draw, each letter (or its count after it: f12) lightsamples draws: f full, u unoccluded, b \
     bounded, c conservative, g lobe",
);
/// `lightsamples`: draws per letter.
pub const LIGHTSAMPLES: ParamDef<i64> = ParamDef::int(
    "lightsamples",
    DEFAULT_LIGHT_SAMPLES as i64,
    "VPLs each letter of distributions (times its count) draws per sub-pixel sample (the paper: 1 with \
     distributions fubc, four light samples per shading point)",
)
.between(1, MAX_TECHNIQUE_DRAWS as i64);
/// `mis`: how the techniques combine.
pub const MIS: Choice<Mis> = Choice::new(
    "mis",
    "balance",
    &[("balance", Mis::Balance), ("alphamax", Mis::AlphaMax)],
    "combination of the techniques: balance or alphamax",
);
/// `sampling`: caches or a many-light baseline.
pub const SAMPLING: Choice<Sampling> = Choice::new(
    "sampling",
    "cache",
    &[("cache", Sampling::Cache), ("uniform", Sampling::Uniform), ("power", Sampling::Power)],
    "cache: importance caching; uniform or power: many-light baselines without caches",
);
/// `draws`: the baselines' VPLs per sample.
pub const DRAWS: ParamDef<i64> = ParamDef::int(
    "draws",
    0,
    "VPLs the uniform and power baselines draw per sample (0: as many as f, u, b and c draw together)",
)
.between(0, 1 << 20);
/// `fallbackdraws`: VPLs drawn by flux at a vertex no cache serves.
pub const FALLBACKDRAWS: ParamDef<i64> = ParamDef::int(
    "fallbackdraws",
    0,
    "VPLs drawn by flux at a vertex seen after a specular bounce that no cache serves (0: four times draws)",
)
.between(0, 1 << 20);
/// `splitcone`.
pub const SPLITCONE: ParamDef<f64> = ParamDef::float(
    "splitcone",
    10.0,
    "degrees: VPLs in a sharper reflection lobe's cone, or whose lobe's cone holds the point, are drawn apart at \
     the shading point by their exact unoccluded light (every sampling; 0: off)",
)
.between(0.0, 90.0, "degrees");
/// `splitnear`.
pub const SPLITNEAR: ParamDef<f64> = ParamDef::float(
    "splitnear",
    1.0,
    "VPLs closer to the shading point than this many clamp distances d_c are drawn apart there too (every \
     sampling; 0: off)",
)
.between(0.0, 100.0, "clamp distances");
/// `visangle`.
pub const VISANGLE: ParamDef<f64> = ParamDef::float(
    "visangle",
    10.0,
    "degrees: a cache traces only the two ends of a run of VPLs this close together as it sees them, and takes \
     the run as visible when both are (else traces every member; 0: one ray per VPL)",
)
.between(0.0, 45.0, "degrees");
/// `lobecone`.
pub const LOBECONE: ParamDef<f64> = ParamDef::float(
    "lobecone",
    45.0,
    "degrees: the widest glossy lobe (wider than splitcone) for which the lobe technique g draws a VPL among \
     those in its cone, by flux times the lobe's falloff over clamped squared distance",
)
.between(0.0, 90.0, "degrees");
/// `stratify`.
pub const STRATIFY: ParamDef<bool> = ParamDef::bool(
    "stratify",
    true,
    "the VPL draws of a pixel's sub-pixel samples are stratified across them (false: independent draws)",
);

/// `learnshares`.
pub const LEARNSHARES: ParamDef<i64> = ParamDef::int(
    "learnshares",
    2,
    "most times a cache halves the draws of u and b in favour of f, as its neighbours' distributions sample its \
     own light best (c keeps its draws; 0: the shares of distributions everywhere)",
)
.between(0, MAX_SHARE_LEVEL as i64);

/// `sharelevel`: how a shading point combines its caches' learnt levels.
pub const SHARELEVEL: Choice<ShareLevel> = Choice::new(
    "sharelevel",
    "mean",
    &[("mean", ShareLevel::Mean), ("min", ShareLevel::Min)],
    "how a shading point takes the learnt levels of its caches: mean (rounded down) or min (the most defensive \
     of them)",
);

/// `mixweight`: the power of the interpolation weight by which the selected caches are mixed.
pub const MIXWEIGHT: ParamDef<f64> = ParamDef::float(
    "mixweight",
    1.0,
    "a shading point draws from each selected cache in proportion to its interpolation weight 1/Dist (Eq. 5) \
     to this power (0: every cache alike, the uniform mixture of ALGORITHMS.md 6.3)",
)
.between(0.0, 8.0, "");

/// The table, in its page's order.
pub const PARAMETERS: &[Parameter] = &[
    VPLS.row,
    VPLDEPTH.row,
    VPLSEED.row,
    CLAMP.row,
    COMPENSATE.row,
    DISTRIBUTIONS.row,
    LIGHTSAMPLES.row,
    MIS.row,
    SAMPLING.row,
    DRAWS.row,
    FALLBACKDRAWS.row,
    SPLITCONE.row,
    SPLITNEAR.row,
    VISANGLE.row,
    LOBECONE.row,
    STRATIFY.row,
    LEARNSHARES.row,
    SHARELEVEL.row,
    MIXWEIGHT.row,
];

impl ImportanceCache {
    /// Reads [`PARAMETERS`]; `l` is the scene's length scale L, which `clamp` is a fraction of.
    pub(super) fn read(p: &IntegratorParams<'_>, l: f32) -> Result<Self> {
        let vpls = read_vpls(p)?;
        let max_depth = p.get(&VPLDEPTH)?;
        let clamp = p.get(&CLAMP)?;
        let letters = p.get(&DISTRIBUTIONS)?;
        let light_samples = p.get(&LIGHTSAMPLES)? as u32;
        let techniques = techniques(p, &letters, light_samples)?;
        let mis = p.choice(&MIS)?;
        let sampling = p.choice(&SAMPLING)?;
        let draws = p.get(&DRAWS)?;
        let split_cone = p.get(&SPLITCONE)?;
        let split_near = p.get(&SPLITNEAR)?;
        let vis_angle = p.get(&VISANGLE)?;
        let lobe_cone = p.get(&LOBECONE)?;
        Ok(ImportanceCache {
            lobe_cone: lobe_cone as f32,
            stratify: p.get(&STRATIFY)?,
            learn_shares: p.get(&LEARNSHARES)? as u32,
            share_level: p.choice(&SHARELEVEL)?,
            mix_weight: p.get(&MIXWEIGHT)? as f32,
            vis_angle: vis_angle as f32,
            split_cone: split_cone as f32,
            split_near: split_near as f32,
            draws: draws as u32,
            fallback_draws: p.get(&FALLBACKDRAWS)? as u32,
            vpls: vpls as usize,
            max_depth: max_depth as u32,
            vpl_seed: p.get(&VPLSEED)? as u64,
            clamp: clamp as f32,
            clamp_distance: clamp as f32 * l,
            compensate: p.get(&COMPENSATE)? as u32,
            techniques,
            light_samples,
            mis,
            sampling,
        })
    }

    /// The resolved parameters for the `--stats` report.
    pub(super) fn settings_report(&self) -> Vec<(&'static str, serde_json::Value)> {
        let number = |v: f32| serde_json::Number::from_f64(v as f64).map_or(serde_json::Value::Null, Into::into);
        vec![
            ("vpls", self.vpls.into()),
            ("vpldepth", self.max_depth.into()),
            ("vplseed", self.vpl_seed.into()),
            ("clamp", number(self.clamp)),
            ("compensate", self.compensate.into()),
            ("distributions", self.letters().into()),
            ("lightsamples", self.light_samples.into()),
            ("mis", if self.mis == Mis::Balance { "balance" } else { "alphamax" }.into()),
            ("sampling", self.sampling.name().into()),
            ("draws", self.baseline_draws().into()),
            ("fallbackdraws", self.fallback_draws().into()),
            ("splitcone", number(self.split_cone)),
            ("splitnear", number(self.split_near)),
            ("visangle", number(self.vis_angle)),
            ("lobecone", number(self.lobe_cone)),
            ("stratify", self.stratify.into()),
            ("learnshares", self.learn_shares.into()),
            ("sharelevel", self.share_level.name().into()),
            ("mixweight", number(self.mix_weight)),
        ]
    }

    /// Power sampling, then uniform sampling, with the same VPLs and sub-pixel samples; their sample count
    /// is `draws` (VPLs per sample), so their pixels integrate the same footprint as the reference's.
    pub(super) fn baselines(&self) -> Vec<Baseline> {
        [Sampling::Power, Sampling::Uniform]
            .into_iter()
            .map(|sampling| {
                let set = [
                    ("sampling", sampling.name().to_string()),
                    ("vpls", self.vpls.to_string()),
                    ("vpldepth", self.max_depth.to_string()),
                    ("vplseed", self.vpl_seed.to_string()),
                    ("clamp", self.clamp.to_string()),
                    ("compensate", self.compensate.to_string()),
                    ("distributions", self.letters()),
                    ("splitcone", self.split_cone.to_string()),
                    ("splitnear", self.split_near.to_string()),
                ];
                Baseline {
                    label: sampling.name(),
                    integrator: Self::NAME,
                    set: set.into_iter().map(|(k, v)| (k.to_string(), v)).collect(),
                    samples: "draws",
                    scale: 1.0,
                }
            })
            .collect()
    }
}

/// `vpls`, refused with the memory its VPLs would take when out of range or beyond the memory available.
fn read_vpls(p: &IntegratorParams<'_>) -> Result<i64> {
    let vpls = p.get_unchecked(&VPLS)?;
    if vpls < 1 {
        return p.check(&VPLS, vpls);
    }
    // What the VPLs alone would occupy (an upper bound: every one with its own BSDF).
    let need = (vpls as u128 * Vpls::bytes_for(1) as u128).min(u64::MAX as u128) as u64;
    if vpls > MAX_VPLS {
        let range = format!("must be between 1 and {MAX_VPLS}, got {vpls}");
        return Err(p.invalid(&VPLS.row, format!("{range} (up to {} of VPLs)", gib(need))));
    }
    if let Some(avail) = crate::os::available_memory_bytes()
        && need > avail
    {
        let what = format!("{vpls} would need up to {} of memory; {} is available", gib(need), gib(avail));
        return Err(p.invalid(&VPLS.row, what));
    }
    Ok(vpls)
}

/// Most draws of one of F, U, B and C per sample (G's are [`MAX_TECHNIQUE_DRAWS`]: its walk keeps its picks
/// on the stack).
const MAX_DRAWS_FUBC: u32 = 64;

/// Most draws technique `t` may make per sample.
fn max_draws(t: usize) -> u32 {
    if t == LOBE { MAX_TECHNIQUE_DRAWS } else { MAX_DRAWS_FUBC }
}

/// Draws per technique from `distributions`: letters, each optionally followed by a count (`f12` is twelve f's),
/// each letter drawing `light_samples` times.
fn techniques(p: &IntegratorParams<'_>, letters: &str, light_samples: u32) -> Result<[u32; TECHNIQUES]> {
    let invalid = || {
        p.invalid(
            &DISTRIBUTIONS.row,
            format!(
                "must be letters of f, u, b, c, g, each followed by an optional count, each technique drawing at most \
                 {MAX_DRAWS_FUBC} times (g: {MAX_TECHNIQUE_DRAWS}; a letter's count times lightsamples {light_samples}; \
                 e.g. \"{}\"), got \"{letters}\"",
                DEFAULT_DISTRIBUTIONS
            ),
        )
    };
    let mut techniques = [0u32; TECHNIQUES];
    let mut chars = letters.chars().peekable();
    while let Some(ch) = chars.next() {
        let t = LETTERS.iter().position(|&l| l == ch.to_ascii_lowercase()).ok_or_else(invalid)?;
        let mut digits = String::new();
        while let Some(d) = chars.next_if(char::is_ascii_digit) {
            digits.push(d);
        }
        let count: u32 = if digits.is_empty() { 1 } else { digits.parse().map_err(|_| invalid())? };
        let draws = count.checked_mul(light_samples).and_then(|d| d.checked_add(techniques[t]));
        match draws {
            Some(d) if d <= max_draws(t) => techniques[t] = d,
            _ => return Err(invalid()),
        }
    }
    if techniques.iter().all(|&n| n == 0) {
        return Err(p.invalid(&DISTRIBUTIONS.row, "must name at least one of f, u, b, c, g"));
    }
    Ok(techniques)
}

/// `bytes` in GiB for messages.
fn gib(bytes: u64) -> String {
    format!("{:.2} GiB", bytes as f64 / (1u64 << 30) as f64)
}
