//! The run record written as `summary.json` and stored by the coordinator. Versioned: readers
//! check `format` and `version` before trusting the rest.

use serde::{Deserialize, Serialize};
use sim_core::explore::{EndReason, RunResult};

use crate::{Job, Settings, FLOORCAST_VERSION};

pub const SUMMARY_FORMAT: &str = "floorcast-run-summary";
/// The version written. Version 2 (0.7.0) added `suite` and `suite_hash`; version 1 records
/// (without them) are read as they are.
pub const SUMMARY_VERSION: u32 = 2;
/// The oldest version read.
pub const SUMMARY_OLDEST_VERSION: u32 = 1;
/// The result format a job's id hashes (`floorcast_coordinator::grid::job_id`): still 1, as
/// the only change of version 2, the suite a building was planned from, is the coordinator's
/// label on a result, not part of it, so stores written before stay resumable. A new version
/// that changes what a result holds must change this too.
pub const JOB_ID_RESULT_FORMAT: u32 = 1;

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RunSummary {
    pub format: String,
    pub version: u32,
    pub floorcast_version: String,
    pub building: String,
    pub building_hash: String,
    /// The suite the building was planned from (a grid's `suites`), set by the coordinator from
    /// its plan; absent for a building of the grid's `buildings` or `[[generated]]`, in
    /// `explore`'s summaries and in version 1 records.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub suite: Option<String>,
    /// That suite's hash (`floorcast suite list`): two results of one suite name and hash ran
    /// the same buildings.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub suite_hash: Option<String>,
    /// The built-in strategy's name, or the external strategy's label.
    pub strategy: String,
    /// An external strategy's program: its command, the hash of its files, its reply timeout
    /// (absent for built-in strategies).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub strategy_program: Option<crate::StrategyProgram>,
    /// The name an external strategy gave itself.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub strategy_name: Option<String>,
    /// Wall seconds an external strategy took to answer, summed over its replies (charged to
    /// simulated time with `charge_compute`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub strategy_compute_s: Option<f64>,
    /// Decision messages an external strategy answered.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub strategy_replies: Option<u64>,
    pub seed: u64,
    /// Every setting, written whole ([`Settings::to_table`]): given back as a settings file
    /// they run the same run (earlier records leave out those at 0 or off, and are read with
    /// them at 0 or off).
    #[serde(serialize_with = "settings_whole")]
    pub settings: Settings,
    /// Start pose `[x_m, y_m, theta_rad]` and where it came from.
    pub start: [f64; 3],
    pub start_source: String,
    /// Simulated seconds until exploration ended (before any return home).
    pub exploration_time_s: f64,
    /// Simulated seconds until the run ended.
    pub total_time_s: f64,
    pub explored_area_m2: f64,
    /// The explorable free area (m2): free space connected to the start that the laser can see
    /// from where the robot's body fits; the explored fraction's denominator. Before 0.4 it
    /// was all free space connected to the start.
    pub free_area_m2: f64,
    /// Free area connected to the start that is not explorable (m2): behind openings narrower
    /// than the robot and out of the laser's sight (absent before 0.4).
    #[serde(default)]
    pub unexplorable_free_m2: f64,
    pub explored_fraction: f64,
    pub path_length_m: f64,
    pub decisions: usize,
    /// Ended by the strategy's early-stopping rule (`explored_fraction` is then the fraction at
    /// the stop).
    pub stopped_early: bool,
    /// Explorable free area the map had not observed at the end (m2).
    pub unexplored_free_m2: f64,
    /// Ground-truth rooms the robot never entered (`null` without ground truth).
    pub rooms_never_entered: Option<usize>,
    /// Ground-truth rooms of which less than half the reachable free area was explored (`null`
    /// without ground truth, and in summaries written before the field existed): the rooms an
    /// early stop left out. A room seen from its door is explored, though never entered.
    #[serde(default)]
    pub rooms_unexplored: Option<usize>,
    /// Layouts reconstructed during the run (layout strategies).
    pub layouts_computed: u64,
    /// Layout compute time added to simulated time (s; 0 unless `settings.charge_compute`).
    #[serde(default)]
    pub layout_compute_s: f64,
    /// Whether compute time was charged (then the times depend on the machine).
    #[serde(default)]
    pub charge_compute: bool,
    /// Why the run ended: "complete" (no frontier left that the robot had not looked into),
    /// "early stop", "time limit", "stuck" (frontiers left that a path leads to, every goal
    /// toward them given up) or "frontiers unreachable". Summaries before 0.4 say "no
    /// frontiers" for the last three of these alike, read as "complete" (what reports always
    /// counted them as).
    #[serde(with = "end_reason_name")]
    pub end_reason: EndReason,
    /// Frontier cells left on the map at the end that the robot had not looked into (0 when
    /// complete, early stop or time limit; absent before 0.4).
    #[serde(default)]
    pub frontier_cells_left: usize,
    pub blacklisted_goals: usize,
    pub scans: u64,
    pub scan_matches_accepted: u64,
    /// Fraction of map-free cells that are free in the building.
    pub map_free_precision: f64,
    /// Fraction of map-occupied cells within one cell of a true wall (doubled walls lower it).
    pub map_occupied_precision: f64,
    /// The same after the best small rotation (about the start) and translation of the whole
    /// map: separates a map turned as a whole from doubled or bent walls.
    #[serde(default)]
    pub map_occupied_precision_aligned: f64,
    /// Wall-clock seconds the run took (the only field that differs between identical runs).
    pub wall_time_s: f64,
    /// Simulated seconds per wall second.
    pub speedup: f64,
    /// A team's figures (`settings.robots` > 1; absent for one robot). The fields above are
    /// then the team's: its exploration ends when the last robot's does, its explored area is
    /// the shared map's, its path length the robots' summed, its decisions every robot's.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub team: Option<TeamSummary>,
}

