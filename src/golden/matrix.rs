//! The project's own golden matrix (the repository's `golden/` folder), enumerated from the registries: every
//! placement of `placement::registry` and `none`, × every application of `application::registry` (with its
//! quick settings, `Study::quick`), × the shipped scenes [`SCENES`]; and each per-pixel integrator of
//! `render::INTEGRATORS` on one scene. Registering a placement or an application adds its entries here; the
//! goldens themselves are made by `cachert golden update --matrix`, and a test fails while any is missing.
//!
//! Depends on the registries only.

use std::collections::BTreeMap;

use crate::application::registry::APPLICATIONS;
use crate::integrator::cache::Placement;
use crate::placement::registry::NAMES;
use crate::render::INTEGRATORS;

use super::Spec;

/// The shipped scenes of the matrix, by file stem under the repository's `scenes/`.
pub const SCENES: [&str; 2] = ["spheres", "room"];

/// Film resolution of every matrix entry (the shipped scenes are 4:3).
pub const RESOLUTION: [u32; 2] = [64, 48];

/// Cache budget of every cache-based entry: about one cache per six pixels at [`RESOLUTION`], so that each
/// golden is within a few per cent of its `none` golden and a wrong one stands out (tests/golden.rs).
pub const CACHES: usize = 500;

/// Pixel samples of the per-pixel entries (their pbrt-v3 references in tests/data/pbrt-v3/golden have 64 to
/// 256 times as many).
pub const PER_PIXEL_SPP: u32 = 16;

/// Seed of every matrix entry.
pub const SEED: u64 = 0;

/// The scene each per-pixel integrator is checked on: `path` on the closed room, where indirect light
/// matters; the others on the spheres under a point light.
pub fn per_pixel_scene(integrator: &str) -> &'static str {
    if integrator == "path" { "room" } else { "spheres" }
}

/// Every placement of the matrix: `none` (the per-sample reference), then the registry's.
pub fn placements() -> impl Iterator<Item = &'static str> {
    std::iter::once(Placement::REFERENCE).chain(NAMES)
}

/// The name of a matrix entry: `scene.integrator` or `scene.integrator.placement`.
pub fn name(scene: &str, integrator: &str, placement: Option<&str>) -> String {
    match placement {
        Some(p) => format!("{scene}.{integrator}.{p}"),
        None => format!("{scene}.{integrator}"),
    }
}

/// The matrix: `(name, spec)` with scene paths relative to the repository's `golden/` folder.
pub fn entries() -> Vec<(String, Spec)> {
    let scene = |s: &str| format!("../scenes/{s}.pbrt");
    let mut out = Vec::new();
    for s in SCENES {
        for app in APPLICATIONS {
            let set: BTreeMap<String, String> = app.quick.iter().map(|(k, v)| (k.to_string(), v.to_string())).collect();
            for p in placements() {
                let spec = Spec {
                    scene: scene(s),
                    integrator: app.name.to_string(),
                    placement: Some(p.to_string()),
                    caches: Some(CACHES),
                    resolution: Some(RESOLUTION),
                    spp: None,
                    seed: SEED,
                    set: set.clone(),
                };
                out.push((name(s, app.name, Some(p)), spec));
            }
        }
    }
    for integrator in INTEGRATORS {
        let s = per_pixel_scene(integrator);
        let spec = Spec {
            scene: scene(s),
            integrator: integrator.to_string(),
            placement: None,
            caches: None,
            resolution: Some(RESOLUTION),
            spp: Some(PER_PIXEL_SPP),
            seed: SEED,
            set: BTreeMap::new(),
        };
        out.push((name(s, integrator, None), spec));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_matrix_covers_every_registered_pair_once() {
        let e = entries();
        let per_scene = (NAMES.len() + 1) * APPLICATIONS.len();
        assert_eq!(e.len(), SCENES.len() * per_scene + INTEGRATORS.len());
        let names: std::collections::HashSet<_> = e.iter().map(|(n, _)| n.as_str()).collect();
        assert_eq!(names.len(), e.len());
        for app in APPLICATIONS {
            for p in placements() {
                assert!(names.contains(name("room", app.name, Some(p)).as_str()), "{} {p}", app.name);
            }
        }
    }
}
