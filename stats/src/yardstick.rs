//! The known-map yardstick of a grid: the tours its runs are measured against, and each run's
//! **efficiency** = yardstick time / exploration time (docs/known-map-tour.md).
//!
//! A grid's runs need one tour per building, start pose and [`TourKey`] (six settings and the
//! grid's coverage level): the coordinator lists them (`floorcast_coordinator::tours`), `run`
//! makes those its store lacks and stores them. A run's tour is the stored one of its
//! building hash, its summary's start (bit for bit) and its settings' key at the report's
//! coverage level. A run that did not reach that level (or failed) has efficiency 0: it never
//! saw what the tour sees, as its time to it is infinite in every comparison
//! ([`crate::outcome`]).
//!
//! **The yardstick is never slower than a run** ([`yardsticks`]): an explorer's own path is a
//! tour of the known building (a robot that knew the building could drive it), so the yardstick
//! of a building, start and key is the fastest of the computed tour and every stored run there
//! that reached the coverage level (its time to that level, from its progress curve, or its
//! exploration time if sooner). Every efficiency is then at most 1, and a run whose yardstick is
//! a run says which (`yardstick` in `report --json`). Beside it the tour's lower bound
//! ([`sim_core::tour::lower_bound`], stored with tours of record version 4): no tour of that
//! building can be faster, so yardstick / bound brackets how far the yardstick may be from the
//! best possible.

use std::collections::BTreeMap;

use floorcast_worker::tour::{TourKey, TourRecord};

use crate::metric::time_to_fraction;
use crate::outcome::{achieves, coverage_text};
use crate::stats::interquartile_mean;
use crate::StoredResult;

/// The yardstick of a building, start and key: the fastest known-map tour there.
#[derive(Debug, Clone, PartialEq)]
pub struct Yardstick {
    pub time_s: f64,
    /// `None`: the computed tour; else the job id of the stored run that was faster.
    pub run: Option<String>,
    /// The computed tour's time.
    pub tour_s: f64,
    /// No tour can be faster (`None` for tours stored before bounds were).
    pub lower_bound_s: Option<f64>,
}

/// What a yardstick is kept under: building hash, start bits, key.
type Place = (String, [u64; 3], String);

fn place(hash: &str, start: &[f64; 3], key: &TourKey) -> Place {
    (
        hash.to_string(),
        [start[0].to_bits(), start[1].to_bits(), start[2].to_bits()],
        key.text(),
    )
}

/// The yardsticks of `results` at `coverage`: per building, start and key with a stored tour,
/// the fastest of the tour and the successful runs there that reached `coverage` (each at its
/// time to `coverage`, or its exploration time if sooner; equal times: the tour, then the run
/// stored first).
pub fn yardsticks(
    results: &[StoredResult],
    tours: &[TourRecord],
    coverage: f64,
) -> BTreeMap<Place, Yardstick> {
    let mut out: BTreeMap<Place, Yardstick> = BTreeMap::new();
    for t in tours {
        let at = place(&t.building_hash, &t.start, &t.key);
        let candidate = Yardstick {
            time_s: t.time_s,
            run: None,
            tour_s: t.time_s,
            lower_bound_s: t.lower_bound_s,
        };
        // Tours of an older method never match a run's key; of equal keys the first is used.
        out.entry(at).or_insert(candidate);
    }
    for r in results.iter().filter(|r| r.status.is_ok()) {
        let Some(s) = r.summary.as_ref().filter(|s| achieves(s, coverage)) else {
            continue;
        };
        let key = TourKey::of(&r.settings, coverage);
        let Some(y) = out.get_mut(&place(&r.building_hash, &s.start, &key)) else {
            continue;
        };
        let reached = r
            .progress
            .as_deref()
            .and_then(|p| time_to_fraction(p, coverage))
            .filter(|t| t.is_finite() && *t > 0.0)
            .map_or(s.exploration_time_s, |t| t.min(s.exploration_time_s));
        if reached < y.time_s {
            y.time_s = reached;
            y.run = Some(r.job_id.clone());
        }
    }
    out
}

/// The yardstick of a stored run at `coverage` among `yardsticks`, if it has one.
fn yardstick_of<'a>(
    r: &StoredResult,
    yardsticks: &'a BTreeMap<Place, Yardstick>,
    coverage: f64,
) -> Option<(&'a Yardstick, f64)> {
    let s = r.summary.as_ref().filter(|_| r.status.is_ok())?;
    let key = TourKey::of(&r.settings, coverage);
    let y = yardsticks.get(&place(&r.building_hash, &s.start, &key))?;
    Some((
        y,
        if achieves(s, coverage) {
            y.time_s / s.exploration_time_s
        } else {
            0.0
        },
    ))
}

