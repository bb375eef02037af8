//! STAGE 2 (scene builder): appearance directives — Material, MakeNamedMaterial, NamedMaterial, Texture,
//! LightSource, AreaLightSource — and object definitions (ObjectBegin/End/Instance).

use std::rc::Rc;

use crate::error::{Error, Result, SourceLoc};
use crate::parse::Named;
use crate::scene::accel::{InstanceXf, Shapes, check_extent};
use crate::scene::geometry::ObjectDef;
use crate::scene::light::{self, LightSpec};
use crate::scene::material::{MaterialKind, MaterialSpec};
use crate::scene::props::{Capture, Prop, Props};
use crate::scene::texture::{self, TextureSpec, TextureValue};
use crate::scene::transform::transform_bounds;

use super::state::Block;
use super::{ObjectRecord, SceneBuilder};

impl SceneBuilder {
    /// Creates a material of type `type_name` from `n`'s parameters (unknown type: warning + matte).
    fn make_material(&mut self, type_name: &str, n: &Named, type_loc: &SourceLoc) -> Result<u32> {
        let kind = match MaterialKind::from_name(type_name) {
            Some(k) => k,
            None => {
                self.warnings.at(type_loc, format!("unknown material type \"{type_name}\"; using matte"));
                n.params.mark_all_used();
                self.materials.push(MaterialSpec { loc: Some(type_loc.clone()), ..MaterialSpec::default_matte() });
                return Ok(self.materials.len() as u32 - 1);
            }
        };
        let mut props = Props::default();
        let textures = Rc::clone(&self.gs.textures);
        Capture { textures: &textures, loc: &n.name_loc, warnings: &mut self.warnings }.read(
            &n.params,
            kind.schema(),
            &mut props,
        )?;
        let mut mix = None;
        if kind == MaterialKind::Mix {
            let mut ids = [0u32; 2];
            for (k, key) in ["namedmaterial1", "namedmaterial2"].iter().enumerate() {
                let name = props.str(key).unwrap_or("").to_string();
                ids[k] = match self.gs.named_materials.get(&name) {
                    Some(&id) => id,
                    None => {
                        let loc = n.params.loc_of(key).unwrap_or(&n.name_loc);
                        self.warnings.at(loc, format!("mix: no named material \"{name}\"; using the default matte"));
                        0
                    }
                };
            }
            mix = Some(ids);
        }
        let param_locs =
            kind.schema().iter().filter_map(|&(name, _)| n.params.loc_of(name).map(|l| (name, l.clone()))).collect();
        self.materials.push(MaterialSpec {
            type_name: type_name.to_string(),
            kind,
            props,
            mix,
            loc: Some(type_loc.clone()),
            param_locs,
        });
        Ok(self.materials.len() as u32 - 1)
    }

    pub(super) fn material_directive(&mut self, n: Named, _loc: &SourceLoc) -> Result<()> {
        let id = self.make_material(&n.name.clone(), &n, &n.name_loc.clone())?;
        self.report_unused(&n.params, "Material");
        self.gs.material = id;
        Ok(())
    }

    pub(super) fn make_named_material(&mut self, n: Named, loc: &SourceLoc) -> Result<()> {
        let Some(type_name) = n.params.string("type")?.map(str::to_string) else {
            return Err(Error::at(loc, format!("MakeNamedMaterial \"{}\": missing parameter \"string type\"", n.name)));
        };
        let type_loc = n.params.loc_of("type").unwrap_or(loc).clone();
        let id = self.make_material(&type_name, &n, &type_loc)?;
        self.report_unused(&n.params, "MakeNamedMaterial");
        if self.gs.named_materials.contains_key(&n.name) {
            self.warnings.at(loc, format!("named material \"{}\" redefined", n.name));
        }
        Rc::make_mut(&mut self.gs.named_materials).insert(n.name, id);
        Ok(())
    }

    pub(super) fn named_material(&mut self, name: &str, loc: &SourceLoc) -> Result<()> {
        match self.gs.named_materials.get(name) {
            Some(&id) => {
                self.gs.material = id;
                Ok(())
            }
            None => Err(Error::at(
                loc,
                format!(
                    "NamedMaterial: no material named \"{name}\" has been defined (MakeNamedMaterial) in this scope"
                ),
            )),
        }
    }

    pub(super) fn texture_directive(
        &mut self,
        name: String,
        value_type: &str,
        class: Named,
        loc: &SourceLoc,
    ) -> Result<()> {
        let value = match value_type {
            "float" => TextureValue::Float,
            "spectrum" | "color" | "rgb" => TextureValue::Spectrum,
            other => {
                return Err(Error::at(
                    loc,
                    format!("Texture \"{name}\": unknown texture type \"{other}\"; expected \"float\" or \"spectrum\""),
                ));
            }
        };
        let mut props = Props::default();
        let mut class_name = class.name.clone();
        match texture::schema(&class.name, value) {
            Some(schema) => {
                let textures = Rc::clone(&self.gs.textures);
                Capture { textures: &textures, loc: &class.name_loc, warnings: &mut self.warnings }.read(
                    &class.params,
                    &schema,
                    &mut props,
                )?;
                if let Some(Prop::Str(file)) = props.get("filename")
                    && !std::path::Path::new(file).is_file()
                {
                    let floc = class.params.loc_of("filename").unwrap_or(&class.name_loc);
                    // Said once, here at load; the shading stage puts pbrt-v3's grey texel in its place.
                    self.warnings.at(
                        floc,
                        format!("texture \"{name}\": cannot read image \"{file}\"; using pbrt-v3's grey 0.5 texel"),
                    );
                }
            }
            None => {
                self.warnings.at(
                    &class.name_loc,
                    format!("texture \"{name}\": unknown texture class \"{}\"; using the constant 1", class.name),
                );
                class.params.mark_all_used();
                class_name = "constant".into();
            }
        }
        self.report_unused(&class.params, "Texture");
        let texture_from_world =
            self.ctm[0].inverse().to_affine().map_err(|e| Error::at(loc, format!("Texture: {e}")))?;
        let id = self.textures.len() as u32;
        self.textures.push(TextureSpec {
            name: name.clone(),
            value,
            class: class_name,
            props,
            texture_from_world,
            loc: loc.clone(),
        });
        let scope = Rc::make_mut(&mut self.gs.textures);
        let map = if value == TextureValue::Float { &mut scope.float } else { &mut scope.spectrum };
        if map.insert(name.clone(), id).is_some() {
            self.warnings.at(loc, format!("texture \"{name}\" redefined"));
        }
        Ok(())
    }

