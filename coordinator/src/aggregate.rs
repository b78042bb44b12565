//! Aggregates across buildings, as Agarwal, Schwarzer, Castro, Courville and Bellemare recommend
//! for comparing methods over many tasks ("Deep reinforcement learning at the edge of the
//! statistical precipice", NeurIPS 2021; their library `rliable`), with buildings as tasks and
//! exploration time (lower is better) as the score:
//!
//! - each run's **normalized time**: its charged time (its exploration time if it achieved the
//!   outcome at the coverage level, else its horizon, [`crate::outcome`]) over the reference's
//!   median charged time on that building;
//! - the **interquartile mean** (IQM) of a label's normalized times over all its runs, with a
//!   stratified bootstrap interval (runs resampled within each building);
//! - the **probability of improvement**: per building the probability that a run of the label
//!   is faster than a run of the reference (Mann-Whitney, ties half, a run that did not achieve
//!   the outcome slower than any that did), averaged over buildings, with its stratified
//!   bootstrap interval;
//! - the **performance profile**: the fraction of a label's runs whose normalized time is at
//!   most `tau`, for `tau` from 1/2 to 2 (a run that did not achieve the outcome never counts),
//!   with a stratified bootstrap band.
//!
//! Pure functions of stored results; the bootstrap is seeded ([`crate::stats::BOOTSTRAP_SEED`]).

use std::collections::BTreeMap;

use crate::outcome::{outcome_of, RunOutcome};
use crate::stats::{interquartile_mean, probability_lower, stratified_bootstrap_ci95};
use crate::store::StoredResult;

/// Points of a performance profile: `tau = 2^(k / 20 - 1)` for `k = 0..=40` (1/2 to 2).
pub const PROFILE_POINTS: usize = 41;

/// The thresholds of a performance profile.
pub fn profile_taus() -> Vec<f64> {
    (0..PROFILE_POINTS)
        .map(|k| 2f64.powf(k as f64 / 20.0 - 1.0))
        .collect()
}

/// One point of a performance profile.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct ProfilePoint {
    pub tau: f64,
    /// Fraction of the label's runs with a normalized time at most `tau`.
    pub fraction: f64,
    /// The stratified bootstrap 95 % band of `fraction`.
    pub lo: f64,
    pub hi: f64,
}

/// A label's aggregates across buildings.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct LabelAggregate {
    pub label: String,
    /// Runs counted (on buildings where the reference ran) and buildings.
    pub runs: usize,
    pub buildings: usize,
    /// Share of those runs that achieved the outcome.
    pub achieved_fraction: f64,
    /// Interquartile mean of normalized times (1: the reference's median; lower is faster).
    pub iqm_normalized_time: Option<f64>,
    pub iqm_ci95: Option<[f64; 2]>,
    /// Probability that a run of this label is faster than one of the reference, averaged over
    /// buildings (0.5: no difference); `None` for the reference itself.
    pub probability_of_improvement: Option<f64>,
    pub probability_of_improvement_ci95: Option<[f64; 2]>,
    pub profile: Vec<ProfilePoint>,
}

/// The aggregates of every label.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Aggregates {
    pub reference: String,
    pub coverage: f64,
    /// Per building: the reference's median charged time (s), the normalizer.
    pub reference_median_s: BTreeMap<String, f64>,
    pub labels: Vec<LabelAggregate>,
}

/// The charged time of a run alone: its exploration time if it achieved, else its horizon.
fn charged(r: &RunOutcome) -> f64 {
    r.achieved_s.unwrap_or(r.horizon_s)
}

fn median(xs: &[f64]) -> Option<f64> {
    if xs.is_empty() {
        return None;
    }
    let mut v = xs.to_vec();
    v.sort_by(f64::total_cmp);
    let n = v.len();
    Some(if n % 2 == 1 {
        v[n / 2]
    } else {
        (v[n / 2 - 1] + v[n / 2]) / 2.0
    })
}

