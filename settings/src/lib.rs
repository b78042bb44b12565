//! The user-facing run settings (robot, laser, odometry, mapping, strategy parameters): what a
//! grid file's `[settings]` or the command line sets, what every summary records, and what a
//! job's identity hashes. Each setting is declared once (`declare_settings!`): its field, default,
//! range, unit, meaning and place in `sim-core`'s config.

use serde::{Deserialize, Serialize};
use sim_core::explore::{ExploreConfig, Localization, Strategy, StrategyParams, UtilityDistance};

/// Where the map's poses come from (setting `localization`, flag `--localization`): written as
/// `slam`, `odometry` or `ground-truth`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum LocalizationSetting {
    // Scan matching against the map, odometry as the prior (the default).
    #[default]
    Slam,
    // Dead reckoning from the noisy odometry.
    Odometry,
    // The true pose (an oracle).
    GroundTruth,
}

impl LocalizationSetting {
    /// Every value, in the order of the settings reference.
    pub const ALL: [Self; 3] = [Self::Slam, Self::Odometry, Self::GroundTruth];

    /// The word written in files and records.
    pub fn as_str(self) -> &'static str {
        Localization::from(self).as_str()
    }
}

impl From<LocalizationSetting> for Localization {
    fn from(l: LocalizationSetting) -> Self {
        match l {
            LocalizationSetting::Slam => Localization::Slam,
            LocalizationSetting::Odometry => Localization::Odometry,
            LocalizationSetting::GroundTruth => Localization::GroundTruth,
        }
    }
}

impl From<Localization> for LocalizationSetting {
    fn from(l: Localization) -> Self {
        match l {
            Localization::Slam => LocalizationSetting::Slam,
            Localization::Odometry => LocalizationSetting::Odometry,
            Localization::GroundTruth => LocalizationSetting::GroundTruth,
        }
    }
}

/// What the utility's distance measures (setting `utility_distance`, flag
/// `--utility-distance`): written as `path` or `euclidean`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum UtilityDistanceSetting {
    // The planned path's length (the default).
    #[default]
    Path,
    // The straight line from the robot to the candidate (the paper's).
    Euclidean,
}

impl UtilityDistanceSetting {
    /// Every value, in the order of the settings reference.
    pub const ALL: [Self; 2] = [Self::Path, Self::Euclidean];

    /// The word written in files and records.
    pub fn as_str(self) -> &'static str {
        UtilityDistance::from(self).as_str()
    }
}

impl From<UtilityDistanceSetting> for UtilityDistance {
    fn from(d: UtilityDistanceSetting) -> Self {
        match d {
            UtilityDistanceSetting::Path => UtilityDistance::Path,
            UtilityDistanceSetting::Euclidean => UtilityDistance::Euclidean,
        }
    }
}

impl From<UtilityDistance> for UtilityDistanceSetting {
    fn from(d: UtilityDistance) -> Self {
        match d {
            UtilityDistance::Path => UtilityDistanceSetting::Path,
            UtilityDistance::Euclidean => UtilityDistanceSetting::Euclidean,
        }
    }
}

/// The type of a setting's value.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum SettingKind {
    /// A number in `[min, max]`.
    Number {
        min: f64,
        max: f64,
    },
    /// A whole number in `[min, max]`.
    Integer {
        min: u64,
        max: u64,
    },
    Bool,
    /// One of these words.
    Choice(&'static [&'static str]),
}

/// One setting: name, type and range, unit, meaning. The default is [`Settings::default`]'s.
#[derive(Debug, Clone, Copy)]
pub struct SettingInfo {
    pub name: &'static str,
    pub kind: SettingKind,
    /// Unit of the value ("m", "m/s"; "" for none).
    pub unit: &'static str,
    /// One line saying what it does.
    pub meaning: &'static str,
}

// ---------------------------------------------------------------------------------------------
// Every setting is declared once, below: its field (doc and serde attributes), its default, its
// type and range, unit and meaning (the table behind validation, `--help` and the reference),
// and where it goes in the core's config. The macro makes the struct, its `Default`, the table
// (`SETTINGS`), `Settings::value` and the conversion from that one declaration.

