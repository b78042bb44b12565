//! The known-map yardstick of a grid: the tours its runs are measured against, and each run's
//! **efficiency** = tour time / exploration time (docs/known-map-tour.md).
//!
//! A grid's runs need one tour per building, start pose and [`TourKey`] (six settings and the
//! grid's coverage level): [`planned_tours`] lists them, `run` makes those its store lacks and
//! stores them ([`crate::store::Store::record_tour`]). A run's tour is the stored one of its
//! building hash, its summary's start (bit for bit) and its settings' key at the report's
//! coverage level. A run that did not reach that level (or failed) has efficiency 0: it never
//! saw what the tour sees, as its time to it is infinite in every comparison
//! ([`crate::outcome`]).

use std::collections::BTreeMap;

use floorcast_worker::tour::{TourKey, TourRecord};
use floorcast_worker::Settings;
use sim_core::Pose;

use crate::grid::{Plan, PlannedJob};
use crate::outcome::{achieves, coverage_text};
use crate::stats::interquartile_mean;
use crate::store::StoredResult;

/// A tour a grid's runs need: its building (an index into [`Plan::buildings`]), start and the
/// settings its key is made of.
#[derive(Debug, Clone)]
pub struct PlannedTour {
    pub building: usize,
    pub start: Pose,
    pub settings: Settings,
    pub key: TourKey,
}

/// The tours `jobs` need, one per building, start and key, in the jobs' order; a job whose
/// start cannot be found (its building has none) needs none (the job fails and says why).
pub fn planned_tours(plan: &Plan, jobs: &[PlannedJob]) -> Vec<PlannedTour> {
    let mut seen = std::collections::BTreeSet::new();
    let mut out = Vec::new();
    for job in jobs {
        let building = &plan.buildings[job.building].building;
        let start = match &job.start {
            Some(g) => g.pose,
            None => match building.default_start(job.settings.robot_radius_m) {
                Ok((pose, _)) => pose,
                Err(_) => continue,
            },
        };
        let key = TourKey::of(&job.settings, plan.coverage);
        let id = (job.building, pose_bits(start), key.text());
        if seen.insert(id) {
            out.push(PlannedTour {
                building: job.building,
                start,
                settings: job.settings.clone(),
                key,
            });
        }
    }
    out
}

fn pose_bits(p: Pose) -> [u64; 3] {
    [p.x_m.to_bits(), p.y_m.to_bits(), p.theta_rad.to_bits()]
}

/// Of `planned`, those `stored` lacks.
pub fn missing<'a>(
    plan: &Plan,
    planned: &'a [PlannedTour],
    stored: &[TourRecord],
) -> Vec<&'a PlannedTour> {
    planned
        .iter()
        .filter(|t| {
            let hash = &plan.buildings[t.building].hash;
            let start = [t.start.x_m, t.start.y_m, t.start.theta_rad];
            !stored
                .iter()
                .any(|s| &s.building_hash == hash && s.starts_at(&start) && s.key == t.key)
        })
        .collect()
}

/// The efficiency of a stored run at `coverage`: `None` without a successful summary or a
/// stored tour for it; 0 when it did not reach `coverage`.
pub fn efficiency(r: &StoredResult, tours: &[TourRecord], coverage: f64) -> Option<f64> {
    let s = r.summary.as_ref().filter(|_| r.status.is_ok())?;
    let key = TourKey::of(&r.settings, coverage);
    let tour = tours
        .iter()
        .find(|t| t.building_hash == r.building_hash && t.starts_at(&s.start) && t.key == key)?;
    Some(if achieves(s, coverage) {
        tour.time_s / s.exploration_time_s
    } else {
        0.0
    })
}

/// A label's efficiencies: over all its runs with a tour, and per suite.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct LabelEfficiency {
    pub label: String,
    /// Runs with a tour, and of the label's successful runs those without one.
    pub runs: usize,
    pub without_tour: usize,
    pub median: f64,
    /// Interquartile mean (the aggregates' robust mean).
    pub iqm: f64,
    /// First and third quartiles.
    pub q1: f64,
    pub q3: f64,
    /// Runs that did not reach the coverage level (efficiency 0).
    pub not_achieved: usize,
    /// Per suite (runs of buildings planned from one): its name, runs and median.
    pub suites: Vec<SuiteEfficiency>,
}

#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct SuiteEfficiency {
    pub suite: String,
    pub runs: usize,
    pub median: f64,
}

/// One run's efficiency, for `report --json`.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct RunEfficiency {
    pub job_id: String,
    pub label: String,
    pub building: String,
    pub seed: u64,
    pub efficiency: f64,
}

/// A label's efficiencies as gathered: all, the successful runs without a tour, per suite.
type Gathered = (Vec<f64>, usize, BTreeMap<String, Vec<f64>>);

