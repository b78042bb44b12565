//! The known-map yardstick as a record: a tour of a building ([`sim_core::tour`]) for the robot
//! and laser of a run's settings, from its start, kept beside the runs it measures.
//!
//! A tour depends on the building, the start pose, the coverage it must reach, six settings
//! (the robot's radius, speed and turn rate, the laser's range and field of view, the map
//! resolution) and the method that made it ([`sim_core::tour::TOUR_METHOD`]): its [`TourKey`]. `floorcast tour --json` writes a [`TourRecord`], and a grid's
//! results store one per key, which `report` divides by each run's exploration time (its
//! efficiency).

use serde::{Deserialize, Serialize};
use sim_core::tour::{known_map_tour_with, TourError, TourEstimate, TourProgress, TourSettings};
use sim_core::{Building, Pose};

use crate::{Settings, SettingsError};

pub const TOUR_FORMAT: &str = "floorcast-tour";
/// 4: the lower bound (`lower_bound_s`, `bound_regions`); 3: the tour's method in the key; 2:
/// the key and the start in the record (1: `floorcast tour --json` of 0.7.0). Records of
/// version 3 are read without a bound; of version 2 as of method 0 (made before methods were
/// numbered: a store recomputes them).
pub const TOUR_VERSION: u32 = 4;

/// What a tour depends on besides its building: the settings it reads and the coverage wanted.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TourKey {
    pub robot_radius_m: f64,
    pub max_speed_mps: f64,
    pub max_turn_rate_radps: f64,
    pub laser_fov_deg: f64,
    pub laser_range_m: f64,
    pub map_resolution_m: f64,
    /// The share of the explorable area the tour sees.
    pub coverage: f64,
    /// The method that made the tour ([`sim_core::tour::TOUR_METHOD`]; 0 in records of
    /// version 2, made before methods were numbered).
    #[serde(default)]
    pub method: u32,
}

impl TourKey {
    /// The key of a tour for runs with `settings`, seeing `coverage` of the explorable area.
    pub fn of(settings: &Settings, coverage: f64) -> TourKey {
        TourKey {
            robot_radius_m: settings.robot_radius_m,
            max_speed_mps: settings.max_speed_mps,
            max_turn_rate_radps: settings.max_turn_rate_radps,
            laser_fov_deg: settings.laser_fov_deg,
            laser_range_m: settings.laser_range_m,
            map_resolution_m: settings.map_resolution_m,
            coverage,
            method: sim_core::tour::TOUR_METHOD,
        }
    }

    /// The key as stored: its JSON (fields in declaration order, numbers round-tripping).
    pub fn text(&self) -> String {
        serde_json::to_string(self).expect("a tour key encodes")
    }
}

/// A tour of a building and what it was made for.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TourRecord {
    pub format: String,
    pub version: u32,
    pub floorcast_version: String,
    /// The building as named where the tour was made (its file, or a grid's name for it).
    pub building: String,
    pub building_hash: String,
    /// `[x_m, y_m, heading_rad]`: the start pose, as a run's summary records it.
    pub start: [f64; 3],
    pub key: TourKey,
    pub time_s: f64,
    pub length_m: f64,
    pub covered_fraction: f64,
    /// The share the run's laser sees when the tour is replayed ([`sim_core::tour::replay`]):
    /// the check of `covered_fraction`, at least `key.coverage` unless three tries fell short.
    pub replayed_fraction: f64,
    pub explorable_m2: f64,
    /// No tour of the building from the start for the robot (this one, an explorer's, the best
    /// possible) is faster ([`sim_core::tour::lower_bound`], s); absent in records of version
    /// 2 and 3.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub lower_bound_s: Option<f64>,
    /// The regions the bound's tours must enter (absent with the bound).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub bound_regions: Option<usize>,
    /// `[x_m, y_m, heading_rad]`, the start first, in the order visited.
    pub viewpoints: Vec<[f64; 3]>,
    /// `[x_m, y_m]` points of the path driven.
    pub path: Vec<[f64; 2]>,
}

