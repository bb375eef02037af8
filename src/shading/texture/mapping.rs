//! STAGE 5 (shading): texture-coordinate mappings — where on a texture a surface point lands (pbrt-v3's
//! `UVMapping2D`, `SphericalMapping2D`, `CylindricalMapping2D`, `PlanarMapping2D` and `IdentityMapping3D`).
//!
//! Only the coordinates are computed: cachert traces no ray differentials, so the mappings' derivative
//! outputs (which pbrt-v3 uses to pick a filter width) do not exist here. Depends on the scene's surface
//! interaction and the texture's parameters; nothing else.

use std::f32::consts::PI;

use glam::{Affine3A, Vec3A};

use crate::scene::geometry::SurfaceInteraction;
use crate::scene::props::{Prop, Props};

/// A 2-D texture mapping: surface interaction → (s, t).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Mapping2D {
    /// `(uscale·u + udelta, vscale·v + vdelta)` from the surface's (u, v).
    Uv {
        /// `uscale`
        su: f32,
        /// `vscale`
        sv: f32,
        /// `udelta`
        du: f32,
        /// `vdelta`
        dv: f32,
    },
    /// Polar angles of the point seen from the texture-space origin: (θ/π, φ/2π).
    Spherical {
        /// Texture space ← world.
        texture_from_world: Affine3A,
    },
    /// Angle around and height along the texture-space z axis of the unit direction to the point.
    Cylindrical {
        /// Texture space ← world.
        texture_from_world: Affine3A,
    },
    /// Projections of the world-space point on two vectors, plus offsets.
    Planar {
        /// `v1`
        vs: Vec3A,
        /// `v2`
        vt: Vec3A,
        /// `udelta`
        ds: f32,
        /// `vdelta`
        dt: f32,
    },
}

/// The mapping names pbrt-v3 knows.
pub const MAPPING_NAMES: [&str; 4] = ["uv", "spherical", "cylindrical", "planar"];

impl Mapping2D {
    /// The mapping a texture's parameters describe (pbrt-v3's defaults), or `Err(name)` for an unknown
    /// `mapping` name (pbrt-v3 then reports an error and uses the default uv mapping).
    pub fn from_props(props: &Props, texture_from_world: Affine3A) -> Result<Mapping2D, String> {
        let vec = |name: &str, default: [f32; 3]| match props.get(name) {
            Some(Prop::Vec3(v)) => Vec3A::from(*v),
            _ => Vec3A::from(default),
        };
        match props.str("mapping").unwrap_or("uv") {
            "uv" => Ok(Mapping2D::Uv {
                su: props.float("uscale", 1.0),
                sv: props.float("vscale", 1.0),
                du: props.float("udelta", 0.0),
                dv: props.float("vdelta", 0.0),
            }),
            "spherical" => Ok(Mapping2D::Spherical { texture_from_world }),
            "cylindrical" => Ok(Mapping2D::Cylindrical { texture_from_world }),
            "planar" => Ok(Mapping2D::Planar {
                vs: vec("v1", [1.0, 0.0, 0.0]),
                vt: vec("v2", [0.0, 1.0, 0.0]),
                ds: props.float("udelta", 0.0),
                dt: props.float("vdelta", 0.0),
            }),
            other => Err(other.to_string()),
        }
    }

    /// pbrt-v3's default mapping (uv, unscaled).
    pub const IDENTITY: Mapping2D = Mapping2D::Uv { su: 1.0, sv: 1.0, du: 0.0, dv: 0.0 };

    /// The (s, t) texture coordinates of `si`; never NaN or infinite (a non-finite result becomes 0).
    #[inline]
    pub fn map(&self, si: &SurfaceInteraction) -> [f32; 2] {
        let st = match *self {
            Mapping2D::Uv { su, sv, du, dv } => [su * si.uv[0] + du, sv * si.uv[1] + dv],
            Mapping2D::Spherical { texture_from_world } => {
                let d = texture_from_world.transform_point3a(si.p).normalize_or_zero();
                let theta = d.z.clamp(-1.0, 1.0).acos();
                [theta / PI, phi(d) / (2.0 * PI)]
            }
            Mapping2D::Cylindrical { texture_from_world } => {
                let d = texture_from_world.transform_point3a(si.p).normalize_or_zero();
                [(PI + d.y.atan2(d.x)) / (2.0 * PI), d.z]
            }
            Mapping2D::Planar { vs, vt, ds, dt } => [ds + si.p.dot(vs), dt + si.p.dot(vt)],
        };
        st.map(|x| if x.is_finite() { x } else { 0.0 })
    }
}

/// pbrt-v3's `SphericalPhi`: the azimuth of `d` in [0, 2π).
#[inline]
fn phi(d: Vec3A) -> f32 {
    let p = d.y.atan2(d.x);
    if p < 0.0 { p + 2.0 * PI } else { p }
}