    pub(super) fn light_source(&mut self, n: Named, loc: &SourceLoc) -> Result<()> {
        let Some(schema) = light::schema(&n.name) else {
            self.warnings.at(&n.name_loc, format!("unknown light type \"{}\"; ignored", n.name));
            n.params.mark_all_used();
            return Ok(());
        };
        let mut props = Props::default();
        let textures = Rc::clone(&self.gs.textures);
        Capture { textures: &textures, loc: &n.name_loc, warnings: &mut self.warnings }
            .read(&n.params, schema, &mut props)?;
        self.report_unused(&n.params, "LightSource");
        let world_from_light = self.ctm[0].to_affine().map_err(|e| Error::at(loc, format!("LightSource: {e}")))?;
        self.lights.push(LightSpec { type_name: n.name, props, world_from_light, loc: loc.clone() });
        Ok(())
    }

    pub(super) fn area_light_source(&mut self, n: Named, loc: &SourceLoc) -> Result<()> {
        if n.name != "diffuse" && n.name != "area" {
            self.warnings.at(&n.name_loc, format!("unknown area light type \"{}\"; shapes will not emit", n.name));
            n.params.mark_all_used();
            self.gs.area_light = None;
            return Ok(());
        }
        let mut props = Props::default();
        let textures = Rc::clone(&self.gs.textures);
        Capture { textures: &textures, loc: &n.name_loc, warnings: &mut self.warnings }.read(
            &n.params,
            light::AREA_SCHEMA,
            &mut props,
        )?;
        self.report_unused(&n.params, "AreaLightSource");
        self.gs.area_light = Some((props, loc.clone()));
        Ok(())
    }

    pub(super) fn object_begin(&mut self, name: String, loc: &SourceLoc) -> Result<()> {
        if let Some(o) = self.current_object {
            let outer = &self.objects[o as usize];
            return Err(Error::at(
                loc,
                format!(
                    "ObjectBegin \"{name}\" inside the definition of \"{}\" (started at {}): missing ObjectEnd",
                    outer.def.name, outer.loc
                ),
            ));
        }
        self.push(Block::Object, loc);
        let id = self.objects.len() as u32;
        if self.object_names.insert(name.clone(), id).is_some() {
            self.warnings.at(loc, format!("object \"{name}\" redefined"));
        }
        self.objects.push(ObjectRecord {
            def: ObjectDef { name, meshes: Vec::new() },
            prims: Vec::new(),
            loc: loc.clone(),
            bounds: None,
        });
        self.current_object = Some(id);
        Ok(())
    }

    pub(super) fn object_end(&mut self, loc: &SourceLoc) -> Result<()> {
        if self.current_object.is_none() {
            return Err(Error::at(loc, "ObjectEnd without a matching ObjectBegin"));
        }
        self.pop(Block::Object, loc)?;
        if let Some(o) = self.current_object.take() {
            let rec = &self.objects[o as usize];
            let shapes =
                Shapes { quadrics: &self.quadrics, curves: &self.curves, curve_segments: &self.curve_segments };
            let bounds =
                rec.prims.iter().filter_map(|p| shapes.bounds(p)).reduce(|(lo, hi), (a, b)| (lo.min(a), hi.max(b)));
            self.objects[o as usize].bounds = bounds;
        }
        Ok(())
    }

    pub(super) fn object_instance(&mut self, name: &str, loc: &SourceLoc) -> Result<()> {
        if let Some(o) = self.current_object {
            return Err(Error::at(
                loc,
                format!(
                    "ObjectInstance inside the definition of \"{}\": pbrt-v3 does not nest instances",
                    self.objects[o as usize].def.name
                ),
            ));
        }
        let Some(&object) = self.object_names.get(name) else {
            return Err(Error::at(
                loc,
                format!(
                    "ObjectInstance: no object named \"{name}\" has been defined (ObjectBegin \"{name}\" … ObjectEnd must come first)"
                ),
            ));
        };
        let world_from_object = self.ctm[0].to_affine().map_err(|e| Error::at(loc, format!("ObjectInstance: {e}")))?;
        let object_from_world =
            self.ctm[0].inverse().to_affine().map_err(|e| Error::at(loc, format!("ObjectInstance: {e}")))?;
        if self.objects[object as usize].prims.is_empty() {
            return Ok(());
        }
        if let Some((lo, hi)) = self.objects[object as usize].bounds {
            let (lo, hi) = transform_bounds(&world_from_object, lo, hi);
            check_extent(lo, hi).map_err(|e| Error::at(loc, format!("ObjectInstance \"{name}\": {e}")))?;
        }
        let id = self.instances.len() as u32;
        self.instances.push(InstanceXf { object, world_from_object, object_from_world });
        self.top.push(crate::scene::accel::BuildPrim {
            r: crate::scene::accel::PrimRef::Instance(id),
            verts: [[0.0; 3]; 3],
        });
        Ok(())
    }
}
