//! STAGE 2 (scene builder): render options before WorldBegin — Camera, Film, Sampler, PixelFilter,
//! Accelerator — and participating media declarations (accepted, not rendered).

use crate::error::{Result, SourceLoc};
use crate::parse::Named;
use crate::scene::film::{FilmSpec, check_memory};
use crate::scene::filter::FilterSpec;
use crate::scene::sampler::SamplerSpec;

use super::SceneBuilder;

impl SceneBuilder {
    pub(super) fn camera_directive(&mut self, n: Named, loc: &SourceLoc) -> Result<()> {
        // pbrt-v3: the CTM at Camera is camera-from-world; "camera" names its inverse.
        let world_from_camera = self.ctm[0].inverse();
        self.named_coords.insert("camera".into(), [world_from_camera, self.ctm[1].inverse()]);
        self.camera = Some((n, world_from_camera, loc.clone()));
        Ok(())
    }

    pub(super) fn film_directive(&mut self, n: Named, loc: &SourceLoc) -> Result<()> {
        let mut film = FilmSpec::from_directive(&n)?;
        if self.opts.quick {
            film.resolution = film.resolution.map(|r| (r / 4).max(1));
        }
        // A resolution given with the load options replaces this one and is checked instead.
        if self.opts.resolution.is_none() {
            check_memory(film.resolution, &n.name_loc)?;
        }
        self.report_unused(&n.params, "Film");
        self.film = film;
        self.film_loc = Some(loc.clone());
        Ok(())
    }

    pub(super) fn sampler_directive(&mut self, n: Named) -> Result<()> {
        let mut s = SamplerSpec::from_directive(&n, &mut self.warnings)?;
        if self.opts.quick {
            s.spp = 1;
        }
        self.report_unused(&n.params, "Sampler");
        self.sampler = s;
        self.declared.sampler = Some(n.name_loc.clone());
        Ok(())
    }

    pub(super) fn filter_directive(&mut self, n: Named) -> Result<()> {
        self.filter = FilterSpec::from_directive(&n, &mut self.warnings)?;
        self.declared.filter = Some(n.name_loc.clone());
        self.report_unused(&n.params, "PixelFilter");
        Ok(())
    }

    pub(super) fn accelerator_directive(&mut self, n: Named) {
        // cachert always builds its own BVH; pbrt-v3's accelerator settings do not change the image.
        n.params.mark_all_used();
        if n.name != "bvh" && n.name != "kdtree" {
            self.warnings.at(&n.name_loc, format!("unknown accelerator \"{}\"; cachert always uses its BVH", n.name));
        }
    }

    pub(super) fn medium_directive(&mut self, n: Named, loc: &SourceLoc) -> Result<()> {
        n.params.mark_all_used();
        if !self.media_warned {
            self.media_warned = true;
            self.warnings
                .at(loc, "participating media are not rendered by cachert; MakeNamedMedium is accepted and ignored");
        }
        self.media.insert(n.name, loc.clone());
        Ok(())
    }

    pub(super) fn medium_interface(&mut self, inside: &str, outside: &str, loc: &SourceLoc) -> Result<()> {
        for name in [inside, outside] {
            if !name.is_empty() && !self.media.contains_key(name) {
                self.warnings.at(loc, format!("MediumInterface: no medium named \"{name}\""));
            }
        }
        Ok(())
    }
}
