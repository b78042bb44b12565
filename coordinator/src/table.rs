//! The grid's version of the paper's Table 1, computed from stored results: per strategy label
//! the mean and standard deviation of exploration time over all runs, and the gain over the
//! baseline in per cent with its spread (paired by building and seed: the mean of the per-pair
//! gains and a 95 % confidence interval); the same per building; and a CSV export.
//!
//! Only runs that ended by exploring what they could have an exploration time: complete (no
//! frontier left), the strategy's early stop, or stuck or with frontiers unreachable after
//! exploring at least [`SHORT_OF_FRACTION`] of the explorable area (the frontiers left are
//! slivers no goal reaches, as on most real maps). Runs cut off by the time limit, and stuck
//! or unreachable runs short of that fraction, are counted per class and left out of the time
//! statistics and gains, and a note under the table says how many and why. Runs ending short
//! of [`SHORT_OF_FRACTION`] explored are marked.

use std::collections::BTreeMap;
use std::fmt::Write as _;

use floorcast_worker::RunSummary;
use sim_core::explore::EndReason;

use crate::store::StoredResult;

/// Mean and sample standard deviation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Stat {
    pub n: usize,
    pub mean: f64,
    pub sd: f64,
}

impl Stat {
    pub fn of(xs: &[f64]) -> Stat {
        let n = xs.len();
        if n == 0 {
            return Stat {
                n,
                mean: f64::NAN,
                sd: f64::NAN,
            };
        }
        let mean = xs.iter().sum::<f64>() / n as f64;
        let sd = if n > 1 {
            (xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1) as f64).sqrt()
        } else {
            0.0
        };
        Stat { n, mean, sd }
    }
}

/// Runs that end with less than this fraction explored are marked in the tables.
pub const SHORT_OF_FRACTION: f64 = 0.97;

/// The end classes in the order tables list them (`sim_core`'s [`EndReason`] names).
pub fn end_classes() -> [&'static str; 5] {
    EndReason::ALL.map(EndReason::as_str)
}

/// The end class of a stored summary: its `end_reason`, with the "no frontiers" of summaries
/// written before the classes existed read as "complete".
pub fn end_class(s: &RunSummary) -> &str {
    match s.end_reason.as_str() {
        "no frontiers" => EndReason::Complete.as_str(),
        other => other,
    }
}

/// Whether a run's exploration time is the time to explore the building (or to decide to
/// stop): it ended complete or by an early stop, or stuck or with frontiers unreachable after
/// exploring at least [`SHORT_OF_FRACTION`]. Not at the time limit, nor with an unknown end.
pub fn ended_normally(s: &RunSummary) -> bool {
    let class = end_class(s);
    is_normal_class(class)
        || ([EndReason::Stuck, EndReason::Unreachable]
            .iter()
            .any(|r| r.as_str() == class)
            && s.explored_fraction >= SHORT_OF_FRACTION)
}

/// One row per strategy label.
#[derive(Debug, Clone, PartialEq)]
pub struct LabelRow {
    pub label: String,
    /// Exploration time of the runs that ended normally (see [`ended_normally`]).
    pub time: Stat,
    /// Explored fraction of every successful run.
    pub explored_fraction: Stat,
    pub stopped_early: usize,
    pub failed: usize,
    /// Successful runs per end class: every class of [`end_classes`] in order (zeros
    /// included), then any other `end_reason` found.
    pub ends: Vec<(String, usize)>,
    /// Successful runs left out of `time` (and the gains): ended by the time limit, stuck or
    /// with frontiers unreachable short of [`SHORT_OF_FRACTION`], or an unknown end.
    pub left_out: usize,
    /// The left-out runs per end class (classes with none omitted).
    pub left_out_ends: Vec<(String, usize)>,
    /// Successful runs that ended with less than [`SHORT_OF_FRACTION`] explored.
    pub short: usize,
    /// Gain of mean time over the reference label, per cent (positive = faster); `None` unless
    /// this label's successful runs are of exactly the reference's buildings and seeds (means
    /// over different runs would compare buildings, not strategies).
    pub gain_pct: Option<f64>,
    /// Gain over the reference paired by (building, seed); `None` without common pairs.
    pub paired: Option<PairedGain>,
}

/// Per-pair gains `(t_ref - t) / t_ref` in per cent, over the runs of a label and of the
/// reference with the same building and seed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PairedGain {
    pub pairs: usize,
    pub mean_pct: f64,
    pub sd_pct: f64,
    /// Half-width of the 95 % confidence interval of the mean (Student's t); NaN for one pair.
    pub ci95_pct: f64,
}

impl PairedGain {
    /// From per-pair gains in per cent.
    pub fn of(gains_pct: &[f64]) -> Option<PairedGain> {
        let s = Stat::of(gains_pct);
        (s.n > 0).then(|| PairedGain {
            pairs: s.n,
            mean_pct: s.mean,
            sd_pct: s.sd,
            ci95_pct: if s.n > 1 {
                t95(s.n - 1) * s.sd / (s.n as f64).sqrt()
            } else {
                f64::NAN
            },
        })
    }
}

impl PairedGain {
    /// `+1.9 ± 16.9 % (n=3)`, or without the interval for one pair.
    pub fn cell(&self) -> String {
        if self.ci95_pct.is_finite() {
            format!(
                "{:+.1} ± {:.1} % (n={})",
                self.mean_pct, self.ci95_pct, self.pairs
            )
        } else {
            format!("{:+.1} % (n={})", self.mean_pct, self.pairs)
        }
    }
}

/// Two-sided 95 % quantile of Student's t with `df` degrees of freedom (NaN for none).
fn t95(df: usize) -> f64 {
    use statrs::distribution::{ContinuousCDF, StudentsT};
    StudentsT::new(0.0, 1.0, df as f64).map_or(f64::NAN, |t| t.inverse_cdf(0.975))
}

/// What pairs a run with the reference's: building, seed and start pose (bits).
pub(crate) type PairKey = (String, u64, [u64; 3]);

/// Exploration time of the successful runs of `label` in `subset` that ended normally, by
/// (building, seed, start pose).
fn times_by_pair(subset: &[&StoredResult], label: &str) -> BTreeMap<PairKey, f64> {
    times_by(subset, label, |r| r.building.clone())
}

/// The per-pair gains `(t_ref - t) / t_ref` in per cent of the runs in `mine` that have a
/// partner in `reference`.
fn paired_gains(mine: &BTreeMap<PairKey, f64>, reference: &BTreeMap<PairKey, f64>) -> Vec<f64> {
    mine.iter()
        .filter_map(|(k, t)| {
            let b = *reference.get(k)?;
            (b > 0.0).then(|| (b - t) / b * 100.0)
        })
        .collect()
}

/// The exploration times of `label`'s successful runs in `subset` that ended normally, by
/// (building, seed, start pose): the pairs of a sequential test.
pub(crate) fn normal_times_by_pair(
    subset: &[&StoredResult],
    label: &str,
) -> BTreeMap<PairKey, f64> {
    times_by_pair(subset, label)
}

/// [`times_by_pair`] with the building named by `building` (its name, or its content hash when
/// runs of two results sets are paired).
fn times_by(
    subset: &[&StoredResult],
    label: &str,
    building: impl Fn(&StoredResult) -> String,
) -> BTreeMap<PairKey, f64> {
    subset
        .iter()
        .filter(|r| r.label == label && r.status == "ok")
        .filter_map(|r| {
            let s = RunSummary::from_json(r.summary_json.as_deref()?).ok()?;
            ended_normally(&s).then(|| {
                (
                    (building(r), r.seed, s.start.map(f64::to_bits)),
                    s.exploration_time_s,
                )
            })
        })
        .collect()
}

/// The strategy labels of `results`, in the order they first appear.
pub fn labels_of(results: &[StoredResult]) -> Vec<&str> {
    let mut labels: Vec<&str> = Vec::new();
    for r in results {
        if !labels.contains(&r.label.as_str()) {
            labels.push(&r.label);
        }
    }
    labels
}