/// Declares the settings (see the block above).
macro_rules! declare_settings {
    (
        defaults($c:ident, $p:ident);
        apply($cfg:ident);
        $(
            $(#[$attr:meta])*
            $name:ident: $ty:ty = $default:expr,
                $kind:expr, $unit:literal,
                $meaning:expr $(, apply $apply:expr)?;
        )*
    ) => {
        /// Settings as written in files and records. Every field has the documented default.
        #[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
        #[serde(default, deny_unknown_fields)]
        pub struct Settings {
            $( $(#[$attr])* pub $name: $ty, )*
        }

        impl Default for Settings {
            fn default() -> Self {
                let $c = ExploreConfig::default();
                let $p = StrategyParams::default();
                Self { $( $name: $default, )* }
            }
        }

        /// Every setting, in the order of [`Settings`]' fields. Ranges are physically sensible:
        /// a value outside them is refused on every path (command line, settings file, grid
        /// file, wire).
        pub const SETTINGS: &[SettingInfo] = &[
            $(
                SettingInfo {
                    name: stringify!($name),
                    kind: $kind,
                    unit: $unit,
                    meaning: $meaning,
                },
            )*
        ];

        impl Settings {
            /// The value of setting `name` (a row of [`SETTINGS`]).
            pub fn value(&self, name: &str) -> Option<SettingValue> {
                match name {
                    $( stringify!($name) => Some(self.$name.setting_value()), )*
                    _ => None,
                }
            }

            /// Writes the settings that shape a run into the core's config (those without a
            /// place there shape the strategy, [`Settings::strategy_params`], or the worker).
            fn apply(&self, $cfg: &mut ExploreConfig) {
                $( $( {
                    let $name = self.$name;
                    $apply;
                } )? )*
            }
        }
    };
}

/// A setting's type: how its value is shown and checked.
trait SettingType {
    fn setting_value(&self) -> SettingValue;
}

impl SettingType for f64 {
    fn setting_value(&self) -> SettingValue {
        SettingValue::Number(*self)
    }
}

impl SettingType for usize {
    fn setting_value(&self) -> SettingValue {
        SettingValue::Number(*self as f64)
    }
}

impl SettingType for bool {
    fn setting_value(&self) -> SettingValue {
        SettingValue::Bool(*self)
    }
}

impl SettingType for LocalizationSetting {
    fn setting_value(&self) -> SettingValue {
        SettingValue::Word(self.as_str().to_string())
    }
}

impl SettingType for UtilityDistanceSetting {
    fn setting_value(&self) -> SettingValue {
        SettingValue::Word(self.as_str().to_string())
    }
}

const fn number(min: f64, max: f64) -> SettingKind {
    SettingKind::Number { min, max }
}

const fn integer(min: u64, max: u64) -> SettingKind {
    SettingKind::Integer { min, max }
}

const BOOL: SettingKind = SettingKind::Bool;

declare_settings! {
    defaults(c, p);
    apply(cfg);
    /// Robot radius (m).
    robot_radius_m: f64 = c.sim.robot.radius_m,
        number(0.05, 2.0), "m",
        "Robot radius.",
        apply cfg.sim.robot.radius_m = robot_radius_m;
    /// Maximum forward speed (m/s).
    max_speed_mps: f64 = c.sim.robot.max_speed_mps,
        number(0.01, 5.0), "m/s",
        "Maximum forward speed.",
        apply cfg.sim.robot.max_speed_mps = max_speed_mps;
    /// Maximum turn rate (rad/s).
    max_turn_rate_radps: f64 = c.sim.robot.max_turn_rate_radps,
        number(0.01, 10.0), "rad/s",
        "Maximum turn rate.",
        apply cfg.sim.robot.max_turn_rate_radps = max_turn_rate_radps;
    /// Laser field of view (degrees).
    laser_fov_deg: f64 = c.sim.laser.fov_rad.to_degrees(),
        number(1.0, 360.0), "deg",
        "Laser field of view.",
        apply cfg.sim.laser.fov_rad = laser_fov_deg.to_radians();
    /// Laser range (m).
    laser_range_m: f64 = c.sim.laser.max_range_m,
        number(0.5, 30.0), "m",
        "Laser range.",
        apply cfg.sim.laser.max_range_m = laser_range_m;
    /// Number of beams per scan.
    laser_beams: usize = c.sim.laser.beams,
        integer(2, 3600), "",
        "Beams per scan.",
        apply cfg.sim.laser.beams = laser_beams;
    /// Scans per second available to the mapper.
    laser_rate_hz: f64 = c.sim.laser.rate_hz,
        number(1.0, 100.0), "Hz",
        "Scans per second (also the simulation step).",
        apply cfg.sim.laser.rate_hz = laser_rate_hz;
    /// Standard deviation of the Gaussian range noise (m).
    laser_noise_sd_m: f64 = c.sim.laser.range_noise_sd_m,
        number(0.0, 1.0), "m",
        "Standard deviation of the Gaussian range noise.",
        apply cfg.sim.laser.range_noise_sd_m = laser_noise_sd_m;
    /// Maximum proportional translation error of odometry (m per m).
    odometry_translation_error: f64 = c.sim.odometry.max_translation_error,
        number(0.0, 0.5), "m/m",
        "Largest proportional translation error of odometry.",
        apply cfg.sim.odometry.max_translation_error = odometry_translation_error;
    /// Maximum proportional rotation error of odometry (degrees per radian).
    odometry_rotation_error_deg_per_rad: f64 = c.sim.odometry.max_rotation_error.to_degrees(),
        number(0.0, 30.0), "deg/rad",
        "Largest proportional rotation error of odometry.",
        apply cfg.sim.odometry.max_rotation_error = odometry_rotation_error_deg_per_rad.to_radians();
    /// Where the map's poses come from.
    localization: LocalizationSetting = c.localization.into(),
        SettingKind::Choice(&["slam", "odometry", "ground-truth"]), "",
        "Where the map's poses come from.",
        apply cfg.localization = localization.into();
    /// Occupancy grid cell size (m).
    map_resolution_m: f64 = c.map_resolution_m,
        number(0.01, 0.5), "m",
        "Occupancy grid cell size.",
        apply cfg.map_resolution_m = map_resolution_m;
    /// The map is updated (and the scan matched) after this much motion (m)...
    map_update_distance_m: f64 = c.map_update_distance_m,
        number(0.01, 10.0), "m",
        "Update the map (and match the scan) after this much motion...",
        apply cfg.map_update_distance_m = map_update_distance_m;
    /// ...or this much turning (rad)...
    map_update_angle_rad: f64 = c.map_update_angle_rad,
        number(0.01, 6.3), "rad",
        "...or this much turning...",
        apply cfg.map_update_angle_rad = map_update_angle_rad;
    /// ...or this much simulated time (s), whichever comes first.
    map_update_period_s: f64 = c.map_update_period_s,
        number(0.01, 100.0), "s",
        "...or this much simulated time, whichever comes first.",
        apply cfg.map_update_period_s = map_update_period_s;
    /// Weight of distance in the utility (the paper's alpha).
    alpha: f64 = p.alpha,
        number(0.0, 1.0), "",
        "Weight of distance against gain in the utility (the paper's alpha).";
    /// In the utility, a candidate's gain counts as at least this much (m2); 0 = the paper's
    /// utility. Not in the paper: it keeps the robot from crossing the building for one small
    /// residual frontier while leaving another behind (see the README).
    gain_floor_m2: f64 = p.gain_floor_m2,
        number(0.0, 10000.0), "m2",
        "In the utility a candidate's gain counts as at least this much (0 = the paper's utility).";
    /// What the utility's distance `D(p)` measures: "path" (default: the planned path's length)
    /// or "euclidean" (the straight line from the robot to the candidate, as the paper defines
    /// it). Written only when not "path", so that the records and job identities of runs with
    /// the default are those of earlier versions.
    #[serde(skip_serializing_if = "is_path")]
    utility_distance: UtilityDistanceSetting = c.utility_distance.into(),
        SettingKind::Choice(&["path", "euclidean"]), "",
        "The utility's distance: the planned path's length, or the straight line (the paper's).",
        apply cfg.utility_distance = utility_distance.into();
    /// Bound each decision's distance search to paths of this length (m; 0 = off, the paper's
    /// exact distances at every decision); candidates beyond take their path lengths from the
    /// last search of everything reachable, made within a quarter of the bound of where the
    /// robot stands, and a decision that heads beyond the bound, passes or stops is made again
    /// with every distance searched. Built-in strategies only. Written only when not 0, so that
    /// the records and job identities of runs without it are those of earlier versions.
    #[serde(skip_serializing_if = "is_zero", default)]
    distance_bound_m: f64 = c.distance_bound_m,
        number(0.0, 10000.0), "m",
        "Bound each decision's distance search to paths this long; farther candidates take the lengths of the last whole search, made within a quarter of it, and a choice beyond it is made again exactly (0 = off, the paper's exact distances; built-in strategies: docs/scale.md).",
        apply cfg.distance_bound_m = distance_bound_m;
    /// Frontiers shorter than this are ignored (m).
    min_frontier_m: f64 = c.min_frontier_m,
        number(0.0, 100.0), "m",
        "Frontiers shorter than this are ignored.",
        apply cfg.min_frontier_m = min_frontier_m;
    /// Frontier cells closer than this to an observed wall are ignored (m; 0 = none), as by
    /// explorers that look for frontiers in an inflated costmap. Not in floorcast's default
    /// explorer. Written only when set, so that the records and job identities of runs without
    /// it are those of earlier versions.
    #[serde(skip_serializing_if = "is_zero")]
    frontier_clearance_m: f64 = c.frontier_clearance_m,
        number(0.0, 5.0), "m",
        "Frontier cells nearer than this to an observed wall are ignored (0 = none).",
        apply cfg.frontier_clearance_m = frontier_clearance_m;
    /// When a frontier's candidate (its middle cell, or a traversable cell within 0.5 m) cannot
    /// be reached, aim at the reachable cell of the frontier nearest to it instead of passing
    /// the frontier over. Not in the paper (false = its rule). Written only when true, so that
    /// the records and job identities of runs without it are those of earlier versions.
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    candidate_from_reachable_part: bool = c.candidate_from_reachable_part,
        BOOL, "",
        "Aim at a frontier's reachable part when its middle cell cannot be reached (not the paper's rule).",
        apply cfg.candidate_from_reachable_part = candidate_from_reachable_part;
    /// Resolve frontiers by the paper's rule (false = floorcast's since 0.4): a frontier whose
    /// middle cell is blacklisted is dropped whole, and a goal whose unknown side surrounds the
    /// robot counts as seen without a turn. Written only when true.
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    paper_frontiers: bool = !c.robust_frontiers,
        BOOL, "",
        "The paper's frontier rule: a frontier whose middle cell is blacklisted is dropped whole, a goal around the robot counts as seen without a turn, an early stop weighs only the frontiers whose goal is reachable as they stand (before 0.4).",
        apply cfg.robust_frontiers = !paper_frontiers;
    /// The layout gain I(p) by the paper's rule (false = floorcast's since 0.4): predicted
    /// walls block the gain's rays also across doorways, and unknown space outside the
    /// predicted rooms counts nothing. Written only when true.
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    paper_layout_gain: bool = !c.layout_use.through_openings,
        BOOL, "",
        "The paper's layout gain: predicted walls block it across doorways, unknown space outside predicted rooms counts nothing (before 0.4).",
        apply cfg.layout_use.through_openings = !paper_layout_gain;
    /// Re-decide this often while driving to a goal (s of simulated time)...
    redecide_period_s: f64 = c.redecide_period_s,
        number(0.1, 1000000000.0), "s",
        "Re-decide this often while driving to a goal (simulated time)...",
        apply cfg.redecide_period_s = redecide_period_s;
    /// ...once the map has grown by at least this much since the last decision (m2; 0 = at
    /// every period).
    redecide_min_growth_m2: f64 = c.redecide_min_growth_m2,
        number(0.0, 1000000.0), "m2",
        "...once the map grew by at least this much since the last decision (0 = every period).",
        apply cfg.redecide_min_growth_m2 = redecide_min_growth_m2;
    /// Radius of the blacklist around unreachable goals (m).
    blacklist_radius_m: f64 = c.blacklist_radius_m,
        number(0.0, 10.0), "m",
        "Radius of the blacklist around unreachable goals.",
        apply cfg.blacklist_radius_m = blacklist_radius_m;
    /// Abandon a goal after this long without progress (s).
    progress_timeout_s: f64 = c.progress_timeout_s,
        number(0.5, 3600.0), "s",
        "Abandon a goal after this long without progress.",
        apply cfg.progress_timeout_s = progress_timeout_s;
    /// Stop a run at this simulated time (s).
    time_limit_s: f64 = c.time_limit_s,
        number(1.0, 100000.0), "s",
        "Stop a run at this simulated time.",
        apply cfg.time_limit_s = time_limit_s;
    /// Drive back to the start after exploring.
    return_home: bool = c.return_home,
        BOOL, "",
        "Drive back to the start after exploring.",
        apply cfg.return_home = return_home;
    /// `layout-es`: stop when the summed gain of all candidates is below this (m2; paper: 1).
    es_threshold_m2: f64 = p.es_threshold_m2,
        number(0.0, 10000.0), "m2",
        "layout-es: stop when the summed gain of all candidates is below this.";
    /// `layout-aes`: drop candidates whose gain is below this (m2); stop when none is left.
    aes_min_gain_m2: f64 = p.aes_min_gain_m2,
        number(0.0, 10000.0), "m2",
        "layout-aes: drop candidates whose gain is below this; stop when none is left.";
    /// `utility-exp`: the weight of path length in `I * exp(-lambda * L)` (per m). Written only
    /// when not the default, so that the records and job identities of runs with the default
    /// are those of earlier versions.
    #[serde(skip_serializing_if = "is_default_lambda")]
    utility_exp_lambda_per_m: f64 = p.utility_exp_lambda_per_m,
        number(0.0, 100.0), "1/m",
        "utility-exp: the weight of path length L in I * exp(-lambda * L).";
    /// `cost-utility`: the price of path length in `I - beta * L` (m2 per m). Written only when
    /// not the default.
    #[serde(skip_serializing_if = "is_default_beta")]
    cost_utility_beta_m2_per_m: f64 = p.cost_utility_beta_m2_per_m,
        number(0.0, 10000.0), "m2/m",
        "cost-utility: the price of path length L in I - beta * L.";
    /// Layout strategies: rebuild the layout when the known area grew by this much (m2).
    layout_update_m2: f64 = c.layout_use.update_m2,
        number(0.1, 1000000.0), "m2",
        "Layout strategies: rebuild the layout when the known area grew by this much.",
        apply cfg.layout_use.update_m2 = layout_update_m2;
    /// Layout strategies: ...and by this fraction of the known area (0 = off, the paper's;
    /// 0.1 by default since 0.7). Written only when not 0, and read as 0 where a record does
    /// not have it (records written before it had another default, and runs of the paper's 0,
    /// keep their meaning and job identities); a settings table without it (a grid, a
    /// `--settings` file) gets the default, as every setting ([`settings_from_map`]).
    #[serde(skip_serializing_if = "is_zero", default)]
    layout_update_fraction: f64 = c.layout_use.update_fraction,
        number(0.0, 1.0), "",
        "Layout strategies: ...and by this fraction of the known area (0 = off, the paper's; the default keeps the layout's cost from growing with the building, tested no slower: docs/scale.md).",
        apply cfg.layout_use.update_fraction = layout_update_fraction;
    /// Layout strategies: the layout's wall lines close gaps in observed walls up to this long (m).
    max_wall_gap_m: f64 = c.layout_use.max_wall_gap_m,
        number(0.0, 20.0), "m",
        "Layout strategies: the layout's wall lines close gaps in observed walls up to this long.",
        apply cfg.layout_use.max_wall_gap_m = max_wall_gap_m;
    /// Add the measured wall time of every layout computation to simulated time (the robot
    /// waits for it). The result then depends on the machine: not reproducible.
    charge_compute: bool = false,
        BOOL, "",
        "Add the measured wall time of every layout to simulated time (not reproducible).";
    /// Robots in the team (1 = one robot). A team shares one map (their relative starts
    /// known, every map update reaching every robot at once), each robot with its own body,
    /// noise, odometry, estimate and goal; robots 2 to N start around robot 0's start, or
    /// drawn at random with a random start (docs/teams.md). Written only when not 1, so that
    /// the records and job identities of one robot's runs are those of earlier versions.
    #[serde(skip_serializing_if = "is_one")]
    robots: usize = 1,
        integer(1, 8), "",
        "Robots in the team, exploring one shared map (1 = one robot; docs/teams.md).";
}

fn is_path(d: &UtilityDistanceSetting) -> bool {
    *d == UtilityDistanceSetting::Path
}

fn is_zero(v: &f64) -> bool {
    *v == 0.0
}

fn is_one(v: &usize) -> bool {
    *v == 1
}

fn is_default_lambda(v: &f64) -> bool {
    *v == StrategyParams::default().utility_exp_lambda_per_m
}

fn is_default_beta(v: &f64) -> bool {
    *v == StrategyParams::default().cost_utility_beta_m2_per_m
}

#[derive(Debug, thiserror::Error, PartialEq)]
pub enum SettingsError {
    #[error("settings.{field}: {value} is out of range, expected {expected}")]
    OutOfRange {
        field: &'static str,
        value: String,
        expected: String,
    },
    #[error("settings.localization: unknown value '{0}', expected slam, odometry or ground-truth")]
    Localization(String),
    #[error("settings.utility_distance: unknown value '{0}', expected path or euclidean")]
    UtilityDistance(String),
    #[error("unknown strategy '{0}' (available: {list})", list = Strategy::names().join(", "))]
    Strategy(String),
    #[error("settings.{field}: expected {expected}, got {got}")]
    Type {
        field: String,
        expected: String,
        got: String,
    },
    #[error("settings.{field}: unknown setting; expected one of {list}", list = setting_names().join(", "))]
    Unknown { field: String },
    #[error("settings: {0}")]
    Shape(String),
}

impl SettingsError {
    /// The setting the error is about (`alpha`), if one.
    pub fn field(&self) -> Option<&str> {
        match self {
            SettingsError::OutOfRange { field, .. } => Some(field),
            SettingsError::Localization(_) => Some("localization"),
            SettingsError::UtilityDistance(_) => Some("utility_distance"),
            SettingsError::Type { field, .. } | SettingsError::Unknown { field } => Some(field),
            SettingsError::Strategy(_) | SettingsError::Shape(_) => None,
        }
    }

    /// The message without the `settings.<field>: ` prefix.
    pub fn problem(&self) -> String {
        let s = self.to_string();
        match self.field() {
            Some(f) => s
                .strip_prefix(&format!("settings.{f}: "))
                .map(str::to_string)
                .unwrap_or(s),
            None => s
                .strip_prefix("settings: ")
                .map(str::to_string)
                .unwrap_or(s),
        }
    }
}

/// The names of every setting, in table order.
pub fn setting_names() -> Vec<&'static str> {
    SETTINGS.iter().map(|s| s.name).collect()
}

/// The row of the table for `name`.
pub fn setting_info(name: &str) -> Option<&'static SettingInfo> {
    SETTINGS.iter().find(|s| s.name == name)
}

/// A setting's value, for validation and display.
#[derive(Debug, Clone, PartialEq)]
pub enum SettingValue {
    Number(f64),
    Bool(bool),
    Word(String),
}

impl std::fmt::Display for SettingValue {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            SettingValue::Number(v) => write!(f, "{}", fmt_num(*v)),
            SettingValue::Bool(b) => write!(f, "{b}"),
            SettingValue::Word(w) => write!(f, "{w}"),
        }
    }
}