impl TourRecord {
    /// Checks a record read from outside (a store's row): its format, version and numbers.
    pub fn validate(&self) -> Result<(), String> {
        if self.format != TOUR_FORMAT {
            return Err(format!(
                "format: expected \"{TOUR_FORMAT}\", got \"{}\"",
                crate::text::excerpt(&self.format)
            ));
        }
        let old = self.version == 3 || self.version == 2 && self.key.method == 0;
        if !(self.version == TOUR_VERSION || old) {
            return Err(format!(
                "version: expected {TOUR_VERSION} (or 3, or 2 of method 0), got {} (of method {})",
                self.version, self.key.method
            ));
        }
        let positive = [
            ("time_s", self.time_s),
            ("explorable_m2", self.explorable_m2),
        ];
        for (field, v) in positive {
            if !(v.is_finite() && v > 0.0) {
                return Err(format!("{field}: expected a positive number, got {v}"));
            }
        }
        if !(self.length_m.is_finite() && self.length_m >= 0.0) {
            return Err(format!(
                "length_m: expected a number at least 0, got {}",
                self.length_m
            ));
        }
        for (field, v) in [
            ("covered_fraction", self.covered_fraction),
            ("replayed_fraction", self.replayed_fraction),
        ] {
            if !(0.0..=1.0).contains(&v) {
                return Err(format!("{field}: expected a fraction in [0, 1], got {v}"));
            }
        }
        match (self.version, self.lower_bound_s, self.bound_regions) {
            (TOUR_VERSION, Some(b), Some(_)) if b.is_finite() && b >= 0.0 && b <= self.time_s * (1.0 + 1e-9) => {}
            (TOUR_VERSION, b, _) => {
                return Err(format!(
                    "lower_bound_s: expected a number from 0 to time_s ({}) with bound_regions, got {b:?}",
                    self.time_s
                ))
            }
            (_, None, None) => {}
            _ => return Err(format!("lower_bound_s: not in records of version {}", self.version)),
        }
        if self.start.iter().any(|v| !v.is_finite()) {
            return Err("start: expected three finite numbers".into());
        }
        Ok(())
    }

    /// Whether this tour measures a run from `start` (the summary's, bit for bit).
    pub fn starts_at(&self, start: &[f64; 3]) -> bool {
        self.start
            .iter()
            .zip(start)
            .all(|(a, b)| a.to_bits() == b.to_bits())
    }
}

/// Why a tour of a building cannot be made: a setting refused, or the robot fits nowhere.
#[derive(Debug)]
pub enum MakeTourError {
    Settings(SettingsError),
    /// The building's name, the robot's radius and what [`sim_core::tour`] said.
    Tour(String, f64, TourError),
}

impl std::fmt::Display for MakeTourError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            MakeTourError::Settings(e) => write!(f, "{e}"),
            MakeTourError::Tour(name, radius, e) => {
                write!(f, "{name}: robot_radius_m = {radius}: no tour: {e}")
            }
        }
    }
}

impl std::error::Error for MakeTourError {}

impl From<SettingsError> for MakeTourError {
    fn from(e: SettingsError) -> Self {
        MakeTourError::Settings(e)
    }
}

/// The tour settings of `coverage`.
fn tour_settings(coverage: f64) -> TourSettings {
    TourSettings {
        coverage,
        ..TourSettings::default()
    }
}

/// What making the tour [`make_tour`] makes would cost ([`sim_core::tour::estimate`]).
pub fn estimate_tour(
    building: &Building,
    name: &str,
    start: Pose,
    settings: &Settings,
    coverage: f64,
) -> Result<TourEstimate, MakeTourError> {
    let config = settings.to_explore_config()?;
    sim_core::tour::estimate(building, start, &config, &tour_settings(coverage))
        .map_err(|e| MakeTourError::Tour(name.to_string(), settings.robot_radius_m, e))
}

/// The tour of `building` (named `name`) from `start` for the robot and laser of `settings`,
/// seeing `coverage` of its explorable area (docs/known-map-tour.md).
pub fn make_tour(
    building: &Building,
    name: &str,
    start: Pose,
    settings: &Settings,
    coverage: f64,
) -> Result<TourRecord, MakeTourError> {
    make_tour_with(building, name, start, settings, coverage, &mut |_| {})
}