/// The paired gain of one label of a results set over a label of another (`report --against`).
#[derive(Debug, Clone, PartialEq)]
pub struct CrossGain {
    pub label: String,
    pub against_label: String,
    /// `None` when the two labels share no run (building content, seed and start pose).
    pub gain: Option<PairedGain>,
}

/// The gain of each label of `results` (in the order they first appear) over `against_label`
/// of `against` (`None`: the same label), paired by building content (its hash: the same
/// building under any name), seed and start pose, over the runs that ended normally. A positive
/// gain is faster in `results`. For grids that change one thing against a reference grid, e.g.
/// `results/paper-alpha` against `results/paper`.
pub fn gains_against(
    results: &[StoredResult],
    against: &[StoredResult],
    against_label: Option<&str>,
) -> Vec<CrossGain> {
    let labels = labels_of(results);
    let mine: Vec<&StoredResult> = results.iter().collect();
    let theirs: Vec<&StoredResult> = against.iter().collect();
    let hash = |r: &StoredResult| r.building_hash.clone();
    labels
        .into_iter()
        .map(|label| {
            let other = against_label.unwrap_or(label);
            let reference = times_by(&theirs, other, hash);
            let gains: Vec<f64> = times_by(&mine, label, hash)
                .iter()
                .filter_map(|(k, t)| {
                    let b = *reference.get(k)?;
                    (b > 0.0).then(|| (b - t) / b * 100.0)
                })
                .collect();
            CrossGain {
                label: label.to_string(),
                against_label: other.to_string(),
                gain: PairedGain::of(&gains),
            }
        })
        .collect()
}

/// `report --against` in the JSON report: the other results directory as given and, per label,
/// the label it is compared with and the paired gain (null without a shared run).
pub fn against_json(gains: &[CrossGain], against: &str) -> serde_json::Value {
    let comparisons: Vec<serde_json::Value> = gains
        .iter()
        .map(|g| {
            serde_json::json!({
                "label": g.label,
                "against_label": g.against_label,
                "pairs": g.gain.as_ref().map_or(0, |p| p.pairs),
                "mean_gain_pct": g.gain.as_ref().and_then(|p| finite(p.mean_pct)),
                "t_ci95_pct": g.gain.as_ref().and_then(|p| {
                    Some([finite(p.mean_pct - p.ci95_pct)?, finite(p.mean_pct + p.ci95_pct)?])
                }),
            })
        })
        .collect();
    serde_json::json!({ "results": against, "comparisons": comparisons })
}

/// The lines of `report --against`: per label, the label it is compared with and the paired
/// gain with its 95 % interval.
pub fn render_against(gains: &[CrossGain], against: &str) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "Against {against} (paired by building content, seed and start pose; positive: faster here):"
    );
    let _ = writeln!(
        out,
        "  {:<16}  {:<16}  {:>22}",
        "strategy", "over (there)", "paired gain (95% CI)"
    );
    for g in gains {
        let cell = g
            .gain
            .map_or_else(|| "no common runs".to_string(), |p| p.cell());
        let _ = writeln!(
            out,
            "  {:<16}  {:<16}  {cell:>22}",
            g.label, g.against_label
        );
    }
    out
}

/// Counts per end class: [`end_classes`] in order, then other names in sorted order.
fn count_ends<'a>(summaries: impl Iterator<Item = &'a RunSummary>) -> Vec<(String, usize)> {
    let mut counts: BTreeMap<&str, usize> = BTreeMap::new();
    for s in summaries {
        *counts.entry(end_class(s)).or_default() += 1;
    }
    let mut out: Vec<(String, usize)> = end_classes()
        .iter()
        .map(|c| (c.to_string(), counts.remove(c).unwrap_or(0)))
        .collect();
    out.extend(counts.into_iter().map(|(c, n)| (c.to_string(), n)));
    out
}

#[derive(Debug, Clone, PartialEq)]
pub struct Table {
    pub reference: Option<String>,
    pub overall: Vec<LabelRow>,
    /// Per building: label rows.
    pub per_building: BTreeMap<String, Vec<LabelRow>>,
}

/// Builds the table. `labels` gives the order (labels found only in the store come after);
/// the reference is `baseline` if present, else the first label.
pub fn table(results: &[StoredResult], labels: &[String]) -> Table {
    table_against(results, labels, None)
}

/// [`table`] with the gains over `reference` (default: `baseline` if present, else the first
/// label).
pub fn table_against(
    results: &[StoredResult],
    labels: &[String],
    reference: Option<&str>,
) -> Table {
    let mut order: Vec<String> = labels.to_vec();
    for r in results {
        if !order.contains(&r.label) {
            order.push(r.label.clone());
        }
    }
    let reference = match reference {
        Some(r) => Some(r.to_string()),
        None => order
            .iter()
            .find(|l| l.as_str() == "baseline")
            .or(order.first())
            .cloned(),
    };
    let reference_label = reference.clone();
    let rows_for = |subset: &[&StoredResult]| -> Vec<LabelRow> {
        let mut rows: Vec<LabelRow> = order
            .iter()
            .filter_map(|label| {
                let mine: Vec<&&StoredResult> =
                    subset.iter().filter(|r| &r.label == label).collect();
                if mine.is_empty() {
                    return None;
                }
                let summaries: Vec<RunSummary> = mine
                    .iter()
                    .filter(|r| r.status == "ok")
                    .filter_map(|r| {
                        r.summary_json
                            .as_deref()
                            .and_then(|s| RunSummary::from_json(s).ok())
                    })
                    .collect();
                let times: Vec<f64> = summaries
                    .iter()
                    .filter(|s| ended_normally(s))
                    .map(|s| s.exploration_time_s)
                    .collect();
                let fracs: Vec<f64> = summaries.iter().map(|s| s.explored_fraction).collect();
                Some(LabelRow {
                    label: label.clone(),
                    time: Stat::of(&times),
                    explored_fraction: Stat::of(&fracs),
                    stopped_early: summaries.iter().filter(|s| s.stopped_early).count(),
                    failed: mine.len() - summaries.len(),
                    ends: count_ends(summaries.iter()),
                    left_out: summaries.len() - times.len(),
                    left_out_ends: count_ends(summaries.iter().filter(|s| !ended_normally(s)))
                        .into_iter()
                        .filter(|(_, n)| *n > 0)
                        .collect(),
                    short: summaries
                        .iter()
                        .filter(|s| s.explored_fraction < SHORT_OF_FRACTION)
                        .count(),
                    gain_pct: None,
                    paired: None,
                })
            })
            .collect();
        let base = reference_label
            .as_ref()
            .and_then(|r| rows.iter().find(|row| &row.label == r))
            .map(|row| row.time.mean);
        let reference_times = reference_label
            .as_deref()
            .map(|r| times_by_pair(subset, r))
            .unwrap_or_default();
        for row in &mut rows {
            let mine = times_by_pair(subset, &row.label);
            let same_runs = mine.keys().eq(reference_times.keys());
            row.gain_pct = base
                .filter(|b| same_runs && b.is_finite() && *b > 0.0)
                .map(|b| (b - row.time.mean) / b * 100.0);
            row.paired = PairedGain::of(&paired_gains(&mine, &reference_times));
        }
        rows
    };
    let all: Vec<&StoredResult> = results.iter().collect();
    let mut per_building = BTreeMap::new();
    let mut buildings: Vec<&str> = results.iter().map(|r| r.building.as_str()).collect();
    buildings.sort();
    buildings.dedup();
    for b in buildings {
        let subset: Vec<&StoredResult> = results.iter().filter(|r| r.building == b).collect();
        per_building.insert(b.to_string(), rows_for(&subset));
    }
    Table {
        reference,
        overall: rows_for(&all),
        per_building,
    }
}

fn is_normal_class(class: &str) -> bool {
    EndReason::ALL
        .iter()
        .any(|r| r.is_normal() && r.as_str() == class)
}