/// A number for messages and tables: `0.2`, `1000000000`, `1e300`.
pub fn fmt_num(v: f64) -> String {
    if v.is_finite() && v.abs() < 1e15 {
        format!("{v}")
    } else {
        format!("{v:e}")
    }
}

impl SettingKind {
    /// The type and range in words, with `unit`: `number in [0.05, 2] m`.
    pub fn describe(&self, unit: &str) -> String {
        let u = if unit.is_empty() {
            String::new()
        } else {
            format!(" {unit}")
        };
        match self {
            SettingKind::Number { min, max } => {
                format!("a number in [{}, {}]{u}", fmt_num(*min), fmt_num(*max))
            }
            SettingKind::Integer { min, max } => format!("an integer in [{min}, {max}]{u}"),
            SettingKind::Bool => "true or false".to_string(),
            SettingKind::Choice(words) => format!("one of {}", words.join(", ")),
        }
    }
}

impl SettingInfo {
    /// The default value (from [`Settings::default`]).
    pub fn default_value(&self) -> SettingValue {
        Settings::default()
            .value(self.name)
            .unwrap_or(SettingValue::Word(String::new()))
    }

    /// Checks one value against the row: type and range.
    fn check(&self, v: &SettingValue) -> Result<(), SettingsError> {
        let expected = || self.kind.describe(self.unit);
        match (&self.kind, v) {
            (SettingKind::Number { min, max }, SettingValue::Number(x)) => {
                if x.is_finite() && *x >= *min && *x <= *max {
                    Ok(())
                } else {
                    Err(SettingsError::OutOfRange {
                        field: self.name,
                        value: fmt_num(*x),
                        expected: expected(),
                    })
                }
            }
            (SettingKind::Integer { min, max }, SettingValue::Number(x)) => {
                if *x >= *min as f64 && *x <= *max as f64 {
                    Ok(())
                } else {
                    Err(SettingsError::OutOfRange {
                        field: self.name,
                        value: fmt_num(*x),
                        expected: expected(),
                    })
                }
            }
            (SettingKind::Bool, SettingValue::Bool(_)) => Ok(()),
            (SettingKind::Choice(words), SettingValue::Word(w)) => {
                if words.contains(&w.as_str()) {
                    Ok(())
                } else if self.name == "localization" {
                    Err(SettingsError::Localization(shown(w)))
                } else if self.name == "utility_distance" {
                    Err(SettingsError::UtilityDistance(shown(w)))
                } else {
                    Err(SettingsError::Type {
                        field: self.name.to_string(),
                        expected: expected(),
                        got: format!("'{}'", shown(w)),
                    })
                }
            }
            (_, v) => Err(SettingsError::Type {
                field: self.name.to_string(),
                expected: expected(),
                got: v.to_string(),
            }),
        }
    }

