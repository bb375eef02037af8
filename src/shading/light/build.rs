//! STAGE 5 (shading): turning the scene's stored `LightSource`/`AreaLightSource` records into [`Lights`] —
//! pbrt-v3's `Create*Light` defaults and transforms, its per-triangle area lights, and the checks on bad
//! values (an error at the directive), zero-power lights (skipped with a warning) and unreadable
//! environment maps (a warning; pbrt-v3's constant-L fallback).
//!
//! Depends on `scene` (stored lights, geometry, bounds), `image` and the light types of this module.

use glam::{Mat3A, Vec3A};

use super::area::{Emission, triangle_area};
use super::envmap::EnvMap;
use super::infinite::InfiniteLight;
use super::shape_sampler::ShapeSampler;
use super::{DistantLight, Entry, Kind, Lights, NO_LIGHT, PointLight, SpotLight};
use crate::error::{Error, Result, SourceLoc, Warnings};
use crate::scene::Scene;
use crate::scene::geometry::ShapeId;
use crate::scene::light::LightSpec;
use crate::scene::props::{Prop, Props};
use crate::shading::Spectrum;

/// A colour parameter times `scale`, checked: every component finite and ≥ 0, else an error at `loc`.
fn colour(props: &Props, name: &str, what: &str, loc: &SourceLoc) -> Result<Spectrum> {
    let v = Spectrum::from(props.rgb(name, [1.0; 3]));
    let s = Spectrum::from(props.rgb("scale", [1.0; 3]));
    for (label, c) in [(name, v), ("scale", s)] {
        if !c.is_finite() || c.min_element() < 0.0 {
            return Err(Error::at(
                loc,
                format!("{what}: \"{label}\" is [{} {} {}]; it must be finite and not negative", c.x, c.y, c.z),
            ));
        }
    }
    let out = v * s;
    if !out.is_finite() {
        return Err(Error::at(loc, format!("{what}: \"{name}\" × \"scale\" overflows")));
    }
    Ok(out)
}

/// pbrt-v3's `nSamples`: `"samples"`, else `"nsamples"`, else 1; values below 1 become 1 with a warning.
fn samples(props: &Props, what: &str, loc: &SourceLoc, warnings: &mut Warnings) -> u32 {
    let get = |n: &str| match props.get(n) {
        Some(Prop::Int(v)) => Some(*v),
        _ => None,
    };
    let n = get("samples").or_else(|| get("nsamples")).unwrap_or(1);
    if n < 1 {
        warnings.at(loc, format!("{what}: {n} light samples; using 1"));
        return 1;
    }
    n.min(1 << 20) as u32
}

fn point3(props: &Props, name: &str, default: [f32; 3]) -> Vec3A {
    match props.get(name) {
        Some(Prop::Vec3(v)) => Vec3A::from(*v),
        _ => Vec3A::from(default),
    }
}

/// Luminance used to decide "zero power".
fn is_black(c: Spectrum) -> bool {
    c.max_element() <= 0.0
}

/// Reads an environment map and multiplies it by `l`, or says why it cannot be used.
fn read_envmap(path: &str, l: Spectrum) -> std::result::Result<EnvMap, String> {
    let im = crate::image::read(std::path::Path::new(path)).map_err(|e| e.to_string())?;
    if im.width == 0 || im.height == 0 {
        return Err(format!("{path}: the image has no pixels"));
    }
    if im.width > 1 << 15 || im.height > 1 << 15 {
        return Err(format!("{path}: {}×{} is too large for an environment map", im.width, im.height));
    }
    let mut bad = 0usize;
    let texels = im
        .pixels
        .iter()
        .map(|p| {
            let c = Spectrum::from(*p);
            if c.is_finite() {
                c * l
            } else {
                bad += 1;
                Spectrum::ZERO
            }
        })
        .collect();
    if bad > 0 {
        return Err(format!("{path}: {bad} texels are not finite"));
    }
    EnvMap::new(im.width, im.height, texels).ok_or_else(|| format!("{path}: the image has no pixels"))
}