/// pbrt-v3's `IdentityMapping3D`: the point in texture space (never NaN or infinite).
#[inline]
pub fn map_3d(texture_from_world: &Affine3A, si: &SurfaceInteraction) -> Vec3A {
    let p = texture_from_world.transform_point3a(si.p);
    Vec3A::select(p.is_finite_mask(), p, Vec3A::ZERO)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::accel::{PrimOrigin, PrimRef};

    fn si_at(p: [f32; 3], uv: [f32; 2]) -> SurfaceInteraction {
        SurfaceInteraction {
            p: Vec3A::from(p),
            p_error: Vec3A::ZERO,
            t: 1.0,
            ng: Vec3A::Z,
            ns: Vec3A::Z,
            dpdu: Vec3A::X,
            uv,
            material: 0,
            area_light: None,
            origin: PrimOrigin { prim: PrimRef::Quadric(0), instance: None },
        }
    }

    fn close(a: [f32; 2], b: [f32; 2]) -> bool {
        (a[0] - b[0]).abs() < 1e-6 && (a[1] - b[1]).abs() < 1e-6
    }

    #[test]
    fn uv_mapping_scales_then_offsets() {
        let m = Mapping2D::Uv { su: 2.0, sv: -3.0, du: 0.25, dv: 1.0 };
        assert!(close(m.map(&si_at([9.0, 9.0, 9.0], [0.5, 0.25])), [1.25, 0.25]));
        assert!(close(Mapping2D::IDENTITY.map(&si_at([0.0; 3], [0.3, 0.7])), [0.3, 0.7]));
    }

    #[test]
    fn spherical_mapping_gives_polar_angles_in_texture_space() {
        let m = Mapping2D::Spherical { texture_from_world: Affine3A::IDENTITY };
        // +z is θ = 0; +x is θ = π/2, φ = 0; +y is φ = π/2; −y is φ = 3π/2.
        assert!(close(m.map(&si_at([0.0, 0.0, 2.0], [0.0; 2])), [0.0, 0.0]));
        assert!(close(m.map(&si_at([3.0, 0.0, 0.0], [0.0; 2])), [0.5, 0.0]));
        assert!(close(m.map(&si_at([0.0, 1.0, 0.0], [0.0; 2])), [0.5, 0.25]));
        assert!(close(m.map(&si_at([0.0, -1.0, 0.0], [0.0; 2])), [0.5, 0.75]));
        assert!(close(m.map(&si_at([0.0, 0.0, -1.0], [0.0; 2])), [1.0, 0.0]));
        // The texture space's origin moved to (0, 0, 1): the world origin is then straight down.
        let moved = Mapping2D::Spherical { texture_from_world: Affine3A::from_translation([0.0, 0.0, -1.0].into()) };
        assert!(close(moved.map(&si_at([0.0; 3], [0.0; 2])), [1.0, 0.0]));
        // The centre itself has no direction: a finite answer, not NaN.
        let st = m.map(&si_at([0.0; 3], [0.0; 2]));
        assert!(st.iter().all(|x| x.is_finite()));
    }

    #[test]
    fn cylindrical_mapping_gives_angle_and_height() {
        let m = Mapping2D::Cylindrical { texture_from_world: Affine3A::IDENTITY };
        // −x is atan2 = π → s = 1 (or 0 from below); +x → s = ½; +y → ¾. t is the unit direction's z.
        assert!(close(m.map(&si_at([1.0, 0.0, 0.0], [0.0; 2])), [0.5, 0.0]));
        assert!(close(m.map(&si_at([0.0, 1.0, 0.0], [0.0; 2])), [0.75, 0.0]));
        let st = m.map(&si_at([0.0, -1.0, 1.0], [0.0; 2]));
        assert!(close(st, [0.25, std::f32::consts::FRAC_1_SQRT_2]), "{st:?}");
    }

    #[test]
    fn planar_mapping_projects_the_world_point() {
        let m = Mapping2D::Planar { vs: Vec3A::new(1.0, 1.0, 0.0), vt: Vec3A::new(0.0, 0.5, 2.0), ds: 0.5, dt: -1.0 };
        assert!(close(m.map(&si_at([1.0, 2.0, 3.0], [0.0; 2])), [3.5, 6.0]));
    }

    #[test]
    fn mapping_parameters_follow_pbrt_v3_defaults() {
        let mut props = Props::default();
        assert_eq!(Mapping2D::from_props(&props, Affine3A::IDENTITY), Ok(Mapping2D::IDENTITY));
        props.set("mapping", Prop::Str("planar".into()));
        props.set("udelta", Prop::Float(0.5));
        let m = Mapping2D::from_props(&props, Affine3A::IDENTITY).unwrap();
        assert_eq!(m, Mapping2D::Planar { vs: Vec3A::X, vt: Vec3A::Y, ds: 0.5, dt: 0.0 });
        props.set("mapping", Prop::Str("cubic".into()));
        assert_eq!(Mapping2D::from_props(&props, Affine3A::IDENTITY), Err("cubic".to_string()));
    }

    #[test]
    fn non_finite_coordinates_become_zero() {
        let m = Mapping2D::Uv { su: f32::INFINITY, sv: 1.0, du: 0.0, dv: f32::NAN };
        assert_eq!(m.map(&si_at([0.0; 3], [1.0, 1.0])), [0.0, 0.0]);
        let scale = Affine3A::from_scale([f32::INFINITY, 1.0, 1.0].into());
        assert_eq!(map_3d(&scale, &si_at([1.0, 2.0, 3.0], [0.0; 2])), Vec3A::new(0.0, 2.0, 3.0));
    }
}