    /// Whether a JSON value has this setting's type (the range is checked later).
    fn type_ok(&self, v: &serde_json::Value) -> bool {
        match self.kind {
            SettingKind::Number { .. } => v.is_number(),
            SettingKind::Integer { .. } => v.is_u64(),
            SettingKind::Bool => v.is_boolean(),
            SettingKind::Choice(_) => v.is_string(),
        }
    }
}

/// A JSON value in a few words, for messages: `a string "x"`, `an array`, `a number 3`.
fn describe_json(v: &serde_json::Value) -> String {
    use serde_json::Value as J;
    let short = |s: String| {
        if s.chars().count() > 40 {
            format!("{}...", s.chars().take(40).collect::<String>())
        } else {
            s
        }
    };
    match v {
        J::Null => "nothing (null)".to_string(),
        J::Bool(b) => format!("the boolean {b}"),
        J::Number(n) => format!("the number {}", short(n.to_string())),
        J::String(s) => format!("the string {}", short(format!("{s:?}"))),
        J::Array(_) => "an array".to_string(),
        J::Object(_) => "a table".to_string(),
    }
}

/// Settings from a table of `name = value` (a settings file's JSON object, a grid's
/// `[settings]`): every key must be a known setting of the right type and range. Missing keys
/// keep their defaults.
pub fn settings_from_map(
    map: &serde_json::Map<String, serde_json::Value>,
) -> Result<Settings, SettingsError> {
    for (k, v) in map {
        let info = setting_info(k).ok_or_else(|| SettingsError::Unknown { field: shown(k) })?;
        if !info.type_ok(v) {
            return Err(SettingsError::Type {
                field: shown(k),
                expected: info.kind.describe(info.unit),
                got: describe_json(v),
            });
        }
        // A word outside the choices is named here, before serde reads the typed value.
        if let (SettingKind::Choice(_), Some(w)) = (info.kind, v.as_str()) {
            info.check(&SettingValue::Word(w.to_string()))?;
        }
    }
    // The table's settings over the defaults: what a table leaves out is at its default, where
    // serde reads a record that lacks a setting as it was made (`layout_update_fraction`: 0).
    let mut table = match serde_json::to_value(Settings::default()) {
        Ok(serde_json::Value::Object(defaults)) => defaults,
        _ => serde_json::Map::new(),
    };
    table.extend(map.iter().map(|(k, v)| (k.clone(), v.clone())));
    let settings: Settings = serde_json::from_value(serde_json::Value::Object(table))
        .map_err(|e| SettingsError::Shape(one_line(&e.to_string())))?;
    settings.validate()?;
    Ok(settings)
}

