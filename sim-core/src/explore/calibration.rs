//! Online calibration of the odometry's proportional error from scan-match corrections.
//!
//! The odometry of a run scales every motion by a constant per axis (x, y, heading). The motion
//! between two accepted matches, as measured by the matcher, against the same motion as reported
//! by the odometry gives a least-squares estimate of the inverse scale on each axis; the
//! explorer applies it to the odometry before matching, so the prior is nearly exact and the
//! estimate does not drift where the scan constrains the pose poorly (facing unknown space, a
//! featureless corridor).

use crate::geom::Pose;

/// Least-squares scale per axis `[x, y, heading]`: `matched ~ scale * odometry`.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct OdometryCalibration {
    /// Sum of odometry * matched motion, per axis.
    sxy: [f64; 3],
    /// Sum of squared odometry motion, per axis.
    sxx: [f64; 3],
    /// Largest correction applied (proportional).
    max_correction: [f64; 3],
    /// Evidence (sum of squared motion: m2 or rad2) needed before correcting an axis.
    min_evidence: [f64; 3],
}

impl OdometryCalibration {
    /// `max_translation` / `max_rotation`: the proportional errors the odometry can have.
    pub(crate) fn new(max_translation: f64, max_rotation: f64) -> Self {
        Self {
            sxy: [0.0; 3],
            sxx: [0.0; 3],
            max_correction: [max_translation, max_translation, max_rotation],
            min_evidence: [1.0, 1.0, 0.3],
        }
    }

    /// Adds one pair of motions between the same two instants (robot frame of the first).
    pub(crate) fn observe(&mut self, odometry: &Pose, matched: &Pose) {
        let o = [odometry.x_m, odometry.y_m, odometry.theta_rad];
        let m = [matched.x_m, matched.y_m, matched.theta_rad];
        for k in 0..3 {
            self.sxy[k] += o[k] * m[k];
            self.sxx[k] += o[k] * o[k];
        }
    }

    /// Whether each axis has enough evidence to be corrected.
    pub(crate) fn calibrated(&self) -> [bool; 3] {
        [0, 1, 2].map(|k| self.sxx[k] >= self.min_evidence[k])
    }

    /// The scale of each axis (1 until there is enough evidence).
    pub(crate) fn scale(&self) -> [f64; 3] {
        let mut s = [1.0; 3];
        for (k, v) in s.iter_mut().enumerate() {
            if self.sxx[k] >= self.min_evidence[k] {
                let m = self.max_correction[k];
                *v = (self.sxy[k] / self.sxx[k]).clamp(1.0 - m, 1.0 + m);
            }
        }
        s
    }

    /// `odometry` motion corrected by the current scale.
    pub(crate) fn apply(&self, odometry: &Pose) -> Pose {
        let s = self.scale();
        Pose::new(
            odometry.x_m * s[0],
            odometry.y_m * s[1],
            odometry.theta_rad * s[2],
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn learns_a_heading_scale_and_clamps() {
        let mut c = OdometryCalibration::new(0.01, 0.05);
        // Not enough evidence yet: identity.
        c.observe(&Pose::new(0.1, 0.0, 0.1), &Pose::new(0.1, 0.0, 0.097));
        assert_eq!(c.scale(), [1.0; 3]);
        assert_eq!(c.calibrated(), [false; 3]);
        for k in 0..400 {
            // Matched heading is 3 % less than odometry, with noise of both signs.
            let noise = if k % 2 == 0 { 0.001 } else { -0.001 };
            c.observe(
                &Pose::new(0.1, 0.0, 0.1),
                &Pose::new(0.1 * 1.002, 0.0, 0.097 + noise),
            );
        }
        let s = c.scale();
        assert!((s[2] - 0.97).abs() < 1e-3, "{s:?}");
        assert!((s[0] - 1.002).abs() < 1e-4, "{s:?}");
        assert_eq!(s[1], 1.0);
        assert_eq!(c.calibrated(), [true, false, true]);
        let p = c.apply(&Pose::new(1.0, 0.0, 1.0));
        assert!((p.theta_rad - 0.97).abs() < 1e-3);
        // A wild estimate is clamped to the plausible range.
        let mut wild = OdometryCalibration::new(0.01, 0.05);
        for _ in 0..300 {
            wild.observe(&Pose::new(0.1, 0.0, 0.1), &Pose::new(0.2, 0.0, 0.2));
        }
        assert_eq!(wild.scale(), [1.01, 1.0, 1.05]);
    }
}