/// A team's figures in a run's summary.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TeamSummary {
    /// Robots in the team.
    pub robots: usize,
    /// How they map: "shared" (one map, relative starts known).
    pub map: String,
    /// How they communicate: "full" (every map update, pose and goal reaches every robot at
    /// once).
    pub communication: String,
    /// Simulated seconds until the team's map held 99 % of the explorable area (`null`: never).
    pub time_to_99_s: Option<f64>,
    /// Map area the laser of more than one robot swept (m2, on a 0.2 m grid), of the area any
    /// swept, and their ratio.
    pub overlap_m2: f64,
    pub seen_m2: f64,
    pub overlap_fraction: f64,
    /// Map updates passed on to teammates (one per update and teammate).
    pub exchanges: u64,
    /// The closest two robots' centres came (m; two radii when their bodies touched).
    pub min_separation_m: f64,
    /// Idle time summed over the robots (s): see `per_robot`.
    pub idle_s: f64,
    /// Each robot's figures, by robot number.
    pub per_robot: Vec<RobotSummary>,
}

/// One robot's figures in a team's summary.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RobotSummary {
    pub robot: usize,
    /// Start pose `[x_m, y_m, theta_rad]`.
    pub start: [f64; 3],
    pub path_length_m: f64,
    /// Map area its laser swept (m2, on a 0.2 m grid).
    pub seen_m2: f64,
    /// When its own exploration ended (s), and why.
    pub exploration_time_s: f64,
    #[serde(with = "end_reason_name")]
    pub end_reason: EndReason,
    /// Time it did not explore while the team did (s): from the end of its own exploration to
    /// the team's, and standing still for charged compute.
    pub idle_s: f64,
    pub decisions: usize,
}

impl TeamSummary {
    /// The summary of a team's result.
    pub fn new(t: &sim_core::explore::TeamResult) -> Self {
        Self {
            robots: t.robots.len(),
            map: "shared".into(),
            communication: "full".into(),
            time_to_99_s: t.time_to_fraction_s(0.99),
            overlap_m2: t.overlap_m2,
            seen_m2: t.seen_m2,
            overlap_fraction: t.overlap_fraction(),
            exchanges: t.exchanges,
            min_separation_m: t.min_separation_m,
            idle_s: t.figures.iter().map(|f| f.idle_s).sum(),
            per_robot: t
                .robots
                .iter()
                .zip(&t.figures)
                .enumerate()
                .map(|(k, (r, f))| RobotSummary {
                    robot: k,
                    start: [r.start.x_m, r.start.y_m, r.start.theta_rad],
                    path_length_m: f.path_length_m,
                    seen_m2: f.seen_m2,
                    exploration_time_s: f.exploration_time_s,
                    end_reason: f.end_reason,
                    idle_s: f.idle_s,
                    decisions: f.decisions,
                })
                .collect(),
        }
    }
}