impl Settings {
    /// Every setting by name, as a settings table that reads back as these settings
    /// ([`settings_from_map`], a `--settings` file, a grid's `[settings]`). The records' own
    /// form leaves some settings out at the value that keeps earlier job identities (0 or off),
    /// and a table without one gets its default, which for `layout_update_fraction` is not that
    /// value; here every setting is written.
    pub fn to_table(&self) -> serde_json::Map<String, serde_json::Value> {
        let mut table = match serde_json::to_value(self) {
            Ok(serde_json::Value::Object(written)) => written,
            _ => serde_json::Map::new(),
        };
        for info in SETTINGS {
            if table.contains_key(info.name) {
                continue;
            }
            let value = match self.value(info.name) {
                Some(SettingValue::Number(x)) => match info.kind {
                    SettingKind::Integer { .. } => serde_json::Value::from(x as u64),
                    _ => serde_json::Value::from(x),
                },
                Some(SettingValue::Bool(b)) => serde_json::Value::Bool(b),
                Some(SettingValue::Word(w)) => serde_json::Value::String(w),
                None => continue,
            };
            table.insert(info.name.to_string(), value);
        }
        table
    }
}

/// Settings from a settings file's text: a JSON object (`{"alpha": 0.8}`).
pub fn settings_from_json_text(text: &str) -> Result<Settings, SettingsError> {
    let v: serde_json::Value = serde_json::from_str(text).map_err(|e| {
        SettingsError::Shape(format!(
            "not valid JSON ({}); expected a JSON object such as {{\"alpha\": 0.8}}",
            one_line(&e.to_string())
        ))
    })?;
    match v {
        serde_json::Value::Object(map) => settings_from_map(&map),
        other => Err(SettingsError::Shape(format!(
            "expected a JSON object of settings such as {{\"alpha\": 0.8}}, got {}",
            describe_json(&other)
        ))),
    }
}

/// The most characters of a value or name from the input that a message quotes: the worker's
/// `floorcast_worker::text::EXCERPT_CHARS` (its tests check that the two agree).
const EXCERPT_CHARS: usize = 80;

/// A value or name from the input as a message shows it: escaped (a key written `"a\nb"` is
/// shown `a\nb`, not broken over two lines), and cut to its first [`EXCERPT_CHARS`] characters
/// with its length when longer (as the worker's `text::excerpt`).
fn shown(s: &str) -> String {
    match s.char_indices().nth(EXCERPT_CHARS) {
        None => s.escape_debug().to_string(),
        Some((cut, _)) => format!(
            "{}... ({} characters in all)",
            s[..cut].escape_debug(),
            s.chars().count()
        ),
    }
}

fn one_line(s: &str) -> String {
    s.split_whitespace().collect::<Vec<_>>().join(" ")
}

/// The settings each built-in strategy reads ([`sim_core::explore::BuiltIn::settings`]) with
/// their defaults, as a markdown table; docs/settings.md carries it between
/// `<!-- strategy-settings:begin -->` and `<!-- strategy-settings:end -->`.
pub fn strategy_settings_markdown() -> String {
    let mut s = String::from("| strategy | settings it reads (default) |\n|---|---|\n");
    for b in sim_core::explore::BUILT_IN {
        let read: Vec<String> = b
            .settings
            .iter()
            .map(|n| match setting_info(n) {
                Some(i) => format!("`{n}` ({})", i.default_value()),
                None => format!("`{n}` (not a setting)"),
            })
            .collect();
        let read = if read.is_empty() {
            "none".to_string()
        } else {
            read.join(", ")
        };
        s.push_str(&format!("| `{}` | {read} |\n", b.name));
    }
    s
}

/// The settings reference as a markdown table (name, type and range, unit, default, meaning);
/// docs/settings.md carries it between `<!-- settings:begin -->` and `<!-- settings:end -->`.
pub fn settings_reference_markdown() -> String {
    let mut s = String::from(
        "| setting | type and range | unit | default | meaning |\n|---|---|---|---|---|\n",
    );
    for i in SETTINGS {
        let range = match i.kind {
            SettingKind::Number { min, max } => {
                format!("number, {} to {}", fmt_num(min), fmt_num(max))
            }
            SettingKind::Integer { min, max } => format!("integer, {min} to {max}"),
            SettingKind::Bool => "true / false".to_string(),
            SettingKind::Choice(w) => w.join(" / "),
        };
        let unit = if i.unit.is_empty() { "-" } else { i.unit };
        s.push_str(&format!(
            "| `{}` | {range} | {unit} | {} | {} |\n",
            i.name,
            i.default_value(),
            i.meaning
        ));
    }
    s
}

