//! STAGE 8 (job): one render job, typed — load a scene, render it with an integrator by name, write the
//! image and the cache outputs asked for (overlay, discontinuity map, statistics) — the one path by which
//! `cachert render`, the experiments and the goldens render. A job is data ([`RenderJob`]); its command
//! line ([`RenderJob::argv`]) exists only to hand jobs to another scheduler (`experiment --emit-jobs`).
//!
//! Depends on `integrator` (the by-name dispatch), `scene` (loading) and `image`; only the studies and the
//! command line depend on it.

pub mod cache_outputs;

use std::path::{Path, PathBuf};

use crate::application::registry;
use crate::error::{Error, Result, Warnings};
use crate::image::{Metadata, Window};
use crate::integrator::{RenderOutput, RenderSettings, render};
use crate::scene::film::FilmSpec;
use crate::scene::{LoadOptions, LoadStats, load};

/// Files a job writes.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Outputs {
    /// The image files (each `.exr`, `.pfm` or `.png`, the same pixels in each; `--outfile` repeated);
    /// none: the Film's `"filename"`, else the scene's stem with `.exr`, in the current folder.
    pub images: Vec<PathBuf>,
    /// Cache-based renders: the image with stage-1 caches (red) and stage-2 caches (cyan) marked.
    pub overlay: Option<PathBuf>,
    /// Cache-based renders: the DGS discontinuity map (EXR/PFM, plus a PNG preview).
    pub dmap: Option<PathBuf>,
    /// Cache-based renders: per-stage times, cache counts, search results, rays and memory as JSON.
    pub stats: Option<PathBuf>,
}

/// A render job: what `cachert render` is given, as data.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RenderJob {
    /// The pbrt-v3 scene file.
    pub scene: PathBuf,
    /// `--quick`, `--resolution` and `--crop`, applied while loading.
    pub load: LoadOptions,
    /// Everything else that decides the image.
    pub settings: RenderSettings,
    /// What to write.
    pub outputs: Outputs,
}

/// A finished job.
#[derive(Debug)]
pub struct Finished {
    /// Where the image went (one path per file written).
    pub image_paths: Vec<PathBuf>,
    /// What the render produced.
    pub output: RenderOutput,
    /// The times of loading.
    pub load: LoadStats,
}

impl RenderJob {
    /// Loads the scene and renders it, writing nothing; the warnings of both go to `warnings`, whether or
    /// not the render succeeds.
    pub fn render(&self, warnings: &mut Warnings) -> Result<RenderOutput> {
        let loaded = load(&self.scene, self.load)?;
        warnings.extend(loaded.warnings);
        render(&loaded.scene, loaded.integrator.as_ref(), &self.settings, warnings)
    }

    /// Renders and writes every output, all or nothing: each requested output is checked before the
    /// render and before any file is written, and every file is written atomically. The warnings of loading
    /// go to `warnings` before the first pixel is rendered, the integrator's as it finds them (a collection
    /// made with [`Warnings::printing`] shows them at once), whether or not the render succeeds.
    pub fn run(&self, warnings: &mut Warnings) -> Result<Finished> {
        // Every output named on the command line is checked before the scene is read, so a typo in a folder
        // or an extension costs nothing; the Film's own file name once the scene is read.
        let o = &self.outputs;
        let named = o.images.iter().map(|p| ("--outfile", p, true));
        let cache = [("--overlay", &o.overlay, true), ("--dmap", &o.dmap, true), ("--stats", &o.stats, false)];
        let cache = cache.into_iter().filter_map(|(f, p, image)| Some((f, p.as_ref()?, image)));
        for (flag, path, image) in named.chain(cache) {
            if path != Path::new("-") {
                crate::image::check_output(flag, path, image)?;
            }
        }
        let loaded = load(&self.scene, self.load)?;
        warnings.extend(loaded.warnings);
        let image_paths = self.image_paths(&loaded.scene.film.filename);
        if o.images.is_empty() {
            for p in &image_paths {
                crate::image::check_output("Film \"filename\"", p, true)?;
            }
        }
        let output = render(&loaded.scene, loaded.integrator.as_ref(), &self.settings, warnings)?;
        let meta = self.metadata(&loaded.scene.film, &output);
        self.write(&output, &image_paths, &meta)?;
        Ok(Finished { image_paths, output, load: loaded.stats })
    }

