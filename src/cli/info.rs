//! `cachert info`: what a scene file loads to — shapes, triangles, instances, lights, materials, bounds,
//! warnings and the time each loading stage took. The warnings are every one `cachert render SCENE` prints:
//! those of loading, then the integrator's, from `integrator::dry_run` — the render's own code path stopped
//! before the first pixel (parameters unused, scene settings a cache-based integrator cannot use, the
//! shading set-up: an unsupported material rendered as matte, an unreadable environment map, a zero-power
//! light). For an integrator cachert does not implement (render refuses it), the shading set-up's.
//!
//! Given an image (`.exr`, `.pfm` or `.png`, by extension) instead, it describes the file: format, size,
//! display and data windows, text attributes, and each channel's mean, min and max over its finite values
//! with the count of non-finite ones (see [`describe_image`]).

use std::fmt::Write;
use std::path::{Path, PathBuf};

use crate::error::Result;
use crate::scene::{LoadOptions, load};

/// Flags of `cachert info`.
#[derive(clap::Args, Debug, Clone)]
pub struct InfoArgs {
    /// The pbrt-v3 scene file, or an image (.exr, .pfm, .png) to describe.
    pub scene: PathBuf,
}

/// Runs `cachert info` and returns the report.
pub fn run(args: &InfoArgs) -> Result<String> {
    if let Ok(format) = crate::image::Format::from_path(&args.scene) {
        return describe_image(&args.scene, format);
    }
    let mut l = load(&args.scene, LoadOptions::default())?;
    integrator_warnings(&l.scene, l.integrator.as_ref(), &mut l.warnings)?;
    let (s, st) = (&l.scene, &l.stats);
    let mut o = String::new();
    let _ = writeln!(o, "scene       {}", s.source.display());
    let _ = writeln!(o, "film        {}x{}  crop {:?}", s.film.resolution[0], s.film.resolution[1], s.film.crop);
    let _ = writeln!(o, "camera      {:?} at {:?}", s.camera.projection, s.camera.position().to_array());
    let _ = writeln!(o, "sampler     {} ({} spp)", s.sampler.name, s.sampler.spp);
    let integrator = l.integrator.as_ref().map_or("path (pbrt-v3 default)", |n| n.name.as_str());
    let name = l.integrator.as_ref().map_or("path", |n| n.name.as_str());
    let stand_in = crate::integrator::STAND_INS.iter().find(|s| s.pbrt == name);
    let kind = match (stand_in, crate::application::registry::entry(name)) {
        (Some(s), _) => format!("rendered by {}: {}", s.cachert, s.why),
        (None, Some(e)) => format!("cache-based: {}", e.about),
        (None, None) if crate::render::INTEGRATORS.contains(&name) => "per-pixel".to_string(),
        (None, None) => {
            format!("not implemented; choose one with --integrator: {}", crate::integrator::integrator_names())
        }
    };
    let _ = writeln!(o, "integrator  {integrator} ({kind})");
    let world_tris: usize = s.geometry.meshes.iter().map(|m| m.triangle_count()).sum();
    let object_tris: usize = s.geometry.objects.iter().flat_map(|o| &o.meshes).map(|m| m.triangle_count()).sum();
    let (_, objects, instances) = s.geometry.accel.counts();
    let instanced: usize = instance_triangles(s);
    let _ = writeln!(
        o,
        "shapes      {} ({} world meshes, {} analytic, {} curves in {} segments)",
        st.shapes,
        s.geometry.meshes.len(),
        s.geometry.accel.quadrics.len(),
        s.geometry.accel.curves.len(),
        s.geometry.accel.curve_segments.len()
    );
    if !st.shape_types.is_empty() {
        let per_type: Vec<String> = st.shape_types.iter().map(|(t, n)| format!("{t} {n}")).collect();
        let _ = writeln!(o, "            by type: {}", per_type.join(", "));
    }
    let _ = writeln!(
        o,
        "triangles   {} stored ({world_tris} world, {object_tris} in {objects} object definitions)",
        st.triangles
    );
    let _ = writeln!(o, "instances   {instances} ({instanced} triangles if flattened)");
    let mut light_types = by_type(s.lights.iter().map(|l| l.type_name.as_str()));
    if !s.area_lights.is_empty() {
        light_types.push(("diffuse area (shapes)".to_string(), s.area_lights.len()));
    }
    let _ = writeln!(o, "lights      {}{}", s.lights.len() + s.area_lights.len(), listing(&light_types));
    let material_types = by_type(s.materials.iter().map(|m| m.type_name.as_str()));
    let _ = writeln!(o, "materials   {}{}", s.materials.len(), listing(&material_types));
    let texture_types = by_type(s.textures.iter().map(|t| t.class.as_str()));
    let _ = writeln!(o, "textures    {}{}", s.textures.len(), listing(&texture_types));
    match s.bounds() {
        Some((lo, hi)) => {
            let _ =
                writeln!(o, "bounds      {:?} .. {:?} (diagonal {:.4})", lo.to_array(), hi.to_array(), s.diagonal());
        }
        None => {
            let _ = writeln!(o, "bounds      empty world");
        }
    }
    let _ = writeln!(
        o,
        "time        parse {:.3} s | scene build {:.3} s | BVH build {:.3} s",
        st.parse_secs, st.build_secs, st.bvh_secs
    );
    let notes = l.warnings.iter().filter(|w| w.is_note()).count();
    let and_notes = if notes > 0 { format!(" (and {notes} notes)") } else { String::new() };
    let _ = writeln!(o, "warnings    {}{and_notes}", l.warnings.len() - notes);
    for w in l.warnings.iter() {
        let _ = writeln!(o, "  {w}");
    }
    Ok(o)
}

