//! STAGE 5 (shading): the scene's materials compiled once ([`Materials::build`]) and turned into a BSDF at
//! each hit ([`Materials::bsdf`]) the way pbrt-v3's `Material::ComputeScatteringFunctions` does.
//!
//! Depends on `scene` (materials, surface interaction), the shading textures, BxDFs and BSDF; never on
//! `render`. No allocation per hit.

pub mod compile;
pub mod copper;
pub mod param;
pub mod scatter;

use crate::error::{Result, Warnings};
use crate::scene::Scene;
use crate::scene::geometry::SurfaceInteraction;
use crate::shading::bsdf::{Bsdf, MAX_LOBES};
use crate::shading::texture::Textures;

use compile::Compiled;
use scatter::MaterialHit;

/// The scene's materials, ready to shade (same ids as `Scene::materials`).
#[derive(Debug, Default)]
pub struct Materials {
    compiled: Vec<Compiled>,
    /// Per material, whether its BSDF can have a perfectly specular lobe ([`Compiled::may_be_specular`]).
    specular: Vec<bool>,
    /// Per material, whether its BSDF can have a glossy reflection lobe ([`Compiled::may_be_glossy`]).
    glossy: Vec<bool>,
    type_names: Vec<String>,
    counted: Vec<bool>,
}

impl Materials {
    /// Compiles every material of `scene`: constants checked once (bad values become warnings at their
    /// parameter), unsupported types and bump maps reported once each, a `mix` with more than pbrt-v3's 8
    /// lobes reported (the extra lobes are dropped).
    pub fn build(scene: &Scene, warnings: &mut Warnings) -> Result<Materials> {
        let copper = copper::copper_eta_k();
        let compiled: Vec<Compiled> = scene.materials.iter().map(|m| compile::compile(m, copper, warnings)).collect();
        let mut lobes = vec![0usize; compiled.len()];
        for (i, c) in compiled.iter().enumerate() {
            // Mix parts are defined before the mix, so their counts are known (a forward id counts 0).
            lobes[i] = c.max_lobes(|id| lobes.get(id as usize).copied().unwrap_or(0));
            if lobes[i] > MAX_LOBES {
                let m = &scene.materials[i];
                let msg = format!(
                    "material \"{}\" can have {} BSDF lobes; pbrt-v3 allows {MAX_LOBES}, the rest are dropped",
                    m.type_name, lobes[i]
                );
                match &m.loc {
                    Some(loc) => warnings.at(loc, msg),
                    None => warnings.general(msg),
                }
            }
        }
        let (mut specular, mut glossy) = (vec![false; compiled.len()], vec![false; compiled.len()]);
        for (i, c) in compiled.iter().enumerate() {
            specular[i] = c.may_be_specular(|id| specular.get(id as usize).copied().unwrap_or(false));
            glossy[i] = c.may_be_glossy(|id| glossy.get(id as usize).copied().unwrap_or(false));
        }
        Ok(Materials {
            compiled,
            specular,
            glossy,
            type_names: scene.materials.iter().map(|m| m.type_name.clone()).collect(),
            counted: scene.materials.iter().map(|m| m.loc.is_some()).collect(),
        })
    }

    /// Whether material `id`'s BSDF can have a perfectly specular lobe (false for an unknown id).
    #[inline]
    pub fn may_be_specular(&self, id: u32) -> bool {
        self.specular.get(id as usize).copied().unwrap_or(false)
    }

    /// Whether material `id`'s BSDF can have a glossy reflection lobe (false for an unknown id).
    #[inline]
    pub fn may_be_glossy(&self, id: u32) -> bool {
        self.glossy.get(id as usize).copied().unwrap_or(false)
    }

    /// The BSDF of material `id` at `si` as pbrt-v3's `path` integrator builds it (`allowMultipleLobes`:
    /// smooth glass is one `FresnelSpecular` lobe). `None` for `none`/`interface` (pass straight through).
    #[inline]
    pub fn bsdf(&self, id: u32, si: &SurfaceInteraction, textures: &Textures) -> Option<Bsdf> {
        self.bsdf_with(id, si, textures, true)
    }

    /// [`Materials::bsdf`] with pbrt-v3's `allowMultipleLobes` given: false is what `directlighting` and
    /// `whitted` pass (smooth glass as separate specular reflection and transmission lobes, which their
    /// specular-bounce code samples with REFLECTION|SPECULAR and TRANSMISSION|SPECULAR).
    #[inline]
    pub fn bsdf_with(
        &self,
        id: u32,
        si: &SurfaceInteraction,
        textures: &Textures,
        allow_multiple_lobes: bool,
    ) -> Option<Bsdf> {
        let mut b = Bsdf::new(si.ng, si.ns, si.dpdu, 1.0);
        self.bsdf_into(id, si, textures, allow_multiple_lobes, &mut b).then_some(b)
    }

    /// [`Materials::bsdf_with`] written into `out` (false, `out` untouched, for a material without a
    /// BSDF): the form for inner loops, which keep one `Bsdf` per path.
    #[inline]
    pub fn bsdf_into(
        &self,
        id: u32,
        si: &SurfaceInteraction,
        textures: &Textures,
        allow_multiple_lobes: bool,
        out: &mut Bsdf,
    ) -> bool {
        scatter::scatter(
            &self.compiled,
            id,
            &MaterialHit { si, textures, multiple_lobes: allow_multiple_lobes },
            0,
            out,
        )
    }

    /// Materials defined in the scene file by type name, sorted by name (the built-in default matte is not
    /// counted; a shape that overrides its material's parameters counts as one more material).
    pub fn count_by_type(&self) -> Vec<(String, usize)> {
        let mut counts: std::collections::BTreeMap<&str, usize> = Default::default();
        for (name, &counted) in self.type_names.iter().zip(&self.counted) {
            if counted {
                *counts.entry(name.as_str()).or_default() += 1;
            }
        }
        counts.into_iter().map(|(k, v)| (k.to_string(), v)).collect()
    }

    /// Number of materials (the same as the scene's).
    pub fn len(&self) -> usize {
        self.compiled.len()
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.compiled.is_empty()
    }
}
