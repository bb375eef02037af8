//! STAGE 2 (scene): pbrt-v3's cameras — perspective (fov on the shorter image axis, screen window, thin
//! lens), orthographic and environment (latitude–longitude) — generating world-space rays from film points.

use std::f32::consts::PI;

use glam::{Affine3A, Vec3A};

use crate::error::{Error, Result, Warnings};
use crate::parse::Named;
use crate::sampling::warp::concentric_disk;
use crate::scene::film::FilmSpec;
use crate::scene::ray::Ray;
use crate::scene::transform::Transform;

/// The projection of a camera.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Projection {
    /// Pinhole or thin-lens perspective; `tan_half_fov` scales the screen window.
    Perspective {
        /// tan(fov / 2).
        tan_half_fov: f32,
    },
    /// Parallel projection: the screen window is in camera-space units.
    Orthographic,
    /// Full-sphere latitude–longitude image.
    Environment,
}

/// A camera ready to generate rays.
#[derive(Clone, Debug, PartialEq)]
pub struct Camera {
    /// Which projection.
    pub projection: Projection,
    /// Camera space → world space (pbrt-v3: the inverse of the transform current at `Camera`).
    pub world_from_camera: Affine3A,
    /// Screen window x0, x1, y0, y1.
    pub screen: [f32; 4],
    /// Full film resolution the screen window maps onto.
    pub resolution: [f32; 2],
    /// Thin-lens radius (0: pinhole).
    pub lens_radius: f32,
    /// Distance of the plane in focus.
    pub focal_distance: f32,
}

impl Camera {
    /// Builds the camera of a `Camera` directive; `world_from_camera` is the inverse of the CTM at it.
    pub fn from_directive(
        d: &Named,
        world_from_camera: &Transform,
        film: &FilmSpec,
        warnings: &mut Warnings,
    ) -> Result<Camera> {
        let p = &d.params;
        let world_from_camera =
            world_from_camera.to_affine().map_err(|e| Error::at(&d.name_loc, format!("camera transform: {e}")))?;
        let open = p.float_or("shutteropen", 0.0)?;
        let close = p.float_or("shutterclose", 1.0)?;
        if close < open {
            warnings
                .at(&d.name_loc, "shutterclose < shutteropen; cachert renders a static scene, so this has no effect");
        }
        let [rx, ry] = film.resolution.map(|r| r as f32);
        let frame = p.float_or("frameaspectratio", (rx / ry) as f64)? as f32;
        if !(frame > 0.0 && frame.is_finite()) {
            let loc = p.loc_of("frameaspectratio").unwrap_or(&d.name_loc);
            return Err(Error::at(loc, format!("frameaspectratio must be positive, got {frame}")));
        }
        let mut screen = if frame > 1.0 { [-frame, frame, -1.0, 1.0] } else { [-1.0, 1.0, -1.0 / frame, 1.0 / frame] };
        if let Some(sw) = p.floats("screenwindow")? {
            let loc = p.loc_of("screenwindow").unwrap_or(&d.name_loc);
            if sw.len() != 4 || sw.iter().any(|v| !v.is_finite()) {
                return Err(Error::at(loc, format!("screenwindow needs 4 finite numbers, got {}", sw.len())));
            }
            if sw[0] == sw[1] || sw[2] == sw[3] {
                return Err(Error::at(loc, "screenwindow is empty"));
            }
            screen = [sw[0] as f32, sw[1] as f32, sw[2] as f32, sw[3] as f32];
        }
        let (lens_radius, focal_distance) = match d.name.as_str() {
            "perspective" | "orthographic" => {
                let lr = p.float_or("lensradius", 0.0)? as f32;
                let fd = p.float_or("focaldistance", 1e6)? as f32;
                if !(lr >= 0.0 && lr.is_finite() && fd > 0.0 && fd.is_finite()) {
                    return Err(Error::at(
                        &d.name_loc,
                        format!("lensradius {lr} / focaldistance {fd}: need lensradius ≥ 0 and focaldistance > 0"),
                    ));
                }
                (lr, fd)
            }
            _ => (0.0, 1e6),
        };
        let projection = match d.name.as_str() {
            "perspective" => {
                let mut fov = p.float_or("fov", 90.0)?;
                let half = p.float_or("halffov", -1.0)?;
                if half > 0.0 {
                    fov = 2.0 * half;
                }
                if !(fov > 0.0 && fov < 180.0) {
                    let loc = p.loc_of("fov").or(p.loc_of("halffov")).unwrap_or(&d.name_loc);
                    return Err(Error::at(loc, format!("fov must be strictly between 0 and 180 degrees, got {fov}")));
                }
                Projection::Perspective { tan_half_fov: (fov.to_radians() / 2.0).tan() as f32 }
            }
            "orthographic" => Projection::Orthographic,
            "environment" => Projection::Environment,
            "realistic" => {
                return Err(Error::at(
                    &d.name_loc,
                    "camera \"realistic\" (lens systems) is not supported by cachert; use perspective",
                ));
            }
            other => {
                return Err(Error::at(
                    &d.name_loc,
                    format!("unknown camera \"{other}\"; expected perspective, orthographic or environment"),
                ));
            }
        };
        Ok(Camera { projection, world_from_camera, screen, resolution: [rx, ry], lens_radius, focal_distance })
    }