/// `cachert info IMAGE`: format, size, windows, text attributes and per-channel statistics of an image.
pub fn describe_image(path: &Path, format: crate::image::Format) -> Result<String> {
    let meta = crate::image::read_metadata(path)?;
    let image = crate::image::read(path)?;
    let mut o = String::new();
    let _ = writeln!(o, "image       {}", path.display());
    let format_name = match format {
        crate::image::Format::Exr => "EXR",
        crate::image::Format::Pfm => "PFM",
        crate::image::Format::Png => "PNG",
    };
    let _ = writeln!(o, "format      {format_name}");
    let _ = writeln!(o, "size        {}x{}", image.width, image.height);
    if let Some(w) = meta.window {
        let _ = writeln!(o, "display     (0, 0) .. ({}, {})", w.full[0].saturating_sub(1), w.full[1].saturating_sub(1));
        let (x1, y1) = (w.origin[0] + image.width - 1, w.origin[1] + image.height - 1);
        let _ = writeln!(o, "data        ({}, {}) .. ({x1}, {y1})", w.origin[0], w.origin[1]);
    }
    let _ = writeln!(o, "attributes  {}", meta.attributes.len());
    for (name, value) in &meta.attributes {
        let _ = writeln!(o, "  {name}  {value}");
    }
    let _ = writeln!(o, "channel     {:>14}{:>14}{:>14}  (finite values)", "mean", "min", "max");
    let mut non_finite = 0usize;
    for (c, name) in ["R", "G", "B"].iter().enumerate() {
        let (mut sum, mut n, mut lo, mut hi) = (0.0f64, 0usize, f32::INFINITY, f32::NEG_INFINITY);
        for v in image.pixels.iter().map(|p| p[c]) {
            if v.is_finite() {
                (sum, n, lo, hi) = (sum + f64::from(v), n + 1, lo.min(v), hi.max(v));
            } else {
                non_finite += 1;
            }
        }
        if n == 0 {
            let _ = writeln!(o, "  {name:<10}{:>14}{:>14}{:>14}", "-", "-", "-");
        } else {
            let mean = sum / n as f64;
            let _ = writeln!(o, "  {name:<10}{:>14}{:>14}{:>14}", number(mean), number(lo.into()), number(hi.into()));
        }
    }
    let _ = writeln!(o, "non-finite  {non_finite}");
    Ok(o)
}

/// A statistic for the table: fixed point for ordinary magnitudes, scientific otherwise.
fn number(v: f64) -> String {
    if v == 0.0 || (1e-3..1e6).contains(&v.abs()) { format!("{v:.6}") } else { format!("{v:.4e}") }
}

/// The warnings `cachert render` adds to loading's for the scene's integrator (and its errors before the
/// first pixel: what render refuses, info refuses too), from the render's own code path
/// (`integrator::dry_run`, default settings as `render SCENE` has). An integrator cachert does not
/// implement gives the shading set-up's warnings instead, which any integrator chosen in its place with
/// `--integrator` (except `ambientocclusion`) would print.
fn integrator_warnings(
    scene: &crate::scene::Scene,
    integrator: Option<&crate::parse::Named>,
    warnings: &mut crate::error::Warnings,
) -> Result<()> {
    let name = integrator.map_or("path", |n| n.name.as_str());
    let implemented = crate::render::INTEGRATORS.contains(&name) || crate::application::registry::entry(name).is_some();
    if implemented {
        let settings = crate::integrator::RenderSettings::default();
        crate::integrator::dry_run(scene, integrator, &settings, warnings)
    } else {
        shading_warnings(scene, warnings)
    }
}

/// Builds the scene's textures, materials and lights as a shading integrator does, for their warnings (and
/// their errors).
fn shading_warnings(scene: &crate::scene::Scene, warnings: &mut crate::error::Warnings) -> Result<()> {
    crate::shading::texture::Textures::build(scene, warnings)?;
    crate::shading::material::Materials::build(scene, warnings)?;
    crate::shading::light::Lights::build(scene, warnings)?;
    Ok(())
}

fn instance_triangles(s: &crate::scene::Scene) -> usize {
    let per_object: Vec<usize> =
        s.geometry.objects.iter().map(|o| o.meshes.iter().map(|m| m.triangle_count()).sum()).collect();
    (0..s.geometry.accel.counts().2).map(|i| per_object[s.geometry.accel.instance(i as u32).object as usize]).sum()
}

/// Counts names, in order of first appearance.
fn by_type<'a>(names: impl Iterator<Item = &'a str>) -> Vec<(String, usize)> {
    let mut out: Vec<(String, usize)> = Vec::new();
    for n in names {
        let n = if n.is_empty() { "none" } else { n };
        match out.iter_mut().find(|(t, _)| t == n) {
            Some(e) => e.1 += 1,
            None => out.push((n.to_string(), 1)),
        }
    }
    out
}

/// ": a 2, b 1" (empty for no entries).
fn listing(types: &[(String, usize)]) -> String {
    if types.is_empty() {
        return String::new();
    }
    let parts: Vec<String> = types.iter().map(|(t, n)| format!("{t} {n}")).collect();
    format!(": {}", parts.join(", "))
}
