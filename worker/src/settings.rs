//! The user-facing run settings (robot, laser, odometry, mapping, strategy parameters): what a
//! grid file's `[settings]` or the command line sets, what every summary records, and what a
//! job's identity hashes. Converted by hand into `sim-core`'s config and validated on the way.

use serde::{Deserialize, Serialize};
use sim_core::explore::{EarlyStop, ExploreConfig, Localization, Strategy, UtilityDistance};

/// Settings as written in files and records. Every field has the documented default.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Settings {
    /// Robot radius (m).
    pub robot_radius_m: f64,
    /// Maximum forward speed (m/s).
    pub max_speed_mps: f64,
    /// Maximum turn rate (rad/s).
    pub max_turn_rate_radps: f64,
    /// Laser field of view (degrees).
    pub laser_fov_deg: f64,
    /// Laser range (m).
    pub laser_range_m: f64,
    /// Number of beams per scan.
    pub laser_beams: usize,
    /// Scans per second available to the mapper.
    pub laser_rate_hz: f64,
    /// Standard deviation of the Gaussian range noise (m).
    pub laser_noise_sd_m: f64,
    /// Maximum proportional translation error of odometry (m per m).
    pub odometry_translation_error: f64,
    /// Maximum proportional rotation error of odometry (degrees per radian).
    pub odometry_rotation_error_deg_per_rad: f64,
    /// "slam" (default), "odometry" or "ground-truth".
    pub localization: String,
    /// Occupancy grid cell size (m).
    pub map_resolution_m: f64,
    /// The map is updated (and the scan matched) after this much motion (m)...
    pub map_update_distance_m: f64,
    /// ...or this much turning (rad)...
    pub map_update_angle_rad: f64,
    /// ...or this much simulated time (s), whichever comes first.
    pub map_update_period_s: f64,
    /// Weight of distance in the utility (the paper's alpha).
    pub alpha: f64,
    /// In the utility, a candidate's gain counts as at least this much (m2); 0 = the paper's
    /// utility. Not in the paper: it keeps the robot from crossing the building for one small
    /// residual frontier while leaving another behind (see the README).
    pub gain_floor_m2: f64,
    /// What the utility's distance `D(p)` measures: "path" (default: the planned path's length)
    /// or "euclidean" (the straight line from the robot to the candidate, as the paper defines
    /// it). Written only when not "path", so that the records and job identities of runs with
    /// the default are those of earlier versions.
    #[serde(skip_serializing_if = "is_path")]
    pub utility_distance: String,
    /// Frontiers shorter than this are ignored (m).
    pub min_frontier_m: f64,
    /// Frontier cells closer than this to an observed wall are ignored (m; 0 = none), as by
    /// explorers that look for frontiers in an inflated costmap. Not in floorcast's default
    /// explorer. Written only when set, so that the records and job identities of runs without
    /// it are those of earlier versions.
    #[serde(skip_serializing_if = "is_zero")]
    pub frontier_clearance_m: f64,
    /// When a frontier's candidate (its middle cell, or a traversable cell within 0.5 m) cannot
    /// be reached, aim at the reachable cell of the frontier nearest to it instead of passing
    /// the frontier over. Not in the paper (false = its rule). Written only when true, so that
    /// the records and job identities of runs without it are those of earlier versions.
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub candidate_from_reachable_part: bool,
    /// Re-decide this often while driving to a goal (s of simulated time)...
    pub redecide_period_s: f64,
    /// ...once the map has grown by at least this much since the last decision (m2; 0 = at
    /// every period).
    pub redecide_min_growth_m2: f64,
    /// Radius of the blacklist around unreachable goals (m).
    pub blacklist_radius_m: f64,
    /// Abandon a goal after this long without progress (s).
    pub progress_timeout_s: f64,
    /// Stop a run at this simulated time (s).
    pub time_limit_s: f64,
    /// Drive back to the start after exploring.
    pub return_home: bool,
    /// `layout-es`: stop when the summed gain of all candidates is below this (m2; paper: 1).
    pub es_threshold_m2: f64,
    /// `layout-aes`: drop candidates whose gain is below this (m2); stop when none is left.
    pub aes_min_gain_m2: f64,
    /// Layout strategies: rebuild the layout when the known area grew by this much (m2).
    pub layout_update_m2: f64,
    /// Layout strategies: the layout's wall lines close gaps in observed walls up to this long (m).
    pub max_wall_gap_m: f64,
    /// Add the measured wall time of every layout computation to simulated time (the robot
    /// waits for it). The result then depends on the machine: not reproducible.
    pub charge_compute: bool,
}