/// The settings as plain text for `--help`: one line per setting.
pub fn settings_help_text() -> String {
    let width = SETTINGS.iter().map(|i| i.name.len()).max().unwrap_or(0);
    let mut s = String::from(
        "Settings (in a --settings JSON file or a grid's [settings]; name: type and range, unit; default; meaning):\n",
    );
    for i in SETTINGS {
        s.push_str(&format!(
            "  {:width$}  {}; default {}; {}\n",
            i.name,
            i.kind.describe(i.unit),
            i.default_value(),
            i.meaning
        ));
    }
    s
}

impl Settings {
    /// Checks every setting against its row of [`SETTINGS`] (type and range).
    pub fn validate(&self) -> Result<(), SettingsError> {
        for info in SETTINGS {
            let v = self
                .value(info.name)
                .ok_or_else(|| SettingsError::Unknown {
                    field: info.name.to_string(),
                })?;
            info.check(&v)?;
        }
        Ok(())
    }

    /// The simulation config for strategy `name` (see [`sim_core::explore::Strategy::by_name`]),
    /// with this file's thresholds.
    pub fn to_explore_config_for(&self, name: &str) -> Result<ExploreConfig, SettingsError> {
        let strategy = sim_core::explore::BuiltIn::find(name)
            .ok_or_else(|| SettingsError::Strategy(shown(name)))?;
        self.to_explore_config_with(strategy)
    }

    /// The simulation config for the built-in `strategy`, with this file's thresholds.
    pub fn to_explore_config_with(
        &self,
        strategy: &sim_core::explore::BuiltIn,
    ) -> Result<ExploreConfig, SettingsError> {
        let mut c = self.to_explore_config()?;
        c.strategy = (strategy.make)(&self.strategy_params());
        Ok(c)
    }

    /// The settings a strategy's definition reads.
    pub fn strategy_params(&self) -> StrategyParams {
        StrategyParams {
            alpha: self.alpha,
            gain_floor_m2: self.gain_floor_m2,
            es_threshold_m2: self.es_threshold_m2,
            aes_min_gain_m2: self.aes_min_gain_m2,
            utility_exp_lambda_per_m: self.utility_exp_lambda_per_m,
            cost_utility_beta_m2_per_m: self.cost_utility_beta_m2_per_m,
        }
    }

    /// Checks every setting and builds the simulation config, with the baseline for a strategy.
    pub fn to_explore_config(&self) -> Result<ExploreConfig, SettingsError> {
        self.validate()?;
        let mut c = ExploreConfig::default();
        self.apply(&mut c);
        c.sim.step_s = 1.0 / c.sim.laser.rate_hz;
        c.strategy = Strategy::baseline_with(&self.strategy_params());
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
        assert_eq!(c.strategy, d.strategy);
        assert_eq!(c.layout_use, d.layout_use);
    }