impl RunSummary {
    pub fn new(job: &Job<'_>, r: &RunResult, start_source: &str, wall_time_s: f64) -> Self {
        Self {
            format: SUMMARY_FORMAT.to_string(),
            version: SUMMARY_VERSION,
            floorcast_version: FLOORCAST_VERSION.to_string(),
            building: job.building_name.clone(),
            building_hash: job.building.content_hash(),
            suite: None,
            suite_hash: None,
            strategy: job.strategy.name().to_string(),
            strategy_program: job.strategy.program().cloned(),
            strategy_name: None,
            strategy_compute_s: None,
            strategy_replies: None,
            seed: job.seed,
            settings: job.settings.clone(),
            start: [r.start.x_m, r.start.y_m, r.start.theta_rad],
            start_source: start_source.to_string(),
            exploration_time_s: r.exploration_time_s,
            total_time_s: r.total_time_s,
            explored_area_m2: r.explored_area_m2,
            free_area_m2: r.free_area_m2,
            unexplorable_free_m2: r.unexplorable_free_m2,
            explored_fraction: r.explored_fraction,
            path_length_m: r.path_length_m,
            decisions: r.decisions.len(),
            stopped_early: r.stopped_early,
            unexplored_free_m2: (r.free_area_m2 - r.explored_area_m2).max(0.0),
            rooms_never_entered: r.rooms_never_entered,
            rooms_unexplored: r.rooms_unexplored,
            layouts_computed: r.layouts_computed,
            layout_compute_s: r.layout_compute_s,
            charge_compute: job.settings.charge_compute,
            end_reason: r.end_reason,
            frontier_cells_left: r.frontier_cells_left,
            blacklisted_goals: r.blacklisted_goals,
            scans: r.scans,
            scan_matches_accepted: r.scan_matches_accepted,
            map_free_precision: r.map_quality.free_precision,
            map_occupied_precision: r.map_quality.occupied_precision,
            map_occupied_precision_aligned: r.map_quality.occupied_precision_aligned,
            wall_time_s,
            speedup: if wall_time_s > 0.0 {
                r.total_time_s / wall_time_s
            } else {
                0.0
            },
            team: None,
        }
    }

    /// Parses and checks format and version.
    pub fn from_json(text: &str) -> Result<Self, String> {
        let v: serde_json::Value =
            serde_json::from_str(text).map_err(|e| format!("not JSON ({e})"))?;
        let format = v.get("format").and_then(|f| f.as_str()).unwrap_or("");
        let version = v.get("version").and_then(|f| f.as_u64()).unwrap_or(0);
        if format != SUMMARY_FORMAT
            || !(SUMMARY_OLDEST_VERSION as u64..=SUMMARY_VERSION as u64).contains(&version)
        {
            return Err(format!(
                "not a {SUMMARY_FORMAT} version {SUMMARY_OLDEST_VERSION} to {SUMMARY_VERSION} record (format '{format}', version {version})"
            ));
        }
        if version < 2 {
            for field in ["suite", "suite_hash"] {
                if v.get(field).is_some() {
                    return Err(format!(
                        "field {field} is new in version 2, and this record is version {version}"
                    ));
                }
            }
        }
        let s: RunSummary = serde_json::from_value(v).map_err(|e| e.to_string())?;
        s.check()?;
        Ok(s)
    }