/// The aggregates of every label in `order` (then as they appear) against `reference` at
/// `coverage`.
pub fn aggregates(
    results: &[StoredResult],
    order: &[String],
    reference: &str,
    coverage: f64,
) -> Aggregates {
    // Per building and label: the runs' outcomes.
    let mut by: ByBuilding = BTreeMap::new();
    for r in results {
        by.entry(&r.building)
            .or_default()
            .entry(&r.label)
            .or_default()
            .push(outcome_of(r, coverage, &r.building));
    }
    let reference_median_s: BTreeMap<String, f64> = by
        .iter()
        .filter_map(|(b, labels)| {
            let times: Vec<f64> = labels.get(reference)?.iter().map(charged).collect();
            Some((b.to_string(), median(&times).filter(|m| *m > 0.0)?))
        })
        .collect();
    let taus = profile_taus();
    let labels = crate::outcome::label_order(results, order)
        .into_iter()
        .map(|label| label_aggregate(label, &by, &reference_median_s, reference, &taus))
        .filter(|a| a.runs > 0)
        .collect();
    Aggregates {
        reference: reference.to_string(),
        coverage,
        reference_median_s,
        labels,
    }
}

/// The values of every stratum together.
fn pooled(s: &[[Vec<f64>; 1]]) -> Vec<f64> {
    s.iter().flat_map(|[v]| v.iter().copied()).collect()
}

/// Runs' outcomes per building and label.
type ByBuilding<'a> = BTreeMap<&'a str, BTreeMap<&'a str, Vec<RunOutcome>>>;

/// One label's aggregates over the buildings where the reference has a median time.
fn label_aggregate(
    label: String,
    by: &ByBuilding,
    reference_median_s: &BTreeMap<String, f64>,
    reference: &str,
    taus: &[f64],
) -> LabelAggregate {
    // Per building (with a normalizer): normalized charged times, normalized times for
    // the profile (infinite when not achieved), and the two sides' times for the
    // probability of improvement (infinite when not achieved).
    let mut iqm_strata: Vec<[Vec<f64>; 1]> = Vec::new();
    let mut profile_strata: Vec<[Vec<f64>; 1]> = Vec::new();
    let mut poi_strata: Vec<[Vec<f64>; 2]> = Vec::new();
    let (mut runs, mut achieved) = (0, 0);
    for (b, m) in reference_median_s {
        let Some(mine) = by.get(b.as_str()).and_then(|l| l.get(label.as_str())) else {
            continue;
        };
        runs += mine.len();
        achieved += mine.iter().filter(|r| r.achieved_s.is_some()).count();
        iqm_strata.push([mine.iter().map(|r| charged(r) / m).collect()]);
        profile_strata.push([mine
            .iter()
            .map(|r| r.achieved_s.map_or(f64::INFINITY, |t| t / m))
            .collect()]);
        let speed = |rs: &[RunOutcome]| -> Vec<f64> {
            rs.iter()
                .map(|r| r.achieved_s.unwrap_or(f64::INFINITY))
                .collect()
        };
        poi_strata.push([speed(mine), speed(&by[b.as_str()][reference])]);
    }
    let iqm = |s: &[[Vec<f64>; 1]]| interquartile_mean(&pooled(s));
    let poi = |s: &[[Vec<f64>; 2]]| {
        let ps: Vec<f64> = s
            .iter()
            .filter_map(|[x, y]| probability_lower(x, y))
            .collect();
        (!ps.is_empty()).then(|| ps.iter().sum::<f64>() / ps.len() as f64)
    };
    let is_reference = label == reference;
    let profile = profile(taus, &profile_strata);
    LabelAggregate {
        runs,
        buildings: iqm_strata.len(),
        achieved_fraction: if runs > 0 {
            achieved as f64 / runs as f64
        } else {
            f64::NAN
        },
        iqm_normalized_time: iqm(&iqm_strata),
        iqm_ci95: stratified_bootstrap_ci95(&iqm_strata, iqm).map(|(a, b)| [a, b]),
        probability_of_improvement: (!is_reference).then(|| poi(&poi_strata)).flatten(),
        probability_of_improvement_ci95: (!is_reference)
            .then(|| stratified_bootstrap_ci95(&poi_strata, poi))
            .flatten()
            .map(|(a, b)| [a, b]),
        profile,
        label,
    }
}