    #[test]
    fn bad_values_name_the_field() {
        let s = Settings {
            alpha: 1.5,
            ..Settings::default()
        };
        let e = s.to_explore_config().unwrap_err().to_string();
        assert!(e.contains("settings.alpha") && e.contains("[0, 1]"), "{e}");
        let e = settings_from_json_text(r#"{"localization": "gps"}"#).unwrap_err();
        assert!(
            e.to_string().contains("settings.localization") && e.to_string().contains("gps"),
            "{e}"
        );
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
            utility_distance: UtilityDistanceSetting::Euclidean,
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
        let e = settings_from_json_text(r#"{"utility_distance": "manhattan"}"#)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("settings.utility_distance") && e.contains("manhattan"),
            "{e}"
        );
    }

    /// The paper's rules are off by default, recorded only when on, and reach the explorer
    /// (`paper_layout_gain` for every strategy, whatever its name).
    #[test]
    fn the_paper_rules_are_switches_recorded_only_when_on() {
        let default = Settings::default();
        let v = serde_json::to_value(&default).unwrap();
        assert!(v.get("paper_frontiers").is_none() && v.get("paper_layout_gain").is_none());
        for name in ["baseline", "layout-es", "layout-aes"] {
            let c = default.to_explore_config_for(name).unwrap();
            assert!(
                c.robust_frontiers && c.layout_use.through_openings,
                "{name}"
            );
        }
        let paper = Settings {
            paper_frontiers: true,
            paper_layout_gain: true,
            ..Settings::default()
        };
        let back: Settings = serde_json::from_value(serde_json::to_value(&paper).unwrap()).unwrap();
        assert_eq!(back, paper);
        for name in ["baseline", "layout-es", "layout-aes"] {
            let c = paper.to_explore_config_for(name).unwrap();
            assert!(
                !c.robust_frontiers && !c.layout_use.through_openings,
                "{name}"
            );
        }
    }

    /// A word choice is written the same in the settings table, in files and records (serde)
    /// and on the command line (the binary's parsers are made from `ALL` and `as_str`), `ALL`
    /// holds every value once, and it reaches the explorer as the core's value.
    #[test]
    fn word_choices_are_one_set_of_words_everywhere() {
        /// Per value: its `as_str` word, its serde word, and whether serde reads the word back
        /// as the same value.
        fn words<T: Serialize + serde::de::DeserializeOwned + PartialEq + Copy>(
            all: &[T],
            as_str: fn(T) -> &'static str,
        ) -> Vec<(&'static str, String, bool)> {
            all.iter()
                .map(|&v| {
                    let serde = serde_json::to_value(v)
                        .unwrap()
                        .as_str()
                        .unwrap()
                        .to_string();
                    let back: T = serde_json::from_value(serde_json::json!(as_str(v))).unwrap();
                    (as_str(v), serde, back == v)
                })
                .collect()
        }
        // Each value's place in `ALL`, by an exhaustive match: a new value fails to compile here
        // until it is placed (and so added to `ALL`).
        let localization_place = |v: LocalizationSetting| match v {
            LocalizationSetting::Slam => 0,
            LocalizationSetting::Odometry => 1,
            LocalizationSetting::GroundTruth => 2,
        };
        let distance_place = |v: UtilityDistanceSetting| match v {
            UtilityDistanceSetting::Path => 0,
            UtilityDistanceSetting::Euclidean => 1,
        };
        for (i, v) in LocalizationSetting::ALL.into_iter().enumerate() {
            assert_eq!(localization_place(v), i, "{v:?}");
            assert_eq!(LocalizationSetting::from(Localization::from(v)), v);
        }
        for (i, v) in UtilityDistanceSetting::ALL.into_iter().enumerate() {
            assert_eq!(distance_place(v), i, "{v:?}");
            assert_eq!(UtilityDistanceSetting::from(UtilityDistance::from(v)), v);
        }
        let cases = [
            (
                "localization",
                words(&LocalizationSetting::ALL, LocalizationSetting::as_str),
            ),
            (
                "utility_distance",
                words(&UtilityDistanceSetting::ALL, UtilityDistanceSetting::as_str),
            ),
        ];
        for (name, words) in cases {
            let SettingKind::Choice(table) = setting_info(name).unwrap().kind else {
                panic!("{name} is not a choice");
            };
            let words_of_as_str: Vec<&str> = words.iter().map(|w| w.0).collect();
            assert_eq!(table, &words_of_as_str[..], "{name}");
            for (word, serde, read_back) in &words {
                assert_eq!(serde, word, "{name}");
                assert!(read_back, "{name}: {word}");
            }
        }
        let c = settings_from_json_text(
            r#"{"localization": "ground-truth", "utility_distance": "euclidean"}"#,
        )
        .unwrap()
        .to_explore_config()
        .unwrap();
        assert_eq!(
            (c.localization, c.utility_distance),
            (Localization::GroundTruth, UtilityDistance::Euclidean)
        );
    }

    #[test]
    fn the_table_has_one_row_per_field_in_order_and_the_defaults_pass() {
        let all_written = Settings {
            utility_distance: UtilityDistanceSetting::Euclidean,
            frontier_clearance_m: 0.4,
            candidate_from_reachable_part: true,
            paper_frontiers: true,
            paper_layout_gain: true,
            utility_exp_lambda_per_m: 0.5,
            cost_utility_beta_m2_per_m: 2.0,
            layout_update_fraction: 0.025,
            distance_bound_m: 20.0,
            robots: 2,
            ..Settings::default()
        };
        let v = serde_json::to_value(&all_written).unwrap();
        let fields: Vec<&str> = v.as_object().unwrap().keys().map(String::as_str).collect();
        let mut names = setting_names();
        let mut sorted_fields = fields.clone();
        sorted_fields.sort_unstable();
        names.sort_unstable();
        assert_eq!(sorted_fields, names);
        for info in SETTINGS {
            assert!(
                Settings::default().value(info.name).is_some(),
                "{}",
                info.name
            );
            info.check(&info.default_value())
                .unwrap_or_else(|e| panic!("default of {}: {e}", info.name));
        }
        Settings::default().validate().unwrap();
    }

    #[test]
    fn settings_files_are_checked_field_by_field() {
        // (file text, words the message must hold; "" = accepted)
        let cases: &[(&str, &[&str])] = &[
            ("{}", &[]),
            (r#"{"alpha": 0.8, "time_limit_s": 600}"#, &[]),
            ("[1, 2, 3]", &["expected a JSON object", "an array"]),
            ("3", &["expected a JSON object", "the number 3"]),
            ("{", &["not valid JSON"]),
            (
                r#"{"alpha": "high"}"#,
                &[
                    "settings.alpha",
                    "expected a number in [0, 1]",
                    "the string \"high\"",
                ],
            ),
            (
                r#"{"laser_beams": 1.5}"#,
                &["settings.laser_beams", "an integer"],
            ),
            (
                r#"{"laser_beams": -4}"#,
                &["settings.laser_beams", "an integer"],
            ),
            (
                r#"{"return_home": 1}"#,
                &["settings.return_home", "true or false"],
            ),
            (
                r#"{"localization": "magic"}"#,
                &["settings.localization", "magic", "slam"],
            ),
            (
                r#"{"localization": 3}"#,
                &["settings.localization", "one of slam"],
            ),
            (
                r#"{"utility_distance": "manhattan"}"#,
                &["settings.utility_distance", "manhattan"],
            ),
            (
                r#"{"alpah": 0.3}"#,
                &["settings.alpah", "unknown setting", "alpha"],
            ),
            (
                r#"{"laser_rate_hz": 1e6}"#,
                &["settings.laser_rate_hz", "[1, 100] Hz"],
            ),
            (
                r#"{"robot_radius_m": 50}"#,
                &["settings.robot_radius_m", "[0.05, 2] m"],
            ),
            (
                r#"{"max_speed_mps": 1e9}"#,
                &["settings.max_speed_mps", "m/s"],
            ),
            (
                r#"{"laser_noise_sd_m": 1000}"#,
                &["settings.laser_noise_sd_m"],
            ),
            (
                r#"{"odometry_translation_error": 5}"#,
                &["settings.odometry_translation_error"],
            ),
            (
                r#"{"time_limit_s": 1e300}"#,
                &["settings.time_limit_s", "1e300"],
            ),
            (r#"{"map_resolution_m": 0}"#, &["settings.map_resolution_m"]),
            (r#"{"alpha": null}"#, &["settings.alpha", "null"]),
            // Names and words with escapes are shown escaped, on one line.
            (
                r#"{"localizatio\n": 1}"#,
                &["settings.localizatio\\n: unknown setting"],
            ),
            (
                r#"{"localization": "od\nometry"}"#,
                &["settings.localization", "'od\\nometry'"],
            ),
            (
                r#"{"utility_distance": "path\r"}"#,
                &["settings.utility_distance", "'path\\r'"],
            ),
        ];
        for (text, words) in cases {
            let r = settings_from_json_text(text);
            match (r, words.is_empty()) {
                (Ok(_), true) => {}
                (Err(e), false) => {
                    let e = e.to_string();
                    assert_eq!(e.lines().count(), 1, "{e}");
                    for w in *words {
                        assert!(e.contains(w), "{text}: {w:?} not in {e}");
                    }
                }
                (r, _) => panic!("{text}: {r:?}"),
            }
        }
    }

    #[test]
    fn the_reference_lists_every_setting_with_its_default() {
        let md = settings_reference_markdown();
        assert_eq!(md.lines().count(), SETTINGS.len() + 2);
        assert!(
            md.contains("| `robot_radius_m` | number, 0.05 to 2 | m | 0.2 | Robot radius. |"),
            "{md}"
        );
        assert!(
            md.contains("| `localization` | slam / odometry / ground-truth | - | slam |"),
            "{md}"
        );
        let help = settings_help_text();
        for i in SETTINGS {
            assert!(help.contains(i.name), "{}", i.name);
        }
    }

    /// docs/settings.md carries the reference generated from the table (print it with
    /// `floorcast settings --markdown`).
    #[test]
    fn docs_hold_the_settings_reference() {
        let readme = std::fs::read_to_string(
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../docs/settings.md"),
        )
        .unwrap();
        let begin = "<!-- settings:begin -->\n";
        let end = "<!-- settings:end -->";
        let a = readme
            .find(begin)
            .expect("docs/settings.md has no <!-- settings:begin --> line")
            + begin.len();
        let b = readme[a..]
            .find(end)
            .expect("docs/settings.md has no <!-- settings:end --> line")
            + a;
        assert_eq!(
            &readme[a..b],
            settings_reference_markdown(),
            "docs/settings.md's settings block is stale: replace it with the output of `floorcast settings --markdown`"
        );
    }

    /// Every setting a built-in strategy lists as read is a setting, and docs/settings.md
    /// carries the table of them (print it with `floorcast strategy list --settings-markdown`).
    #[test]
    fn docs_hold_the_settings_of_each_strategy() {
        for b in sim_core::explore::BUILT_IN {
            for n in b.settings {
                assert!(
                    setting_info(n).is_some(),
                    "{}: '{n}' is not a setting",
                    b.name
                );
            }
        }
        let doc = std::fs::read_to_string(
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../docs/settings.md"),
        )
        .unwrap();
        let (begin, end) = (
            "<!-- strategy-settings:begin -->\n",
            "<!-- strategy-settings:end -->",
        );
        let a = doc
            .find(begin)
            .expect("docs/settings.md has no <!-- strategy-settings:begin --> line")
            + begin.len();
        let b = doc[a..]
            .find(end)
            .expect("docs/settings.md has no <!-- strategy-settings:end --> line")
            + a;
        assert_eq!(
            &doc[a..b],
            strategy_settings_markdown(),
            "docs/settings.md's strategies' settings are stale: replace them with the output of `floorcast strategy list --settings-markdown`"
        );
    }

    /// The README carries the table generated from sim-core's `BUILT_IN`.
    #[test]
    fn the_readme_holds_the_strategies_table() {
        let readme = std::fs::read_to_string(
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../README.md"),
        )
        .unwrap();
        let (begin, end) = ("<!-- strategies:begin -->\n", "<!-- strategies:end -->");
        let a = readme
            .find(begin)
            .expect("README.md has no strategies:begin line")
            + begin.len();
        let b = readme[a..]
            .find(end)
            .expect("README.md has no strategies:end line")
            + a;
        assert_eq!(
            &readme[a..b],
            sim_core::explore::strategies::strategies_markdown(),
            "README.md's strategies table is stale: replace it with `floorcast strategy list --markdown`"
        );
    }

    /// Every setting but `charge_compute` (the worker's) and `robots` (the team's size, not a
    /// robot's config) reaches the run: a value other than
    /// the default changes the core's config of at least one built-in strategy.
    #[test]
    fn every_setting_reaches_the_run() {
        let default = serde_json::to_value(Settings::default()).unwrap();
        let configs = |s: &Settings| -> Vec<ExploreConfig> {
            Strategy::names()
                .into_iter()
                .map(|n| s.to_explore_config_for(n).unwrap())
                .collect()
        };
        let before = configs(&Settings::default());
        for info in SETTINGS {
            let now = info.default_value();
            let other = match (info.kind, &now) {
                (SettingKind::Number { min, max }, SettingValue::Number(v)) => {
                    serde_json::json!(if *v == max { min } else { max })
                }
                (SettingKind::Integer { min, max }, SettingValue::Number(v)) => {
                    serde_json::json!(if *v == max as f64 { min } else { max })
                }
                (SettingKind::Bool, SettingValue::Bool(b)) => serde_json::json!(!b),
                (SettingKind::Choice(words), SettingValue::Word(w)) => {
                    serde_json::json!(words.iter().find(|x| *x != w).unwrap())
                }
                (kind, v) => panic!("{}: {kind:?} with the default {v}", info.name),
            };
            let mut map = default.as_object().unwrap().clone();
            map.insert(info.name.to_string(), other);
            let changed = settings_from_map(&map).unwrap();
            // (`charge_compute` is the worker's; `robots` makes a team of the run's config.)
            assert_eq!(
                configs(&changed) != before,
                !["charge_compute", "robots"].contains(&info.name),
                "{}",
                info.name
            );
        }
    }

    /// `layout_update_fraction` changed its default (0, the paper's, to 0.1): a record without
    /// it was made with 0 and reads so (keeping its meaning and, written back, its job
    /// identity), where a settings table without it asks for the default; every value is
    /// written and read back as it was.
    #[test]
    fn a_record_without_the_layout_fraction_was_made_with_0_a_table_without_it_gets_the_default() {
        let default = Settings::default().layout_update_fraction;
        assert_eq!(default, 0.1);
        let record: Settings = serde_json::from_str(r#"{"alpha": 0.5}"#).unwrap();
        assert_eq!(record.layout_update_fraction, 0.0);
        assert_eq!(record.alpha, 0.5);
        let table = settings_from_json_text(r#"{"alpha": 0.5}"#).unwrap();
        assert_eq!(table.layout_update_fraction, default);
        assert_eq!(
            table,
            Settings {
                alpha: 0.5,
                ..Settings::default()
            }
        );
        for (value, written) in [(0.0, false), (0.1, true), (0.025, true), (1.0, true)] {
            let s = Settings {
                layout_update_fraction: value,
                ..Settings::default()
            };
            let json = serde_json::to_value(&s).unwrap();
            assert_eq!(
                json.get("layout_update_fraction").is_some(),
                written,
                "{value}"
            );
            assert_eq!(serde_json::from_value::<Settings>(json.clone()).unwrap(), s);
            let map = json.as_object().unwrap();
            assert_eq!(settings_from_map(map).unwrap().layout_update_fraction, {
                if written {
                    value
                } else {
                    default
                }
            });
        }
        // Written as 0 in a table, it is 0.
        let paper = settings_from_json_text(r#"{"layout_update_fraction": 0}"#).unwrap();
        assert_eq!(paper.layout_update_fraction, 0.0);
    }

    /// A record's settings written whole ([`Settings::to_table`]) name every setting and read
    /// back, as a settings table, as the same settings: a summary's `settings` given to
    /// `explore --settings` runs the same run, whatever the settings the record form leaves out.
    #[test]
    fn settings_written_whole_name_every_setting_and_read_back_as_a_table() {
        let cases = [
            Settings::default(),
            Settings {
                layout_update_fraction: 0.0,
                ..Settings::default()
            },
            Settings {
                layout_update_fraction: 0.0,
                distance_bound_m: 20.0,
                frontier_clearance_m: 0.3,
                utility_distance: UtilityDistanceSetting::Euclidean,
                laser_beams: 361,
                return_home: true,
                ..Settings::default()
            },
        ];
        for s in cases {
            let table = s.to_table();
            assert_eq!(table.len(), SETTINGS.len(), "{table:?}");
            assert!(SETTINGS.iter().all(|i| table.contains_key(i.name)));
            assert_eq!(settings_from_map(&table).unwrap(), s);
            assert_eq!(
                serde_json::from_value::<Settings>(serde_json::Value::Object(table)).unwrap(),
                s
            );
        }
    }

    #[test]
    fn unknown_keys_are_rejected() {
        let e = serde_json::from_str::<Settings>(r#"{"alpah": 0.3}"#)
            .unwrap_err()
            .to_string();
        assert!(e.contains("alpah"), "{e}");
    }
}
