//! STAGE 2 (scene): the `Sampler` directive — which pbrt-v3 sampler and how many samples per pixel it
//! takes. The sample values themselves come from `sampling::pixel_samples`, keyed by pixel and sample index.

use crate::error::{Error, Result, Warnings};
use crate::parse::Named;
use crate::sampling::pixel_samples::SamplerKind;

/// The sampler as described in the scene.
#[derive(Clone, Debug, PartialEq)]
pub struct SamplerSpec {
    /// pbrt-v3's name for it.
    pub name: String,
    /// How values are generated.
    pub kind: SamplerKind,
    /// Samples per pixel, after pbrt-v3's rounding.
    pub spp: u32,
    /// Whether array requests (e.g. AO directions) are rounded up to a power of two, as pbrt-v3's
    /// `02sequence` and `maxmindist` samplers do.
    pub pow2_arrays: bool,
}

impl Default for SamplerSpec {
    fn default() -> Self {
        SamplerSpec { name: "halton".into(), kind: SamplerKind::Stratified, spp: 16, pow2_arrays: false }
    }
}

/// The largest sample count per pixel accepted.
pub const MAX_SPP: i64 = 1 << 24;

impl SamplerSpec {
    /// Reads a `Sampler` directive with pbrt-v3's defaults and rounding (warning when it rounds).
    pub fn from_directive(d: &Named, warnings: &mut Warnings) -> Result<SamplerSpec> {
        let p = &d.params;
        let count = |name: &str, default: i64| -> Result<i64> {
            let v = p.int_or(name, default)?;
            if !(1..=MAX_SPP).contains(&v) {
                let loc = p.loc_of(name).unwrap_or(&d.name_loc);
                return Err(Error::at(loc, format!("\"{name}\" must be between 1 and {MAX_SPP}, got {v}")));
            }
            Ok(v)
        };
        let (kind, spp, pow2_spp, pow2_arrays) = match d.name.as_str() {
            "random" => (SamplerKind::Random, count("pixelsamples", 4)?, false, false),
            "stratified" => {
                let _ = p.bool_or("jitter", true)?;
                let _ = p.int_or("dimensions", 4)?;
                (SamplerKind::Stratified, count("xsamples", 4)? * count("ysamples", 4)?, false, false)
            }
            "halton" => {
                let _ = p.bool_or("samplepixelcenter", false)?;
                (SamplerKind::Stratified, count("pixelsamples", 16)?, false, false)
            }
            "sobol" => (SamplerKind::Stratified, count("pixelsamples", 16)?, true, false),
            "02sequence" | "lowdiscrepancy" | "maxmindist" => {
                let _ = p.int_or("dimensions", 4)?;
                (SamplerKind::Stratified, count("pixelsamples", 16)?, true, true)
            }
            other => {
                return Err(Error::at(
                    &d.name_loc,
                    format!(
                        "unknown sampler \"{other}\"; expected random, stratified, halton, sobol, 02sequence or maxmindist"
                    ),
                ));
            }
        };
        let mut spp = spp.min(MAX_SPP) as u32;
        if pow2_spp && !spp.is_power_of_two() {
            let r = spp.next_power_of_two();
            warnings.at(&d.name_loc, format!("sampler \"{}\" rounds {spp} pixel samples up to {r}", d.name));
            spp = r;
        }
        Ok(SamplerSpec { name: d.name.clone(), kind, spp, pow2_arrays })
    }

    /// How many values a request for an array of `n` will get (pbrt-v3 `Sampler::RoundCount`).
    pub fn round_count(&self, n: u32) -> u32 {
        if self.pow2_arrays { n.next_power_of_two() } else { n }
    }
}