fn is_path(s: &str) -> bool {
    s == UtilityDistance::Path.as_str()
}

fn is_zero(v: &f64) -> bool {
    *v == 0.0
}

impl Default for Settings {
    fn default() -> Self {
        let c = ExploreConfig::default();
        Self {
            robot_radius_m: c.sim.robot.radius_m,
            max_speed_mps: c.sim.robot.max_speed_mps,
            max_turn_rate_radps: c.sim.robot.max_turn_rate_radps,
            laser_fov_deg: c.sim.laser.fov_rad.to_degrees(),
            laser_range_m: c.sim.laser.max_range_m,
            laser_beams: c.sim.laser.beams,
            laser_rate_hz: c.sim.laser.rate_hz,
            laser_noise_sd_m: c.sim.laser.range_noise_sd_m,
            odometry_translation_error: c.sim.odometry.max_translation_error,
            odometry_rotation_error_deg_per_rad: c.sim.odometry.max_rotation_error.to_degrees(),
            localization: c.localization.as_str().to_string(),
            map_resolution_m: c.map_resolution_m,
            map_update_distance_m: c.map_update_distance_m,
            map_update_angle_rad: c.map_update_angle_rad,
            map_update_period_s: c.map_update_period_s,
            alpha: c.alpha,
            gain_floor_m2: c.gain_floor_m2,
            utility_distance: c.utility_distance.as_str().to_string(),
            min_frontier_m: c.min_frontier_m,
            frontier_clearance_m: c.frontier_clearance_m,
            candidate_from_reachable_part: c.candidate_from_reachable_part,
            redecide_period_s: c.redecide_period_s,
            redecide_min_growth_m2: c.redecide_min_growth_m2,
            blacklist_radius_m: c.blacklist_radius_m,
            progress_timeout_s: c.progress_timeout_s,
            time_limit_s: c.time_limit_s,
            return_home: c.return_home,
            es_threshold_m2: 1.0,
            aes_min_gain_m2: 2.0,
            layout_update_m2: c.strategy.layout_update_m2,
            max_wall_gap_m: c.strategy.max_wall_gap_m,
            charge_compute: false,
        }
    }
}

#[derive(Debug, thiserror::Error, PartialEq)]
pub enum SettingsError {
    #[error("settings.{field}: {value} is out of range, expected {expected}")]
    OutOfRange {
        field: &'static str,
        value: String,
        expected: &'static str,
    },
    #[error("settings.localization: unknown value '{0}', expected slam, odometry or ground-truth")]
    Localization(String),
    #[error("settings.utility_distance: unknown value '{0}', expected path or euclidean")]
    UtilityDistance(String),
    #[error("unknown strategy '{0}' (available: {list})", list = Strategy::NAMES.join(", "))]
    Strategy(String),
}

impl Settings {
    /// The simulation config for strategy `name` (see [`sim_core::explore::Strategy::by_name`]),
    /// with this file's thresholds.
    pub fn to_explore_config_for(&self, name: &str) -> Result<ExploreConfig, SettingsError> {
        let mut c = self.to_explore_config()?;
        let mut st =
            Strategy::by_name(name).ok_or_else(|| SettingsError::Strategy(name.to_string()))?;
        st.layout_update_m2 = c.strategy.layout_update_m2;
        st.max_wall_gap_m = c.strategy.max_wall_gap_m;
        st.early_stop = match st.early_stop {
            EarlyStop::TotalGainBelow(_) => EarlyStop::TotalGainBelow(self.es_threshold_m2),
            EarlyStop::DropCandidatesBelow(_) => {
                EarlyStop::DropCandidatesBelow(self.aes_min_gain_m2)
            }
            EarlyStop::Never => EarlyStop::Never,
        };
        c.strategy = st;
        Ok(c)
    }