/// The efficiency of a stored run at `coverage` (at most 1: see [`yardsticks`]): `None` without
/// a successful summary or a stored tour for it; 0 when it did not reach `coverage`.
pub fn efficiency(
    r: &StoredResult,
    results: &[StoredResult],
    tours: &[TourRecord],
    coverage: f64,
) -> Option<f64> {
    yardstick_of(r, &yardsticks(results, tours, coverage), coverage).map(|(_, e)| e)
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
    /// Runs whose yardstick is a stored run faster than the computed tour.
    pub yardstick_runs: usize,
    /// Median of yardstick / lower bound over the runs whose tour has a bound (`None`
    /// without): how far the yardstick may be from the best possible tour, at most.
    pub median_gap: Option<f64>,
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
    /// The yardstick's time (s): the computed tour's, or a faster stored run's.
    pub yardstick_s: f64,
    /// `"tour"`, or the job id of the stored run that is the yardstick.
    pub yardstick: String,
    pub tour_s: f64,
    /// No tour can be faster (s; `null` for tours stored before bounds were).
    pub lower_bound_s: Option<f64>,
}

/// A label's efficiencies as gathered: all, the successful runs without a tour, per suite, the
/// runs measured against a run, and the yardsticks' gaps to their bounds.
type Gathered = (Vec<f64>, usize, BTreeMap<String, Vec<f64>>, usize, Vec<f64>);

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
    let yardsticks = yardsticks(results, tours, coverage);
    for r in results.iter().filter(|r| r.status.is_ok()) {
        let entry = per_label.entry(r.label.as_str()).or_default();
        let Some((y, e)) = yardstick_of(r, &yardsticks, coverage) else {
            entry.1 += 1;
            continue;
        };
        entry.0.push(e);
        entry.3 += usize::from(y.run.is_some());
        if let Some(b) = y.lower_bound_s.filter(|b| *b > 0.0) {
            entry.4.push(y.time_s / b);
        }
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
            yardstick_s: y.time_s,
            yardstick: y.run.clone().unwrap_or_else(|| "tour".into()),
            tour_s: y.tour_s,
            lower_bound_s: y.lower_bound_s,
        });
    }
    let labels = order
        .iter()
        .filter_map(|label| {
            let (xs, without_tour, suites, yardstick_runs, gaps) = per_label.get(label.as_str())?;
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
                yardstick_runs: *yardstick_runs,
                median_gap: (!gaps.is_empty()).then(|| quantile(gaps, 0.5)),
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

/// Why a run has no tour, as the report says it.
const WHY_NO_TOUR: &str = "`run` makes the missing tours when the grid runs again, except those it skipped, saying why: made with --no-tours, a robot that fits nowhere, or a tour whose estimate exceeded `run --tour-budget`";

/// The report's efficiency section of the results (`successful` of them successful runs with a
/// summary): when no run has a tour, one line saying why there is no efficiency (nothing
/// without a successful run).
pub fn render(labels: &[LabelEfficiency], successful: usize, coverage: f64) -> String {
    use std::fmt::Write;
    if labels.is_empty() {
        let ok = successful;
        if ok == 0 {
            return String::new();
        }
        return format!(
            "\nno efficiency: {ok} successful runs have no stored tour ({WHY_NO_TOUR})\n"
        );
    }
    let cov = coverage_text(coverage);
    let mut out = format!(
        "\nefficiency at {cov}: yardstick time / exploration time (the yardstick: the fastest known-map tour of the building, start and robot, the computed tour or a stored run that reached {cov} there; 1: as fast as that; a run below {cov} counts 0)\n"
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
    let from_runs: usize = labels.iter().map(|l| l.yardstick_runs).sum();
    let measured: usize = labels.iter().map(|l| l.runs).sum();
    if from_runs > 0 {
        let _ = writeln!(
            out,
            "{from_runs} of {measured} runs are measured against a stored run faster than the computed tour (`report --json`: efficiency.runs[].yardstick)"
        );
    }
    let gaps: Vec<String> = labels
        .iter()
        .filter_map(|l| Some(format!("{} {:.2}", l.label, l.median_gap?)))
        .collect();
    if gaps.is_empty() {
        let _ = writeln!(
            out,
            "no stored tour has a lower bound (tours of record version 3 or older; `floorcast tour` gives one): the yardstick's gap to the best possible is not known"
        );
    } else {
        let _ = writeln!(
            out,
            "yardstick / lower bound (no tour is faster than the bound; median per label): {}",
            gaps.join(", ")
        );
    }
    let without: usize = labels.iter().map(|l| l.without_tour).sum();
    if without > 0 {
        let _ = writeln!(
            out,
            "{without} successful runs have no stored tour, so no efficiency ({WHY_NO_TOUR})"
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