fn fmt_rows(out: &mut String, rows: &[LabelRow], reference: Option<&String>) {
    let _ = writeln!(
        out,
        "  {:<16} {:>5} {:>10} {:>9} {:>9} {:>22} {:>10} {:>6}",
        "strategy", "runs", "time (s)", "sd (s)", "gain", "paired gain (95% CI)", "explored", "ES"
    );
    for r in rows {
        let is_reference = reference.is_some_and(|reference| &r.label == reference);
        let gain = match r.gain_pct {
            _ if is_reference => "ref".to_string(),
            Some(g) => format!("{g:+.1} %"),
            None => "-".into(),
        };
        let paired = match r.paired {
            _ if is_reference => String::new(),
            Some(p) => p.cell(),
            None => "-".into(),
        };
        let mut marks = Vec::new();
        if r.failed > 0 {
            marks.push(format!("{} failed", r.failed));
        }
        if r.left_out > 0 {
            let classes: Vec<String> = r
                .left_out_ends
                .iter()
                .map(|(c, n)| format!("{n} {c}"))
                .collect();
            marks.push(format!("{} left out: {}", r.left_out, classes.join(", ")));
        }
        if r.short > 0 {
            marks.push(format!(
                "{} short of {:.0} %",
                r.short,
                SHORT_OF_FRACTION * 100.0
            ));
        }
        // A label without a run to average (all failed) shows dashes, not NaN.
        let number = |v: f64, digits: usize| {
            if v.is_finite() {
                format!("{v:.digits$}")
            } else {
                "-".to_string()
            }
        };
        let explored = match number(r.explored_fraction.mean * 100.0, 1).as_str() {
            "-" => "-".to_string(),
            e => format!("{e}%"),
        };
        let _ = writeln!(
            out,
            "  {:<16} {:>5} {:>10} {:>9} {:>9} {:>22} {:>10} {:>6}{}",
            r.label,
            r.time.n,
            number(r.time.mean, 0),
            number(r.time.sd, 0),
            gain,
            paired,
            explored,
            r.stopped_early,
            if marks.is_empty() {
                String::new()
            } else {
                format!("  ({})", marks.join("; "))
            }
        );
    }
}

/// One comparison of a label with the reference, over all buildings (`building` = `None`) or on
/// one: statistics of the per-pair gains `(t_ref - t) / t_ref` in per cent, over the pairs of
/// runs (same building, seed and start pose) that both ended normally.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Comparison {
    pub label: String,
    pub reference: String,
    pub building: Option<String>,
    pub pairs: usize,
    /// The label's normally ended runs without a partner among the reference's.
    pub unpaired: usize,
    pub mean_gain_pct: Option<f64>,
    pub sd_gain_pct: Option<f64>,
    /// Student's t 95 % interval of the mean gain.
    pub t_ci95_pct: Option<[f64; 2]>,
    /// The seeded percentile bootstrap 95 % interval of the mean gain
    /// ([`crate::stats::bootstrap_mean_ci95`]).
    pub bootstrap_ci95_pct: Option<[f64; 2]>,
    /// Two-sided Wilcoxon signed-rank p-value of the gains.
    pub wilcoxon_p: Option<f64>,
    /// `wilcoxon_p` adjusted by Holm's method over every comparison of the report.
    pub holm_p: Option<f64>,
    /// Cohen's d_z: the mean gain over its standard deviation.
    pub effect_size_dz: Option<f64>,
    /// The other metrics, paired the same way over the successful runs (see [`METRICS`]).
    pub metrics: BTreeMap<String, MetricGain>,
}

/// A paired comparison of one metric: per pair, the gain `(ref - x) / ref` in per cent for the
/// metrics where lower is better, and `x - ref` in percentage points for the explored fraction.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct MetricGain {
    pub pairs: usize,
    pub mean: Option<f64>,
    /// Student's t 95 % interval of the mean.
    pub t_ci95: Option<[f64; 2]>,
}

/// The metrics compared besides the exploration time: name, and its value of a successful run
/// (summary, progress CSV); all lower-is-better gains but the explored fraction's points.
pub const METRICS: [&str; 6] = [
    "time_to_90_s",
    "time_to_95_s",
    "time_to_99_s",
    "unexplored_area_s",
    "path_length_m",
    "explored_fraction_points",
];

fn metric_of(name: &str, s: &RunSummary, progress_csv: &str) -> Option<f64> {
    match name {
        "time_to_90_s" => time_to_fraction(progress_csv, 0.90),
        "time_to_95_s" => time_to_fraction(progress_csv, 0.95),
        "time_to_99_s" => time_to_fraction(progress_csv, 0.99),
        "unexplored_area_s" => unexplored_area_s(progress_csv),
        "path_length_m" => Some(s.path_length_m),
        "explored_fraction_points" => Some(s.explored_fraction * 100.0),
        _ => None,
    }
}

/// `name` of `label`'s successful runs in `subset` (those that have it), by pair key.
fn metric_by_pair(subset: &[&StoredResult], label: &str, name: &str) -> BTreeMap<PairKey, f64> {
    subset
        .iter()
        .filter(|r| r.label == label && r.status == "ok")
        .filter_map(|r| {
            let s = RunSummary::from_json(r.summary_json.as_deref()?).ok()?;
            let v = metric_of(name, &s, r.progress_csv.as_deref().unwrap_or(""))?;
            v.is_finite()
                .then(|| ((r.building.clone(), r.seed, s.start.map(f64::to_bits)), v))
        })
        .collect()
}

/// The paired comparisons of every metric of [`METRICS`] of `label` with `reference`.
fn metric_gains(
    subset: &[&StoredResult],
    label: &str,
    reference: &str,
) -> BTreeMap<String, MetricGain> {
    METRICS
        .iter()
        .map(|name| {
            let mine = metric_by_pair(subset, label, name);
            let theirs = metric_by_pair(subset, reference, name);
            let diffs: Vec<f64> = if *name == "explored_fraction_points" {
                mine.iter()
                    .filter_map(|(k, v)| Some(v - theirs.get(k)?))
                    .collect()
            } else {
                paired_gains(&mine, &theirs)
            };
            let p = PairedGain::of(&diffs);
            let gain = MetricGain {
                pairs: diffs.len(),
                mean: p.map(|p| p.mean_pct),
                t_ci95: p
                    .filter(|p| p.ci95_pct.is_finite())
                    .map(|p| [p.mean_pct - p.ci95_pct, p.mean_pct + p.ci95_pct]),
            };
            (name.to_string(), gain)
        })
        .collect()
}

/// The comparisons of every label with `reference`, over all buildings and then per building,
/// with Holm's adjustment across all of them.
pub fn comparisons(results: &[StoredResult], reference: &str) -> Vec<Comparison> {
    let mut out = Vec::new();
    let labels: Vec<String> = labels_of(results)
        .into_iter()
        .filter(|l| *l != reference)
        .map(str::to_string)
        .collect();
    let mut buildings: Vec<Option<String>> = vec![None];
    let mut names: Vec<&str> = results.iter().map(|r| r.building.as_str()).collect();
    names.sort();
    names.dedup();
    buildings.extend(names.into_iter().map(|b| Some(b.to_string())));
    for building in &buildings {
        let subset: Vec<&StoredResult> = results
            .iter()
            .filter(|r| building.as_ref().is_none_or(|b| &r.building == b))
            .collect();
        let reference_times = times_by_pair(&subset, reference);
        for label in &labels {
            let mine = times_by_pair(&subset, label);
            if mine.is_empty() {
                continue;
            }
            let gains = paired_gains(&mine, &reference_times);
            let paired = PairedGain::of(&gains);
            out.push(Comparison {
                label: label.clone(),
                reference: reference.to_string(),
                building: building.clone(),
                pairs: gains.len(),
                unpaired: mine.len() - gains.len(),
                mean_gain_pct: paired.map(|p| p.mean_pct),
                sd_gain_pct: paired.map(|p| p.sd_pct).filter(|v| v.is_finite()),
                t_ci95_pct: paired
                    .filter(|p| p.ci95_pct.is_finite())
                    .map(|p| [p.mean_pct - p.ci95_pct, p.mean_pct + p.ci95_pct]),
                bootstrap_ci95_pct: crate::stats::bootstrap_mean_ci95(&gains).map(|(a, b)| [a, b]),
                wilcoxon_p: crate::stats::wilcoxon_signed_rank_p(&gains),
                holm_p: None,
                effect_size_dz: crate::stats::effect_size_dz(&gains),
                metrics: metric_gains(&subset, label, reference),
            });
        }
    }
    let adjusted = crate::stats::holm(&out.iter().map(|c| c.wilcoxon_p).collect::<Vec<_>>());
    for (c, p) in out.iter_mut().zip(adjusted) {
        c.holm_p = p;
    }
    out
}

