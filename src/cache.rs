//! STAGE 5: the cache index — a kd-tree (kiddo) over cache positions and the paper's selection of the
//! caches that serve a shading point (ALGORITHMS.md §5, Eq. 5): N nearest by distance → normals within
//! θ_max → the M smallest Dist = ‖p_c − p_s‖ + λ·sqrt(1 − n_c·n_s), with a fallback to all N when the
//! normal filter leaves none; inverse-Dist weights for interpolation.
//!
//! Depends on nothing but glam and kiddo; used by placement (DGS, AS) and by the render driver alike.

/// Parameters of the §5 selection.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LookupParams {
    /// N: nearest candidates by Euclidean distance.
    pub candidates: usize,
    /// θ_max in degrees: the normal filter.
    pub theta_max_deg: f32,
    /// M: caches kept.
    pub keep: usize,
}

impl Default for LookupParams {
    fn default() -> Self {
        LookupParams { candidates: 20, theta_max_deg: 30.0, keep: 6 }
    }
}
