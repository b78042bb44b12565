//! A laser scan as the sensor reports it (robot frame, like ROS `sensor_msgs/LaserScan`).

/// One sweep of a planar laser, in the sensor's frame (sensor at the robot's centre, x forward).
#[derive(Debug, Clone, PartialEq)]
pub struct Scan {
    /// Angle of the first beam, relative to the robot's heading.
    pub angle_min_rad: f64,
    /// Angle between consecutive beams.
    pub angle_increment_rad: f64,
    /// Maximum range of the sensor. A beam that hit nothing reports `range_m >= max_range_m`
    /// (exactly `max_range_m`) and must be treated as "free up to max range, no hit".
    pub max_range_m: f64,
    /// One range per beam, noise included, clamped to `[0, max_range_m]`.
    pub ranges_m: Vec<f64>,
}

impl Scan {
    /// Angle of beam `i` relative to the robot's heading.
    pub fn beam_angle_rad(&self, i: usize) -> f64 {
        self.angle_min_rad + i as f64 * self.angle_increment_rad
    }

    /// Whether beam `i` hit something (as opposed to reaching max range).
    pub fn is_hit(&self, i: usize) -> bool {
        self.ranges_m[i] < self.max_range_m
    }

    /// Hit points in the robot frame, for beams that hit.
    pub fn hit_points(&self) -> impl Iterator<Item = crate::geom::Vec2> + '_ {
        (0..self.ranges_m.len())
            .filter(|&i| self.is_hit(i))
            .map(|i| {
                let a = self.beam_angle_rad(i);
                crate::geom::Vec2::new(a.cos(), a.sin()) * self.ranges_m[i]
            })
    }
}