/// The comparisons over all buildings as text: one line each.
pub fn render_comparisons(cs: &[Comparison]) -> String {
    let mut out = String::new();
    let overall: Vec<&Comparison> = cs.iter().filter(|c| c.building.is_none()).collect();
    if overall.is_empty() {
        return out;
    }
    let _ = writeln!(
        out,
        "Paired gains over {} (all buildings): t and bootstrap 95 % intervals, Wilcoxon p (Holm-adjusted over the report's {} comparisons), effect size d_z:",
        overall[0].reference,
        cs.len()
    );
    let range =
        |r: Option<[f64; 2]>| r.map_or("-".to_string(), |[a, b]| format!("[{a:+.1}, {b:+.1}]"));
    let num =
        |v: Option<f64>, digits: usize| v.map_or("-".to_string(), |v| format!("{v:.digits$}"));
    for c in overall {
        let _ = writeln!(
            out,
            "  {:<16} {:>8} % t {:<16} boot {:<16} p {:<7} Holm {:<7} d_z {:<6} {} pairs, {} unpaired",
            c.label,
            c.mean_gain_pct.map_or("-".to_string(), |m| format!("{m:+.1}")),
            range(c.t_ci95_pct),
            range(c.bootstrap_ci95_pct),
            num(c.wilcoxon_p, 4),
            num(c.holm_p, 4),
            num(c.effect_size_dz, 2),
            c.pairs,
            c.unpaired
        );
    }
    out
}

/// The format and version of `report --json`.
pub const REPORT_FORMAT: &str = "floorcast-report";
pub const REPORT_VERSION: u32 = 1;

/// `report --json`: the labels' statistics, every comparison, and sequential grids' decisions
/// (documented in `docs/report-json.md`).
pub fn report_json(
    results: &[StoredResult],
    reference: &str,
    tests: &[(String, crate::sequential::LabelTest)],
) -> serde_json::Value {
    use serde_json::json;
    let t = table_against(results, &[], Some(reference));
    let label_row = |r: &LabelRow, building: Option<&str>| {
        let mut v = json!({
            "label": r.label,
            "runs_timed": r.time.n,
            "time_mean_s": finite(r.time.mean),
            "time_sd_s": finite(r.time.sd),
            "explored_fraction_mean": finite(r.explored_fraction.mean),
            "early_stops": r.stopped_early,
            "failed": r.failed,
            "left_out": r.left_out,
            "ends": r.ends.iter().map(|(c, n)| (c.clone(), *n)).collect::<BTreeMap<String, usize>>(),
        });
        v["metrics"] = label_metrics(
            results
                .iter()
                .filter(|x| building.is_none_or(|b| x.building == b)),
            &r.label,
        );
        v
    };
    // The last test of each (grid, label, reference).
    let mut decided: BTreeMap<(String, String), &crate::sequential::LabelTest> = BTreeMap::new();
    for (_, test) in tests {
        decided.insert((test.label.clone(), test.reference.clone()), test);
    }
    let comparisons: Vec<serde_json::Value> = comparisons(results, reference)
        .into_iter()
        .map(|c| {
            let mut v = serde_json::to_value(&c).unwrap_or_default();
            let seq = c
                .building
                .is_none()
                .then(|| decided.get(&(c.label.clone(), c.reference.clone())))
                .flatten();
            v["decision"] = seq.map_or(serde_json::Value::Null, |s| {
                json!(s.state.decision.as_str())
            });
            v["sequential_pairs"] = seq.map_or(serde_json::Value::Null, |s| json!(s.state.pairs));
            v
        })
        .collect();
    json!({
        "format": REPORT_FORMAT,
        "version": REPORT_VERSION,
        "floorcast_version": floorcast_worker::FLOORCAST_VERSION,
        "reference": reference,
        "runs": results.len(),
        "labels": t.overall.iter().map(|r| label_row(r, None)).collect::<Vec<_>>(),
        "per_building": t.per_building.iter().map(|(b, rows)| (b.clone(), rows.iter().map(|r| label_row(r, Some(b))).collect::<Vec<_>>())).collect::<BTreeMap<String, Vec<serde_json::Value>>>(),
        "comparisons": comparisons,
    })
}

/// The area above a run's explored-fraction curve up to its end, `∫ (1 - f(t)) dt` in seconds
/// (trapezoids between the samples): how long the building stays unseen on average, lower is
/// better; it weighs early progress, where the exploration time sees only the end.
pub fn unexplored_area_s(progress_csv: &str) -> Option<f64> {
    let mut prev: Option<(f64, f64)> = None;
    let mut area = 0.0;
    for (t, f) in progress_curve(progress_csv) {
        if let Some((t0, f0)) = prev {
            area += (t - t0) * (2.0 - f0 - f) / 2.0;
        }
        prev = Some((t, f));
    }
    prev.map(|_| area)
}

/// A label's other metrics, as means over its successful runs (`null` without one): times to
/// 90, 95 and 99 % explored (over the runs that reached them, with how many did), the
/// unexplored area, path length, explored fraction, rooms left unexplored, map quality.
fn label_metrics<'a>(
    results: impl Iterator<Item = &'a StoredResult>,
    label: &str,
) -> serde_json::Value {
    let runs: Vec<(RunSummary, &str)> = results
        .filter(|r| r.label == label && r.status == "ok")
        .filter_map(|r| {
            let s = RunSummary::from_json(r.summary_json.as_deref()?).ok()?;
            Some((s, r.progress_csv.as_deref().unwrap_or("")))
        })
        .collect();
    let mean = |xs: Vec<f64>| finite(Stat::of(&xs).mean).filter(|_| !xs.is_empty());
    let mut v = serde_json::json!({
        "unexplored_area_s_mean": mean(runs.iter().filter_map(|(_, p)| unexplored_area_s(p)).collect()),
        "path_length_m_mean": mean(runs.iter().map(|(s, _)| s.path_length_m).collect()),
        "explored_fraction_min": runs.iter().map(|(s, _)| s.explored_fraction).reduce(f64::min),
        "rooms_unexplored_total": runs.iter().filter_map(|(s, _)| s.rooms_unexplored).reduce(|a, b| a + b),
        "map_occupied_precision_aligned_mean": mean(runs.iter().map(|(s, _)| s.map_occupied_precision_aligned).collect()),
    });
    for pct in [90u32, 95, 99] {
        let times: Vec<f64> = runs
            .iter()
            .filter_map(|(_, p)| time_to_fraction(p, pct as f64 / 100.0))
            .collect();
        v[format!("runs_reaching_{pct}")] = serde_json::json!(times.len());
        v[format!("time_to_{pct}_s_mean")] = serde_json::json!(mean(times));
    }
    v
}

fn finite(v: f64) -> Option<f64> {
    v.is_finite().then_some(v)
}