    /// The images' paths: [`Outputs::images`], else the Film's name, else the scene's stem with `.exr`.
    fn image_paths(&self, film_name: &Option<PathBuf>) -> Vec<PathBuf> {
        if !self.outputs.images.is_empty() {
            return self.outputs.images.clone();
        }
        if let Some(f) = film_name {
            return vec![f.clone()];
        }
        let stem = self.scene.file_stem().unwrap_or(Path::new("cachert").as_os_str());
        vec![PathBuf::from(stem).with_extension("exr")]
    }

    /// What an EXR image records beside its pixels: where a cropped image sits in the film (pbrt-v3's data
    /// window) and the `--stats` essentials — integrator, placement, caches, seed, samples, render time,
    /// cachert's version and commit — for `cachert info IMAGE.exr`. The render time makes two files of the
    /// same render differ in their headers; their pixels are the same, bit for bit.
    fn metadata(&self, film: &FilmSpec, output: &RenderOutput) -> Metadata {
        let b = film.cropped_bounds();
        let full = film.resolution.map(|r| r as usize);
        let origin = b.min.map(|m| m.max(0) as usize);
        let cropped = origin != [0, 0] || [output.image.width, output.image.height] != full;
        let window = cropped.then_some(Window { full, origin });
        let s = &self.settings;
        // A cache render names itself "<application>, placement <name>": the placement has its own attribute.
        let integrator = output.integrator.split_once(", placement").map_or(&*output.integrator, |(name, _)| name);
        let mut a: Vec<(&str, String)> =
            vec![("scene", self.scene.display().to_string()), ("integrator", integrator.to_string())];
        let cache = output.cache.as_deref();
        if let Some(c) = cache {
            let placement = c.settings.get("placement").and_then(|p| p.as_str()).unwrap_or("");
            a.push(("placement", placement.to_string()));
            a.push(("caches", c.stats.total_caches.to_string()));
        }
        a.push(("seed", s.seed.to_string()));
        a.push(("samplesPerPixel", output.spp.to_string()));
        if !s.set.is_empty() {
            a.push(("set", s.set.iter().map(|(k, v)| format!("{k}={v}")).collect::<Vec<_>>().join(" ")));
        }
        let secs = cache.map_or(output.render_secs, |c| c.stats.times.total);
        a.push(("renderTimeSeconds", format!("{secs:.3}")));
        a.push(("cachertVersion", env!("CARGO_PKG_VERSION").to_string()));
        a.push(("cachertCommit", crate::provenance::of_this_build().commit()));
        Metadata { window, attributes: a.into_iter().map(|(k, v)| (k.to_string(), v)).collect() }
    }

    /// Writes the images and the cache outputs, checking every requested output before writing any.
    fn write(&self, result: &RenderOutput, image_paths: &[PathBuf], meta: &Metadata) -> Result<()> {
        let o = &self.outputs;
        let cache = result.cache.as_deref();
        if (o.overlay.is_some() || o.dmap.is_some() || o.stats.is_some()) && cache.is_none() {
            return Err(Error::usage(format!(
                "--overlay, --dmap and --stats need a cache-based integrator (--integrator with one of: {})",
                registry::names()
            )));
        }
        if o.dmap.is_some() && cache.is_some_and(|c| c.discontinuity.is_none()) {
            return Err(Error::usage(
                "--dmap: this placement has no discontinuity map (use vgc+dgs or one of its ablations)",
            ));
        }
        for p in [&o.overlay, &o.dmap].into_iter().flatten() {
            crate::image::Format::from_path(p)?;
        }
        for p in image_paths {
            crate::image::write_with(&result.image, p, meta)?;
        }
        if let Some(c) = cache {
            if let Some(p) = &o.overlay {
                cache_outputs::write_overlay(c, p)?;
            }
            if let Some(p) = &o.dmap {
                cache_outputs::write_dmap(c, p)?;
            }
            if let Some(p) = &o.stats {
                let s = &self.settings;
                let settings = serde_json::json!({
                    "scene": self.scene.display().to_string(),
                    "integrator": result.integrator,
                    "seed": s.seed,
                    "set": s.set.iter().map(|(k, v)| format!("{k}={v}")).collect::<Vec<_>>(),
                    "parameters": c.settings,
                });
                cache_outputs::write_stats(c, &settings, p)?;
            }
        }
        Ok(())
    }