/// The efficiencies of `results` at `coverage`, per run and per label (labels in `order`,
/// those without a run with a tour left out).
pub fn efficiencies(
    results: &[StoredResult],
    tours: &[TourRecord],
    order: &[String],
    coverage: f64,
) -> (Vec<RunEfficiency>, Vec<LabelEfficiency>) {
    let mut runs = Vec::new();
    let mut per_label: BTreeMap<&str, Gathered> = BTreeMap::new();
    for r in results.iter().filter(|r| r.status.is_ok()) {
        let entry = per_label.entry(r.label.as_str()).or_default();
        let Some(e) = efficiency(r, tours, coverage) else {
            entry.1 += 1;
            continue;
        };
        entry.0.push(e);
        let suite = r.summary.as_ref().and_then(|s| s.suite.clone());
        entry
            .2
            .entry(suite.unwrap_or_else(|| "(no suite)".into()))
            .or_default()
            .push(e);
        runs.push(RunEfficiency {
            job_id: r.job_id.clone(),
            label: r.label.clone(),
            building: r.building.clone(),
            seed: r.seed,
            efficiency: e,
        });
    }
    let labels = order
        .iter()
        .filter_map(|label| {
            let (xs, without_tour, suites) = per_label.get(label.as_str())?;
            if xs.is_empty() {
                return None;
            }
            Some(LabelEfficiency {
                label: label.clone(),
                runs: xs.len(),
                without_tour: *without_tour,
                median: quantile(xs, 0.5),
                iqm: interquartile_mean(xs).unwrap_or(f64::NAN),
                q1: quantile(xs, 0.25),
                q3: quantile(xs, 0.75),
                not_achieved: xs.iter().filter(|e| **e == 0.0).count(),
                suites: suites
                    .iter()
                    .map(|(suite, xs)| SuiteEfficiency {
                        suite: suite.clone(),
                        runs: xs.len(),
                        median: quantile(xs, 0.5),
                    })
                    .collect(),
            })
        })
        .collect();
    (runs, labels)
}

/// The `p` quantile of `xs` (not empty), interpolated between order statistics.
fn quantile(xs: &[f64], p: f64) -> f64 {
    let mut v = xs.to_vec();
    v.sort_by(f64::total_cmp);
    let at = p * (v.len() - 1) as f64;
    let (lo, hi) = (at.floor() as usize, at.ceil() as usize);
    v[lo] + (v[hi] - v[lo]) * (at - lo as f64)
}

/// The report's efficiency section (empty when no run has a tour).
pub fn render(labels: &[LabelEfficiency], coverage: f64) -> String {
    use std::fmt::Write;
    if labels.is_empty() {
        return String::new();
    }
    let cov = coverage_text(coverage);
    let mut out = format!(
        "\nefficiency at {cov}: known-map tour time / exploration time (1: as fast as a robot that knew the building; a run below {cov} counts 0)\n"
    );
    let width = labels
        .iter()
        .map(|l| l.label.len())
        .max()
        .unwrap_or(5)
        .max(5);
    let _ = writeln!(
        out,
        "{:<width$}  {:>5}  {:>6}  {:>6}  {:>13}  {:>9}",
        "label", "runs", "median", "IQM", "quartiles", "below"
    );
    for l in labels {
        let _ = writeln!(
            out,
            "{:<width$}  {:>5}  {:>6.3}  {:>6.3}  {:>13}  {:>9}",
            l.label,
            l.runs,
            l.median,
            l.iqm,
            format!("{:.3}-{:.3}", l.q1, l.q3),
            l.not_achieved
        );
    }
    let suites: usize = labels.iter().map(|l| l.suites.len()).max().unwrap_or(0);
    if suites > 1 {
        let _ = writeln!(out, "median efficiency per suite:");
        for l in labels {
            let per: Vec<String> = l
                .suites
                .iter()
                .map(|s| format!("{} {:.3} ({} runs)", s.suite, s.median, s.runs))
                .collect();
            let _ = writeln!(out, "  {:<width$}  {}", l.label, per.join(", "));
        }
    }
    let without: usize = labels.iter().map(|l| l.without_tour).sum();
    if without > 0 {
        let _ = writeln!(
            out,
            "{without} successful runs have no stored tour (run the grid again to make them)"
        );
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quantiles_interpolate() {
        let xs = [4.0, 1.0, 3.0, 2.0];
        let cases = [(0.0, 1.0), (0.5, 2.5), (0.25, 1.75), (1.0, 4.0)];
        for (p, want) in cases {
            assert!((quantile(&xs, p) - want).abs() < 1e-12, "{p}");
        }
        assert_eq!(quantile(&[7.0], 0.75), 7.0);
    }
}