/// The performance profile: per `tau`, the fraction of runs within `tau` times the reference's
/// median, with its stratified bootstrap interval.
fn profile(taus: &[f64], profile_strata: &[[Vec<f64>; 1]]) -> Vec<ProfilePoint> {
    taus.iter()
        .map(|&tau| {
            let frac = |s: &[[Vec<f64>; 1]]| {
                let v = pooled(s);
                (!v.is_empty())
                    .then(|| v.iter().filter(|x| **x <= tau).count() as f64 / v.len() as f64)
            };
            let fraction = frac(profile_strata).unwrap_or(f64::NAN);
            let (lo, hi) =
                stratified_bootstrap_ci95(profile_strata, frac).unwrap_or((fraction, fraction));
            ProfilePoint {
                tau,
                fraction,
                lo,
                hi,
            }
        })
        .filter(|p| p.fraction.is_finite())
        .collect()
}

/// The aggregates in `report --json` (`aggregates`).
pub fn aggregates_json(a: &Aggregates) -> serde_json::Value {
    let mut v = serde_json::to_value(a).unwrap_or_default();
    // NaN (no runs) is not JSON: null.
    if let Some(labels) = v.get_mut("labels").and_then(|l| l.as_array_mut()) {
        for (l, agg) in labels.iter_mut().zip(&a.labels) {
            if !agg.achieved_fraction.is_finite() {
                l["achieved_fraction"] = serde_json::Value::Null;
            }
        }
    }
    v
}

/// The aggregates as text: one line per label.
pub fn render(a: &Aggregates) -> String {
    use std::fmt::Write as _;
    let mut out = String::new();
    if a.labels.is_empty() {
        return out;
    }
    let _ = writeln!(
        out,
        "Across {} buildings (Agarwal et al. 2021; times normalized by {}'s median per building, a run below {} charged the time limit; IQM of normalized times, probability of being faster than a run of the reference, share of runs at most the reference's median; stratified bootstrap 95 % intervals):",
        a.reference_median_s.len(),
        a.reference,
        crate::outcome::coverage_text(a.coverage)
    );
    let range =
        |r: Option<[f64; 2]>| r.map_or("-".to_string(), |[x, y]| format!("[{x:.3}, {y:.3}]"));
    let num = |v: Option<f64>| v.map_or("-".to_string(), |v| format!("{v:.3}"));
    for l in &a.labels {
        let at_one = l
            .profile
            .iter()
            .find(|p| (p.tau - 1.0).abs() < 1e-12)
            .map_or("-".to_string(), |p| format!("{:.2}", p.fraction));
        let poi = if l.label == a.reference {
            format!("{:<24}", "ref")
        } else {
            format!(
                "{} {:<18}",
                num(l.probability_of_improvement),
                range(l.probability_of_improvement_ci95)
            )
        };
        let _ = writeln!(
            out,
            "  {:<16} IQM {} {:<16} P(faster) {poi} at most the median {at_one}; {} runs, {:.0} % reached {}",
            l.label,
            num(l.iqm_normalized_time),
            range(l.iqm_ci95),
            l.runs,
            l.achieved_fraction * 100.0,
            crate::outcome::coverage_text(a.coverage)
        );
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn profile_thresholds_run_from_a_half_to_two_through_one() {
        let t = profile_taus();
        assert_eq!(t.len(), PROFILE_POINTS);
        assert!((t[0] - 0.5).abs() < 1e-12 && (t[40] - 2.0).abs() < 1e-12);
        assert!((t[20] - 1.0).abs() < 1e-12);
    }

    #[test]
    fn medians_of_odd_and_even_counts() {
        assert_eq!(median(&[3.0, 1.0, 2.0]), Some(2.0));
        assert_eq!(median(&[4.0, 1.0, 2.0, 3.0]), Some(2.5));
        assert_eq!(median(&[]), None);
    }
}
