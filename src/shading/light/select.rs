//! STAGE 5 (shading): choosing one light per sample — pbrt-v3's `lightsamplestrategy` "uniform" (every
//! light equally likely) and "power" (probability ∝ the luminance of `Power()`). pbrt-v3's "spatial" is
//! [`super::SpatialSelect`]; asked for here, it falls back to "power" and says so in [`LightSelect::note`].
//!
//! Depends only on [`super::Lights`] and [`super::distribution`].

use super::Lights;
use super::distribution::Distribution1D;
use crate::shading::luminance;

/// A discrete distribution over a scene's lights.
#[derive(Clone, Debug, PartialEq)]
pub struct LightSelect {
    dist: Distribution1D,
    n: usize,
    note: Option<&'static str>,
}

impl LightSelect {
    /// The strategy `strategy` ("uniform", "power" or "spatial") over `lights`; `Err` names an unknown one.
    pub fn new(lights: &Lights, strategy: &str) -> Result<LightSelect, String> {
        let n = lights.len();
        let (weights, note): (Vec<f32>, _) = match strategy {
            "uniform" => (vec![1.0; n], None),
            "power" => ((0..n).map(|i| luminance(lights.power(i))).collect(), None),
            "spatial" => (
                (0..n).map(|i| luminance(lights.power(i))).collect(),
                Some("light sample strategy \"spatial\" is not implemented; using \"power\""),
            ),
            other => {
                return Err(format!(
                    "unknown light sample strategy \"{other}\"; expected \"uniform\", \"power\" or \"spatial\""
                ));
            }
        };
        Ok(LightSelect { dist: Distribution1D::new(&weights), n, note })
    }

    /// Picks a light for `u` ∈ [0, 1): its index and probability; `None` when there are no lights.
    #[inline]
    pub fn sample(&self, u: f32) -> Option<(usize, f32)> {
        if self.n == 0 {
            return None;
        }
        let (i, p) = self.dist.sample_discrete(u);
        (p > 0.0).then_some((i, p))
    }

    /// The probability that [`LightSelect::sample`] picks `light`.
    #[inline]
    pub fn pmf(&self, light: usize) -> f32 {
        if light < self.n { self.dist.discrete_pdf(light) } else { 0.0 }
    }

    /// A message for the user when the requested strategy was replaced (pbrt-v3's "spatial").
    pub fn note(&self) -> Option<&'static str> {
        self.note
    }
}