    /// The job as `cachert` arguments (without the program name), for a scheduler that runs command lines;
    /// `cachert` given them renders the same image. `--set` pairs come after the typed flags, as the typed
    /// settings win over them.
    pub fn argv(&self) -> Vec<String> {
        let s = &self.settings;
        let mut a = vec!["render".to_string(), self.scene.display().to_string()];
        let mut flag = |name: &str, value: String| {
            a.push(format!("--{name}"));
            a.push(value);
        };
        if let Some(i) = &s.integrator {
            flag("integrator", i.clone());
        }
        if let Some(p) = &s.cache.placement {
            flag("placement", p.to_string());
        }
        if let Some(c) = s.cache.caches {
            flag("caches", c.to_string());
        }
        flag("seed", s.seed.to_string());
        if let Some([w, h]) = self.load.resolution {
            flag("resolution", format!("{w}x{h}"));
        }
        if let Some(c) = self.load.crop {
            flag("crop", c.0.map(|v| v.to_string()).join(","));
        }
        if let Some(n) = s.spp {
            flag("spp", n.to_string());
        }
        if let Some(n) = s.threads {
            flag("nthreads", n.to_string());
        }
        for (k, v) in &s.set {
            flag("set", format!("{k}={v}"));
        }
        if self.load.quick {
            a.push("--quick".into());
        }
        if !s.progress {
            a.push("--quiet".into());
        }
        let o = &self.outputs;
        let images = o.images.iter().map(|p| ("outfile", p));
        let cache = [("overlay", &o.overlay), ("stats", &o.stats), ("dmap", &o.dmap)];
        for (name, p) in images.chain(cache.into_iter().filter_map(|(n, p)| Some((n, p.as_ref()?)))) {
            a.push(format!("--{name}"));
            a.push(p.display().to_string());
        }
        a
    }
}

impl Finished {
    /// The end-of-run summary: the image written, load and render times, the cache driver's stage times
    /// for a cache-based render, and the ray throughput.
    pub fn summary(&self) -> String {
        let (result, s) = (&self.output, &self.load);
        let rays = result.rays.total() as f64;
        let cache = result.cache.as_deref();
        let samples = if cache.is_some() { "sub-pixel samples" } else { "spp" };
        let (w, h) = (result.image.width, result.image.height);
        let paths: Vec<String> = self.image_paths.iter().map(|p| p.display().to_string()).collect();
        let wrote = format!("wrote {} ({w}x{h}, {} {samples}, {})", paths.join(", "), result.spp, result.integrator);
        let load =
            format!("parse {:.3} s | scene build {:.3} s | BVH build {:.3} s", s.parse_secs, s.build_secs, s.bvh_secs);
        match cache {
            Some(c) => format!(
                "{wrote}\n{load}\n{}\nrays {:.1} M: {:.2} Mrays/s",
                c.stats.summary(),
                rays / 1e6,
                rays / 1e6 / c.stats.times.total.max(1e-9)
            ),
            None => format!(
                "{wrote}\n{load} | render {:.3} s\nrays {:.1} M (camera {:.2} M, occlusion {:.2} M): {:.2} Mrays/s",
                result.render_secs,
                rays / 1e6,
                result.rays.camera as f64 / 1e6,
                result.rays.shadow as f64 / 1e6,
                rays / 1e6 / result.render_secs.max(1e-9),
            ),
        }
    }
}