    /// Checks every field and builds the simulation config.
    pub fn to_explore_config(&self) -> Result<ExploreConfig, SettingsError> {
        fn check(
            field: &'static str,
            v: f64,
            ok: bool,
            expected: &'static str,
        ) -> Result<f64, SettingsError> {
            if v.is_finite() && ok {
                Ok(v)
            } else {
                Err(SettingsError::OutOfRange {
                    field,
                    value: v.to_string(),
                    expected,
                })
            }
        }
        let pos = |field, v: f64| check(field, v, v > 0.0, "a positive number");
        let nonneg = |field, v: f64| check(field, v, v >= 0.0, "a number >= 0");
        let mut c = ExploreConfig::default();
        c.sim.robot.radius_m = pos("robot_radius_m", self.robot_radius_m)?;
        c.sim.robot.max_speed_mps = pos("max_speed_mps", self.max_speed_mps)?;
        c.sim.robot.max_turn_rate_radps = pos("max_turn_rate_radps", self.max_turn_rate_radps)?;
        c.sim.laser.fov_rad = check(
            "laser_fov_deg",
            self.laser_fov_deg,
            self.laser_fov_deg > 0.0 && self.laser_fov_deg <= 360.0,
            "degrees in (0, 360]",
        )?
        .to_radians();
        c.sim.laser.max_range_m = pos("laser_range_m", self.laser_range_m)?;
        if !(2..=10_000).contains(&self.laser_beams) {
            return Err(SettingsError::OutOfRange {
                field: "laser_beams",
                value: self.laser_beams.to_string(),
                expected: "an integer from 2 to 10000",
            });
        }
        c.sim.laser.beams = self.laser_beams;
        c.sim.laser.rate_hz = pos("laser_rate_hz", self.laser_rate_hz)?;
        c.sim.laser.range_noise_sd_m = nonneg("laser_noise_sd_m", self.laser_noise_sd_m)?;
        c.sim.odometry.max_translation_error = nonneg(
            "odometry_translation_error",
            self.odometry_translation_error,
        )?;
        c.sim.odometry.max_rotation_error = nonneg(
            "odometry_rotation_error_deg_per_rad",
            self.odometry_rotation_error_deg_per_rad,
        )?
        .to_radians();
        c.sim.step_s = 1.0 / c.sim.laser.rate_hz;
        c.localization = match self.localization.as_str() {
            "slam" => Localization::Slam,
            "odometry" => Localization::Odometry,
            "ground-truth" => Localization::GroundTruth,
            other => return Err(SettingsError::Localization(other.to_string())),
        };
        c.map_resolution_m = check(
            "map_resolution_m",
            self.map_resolution_m,
            self.map_resolution_m >= 0.01 && self.map_resolution_m <= 0.5,
            "metres in [0.01, 0.5]",
        )?;
        c.map_update_distance_m = pos("map_update_distance_m", self.map_update_distance_m)?;
        c.map_update_angle_rad = pos("map_update_angle_rad", self.map_update_angle_rad)?;
        c.map_update_period_s = pos("map_update_period_s", self.map_update_period_s)?;
        c.alpha = check(
            "alpha",
            self.alpha,
            (0.0..=1.0).contains(&self.alpha),
            "a number in [0, 1]",
        )?;
        c.gain_floor_m2 = nonneg("gain_floor_m2", self.gain_floor_m2)?;
        c.utility_distance = UtilityDistance::from_name(&self.utility_distance)
            .ok_or_else(|| SettingsError::UtilityDistance(self.utility_distance.clone()))?;
        c.min_frontier_m = nonneg("min_frontier_m", self.min_frontier_m)?;
        c.frontier_clearance_m = nonneg("frontier_clearance_m", self.frontier_clearance_m)?;
        c.candidate_from_reachable_part = self.candidate_from_reachable_part;
        c.redecide_period_s = pos("redecide_period_s", self.redecide_period_s)?;
        c.redecide_min_growth_m2 = nonneg("redecide_min_growth_m2", self.redecide_min_growth_m2)?;
        c.blacklist_radius_m = nonneg("blacklist_radius_m", self.blacklist_radius_m)?;
        c.progress_timeout_s = pos("progress_timeout_s", self.progress_timeout_s)?;
        c.time_limit_s = pos("time_limit_s", self.time_limit_s)?;
        c.return_home = self.return_home;
        nonneg("es_threshold_m2", self.es_threshold_m2)?;
        nonneg("aes_min_gain_m2", self.aes_min_gain_m2)?;
        c.strategy.layout_update_m2 = pos("layout_update_m2", self.layout_update_m2)?;
        c.strategy.max_wall_gap_m = nonneg("max_wall_gap_m", self.max_wall_gap_m)?;
        Ok(c)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_round_trip_to_the_core_defaults() {
        let c = Settings::default().to_explore_config().unwrap();
        let d = ExploreConfig::default();
        assert_eq!(c.sim.robot, d.sim.robot);
        assert_eq!(c.sim.laser.beams, d.sim.laser.beams);
        assert!((c.sim.laser.fov_rad - d.sim.laser.fov_rad).abs() < 1e-12);
        assert_eq!(c.localization, d.localization);
        assert_eq!(c.alpha, d.alpha);
    }

    #[test]
    fn bad_values_name_the_field() {
        let s = Settings {
            alpha: 1.5,
            ..Settings::default()
        };
        let e = s.to_explore_config().unwrap_err().to_string();
        assert!(e.contains("settings.alpha") && e.contains("[0, 1]"), "{e}");
        let s = Settings {
            localization: "gps".into(),
            ..Settings::default()
        };
        assert!(s
            .to_explore_config()
            .unwrap_err()
            .to_string()
            .contains("gps"));
        let s = Settings {
            robot_radius_m: f64::NAN,
            ..Settings::default()
        };
        assert!(s.to_explore_config().is_err());
        let s = Settings {
            map_update_angle_rad: 0.0,
            ..Settings::default()
        };
        let e = s.to_explore_config().unwrap_err().to_string();
        assert!(e.contains("settings.map_update_angle_rad"), "{e}");
        let s = Settings {
            map_update_distance_m: 0.5,
            ..Settings::default()
        };
        assert_eq!(s.to_explore_config().unwrap().map_update_distance_m, 0.5);
    }

    #[test]
    fn the_reachable_part_rule_is_recorded_only_when_on() {
        let off = serde_json::to_value(Settings::default()).unwrap();
        assert!(off.get("candidate_from_reachable_part").is_none(), "{off}");
        let on = Settings {
            candidate_from_reachable_part: true,
            ..Settings::default()
        };
        let v = serde_json::to_value(&on).unwrap();
        assert_eq!(v["candidate_from_reachable_part"], true);
        let back: Settings = serde_json::from_value(v).unwrap();
        assert_eq!(back, on);
        assert!(
            back.to_explore_config()
                .unwrap()
                .candidate_from_reachable_part
        );
        assert!(
            !Settings::default()
                .to_explore_config()
                .unwrap()
                .candidate_from_reachable_part
        );
    }

    #[test]
    fn the_frontier_clearance_is_recorded_only_when_set_and_validated() {
        let off = serde_json::to_value(Settings::default()).unwrap();
        assert!(off.get("frontier_clearance_m").is_none(), "{off}");
        let on = Settings {
            frontier_clearance_m: 0.4,
            ..Settings::default()
        };
        let v = serde_json::to_value(&on).unwrap();
        assert_eq!(v["frontier_clearance_m"], 0.4);
        let back: Settings = serde_json::from_value(v).unwrap();
        assert_eq!(back, on);
        assert_eq!(back.to_explore_config().unwrap().frontier_clearance_m, 0.4);
        let bad = Settings {
            frontier_clearance_m: -0.1,
            ..Settings::default()
        };
        let e = bad.to_explore_config().unwrap_err().to_string();
        assert!(e.contains("settings.frontier_clearance_m"), "{e}");
    }

    #[test]
    fn the_utility_distance_is_recorded_only_when_not_the_default() {
        let off = serde_json::to_value(Settings::default()).unwrap();
        assert!(off.get("utility_distance").is_none(), "{off}");
        let on = Settings {
            utility_distance: "euclidean".into(),
            ..Settings::default()
        };
        let v = serde_json::to_value(&on).unwrap();
        assert_eq!(v["utility_distance"], "euclidean");
        let back: Settings = serde_json::from_value(v).unwrap();
        assert_eq!(back, on);
        assert_eq!(
            back.to_explore_config().unwrap().utility_distance,
            UtilityDistance::Euclidean
        );
        let bad = Settings {
            utility_distance: "manhattan".into(),
            ..Settings::default()
        };
        let e = bad.to_explore_config().unwrap_err().to_string();
        assert!(
            e.contains("settings.utility_distance") && e.contains("manhattan"),
            "{e}"
        );
    }

    #[test]
    fn unknown_keys_are_rejected() {
        let e = serde_json::from_str::<Settings>(r#"{"alpah": 0.3}"#)
            .unwrap_err()
            .to_string();
        assert!(e.contains("alpah"), "{e}");
    }
}