    /// The world-space camera position.
    pub fn position(&self) -> Vec3A {
        self.world_from_camera.translation
    }

    /// The ray through film point `p_film` (raster coordinates of the full image) and lens sample `u_lens`.
    /// Directions are unit length.
    pub fn generate_ray(&self, p_film: [f32; 2], u_lens: [f32; 2]) -> Ray {
        let [x0, x1, y0, y1] = self.screen;
        let sx = x0 + p_film[0] / self.resolution[0] * (x1 - x0);
        let sy = y1 - p_film[1] / self.resolution[1] * (y1 - y0);
        let (o, d) = match self.projection {
            Projection::Perspective { tan_half_fov } => {
                let d = Vec3A::new(sx * tan_half_fov, sy * tan_half_fov, 1.0).normalize();
                self.thin_lens(Vec3A::ZERO, d, u_lens)
            }
            Projection::Orthographic => self.thin_lens(Vec3A::new(sx, sy, 0.0), Vec3A::Z, u_lens),
            Projection::Environment => {
                let theta = PI * p_film[1] / self.resolution[1];
                let phi = 2.0 * PI * p_film[0] / self.resolution[0];
                (Vec3A::ZERO, Vec3A::new(theta.sin() * phi.cos(), theta.cos(), theta.sin() * phi.sin()))
            }
        };
        let d = self.world_from_camera.transform_vector3a(d).normalize();
        Ray::new(self.world_from_camera.transform_point3a(o), d)
    }

    /// Whether [`Camera::generate_ray`] reads its lens sample (a thin lens that is not a pinhole, and not the
    /// environment projection, which has none).
    pub fn uses_lens(&self) -> bool {
        self.lens_radius > 0.0 && !matches!(self.projection, Projection::Environment)
    }

    /// Moves a pinhole ray onto a thin lens, keeping the point at the focal distance fixed (pbrt-v3).
    fn thin_lens(&self, o: Vec3A, d: Vec3A, u: [f32; 2]) -> (Vec3A, Vec3A) {
        if self.lens_radius <= 0.0 {
            return (o, d);
        }
        let [lx, ly] = concentric_disk(u);
        let lens = Vec3A::new(lx * self.lens_radius, ly * self.lens_radius, 0.0);
        let focus = o + d * (self.focal_distance / d.z);
        let o = o + lens;
        (o, (focus - o).normalize())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn camera(fov: f32, res: [f32; 2]) -> Camera {
        let frame = res[0] / res[1];
        let screen = if frame > 1.0 { [-frame, frame, -1.0, 1.0] } else { [-1.0, 1.0, -1.0 / frame, 1.0 / frame] };
        Camera {
            projection: Projection::Perspective { tan_half_fov: (fov.to_radians() / 2.0).tan() },
            world_from_camera: Affine3A::IDENTITY,
            screen,
            resolution: res,
            lens_radius: 0.0,
            focal_distance: 1e6,
        }
    }

    #[test]
    fn fov_spans_the_shorter_axis_and_raster_y_points_down() {
        let c = camera(90.0, [200.0, 100.0]);
        // Top edge centre of a wide image: 45° up.
        let r = c.generate_ray([100.0, 0.0], [0.5, 0.5]);
        assert!((r.d.y - r.d.z).abs() < 1e-6 && r.d.y > 0.0);
        // Right edge: wider than 45°.
        let r = c.generate_ray([200.0, 50.0], [0.5, 0.5]);
        assert!((r.d.x / r.d.z - 2.0).abs() < 1e-5);
        let c = camera(90.0, [100.0, 200.0]);
        let r = c.generate_ray([100.0, 100.0], [0.5, 0.5]);
        assert!((r.d.x - r.d.z).abs() < 1e-6);
    }

    #[test]
    fn thin_lens_rays_meet_at_the_focal_plane() {
        let mut c = camera(60.0, [64.0, 64.0]);
        c.lens_radius = 0.1;
        c.focal_distance = 5.0;
        let a = c.generate_ray([10.0, 20.0], [0.1, 0.9]);
        let b = c.generate_ray([10.0, 20.0], [0.8, 0.3]);
        let pa = a.at((5.0 - a.o.z) / a.d.z);
        let pb = b.at((5.0 - b.o.z) / b.d.z);
        assert!((pa - pb).length() < 1e-4);
    }
}
