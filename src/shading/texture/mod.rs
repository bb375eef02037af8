//! STAGE 5 (shading): textures evaluated at a surface interaction.
//!
//! INTERIM SCAFFOLD (to be replaced before issue 10 lands): only `constant` textures are evaluated; every
//! other class gives 1.

use crate::error::{Result, Warnings};
use crate::scene::Scene;
use crate::scene::geometry::SurfaceInteraction;
use crate::scene::props::Prop;

use super::Spectrum;

/// The scene's textures, ready to evaluate (images loaded).
#[derive(Debug, Default)]
pub struct Textures {
    values: Vec<Spectrum>,
}

impl Textures {
    /// Prepares every texture of `scene`; problems that pbrt-v3 survives are warnings.
    pub fn build(scene: &Scene, _warnings: &mut Warnings) -> Result<Textures> {
        let values = scene
            .textures
            .iter()
            .map(|t| match t.props.get("value") {
                Some(Prop::Rgb(c)) => Spectrum::from(*c),
                Some(Prop::Float(v)) => Spectrum::splat(*v),
                _ => Spectrum::ONE,
            })
            .collect();
        Ok(Textures { values })
    }

    /// Spectrum texture `id` (an index into `Scene::textures`) at `si`.
    pub fn spectrum(&self, id: u32, _si: &SurfaceInteraction) -> Spectrum {
        self.values.get(id as usize).copied().unwrap_or(Spectrum::ONE)
    }

    /// Float texture `id` at `si`.
    pub fn float(&self, id: u32, _si: &SurfaceInteraction) -> f32 {
        self.values.get(id as usize).map_or(1.0, |v| v.x)
    }
}