/// [`make_tour`], telling `progress` what it does.
pub fn make_tour_with(
    building: &Building,
    name: &str,
    start: Pose,
    settings: &Settings,
    coverage: f64,
    progress: &mut dyn FnMut(TourProgress),
) -> Result<TourRecord, MakeTourError> {
    let config = settings.to_explore_config()?;
    let tour = known_map_tour_with(building, start, &config, &tour_settings(coverage), progress)
        .map_err(|e| MakeTourError::Tour(name.to_string(), settings.robot_radius_m, e))?;
    let bound = sim_core::tour::lower_bound(building, start, &config, coverage);
    Ok(TourRecord {
        format: TOUR_FORMAT.to_string(),
        version: TOUR_VERSION,
        floorcast_version: crate::FLOORCAST_VERSION.to_string(),
        building: name.to_string(),
        building_hash: building.content_hash(),
        start: [start.x_m, start.y_m, start.theta_rad],
        key: TourKey::of(settings, coverage),
        time_s: tour.time_s,
        length_m: tour.length_m,
        covered_fraction: tour.covered_fraction,
        replayed_fraction: tour.replayed_fraction,
        explorable_m2: tour.explorable_m2,
        lower_bound_s: Some(bound.time_s),
        bound_regions: Some(bound.regions),
        viewpoints: tour
            .viewpoints
            .iter()
            .map(|v| [v.x_m, v.y_m, v.theta_rad])
            .collect(),
        path: tour.path.iter().map(|p| [p.x, p.y]).collect(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A generated building of 150 m2 and its tour from its start with the default settings.
    fn small_tour() -> (Building, TourRecord) {
        let b = sim_core::generate::generate(&sim_core::generate::GenerateConfig {
            seed: 2,
            area_m2: 150.0,
            ..Default::default()
        });
        let t = make_tour(&b, "b", b.start.unwrap(), &Settings::default(), 0.99).unwrap();
        (b, t)
    }

    #[test]
    fn a_record_round_trips_and_bad_ones_are_refused() {
        let (b, t) = small_tour();
        let start = b.start.unwrap();
        let settings = Settings::default();
        t.validate().unwrap();
        assert!(t.starts_at(&[start.x_m, start.y_m, start.theta_rad]));
        assert!(!t.starts_at(&[start.x_m + 1e-9, start.y_m, start.theta_rad]));
        let text = serde_json::to_string(&t).unwrap();
        let back: TourRecord = serde_json::from_str(&text).unwrap();
        assert_eq!(back, t);
        assert_eq!(t.key, TourKey::of(&settings, 0.99));
        type Spoil = fn(&mut TourRecord);
        let cases: [(&str, Spoil); 9] = [
            ("format", |r| r.format = "x".into()),
            ("version", |r| r.version = 99),
            ("version", |r| r.version = 2),
            ("lower_bound_s", |r| r.lower_bound_s = None),
            ("lower_bound_s", |r| r.lower_bound_s = Some(r.time_s * 1.5)),
            ("lower_bound_s", |r| {
                r.version = 3;
            }),
            ("time_s", |r| r.time_s = f64::NAN),
            ("covered_fraction", |r| r.covered_fraction = 1.5),
            ("start", |r| r.start[1] = f64::INFINITY),
        ];
        for (field, spoil) in cases {
            let mut bad = t.clone();
            spoil(&mut bad);
            let e = bad.validate().unwrap_err();
            assert!(e.starts_with(field), "{field}: {e}");
        }
    }

    /// A record of version 2 (no method in its key) is read as one of method 0, valid, and
    /// its key is not the current one: a store makes the tour again.
    #[test]
    fn a_tour_of_an_older_method_is_read_but_not_used() {
        let (_, t) = small_tour();
        let settings = Settings::default();
        assert_eq!(t.key.method, sim_core::tour::TOUR_METHOD);
        let mut v = serde_json::to_value(&t).unwrap();
        v["version"] = 2.into();
        v["key"].as_object_mut().unwrap().remove("method");
        v.as_object_mut().unwrap().remove("lower_bound_s");
        v.as_object_mut().unwrap().remove("bound_regions");
        let old: TourRecord = serde_json::from_value(v).unwrap();
        old.validate().unwrap();
        assert_eq!(old.key.method, 0);
        assert_ne!(old.key, TourKey::of(&settings, 0.99));
    }
}