    /// Checks what a reader relies on beyond the types: every time, area, length and rate
    /// finite and not negative, every fraction and precision in [0, 1], the exploration time
    /// within the run's (an end reason unknown to this build is shown as it is). The error
    /// names the field and the value.
    pub fn check(&self) -> Result<(), String> {
        let bad = |field: &str, v: f64, want: &str| {
            Err(format!(
                "field {field} is {}, expected {want}",
                crate::settings::fmt_num(v)
            ))
        };
        let mut non_negative = vec![
            ("exploration_time_s", self.exploration_time_s),
            ("total_time_s", self.total_time_s),
            ("explored_area_m2", self.explored_area_m2),
            ("free_area_m2", self.free_area_m2),
            ("unexplorable_free_m2", self.unexplorable_free_m2),
            ("unexplored_free_m2", self.unexplored_free_m2),
            ("path_length_m", self.path_length_m),
            ("layout_compute_s", self.layout_compute_s),
            ("wall_time_s", self.wall_time_s),
            ("speedup", self.speedup),
        ];
        if let Some(v) = self.strategy_compute_s {
            non_negative.push(("strategy_compute_s", v));
        }
        for (field, v) in non_negative {
            if !(v.is_finite() && v >= 0.0) {
                return bad(field, v, "a finite number, 0 or more");
            }
        }
        for (field, v) in [
            ("explored_fraction", self.explored_fraction),
            ("map_free_precision", self.map_free_precision),
            ("map_occupied_precision", self.map_occupied_precision),
            (
                "map_occupied_precision_aligned",
                self.map_occupied_precision_aligned,
            ),
        ] {
            if !(0.0..=1.0).contains(&v) {
                return bad(field, v, "a fraction in [0, 1]");
            }
        }
        if self.exploration_time_s > self.total_time_s {
            return bad(
                "exploration_time_s",
                self.exploration_time_s,
                "at most total_time_s",
            );
        }
        match (&self.suite, &self.suite_hash) {
            (None, None) => {}
            (Some(name), Some(hash)) => {
                if name.is_empty() || name.len() > 64 || name.chars().any(char::is_control) {
                    return Err("field suite is not a suite's name".into());
                }
                if hash.len() != 32 || !hash.chars().all(|c| c.is_ascii_hexdigit()) {
                    return Err("field suite_hash is not 32 hex digits".into());
                }
            }
            _ => return Err("fields suite and suite_hash go together: both or neither".into()),
        }
        for (i, v) in self.start.iter().enumerate() {
            if !v.is_finite() {
                return bad(&format!("start[{i}]"), *v, "a finite number");
            }
        }
        Ok(())
    }
}

/// A summary's `end_reason` as its name ([`EndReason::as_str`]); the "no frontiers" of summaries
/// before 0.4 reads as complete.
pub(crate) mod end_reason_name {
    use serde::{Deserialize, Deserializer, Serializer};
    use sim_core::explore::EndReason;

    pub(crate) fn serialize<S: Serializer>(r: &EndReason, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(r.as_str())
    }

    pub(crate) fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<EndReason, D::Error> {
        let name = String::deserialize(d)?;
        match name.as_str() {
            "no frontiers" => Ok(EndReason::Complete),
            other => EndReason::from_name(other).ok_or_else(|| {
                serde::de::Error::custom(format!(
                    "end_reason '{}' is not one of complete, early stop, time limit, stuck, frontiers unreachable",
                    crate::text::excerpt(other)
                ))
            }),
        }
    }
}

/// Writes a record's settings whole (see [`RunSummary::settings`]).
fn settings_whole<S: serde::Serializer>(settings: &Settings, out: S) -> Result<S::Ok, S::Error> {
    settings.to_table().serialize(out)
}

#[cfg(test)]
mod tests {
    use super::end_reason_name;
    use sim_core::explore::EndReason;

    #[derive(serde::Serialize, serde::Deserialize)]
    struct R(#[serde(with = "end_reason_name")] EndReason);

    /// Every class is written by its name and read back; the "no frontiers" of old summaries
    /// reads as complete; any other word is refused, naming it.
    #[test]
    fn end_reasons_are_written_by_name_and_read_back() {
        for r in EndReason::ALL {
            let text = serde_json::to_string(&R(r)).unwrap();
            assert_eq!(text, format!("\"{}\"", r.as_str()));
            assert_eq!(serde_json::from_str::<R>(&text).unwrap().0, r);
        }
        let old: R = serde_json::from_str("\"no frontiers\"").unwrap();
        assert_eq!(old.0, EndReason::Complete);
        let e = serde_json::from_str::<R>("\"finished\"").err().unwrap();
        assert!(e.to_string().contains("end_reason 'finished'"), "{e}");
    }
}