/// The table as text.
pub fn render_text(t: &Table) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "Exploration time over all runs (mean, standard deviation), gain over {}:",
        t.reference.as_deref().unwrap_or("-")
    );
    fmt_rows(&mut out, &t.overall, t.reference.as_ref());
    if t.per_building.len() > 1 {
        for (b, rows) in &t.per_building {
            let _ = writeln!(out, "{b}:");
            fmt_rows(&mut out, rows, t.reference.as_ref());
        }
    }
    let unbalanced = std::iter::once(&t.overall)
        .chain(t.per_building.values())
        .flatten()
        .any(|r| r.gain_pct.is_none() && t.reference.as_ref() != Some(&r.label));
    if unbalanced {
        let _ = writeln!(
            out,
            "gain '-': the label's runs are not the same buildings and seeds as {}'s (some are \
             missing, failed or left out); the paired gain compares the runs they share",
            t.reference.as_deref().unwrap_or("the reference")
        );
    }
    let left_out: usize = t.overall.iter().map(|r| r.left_out).sum();
    if left_out > 0 {
        let mut classes: BTreeMap<&str, usize> = BTreeMap::new();
        for r in &t.overall {
            for (c, n) in &r.left_out_ends {
                *classes.entry(c.as_str()).or_default() += n;
            }
        }
        let mut listed: Vec<String> = end_classes()
            .iter()
            .filter_map(|c| classes.remove(c).map(|n| format!("{n} {c}")))
            .collect();
        listed.extend(classes.iter().map(|(c, n)| format!("{n} {c}")));
        let _ = writeln!(
            out,
            "left out of the times and gains: {left_out} runs that did not end by exploring \
             everything they could reach (at least {:.0} %) or by an early stop ({}); their times \
             say when they were cut off, not how long exploring took (`runs` counts the rest; see how runs \
             ended below)",
            SHORT_OF_FRACTION * 100.0,
            listed.join(", ")
        );
    }
    let short: usize = t.overall.iter().map(|r| r.short).sum();
    if short > 0 {
        let _ = writeln!(
            out,
            "{short} runs ended with less than {:.0} % of the reachable free area explored \
             (marked 'short'); 'explored' averages every run",
            SHORT_OF_FRACTION * 100.0
        );
    }
    out
}

/// How the runs ended: per strategy label (overall, then per building when there are
/// several), the successful runs of each end class and those short of
/// [`SHORT_OF_FRACTION`] explored.
pub fn render_ends(t: &Table) -> String {
    let mut out = String::new();
    let extra: Vec<String> = std::iter::once(&t.overall)
        .chain(t.per_building.values())
        .flatten()
        .flat_map(|r| {
            r.ends
                .iter()
                .skip(end_classes().len())
                .map(|(c, _)| c.clone())
        })
        .collect::<std::collections::BTreeSet<_>>()
        .into_iter()
        .collect();
    let classes: Vec<&str> = end_classes()
        .iter()
        .copied()
        .chain(extra.iter().map(String::as_str))
        .collect();
    let rows = |out: &mut String, rows: &[LabelRow]| {
        let mut head = format!("  {:<16}", "strategy");
        for c in &classes {
            let _ = write!(head, " {c:>10}");
        }
        let _ = writeln!(
            out,
            "{head} {:>10}",
            format!("< {:.0} %", SHORT_OF_FRACTION * 100.0)
        );
        for r in rows {
            let mut line = format!("  {:<16}", r.label);
            for c in &classes {
                let n = r.ends.iter().find(|(e, _)| e == c).map_or(0, |(_, n)| *n);
                let _ = write!(line, " {:>w$}", n, w = c.len().max(10));
            }
            let _ = writeln!(out, "{line} {:>10}", r.short);
        }
    };
    let _ = writeln!(out, "How runs ended (successful runs per end class):");
    rows(&mut out, &t.overall);
    if t.per_building.len() > 1 {
        for (b, r) in &t.per_building {
            let _ = writeln!(out, "{b}:");
            rows(&mut out, r);
        }
    }
    out
}

/// One label's explored fraction over time on one building, over its successful runs.
#[derive(Debug, Clone, PartialEq)]
pub struct ProgressCurve {
    pub label: String,
    /// `(time_s, mean, least, greatest)` explored fraction over the runs at each sample time
    /// (a run that has ended keeps its final fraction).
    pub points: Vec<(f64, f64, f64, f64)>,
    /// `(exploration_time_s, explored_fraction)` of each run that stopped early.
    pub early_stops: Vec<(f64, f64)>,
    pub runs: usize,
}

/// The explored fraction over time of each label's successful runs of `building` (mean, range
/// and early stops: the paper's Fig. 4), on `samples` evenly spaced times from 0 to the end of
/// the longest run. Labels in `order` first, as in [`table`].
pub fn progress_curves(
    results: &[StoredResult],
    building: &str,
    order: &[String],
    samples: usize,
) -> Vec<ProgressCurve> {
    type Curves = (Vec<Vec<(f64, f64)>>, Vec<(f64, f64)>);
    let mut curves: BTreeMap<&str, Curves> = BTreeMap::new();
    for r in results
        .iter()
        .filter(|r| r.building == building && r.status == "ok")
    {
        let Some(csv) = r.progress_csv.as_deref() else {
            continue;
        };
        let curve: Vec<(f64, f64)> = progress_curve(csv).collect();
        if curve.is_empty() {
            continue;
        }
        let entry = curves.entry(r.label.as_str()).or_default();
        entry.0.push(curve);
        if let Some(s) = r
            .summary_json
            .as_deref()
            .and_then(|j| RunSummary::from_json(j).ok())
        {
            if s.stopped_early {
                entry.1.push((s.exploration_time_s, s.explored_fraction));
            }
        }
    }
    let end = curves
        .values()
        .flat_map(|(runs, _)| runs)
        .filter_map(|c| c.last().map(|p| p.0))
        .fold(0.0f64, f64::max);
    let samples = samples.max(2);
    let mut labels: Vec<&str> = order
        .iter()
        .map(String::as_str)
        .filter(|l| curves.contains_key(l))
        .collect();
    for l in curves.keys() {
        if !labels.contains(l) {
            labels.push(l);
        }
    }
    labels
        .into_iter()
        .map(|label| {
            let (runs, early_stops) = &curves[label];
            let points = (0..samples)
                .map(|k| {
                    let t = end * k as f64 / (samples - 1) as f64;
                    let at: Vec<f64> = runs
                        .iter()
                        .map(|c| {
                            // The last sample at or before t (curves start at t = 0).
                            let i = c.partition_point(|p| p.0 <= t);
                            c[i.saturating_sub(1)].1
                        })
                        .collect();
                    let mean = at.iter().sum::<f64>() / at.len() as f64;
                    let least = at.iter().copied().fold(f64::INFINITY, f64::min);
                    let greatest = at.iter().copied().fold(f64::NEG_INFINITY, f64::max);
                    (t, mean, least, greatest)
                })
                .collect();
            ProgressCurve {
                label: label.to_string(),
                points,
                early_stops: early_stops.clone(),
                runs: runs.len(),
            }
        })
        .collect()
}

/// The `(time_s, explored_fraction)` samples of a stored `progress.csv`
/// (`time_s,explored_area_m2,explored_fraction`); unreadable lines are skipped.
fn progress_curve(progress_csv: &str) -> impl Iterator<Item = (f64, f64)> + '_ {
    progress_csv.lines().skip(1).filter_map(|line| {
        let mut it = line.split(',');
        let t: f64 = it.next()?.trim().parse().ok()?;
        let f: f64 = it.nth(1)?.trim().parse().ok()?;
        Some((t, f))
    })
}

/// The first simulated time at which a stored progress curve reaches `fraction` explored.
pub fn time_to_fraction(progress_csv: &str, fraction: f64) -> Option<f64> {
    progress_curve(progress_csv).find_map(|(t, f)| (f >= fraction).then_some(t))
}