impl<'a> Lights<'a> {
    /// Builds the lights of `scene`. Bad values (negative or non-finite colours, a spot or distant light
    /// whose `from` equals `to`) are errors at the directive; lights that emit nothing are skipped with a
    /// warning; goniometric and projection lights are refused with a warning; an environment map that
    /// cannot be read, is empty or has non-finite texels becomes pbrt-v3's constant L with a warning.
    pub fn build(scene: &'a Scene, warnings: &mut Warnings) -> Result<Lights<'a>> {
        let world_radius = scene.bounds().map_or(0.0, |(lo, hi)| 0.5 * (hi - lo).length());
        let world_center = scene.bounds().map_or(Vec3A::ZERO, |(lo, hi)| 0.5 * (lo + hi));
        let mut lights = Lights {
            geometry: &scene.geometry,
            world_center,
            world_radius,
            entries: Vec::new(),
            infinite: Vec::new(),
            emission: Vec::new(),
            first_slot: Vec::new(),
            slots: Vec::new(),
        };
        for light in &scene.lights {
            lights.add_light(light, world_radius, warnings)?;
        }
        lights.add_area_lights(scene, warnings)?;
        Ok(lights)
    }

    fn add_light(&mut self, light: &LightSpec, world_radius: f32, warnings: &mut Warnings) -> Result<()> {
        let loc = &light.loc;
        let ty = light.type_name.as_str();
        let what = format!("LightSource \"{ty}\"");
        let xf = light.world_from_light;
        let m: Mat3A = xf.matrix3;
        let props = &light.props;
        let kind = match ty {
            "point" => {
                let i = colour(props, "I", &what, loc)?;
                // pbrt-v3: Translate(from) * CTM, so `from` is added in world space.
                let p = xf.translation + point3(props, "from", [0.0; 3]);
                Kind::Point(PointLight { p, i })
            }
            "spot" => Kind::Spot(spot_light(light, &what)?),
            "distant" => {
                let l = colour(props, "L", &what, loc)?;
                let (from, to) = (point3(props, "from", [0.0; 3]), point3(props, "to", [0.0, 0.0, 1.0]));
                let w = (m * (from - to)).normalize_or_zero();
                if w == Vec3A::ZERO {
                    return Err(Error::at(loc, format!("{what}: \"from\" and \"to\" are the same point")));
                }
                Kind::Distant(DistantLight { w, l, world_radius })
            }
            "infinite" | "exinfinite" => {
                let Some(light) = infinite_light(light, &what, world_radius, warnings)? else { return Ok(()) };
                self.infinite.push(light);
                Kind::Infinite(self.infinite.len() as u32 - 1)
            }
            "goniometric" | "projection" => {
                warnings.at(loc, format!("{what} is not supported; the light is skipped"));
                return Ok(());
            }
            other => {
                warnings.at(loc, format!("unknown light type \"{other}\"; skipped"));
                return Ok(());
            }
        };
        let power = match kind {
            Kind::Point(l) => l.power(),
            Kind::Spot(l) => l.power(),
            Kind::Distant(l) => l.power(),
            Kind::Infinite(i) => self.infinite[i as usize].power(),
            _ => Spectrum::ZERO,
        };
        // Zero power decided on what the light emits, not on the world's size (an empty world gives a
        // distant or infinite light zero power in pbrt-v3 but it still lights what the camera sees).
        let emits = match kind {
            Kind::Point(l) => !is_black(l.i),
            Kind::Spot(l) => !is_black(l.power()),
            Kind::Distant(l) => !is_black(l.l),
            _ => true,
        };
        if !emits {
            warnings.at(loc, format!("{what} emits nothing (zero power); skipped"));
            return Ok(());
        }
        let samples = samples(props, &what, loc, warnings);
        let bound = match kind {
            Kind::Point(l) => (l.p, 0.0),
            Kind::Spot(l) => (l.p, 0.0),
            _ => (Vec3A::ZERO, f32::INFINITY),
        };
        self.entries.push(Entry { kind, power, samples, bound });
        Ok(())
    }

    fn add_area_lights(&mut self, scene: &Scene, warnings: &mut Warnings) -> Result<()> {
        for (a, al) in scene.area_lights.iter().enumerate() {
            let loc = &al.loc;
            let what = "AreaLightSource \"diffuse\"";
            let l = colour(&al.props, "L", what, loc)?;
            let two_sided = matches!(al.props.get("twosided"), Some(Prop::Bool(true)));
            let em = Emission { l, two_sided };
            let samples = samples(&al.props, what, loc, warnings);
            self.emission.push(em);
            self.first_slot.push(self.slots.len() as u32);
            let black = is_black(l);
            if black {
                warnings.at(loc, format!("{what} emits nothing (zero L); its shapes are not light sources"));
            }
            match al.shape {
                ShapeId::Mesh(mi) => {
                    let mesh = &scene.geometry.meshes[mi as usize];
                    for tri in 0..mesh.triangle_count() {
                        let area = triangle_area(mesh, tri);
                        if black || !(area > 0.0 && area.is_finite()) {
                            self.slots.push(NO_LIGHT);
                            continue;
                        }
                        self.slots.push(self.entries.len() as u32);
                        let n_face = super::area::face_normal(mesh, tri);
                        let kind = Kind::Triangle { area: a as u32, mesh: mi, tri: tri as u32, tri_area: area, n_face };
                        let v = mesh.triangle(tri).map(Vec3A::from);
                        let c = (v[0] + v[1] + v[2]) / 3.0;
                        let bound = (c, v.iter().map(|p| p.distance(c)).fold(0.0, f32::max));
                        self.entries.push(Entry { kind, power: em.power(area), samples, bound });
                    }
                }
                ShapeId::Quadric(qi) => {
                    let q = &scene.geometry.accel.quadrics[qi as usize];
                    match ShapeSampler::new(q) {
                        Some(sampler) if !black && sampler.area() > 0.0 && sampler.area().is_finite() => {
                            self.slots.push(self.entries.len() as u32);
                            let kind = Kind::Shape { area: a as u32, quadric: qi, sampler };
                            let (lo, hi) = q.world_bounds();
                            let bound = ((lo + hi) * 0.5, (hi - lo).length() * 0.5);
                            self.entries.push(Entry { kind, power: em.power(sampler.area()), samples, bound });
                        }
                        Some(_) => self.slots.push(NO_LIGHT),
                        None => {
                            warnings.at(
                                loc,
                                "hyperboloid area lights cannot be sampled (pbrt-v3 aborts on them); the shape \
                                 still emits where rays hit it",
                            );
                            self.slots.push(NO_LIGHT);
                        }
                    }
                }
            }
        }
        Ok(())
    }
}

/// A `spot` light: position, cone and axis from "from" and "to" in the light's space.
fn spot_light(light: &LightSpec, what: &str) -> Result<SpotLight> {
    let (loc, props, xf) = (&light.loc, &light.props, light.world_from_light);
    let m: Mat3A = xf.matrix3;
    let i = colour(props, "I", what, loc)?;
    let cone = props.float("coneangle", 30.0);
    let delta = props.float("conedeltaangle", 5.0);
    if !cone.is_finite() || !delta.is_finite() {
        return Err(Error::at(loc, format!("{what}: the cone angles must be finite")));
    }
    let (from, to) = (point3(props, "from", [0.0; 3]), point3(props, "to", [0.0, 0.0, 1.0]));
    let axis = (to - from).normalize_or_zero();
    if axis == Vec3A::ZERO {
        return Err(Error::at(loc, format!("{what}: \"from\" and \"to\" are the same point")));
    }
    Ok(SpotLight {
        p: xf.transform_point3a(from),
        i,
        light_from_world: m.inverse(),
        axis,
        cos_total: cone.to_radians().cos(),
        cos_falloff_start: (cone - delta).to_radians().cos(),
    })
}

/// An `infinite` light with its environment map (the constant L, with a warning, when the map cannot be
/// read, as pbrt-v3 does); `None`, with a warning, when it emits nothing.
fn infinite_light(
    light: &LightSpec,
    what: &str,
    world_radius: f32,
    warnings: &mut Warnings,
) -> Result<Option<InfiniteLight>> {
    let (loc, props) = (&light.loc, &light.props);
    let m: Mat3A = light.world_from_light.matrix3;
    let l = colour(props, "L", what, loc)?;
    let map = match props.str("mapname") {
        Some(path) => read_envmap(path, l).unwrap_or_else(|why| {
            warnings.at(loc, format!("{what}: environment map unusable ({why}); using the constant L as pbrt-v3 does"));
            EnvMap::constant(l)
        }),
        None => EnvMap::constant(l),
    };
    if m.determinant() == 0.0 || !m.is_finite() {
        return Err(Error::at(loc, format!("{what}: the transform cannot be inverted")));
    }
    let light = InfiniteLight::new(map, m, world_radius);
    if is_black(light.map().mean()) {
        warnings.at(loc, format!("{what} emits nothing; skipped"));
        return Ok(None);
    }
    Ok(Some(light))
}
