//! The laser: rays cast with parry2d against the building's wall boundary.

use std::sync::Arc;

use parry2d::math::{Isometry, Point as PPoint, Vector as PVector};
use parry2d::query::{Ray, RayCast};
use parry2d::shape::{Polyline, SharedShape};
use rand::Rng;
use rand_distr::{Distribution, Normal};

use crate::geom::{Pose, Segment, Vec2};
use crate::scan::Scan;

/// The laser as in the paper: 180 degree field of view, 6 m range. Defaults: 181 beams (one per
/// degree), 10 scans per second, Gaussian range noise with 0.01 m standard deviation.
#[derive(Debug, Clone, PartialEq)]
pub struct LaserConfig {
    pub fov_rad: f64,
    pub max_range_m: f64,
    pub beams: usize,
    pub rate_hz: f64,
    pub range_noise_sd_m: f64,
}

impl Default for LaserConfig {
    fn default() -> Self {
        Self {
            fov_rad: std::f64::consts::PI,
            max_range_m: 6.0,
            beams: 181,
            rate_hz: 10.0,
            range_noise_sd_m: 0.01,
        }
    }
}

impl LaserConfig {
    /// One scan from `pose`. Beams that hit nothing within range report exactly `max_range_m`.
    pub fn scan(&self, walls: &Walls, pose: &Pose, rng: &mut impl Rng) -> Scan {
        let n = self.beams.max(1);
        let inc = if n > 1 {
            self.fov_rad / (n - 1) as f64
        } else {
            0.0
        };
        let angle_min = if n > 1 { -self.fov_rad / 2.0 } else { 0.0 };
        let noise = (self.range_noise_sd_m > 0.0)
            .then(|| Normal::new(0.0, self.range_noise_sd_m).ok())
            .flatten();
        let origin = pose.position();
        let ranges_m = (0..n)
            .map(|i| {
                let a = pose.theta_rad + angle_min + i as f64 * inc;
                match walls.cast(origin, Vec2::new(a.cos(), a.sin()), self.max_range_m) {
                    Some(r) => {
                        let e = noise.map_or(0.0, |d| d.sample(rng));
                        // A noisy hit never reads as "no hit".
                        (r + e).clamp(0.0, self.max_range_m * (1.0 - 1e-9))
                    }
                    None => self.max_range_m,
                }
            })
            .collect();
        Scan {
            angle_min_rad: angle_min,
            angle_increment_rad: inc,
            max_range_m: self.max_range_m,
            ranges_m,
        }
    }
}

/// The building's walls as one parry2d polyline (a segment soup under a BVH).
#[derive(Clone)]
pub struct Walls {
    shape: Option<Arc<Polyline>>,
    segments: usize,
}

impl std::fmt::Debug for Walls {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Walls")
            .field("segments", &self.segments)
            .finish()
    }
}

impl Walls {
    pub fn new(segments: &[Segment]) -> Self {
        if segments.is_empty() {
            return Self {
                shape: None,
                segments: 0,
            };
        }
        let mut vertices = Vec::with_capacity(segments.len() * 2);
        let mut indices = Vec::with_capacity(segments.len());
        for (i, s) in segments.iter().enumerate() {
            vertices.push(PPoint::new(s.a.x as f32, s.a.y as f32));
            vertices.push(PPoint::new(s.b.x as f32, s.b.y as f32));
            indices.push([2 * i as u32, 2 * i as u32 + 1]);
        }
        Self {
            shape: Some(Arc::new(Polyline::new(vertices, Some(indices)))),
            segments: segments.len(),
        }
    }

    pub fn segment_count(&self) -> usize {
        self.segments
    }

    pub(super) fn shared_shape(&self) -> Option<SharedShape> {
        self.shape.as_ref().map(|s| SharedShape::new((**s).clone()))
    }

    /// Distance along the unit direction `dir` from `origin` to the first wall, if within
    /// `max_range_m`.
    pub fn cast(&self, origin: Vec2, dir: Vec2, max_range_m: f64) -> Option<f64> {
        let shape = self.shape.as_ref()?;
        let ray = Ray::new(
            PPoint::new(origin.x as f32, origin.y as f32),
            PVector::new(dir.x as f32, dir.y as f32),
        );
        shape
            .cast_ray(&Isometry::identity(), &ray, max_range_m as f32, false)
            .map(|t| t as f64)
    }
}