/// One line per stored job, for pandas or R. `time_to_90_s` is the simulated time at which the
/// run had explored 90 % (the paper's point from which layout knowledge pays off), empty if it
/// never did. `rooms_never_entered` and `rooms_unexplored` are empty without ground-truth rooms.
/// `end_reason` is the end class ([`end_class`]). The start pose (`start_x_m`, `start_y_m`,
/// `start_theta_rad`, full precision) and where it came from close each line.
pub fn results_csv(results: &[StoredResult]) -> String {
    const HEADER: [&str; 26] = [
        "job_id",
        "building",
        "building_hash",
        "strategy",
        "label",
        "seed",
        "status",
        "exploration_time_s",
        "explored_area_m2",
        "free_area_m2",
        "explored_fraction",
        "time_to_90_s",
        "path_length_m",
        "decisions",
        "stopped_early",
        "end_reason",
        "unexplored_free_m2",
        "rooms_never_entered",
        "rooms_unexplored",
        "wall_time_s",
        "worker",
        "floorcast_version",
        "start_x_m",
        "start_y_m",
        "start_theta_rad",
        "start_source",
    ];
    let mut w = csv::WriterBuilder::new()
        .terminator(csv::Terminator::Any(b'\n'))
        .from_writer(Vec::new());
    // Writing to memory fails only on a record of another length, which the arrays rule out.
    let _ = w.write_record(HEADER);
    for r in results {
        let sum = r
            .summary_json
            .as_deref()
            .and_then(|j| RunSummary::from_json(j).ok());
        let f = |v: Option<f64>| v.map(|x| format!("{x}")).unwrap_or_default();
        let count = |v: Option<usize>| v.map(|x| x.to_string()).unwrap_or_default();
        let row: [String; HEADER.len()] = [
            r.job_id.clone(),
            r.building.clone(),
            r.building_hash.clone(),
            r.strategy.clone(),
            r.label.clone(),
            r.seed.to_string(),
            r.status.clone(),
            f(sum.as_ref().map(|s| s.exploration_time_s)),
            f(sum.as_ref().map(|s| s.explored_area_m2)),
            f(sum.as_ref().map(|s| s.free_area_m2)),
            f(sum.as_ref().map(|s| s.explored_fraction)),
            f(r.progress_csv
                .as_deref()
                .and_then(|p| time_to_fraction(p, 0.9))),
            f(sum.as_ref().map(|s| s.path_length_m)),
            sum.as_ref()
                .map(|s| s.decisions.to_string())
                .unwrap_or_default(),
            sum.as_ref()
                .map(|s| s.stopped_early.to_string())
                .unwrap_or_default(),
            sum.as_ref().map(end_class).unwrap_or("").to_string(),
            f(sum.as_ref().map(|s| s.unexplored_free_m2)),
            count(sum.as_ref().and_then(|s| s.rooms_never_entered)),
            count(sum.as_ref().and_then(|s| s.rooms_unexplored)),
            r.wall_time_s.to_string(),
            r.worker.clone(),
            r.floorcast_version.clone(),
            f(sum.as_ref().map(|s| s.start[0])),
            f(sum.as_ref().map(|s| s.start[1])),
            f(sum.as_ref().map(|s| s.start[2])),
            sum.as_ref()
                .map(|s| s.start_source.clone())
                .unwrap_or_default(),
        ];
        let _ = w.write_record(&row);
    }
    String::from_utf8(w.into_inner().unwrap_or_default()).unwrap_or_default()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stat_mean_and_sd() {
        let s = Stat::of(&[2.0, 4.0, 4.0, 4.0, 5.0, 5.0, 7.0, 9.0]);
        assert_eq!(s.mean, 5.0);
        assert!((s.sd - 2.138).abs() < 1e-3);
        assert!(Stat::of(&[]).mean.is_nan());
        assert_eq!(Stat::of(&[3.0]).sd, 0.0);
    }

    /// The quantiles against published tables (to their three decimals), including the
    /// range between 31 and 120 degrees of freedom that a coarse table gets wrong.
    /// Labels and names that need quoting come back as they were from a CSV reader.
    #[test]
    fn csv_fields_round_trip_through_a_reader() {
        let awkward = ["plain", "a,b", "say \"hi\"", "two\nlines", "", " spaced "];
        let results: Vec<StoredResult> = awkward
            .iter()
            .enumerate()
            .map(|(i, label)| stored("b1", label, i as u64 + 1, 10.0))
            .collect();
        let text = results_csv(&results);
        let mut reader = csv::Reader::from_reader(text.as_bytes());
        let label = reader
            .headers()
            .unwrap()
            .iter()
            .position(|h| h == "label")
            .unwrap();
        let got: Vec<String> = reader
            .records()
            .map(|r| r.unwrap()[label].to_string())
            .collect();
        assert_eq!(got, awkward);
    }

    /// `scipy.stats.t.ppf(0.975, df)` (scipy 1.17.1).
    #[test]
    fn t_quantiles_match_scipy() {
        let table = [
            (1, 12.706204736174694),
            (2, 4.302652729749462),
            (4, 2.7764451051977934),
            (9, 2.262157162798205),
            (29, 2.045229642132703),
            (30, 2.0422724563012378),
            (31, 2.039513446396408),
            (49, 2.0095752371292392),
            (99, 1.9842169515864174),
            (119, 1.9800998764569397),
            (299, 1.9679296690656698),
        ];
        for (df, want) in table {
            let got = t95(df);
            assert!((got - want).abs() < 1e-9, "df {df}: {got} against {want}");
        }
        assert!(t95(0).is_nan());
    }

    fn stored(building: &str, label: &str, seed: u64, time_s: f64) -> StoredResult {
        // A real summary (small.toml, layout, seed 1) with the time replaced.
        let template: &str = concat!(
            r#"{"format":"floorcast-run-summary","version":1,"floorcast_version":"0.1.0","build"#,
            r#"ing":"small","building_hash":"bd6183b04c0805da57279aa53b7844c1","strategy":"layo"#,
            r#"ut","seed":1,"settings":{"robot_radius_m":0.2,"max_speed_mps":0.5,"max_turn_rate"#,
            r#"_radps":1.0,"laser_fov_deg":180.0,"laser_range_m":6.0,"laser_beams":181,"laser_r"#,
            r#"ate_hz":10.0,"laser_noise_sd_m":0.01,"odometry_translation_error":0.01,"odometry"#,
            r#"_rotation_error_deg_per_rad":2.0,"localization":"slam","map_resolution_m":0.05,""#,
            r#"alpha":0.5,"min_frontier_m":0.5,"redecide_period_s":10.0,"blacklist_radius_m":0."#,
            r#"5,"progress_timeout_s":20.0,"time_limit_s":14400.0,"return_home":false,"es_thres"#,
            r#"hold_m2":1.0,"aes_min_gain_m2":2.0,"layout_update_m2":20.0},"start":[1.199999999"#,
            r#"9999993,9.81368055441612,0.0],"start_source":"building file","exploration_time_s"#,
            r#"":606.2000000000693,"total_time_s":606.2000000000693,"explored_area_m2":407.9825"#,
            r#"000000001,"free_area_m2":408.2100000000001,"explored_fraction":0.999442688812131"#,
            r#","path_length_m":265.2573756983305,"decisions":166,"stopped_early":false,"unexpl"#,
            r#"ored_free_m2":0.22750000000002046,"rooms_never_entered":0,"layouts_computed":17,"#,
            r#""end_reason":"no frontiers","blacklisted_goals":0,"scans":3341,"scan_matches_acc"#,
            r#"epted":3220,"map_free_precision":0.9946381028273507,"map_occupied_precision":0.8"#,
            r#"890061565523307,"wall_time_s":11.839814543,"speedup":51.200126302524744}"#,
        );
        let mut summary: serde_json::Value = serde_json::from_str(template).unwrap();
        summary["exploration_time_s"] = serde_json::json!(time_s);
        StoredResult {
            job_id: format!("{building}-{label}-{seed}"),
            grid: "g".into(),
            building: building.into(),
            building_hash: "h".into(),
            strategy: label.into(),
            label: label.into(),
            seed,
            settings_json: "{}".into(),
            status: "ok".into(),
            error: None,
            summary_json: Some(summary.to_string()),
            progress_csv: None,
            worker: "w".into(),
            wall_time_s: 1.0,
            floorcast_version: "0".into(),
        }
    }

    #[test]
    fn paired_gain_per_building_with_a_confidence_interval() {
        // Building a: layout 10 % faster on every seed; building b: 20 % faster on seed 1,
        // 0 % on seed 2, and seed 3 has no baseline run to pair with.
        let mut results = Vec::new();
        for (seed, t) in [(1, 100.0), (2, 200.0), (3, 300.0)] {
            results.push(stored("a", "baseline", seed, t));
            results.push(stored("a", "layout", seed, t * 0.9));
        }
        results.push(stored("b", "baseline", 1, 100.0));
        results.push(stored("b", "layout", 1, 80.0));
        results.push(stored("b", "baseline", 2, 100.0));
        results.push(stored("b", "layout", 2, 100.0));
        results.push(stored("b", "layout", 3, 50.0));
        let t = table(&results, &["baseline".into(), "layout".into()]);
        let a = &t.per_building["a"][1];
        let p = a.paired.unwrap();
        assert_eq!(p.pairs, 3);
        assert!((p.mean_pct - 10.0).abs() < 1e-9, "{p:?}");
        assert!(p.sd_pct.abs() < 1e-9 && p.ci95_pct.abs() < 1e-9);
        let b = t.per_building["b"][1].paired.unwrap();
        assert_eq!(b.pairs, 2);
        assert!((b.mean_pct - 10.0).abs() < 1e-9);
        // sd of {20, 0} = 14.142; t(1) = 12.706; half-width = 12.706 * 14.142 / sqrt(2).
        assert!((b.ci95_pct - 127.06).abs() < 0.01, "{b:?}");
        // Overall: 5 pairs across both buildings.
        assert_eq!(t.overall[1].paired.unwrap().pairs, 5);
        assert!(t.overall[0].paired.is_some_and(|p| p.mean_pct == 0.0));
        // The plain gain of the means only where both labels ran the same buildings and seeds.
        assert!(a.gain_pct.is_some_and(|g| (g - 10.0).abs() < 1e-9), "{a:?}");
        assert_eq!(t.per_building["b"][1].gain_pct, None);
        assert_eq!(t.overall[1].gain_pct, None);
        let text = render_text(&t);
        assert!(text.contains("+10.0 ± 0.0 % (n=3)"), "{text}");
        assert!(text.contains("b:"), "{text}");
        assert!(text.contains("gain '-'"), "{text}");
        let balanced: Vec<StoredResult> =
            results.into_iter().filter(|r| r.building == "a").collect();
        let text = render_text(&table(&balanced, &["baseline".into(), "layout".into()]));
        assert!(
            text.contains("+10.0 %") && !text.contains("gain '-'"),
            "{text}"
        );
    }

    /// The other metrics are paired like the time: a label whose path is 20 % shorter on every
    /// seed and that explores 1 point less has those as its mean gains, with their pairs; times
    /// to a fraction pair only the runs that reached it.
    #[test]
    fn other_metrics_are_paired_like_the_time() {
        let run = |label: &str, seed: u64, path_m: f64, fraction: f64, progress: &str| {
            let mut r = stored("a", label, seed, 100.0);
            let mut v: serde_json::Value =
                serde_json::from_str(r.summary_json.as_deref().unwrap()).unwrap();
            v["path_length_m"] = serde_json::json!(path_m);
            v["explored_fraction"] = serde_json::json!(fraction);
            r.summary_json = Some(v.to_string());
            r.progress_csv = Some(format!(
                "time_s,explored_area_m2,explored_fraction\n{progress}"
            ));
            r
        };
        let results = vec![
            run("baseline", 1, 100.0, 1.0, "0,0,0\n50,9,0.9\n100,10,1\n"),
            run("layout", 1, 80.0, 0.99, "0,0,0\n40,9,0.9\n100,10,0.99\n"),
            run("baseline", 2, 200.0, 1.0, "0,0,0\n100,9,0.95\n"),
            run("layout", 2, 160.0, 0.99, "0,0,0\n100,9,0.85\n"),
        ];
        let c = comparisons(&results, "baseline");
        let overall = c
            .iter()
            .find(|c| c.label == "layout" && c.building.is_none())
            .unwrap();
        let m = &overall.metrics;
        let close = |a: Option<f64>, b: f64| a.is_some_and(|a| (a - b).abs() < 1e-9);
        assert_eq!(m["path_length_m"].pairs, 2);
        assert!(close(m["path_length_m"].mean, 20.0), "{m:?}");
        assert_eq!(m["path_length_m"].t_ci95, Some([20.0, 20.0]));
        assert!(close(m["explored_fraction_points"].mean, -1.0), "{m:?}");
        // Seed 1 reaches 90 % at 40 s against 50 s; seed 2's layout never does.
        assert_eq!(m["time_to_90_s"].pairs, 1);
        assert!(close(m["time_to_90_s"].mean, 20.0), "{m:?}");
        assert_eq!(m["time_to_90_s"].t_ci95, None);
        assert_eq!(m["time_to_99_s"].pairs, 1);
        assert_eq!(m.len(), METRICS.len());
    }

    /// A stored run with its end class, explored fraction and start pose replaced.
    fn stored_end(
        label: &str,
        seed: u64,
        time_s: f64,
        end_reason: &str,
        fraction: f64,
        start: [f64; 3],
    ) -> StoredResult {
        let mut r = stored("b", label, seed, time_s);
        let mut v: serde_json::Value =
            serde_json::from_str(r.summary_json.as_deref().unwrap()).unwrap();
        v["end_reason"] = serde_json::json!(end_reason);
        v["explored_fraction"] = serde_json::json!(fraction);
        v["stopped_early"] = serde_json::json!(end_reason == "early stop");
        v["start"] = serde_json::json!(start);
        r.summary_json = Some(v.to_string());
        r.job_id = format!("{label}-{seed}-{}", start[0]);
        r
    }

    #[test]
    fn every_end_class_is_counted_and_only_normal_ends_are_timed() {
        let s0 = [1.0, 2.0, 0.0];
        // (seed, time_s, end_reason, explored_fraction): the baseline's runs.
        let runs = [
            (1, 100.0, "complete", 1.0),
            (2, 200.0, "no frontiers", 0.99), // written before the classes: complete
            (3, 300.0, "early stop", 0.98),
            (4, 14400.0, "time limit", 0.6),
            (5, 500.0, "stuck", 0.9),
            (6, 600.0, "frontiers unreachable", 0.95),
            (7, 700.0, "complete", 0.96), // complete, but short of 97 %
            (8, 800.0, "stuck", 0.99),    // slivers left: explored what it could
            (9, 900.0, "frontiers unreachable", 0.98),
        ];
        let mut results: Vec<StoredResult> = runs
            .iter()
            .map(|&(seed, t, end, f)| stored_end("baseline", seed, t, end, f, s0))
            .collect();
        // The other label completes every seed in half the time.
        for &(seed, t, _, _) in &runs {
            results.push(stored_end("layout", seed, t / 2.0, "complete", 1.0, s0));
        }
        let t = table(&results, &["baseline".into(), "layout".into()]);
        let base = &t.overall[0];
        let counts: Vec<(&str, usize)> = base.ends.iter().map(|(c, n)| (c.as_str(), *n)).collect();
        assert_eq!(
            counts,
            [
                ("complete", 3),
                ("early stop", 1),
                ("time limit", 1),
                ("stuck", 2),
                ("frontiers unreachable", 2)
            ]
        );
        // Times of the complete and early-stop runs, and of the stuck and unreachable ones
        // that explored at least 97 %: 100, 200, 300, 700, 800, 900.
        assert_eq!(base.time.n, 6);
        assert_eq!(base.time.mean, 500.0);
        assert_eq!(base.left_out, 3);
        assert_eq!(base.short, 4);
        assert_eq!(base.explored_fraction.n, 9);
        // Pairs only where the baseline ended normally; no plain gain over different runs.
        let layout = &t.overall[1];
        assert_eq!(layout.left_out, 0);
        assert_eq!(layout.paired.unwrap().pairs, 6);
        assert_eq!(layout.paired.unwrap().mean_pct, 50.0);
        assert_eq!(layout.gain_pct, None);
        let text = render_text(&t);
        for needle in [
            "(3 left out: 1 time limit, 1 stuck, 1 frontiers unreachable; 4 short of 97 %)",
            "left out of the times and gains: 3 runs",
            "(1 time limit, 1 stuck, 1 frontiers unreachable)",
            "4 runs ended with less than 97 %",
            "gain '-'",
        ] {
            assert!(text.contains(needle), "{needle}: {text}");
        }
        let ends = render_ends(&t);
        let line = |label: &str| {
            ends.lines()
                .find(|l| l.trim_start().starts_with(label))
                .unwrap()
                .split_whitespace()
                .skip(1)
                .collect::<Vec<_>>()
                .join(" ")
        };
        assert_eq!(line("baseline"), "3 1 1 2 2 4", "{ends}");
        assert_eq!(line("layout"), "9 0 0 0 0 0", "{ends}");
        assert!(ends.contains("frontiers unreachable"), "{ends}");
    }

    #[test]
    fn an_unknown_end_is_left_out_and_shown() {
        let s0 = [1.0, 2.0, 0.0];
        let results = vec![
            stored_end("baseline", 1, 100.0, "complete", 1.0, s0),
            stored_end("baseline", 2, 900.0, "meteor", 1.0, s0),
        ];
        let t = table(&results, &[]);
        assert_eq!(t.overall[0].time.n, 1);
        assert_eq!(t.overall[0].left_out, 1);
        assert!(render_text(&t).contains("1 meteor"), "{}", render_text(&t));
        assert!(render_ends(&t).contains("meteor"));
    }

    #[test]
    fn tables_of_normal_ends_carry_no_marks() {
        let s0 = [1.0, 2.0, 0.0];
        let results: Vec<StoredResult> = [(1, "complete"), (2, "no frontiers"), (3, "early stop")]
            .iter()
            .flat_map(|&(seed, end)| {
                [
                    stored_end("baseline", seed, 100.0, end, 0.99, s0),
                    stored_end("layout", seed, 90.0, end, 0.99, s0),
                ]
            })
            .collect();
        let t = table(&results, &[]);
        let text = render_text(&t);
        assert!(
            !text.contains("left out") && !text.contains("short") && !text.contains("gain '-'"),
            "{text}"
        );
        assert!(text.contains("+10.0 %"), "{text}");
        assert_eq!(t.overall[0].time.n, 3);
    }

    #[test]
    fn runs_from_different_starts_pair_with_the_reference_from_the_same_start() {
        // One seed, two start poses: layout is 10 % faster from one and 30 % from the other.
        let (a, b) = ([1.0, 2.0, 0.5], [3.0, 4.0, -1.0]);
        let results = vec![
            stored_end("baseline", 1, 100.0, "complete", 1.0, a),
            stored_end("baseline", 1, 200.0, "complete", 1.0, b),
            stored_end("layout", 1, 90.0, "complete", 1.0, a),
            stored_end("layout", 1, 140.0, "complete", 1.0, b),
        ];
        let t = table(&results, &[]);
        let p = t.overall[1].paired.unwrap();
        assert_eq!(p.pairs, 2);
        assert!((p.mean_pct - 20.0).abs() < 1e-9, "{p:?}");
        assert_eq!(t.overall[1].time.n, 2);
        // The CSV carries each start pose exactly.
        let csv = results_csv(&results);
        let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
        let col = |row: &str, name: &str| {
            row.split(',')
                .nth(header.iter().position(|h| *h == name).unwrap())
                .unwrap()
                .to_string()
        };
        let row = csv.lines().nth(2).unwrap();
        assert_eq!(col(row, "start_x_m"), "3");
        assert_eq!(col(row, "start_y_m"), "4");
        assert_eq!(col(row, "start_theta_rad"), "-1");
        assert_eq!(col(row, "start_source"), "building file");
    }

    #[test]
    fn the_unexplored_area_integrates_what_is_left_to_see() {
        let csv = "time_s,explored_area_m2,explored_fraction\n0,0,0\n10,5,0.5\n20,10,1.0\n";
        // 10 s at 1 -> 0.5 unexplored (7.5 s), 10 s at 0.5 -> 0 (2.5 s).
        assert_eq!(unexplored_area_s(csv), Some(10.0));
        assert_eq!(
            unexplored_area_s("time_s,explored_area_m2,explored_fraction\n"),
            None
        );
    }

    #[test]
    fn time_to_a_fraction_is_the_first_sample_reaching_it() {
        let p = "time_s,explored_area_m2,explored_fraction\n0,0,0\n2,5,0.5\n4,9,0.9\n6,10,1\n";
        assert_eq!(time_to_fraction(p, 0.9), Some(4.0));
        assert_eq!(time_to_fraction(p, 0.4), Some(2.0));
        assert_eq!(time_to_fraction(p, 1.1), None);
        assert_eq!(time_to_fraction("time_s\nnot,a,number\n", 0.5), None);
        let mut r = stored("b", "baseline", 1, 6.0);
        r.progress_csv = Some(p.into());
        let csv = results_csv(&[r]);
        let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
        let row: Vec<&str> = csv.lines().nth(1).unwrap().split(',').collect();
        let k = header.iter().position(|h| *h == "time_to_90_s").unwrap();
        assert_eq!(row[k], "4");
        assert_eq!(header.len(), row.len());
        // A summary written before `rooms_unexplored` existed still reads; its cell is empty.
        let col = |name: &str| row[header.iter().position(|h| *h == name).unwrap()];
        assert_eq!(col("rooms_never_entered"), "0");
        assert_eq!(col("rooms_unexplored"), "");
        assert_eq!(col("unexplored_free_m2"), "0.22750000000002046");
        // Summaries written before the end classes said "no frontiers": complete.
        assert_eq!(col("end_reason"), "complete");
        assert_eq!(col("start_x_m"), "1.1999999999999993");
        assert_eq!(col("start_theta_rad"), "0");
    }

    #[test]
    fn progress_curves_hold_the_final_fraction_of_runs_that_ended_and_mark_early_stops() {
        let mut a = stored("b1", "baseline", 1, 4.0);
        a.progress_csv =
            Some("time_s,explored_area_m2,explored_fraction\n0,0,0\n2,5,0.5\n4,10,1\n".into());
        let mut b = stored("b1", "baseline", 2, 2.0);
        b.progress_csv =
            Some("time_s,explored_area_m2,explored_fraction\n0,0,0.2\n2,8,0.8\n".into());
        let mut c = stored("b1", "layout", 1, 2.0);
        c.progress_csv = Some("time_s,explored_area_m2,explored_fraction\n0,0,0\n2,1,1\n".into());
        let mut summary: serde_json::Value =
            serde_json::from_str(c.summary_json.as_deref().unwrap()).unwrap();
        summary["stopped_early"] = true.into();
        summary["explored_fraction"] = 0.97.into();
        c.summary_json = Some(summary.to_string());
        let other = stored("b2", "baseline", 1, 1.0);
        let curves = progress_curves(&[c, a, b, other], "b1", &["baseline".into()], 3);
        let labels: Vec<&str> = curves.iter().map(|c| c.label.as_str()).collect();
        assert_eq!(labels, ["baseline", "layout"]);
        // t = 0, 2, 4: baseline (0 + 0.2) / 2, (0.5 + 0.8) / 2, (1 + 0.8) / 2, with the range.
        let want = [
            (0.0, 0.1, 0.0, 0.2),
            (2.0, 0.65, 0.5, 0.8),
            (4.0, 0.9, 0.8, 1.0),
        ];
        for (got, want) in curves[0].points.iter().zip(want) {
            let close = |a: f64, b: f64| (a - b).abs() < 1e-12;
            assert!(
                close(got.0, want.0)
                    && close(got.1, want.1)
                    && close(got.2, want.2)
                    && close(got.3, want.3),
                "{:?}",
                curves[0].points
            );
        }
        assert_eq!(curves[0].runs, 2);
        assert!(curves[0].early_stops.is_empty());
        assert_eq!(curves[1].points[2], (4.0, 1.0, 1.0, 1.0));
        assert_eq!(curves[1].early_stops, [(2.0, 0.97)]);
        assert!(progress_curves(&[], "b1", &[], 10).is_empty());
    }
}
