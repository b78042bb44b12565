//! The grid's version of the paper's Table 1, computed from stored results, and the comparisons
//! of `report` (`docs/statistics.md` says why they are made this way).
//!
//! Every comparison is at a coverage level ([`crate::outcome`]): a run *achieves* the outcome
//! when it ends with at least that fraction of the explorable area explored. Per strategy label
//! the table gives the exploration time of the runs that achieved it (mean and standard
//! deviation: descriptive), how many did not and why, and the **paired gain** over the reference:
//! per pair of runs (same building, seed and start pose) the log ratio `ln t_ref - ln t`, a run
//! that did not achieve the outcome charged the pair's horizon (so it never wins), their mean
//! `m` shown as the gain `1 - exp(-m)` in per cent with its 95 % interval. Swapping the
//! reference negates `m` exactly.

use std::collections::BTreeMap;
use std::fmt::Write as _;

use floorcast_worker::RunSummary;

use crate::metric::{time_to_fraction, Metric};
use crate::outcome::{self, coverage_text, end_class, end_classes, label_order, Pair, PairCounts};
use crate::progress::Sample;
// A gain in per cent of the reference's time from a mean log ratio `m = ln t_ref - ln t`.
use crate::sprt::gain_pct_of_effect as gain_pct;
use crate::StoredResult;

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

/// One row per strategy label.
#[derive(Debug, Clone, PartialEq)]
pub struct LabelRow {
    pub label: String,
    /// The measured time ([`Table::measure`]) of the runs that achieved the outcome
    /// (descriptive: runs that did not are not in it, see `not_achieved`).
    pub time: Stat,
    /// Of the same runs: the time to 90 % and to 99 % explored (those whose stored progress
    /// curve has it) and to the end (their exploration time).
    pub time_to_90: Stat,
    pub time_to_99: Stat,
    pub time_to_end: Stat,
    /// Explored fraction of every successful run.
    pub explored_fraction: Stat,
    pub stopped_early: usize,
    pub failed: usize,
    /// Successful runs per end class: every class of [`end_classes`] in order (zeros
    /// included).
    pub ends: Vec<(String, usize)>,
    /// Successful runs that ended below the coverage level.
    pub not_achieved: usize,
    /// Those runs per end class (classes with none omitted).
    pub not_achieved_ends: Vec<(String, usize)>,
    /// The paired gain over the reference; `None` without common pairs.
    pub paired: Option<PairedGain>,
}

/// The paired gain of a label over the reference: statistics of the per-pair log ratios
/// `ln t_ref - ln t` (runs that did not achieve the outcome charged the pair's horizon).
#[derive(Debug, Clone, PartialEq)]
pub struct PairedGain {
    pub pairs: usize,
    /// Mean and standard deviation of the log ratios.
    pub mean_log: f64,
    pub sd_log: f64,
    /// Half-width of Student's t 95 % interval of the mean log ratio; NaN for one pair.
    pub t_half_log: f64,
    /// The Hodges-Lehmann estimate of the log ratios ([`crate::stats::hodges_lehmann`]): the
    /// headline, which the size of a shortfall's charge cannot swing; and its 95 % interval
    /// (`None` below 6 pairs).
    pub hl_log: f64,
    pub hl_ci95_log: Option<(f64, f64)>,
    /// What the pairs achieved.
    pub counts: PairCounts,
}

impl PairedGain {
    /// From the pairs (`None` without one).
    pub fn of(pairs: &[Pair]) -> Option<PairedGain> {
        let xs: Vec<f64> = pairs.iter().map(Pair::log_ratio).collect();
        let mut g = PairedGain::of_log_ratios(&xs)?;
        g.counts = PairCounts::of(pairs);
        Some(g)
    }

    /// From log ratios alone (`counts` empty).
    pub fn of_log_ratios(xs: &[f64]) -> Option<PairedGain> {
        let s = Stat::of(xs);
        (s.n > 0).then(|| PairedGain {
            pairs: s.n,
            mean_log: s.mean,
            sd_log: s.sd,
            t_half_log: if s.n > 1 {
                t95(s.n - 1) * s.sd / (s.n as f64).sqrt()
            } else {
                f64::NAN
            },
            hl_log: crate::stats::hodges_lehmann(xs).unwrap_or(f64::NAN),
            hl_ci95_log: crate::stats::hodges_lehmann_ci95(xs),
            counts: PairCounts::default(),
        })
    }

    /// The gain in per cent, `1 - exp(-m)`.
    pub fn gain_pct(&self) -> f64 {
        gain_pct(self.mean_log)
    }

    /// The t interval as gains in per cent (`None` for one pair).
    pub fn ci_pct(&self) -> Option<(f64, f64)> {
        self.t_half_log.is_finite().then(|| {
            (
                gain_pct(self.mean_log - self.t_half_log),
                gain_pct(self.mean_log + self.t_half_log),
            )
        })
    }

    /// The Hodges-Lehmann estimate as a gain in per cent, `1 - exp(-hl)`.
    pub fn hl_gain_pct(&self) -> f64 {
        gain_pct(self.hl_log)
    }

    /// `+1.9 % [-3.1, +6.6] (n=3)`: the mean gain with its t interval, or without the interval
    /// for one pair; `, 2 lost` when the label did not achieve the outcome in pairs where the
    /// reference did. A gain below -100 % is shown as a time ratio ("2.2x slower").
    pub fn cell(&self) -> String {
        let lost = match self.counts.label_only_not_achieved {
            0 => String::new(),
            k => format!(", {k} lost"),
        };
        match self.ci_pct() {
            Some((lo, hi)) => format!(
                "{} {} (n={}{lost})",
                gain_text(self.gain_pct(), true),
                gain_range_text(Some([lo, hi])),
                self.pairs
            ),
            None => format!(
                "{} (n={}{lost})",
                gain_text(self.gain_pct(), true),
                self.pairs
            ),
        }
    }
}

/// A gain in per cent as text: `+9.4` (with ` %` when `unit`), or the time ratio when the gain is
/// below -100 % (the label more than twice as slow), `2.2x slower`, where a percentage reads
/// oddly.
pub(crate) fn gain_text(g: f64, unit: bool) -> String {
    if !g.is_finite() {
        "-".to_string()
    } else if g < -100.0 {
        format!("{:.1}x slower", 1.0 - g / 100.0)
    } else if unit {
        format!("{g:+.1} %")
    } else {
        format!("{g:+.1}")
    }
}

/// A p-value as text: four decimals, or scientific notation below 0.001 (`3e-5`, not
/// `0.0000`).
pub(crate) fn p_text(p: Option<f64>) -> String {
    match p {
        None => "-".to_string(),
        Some(p) if p < 1e-3 => format!("{p:.0e}"),
        Some(p) => format!("{p:.4}"),
    }
}

/// Two-sided 95 % quantile of Student's t with `df` degrees of freedom (NaN for none).
fn t95(df: usize) -> f64 {
    use statrs::distribution::{ContinuousCDF, StudentsT};
    StudentsT::new(0.0, 1.0, df as f64).map_or(f64::NAN, |t| t.inverse_cdf(0.975))
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

/// What a stored run of a label was run with: the strategy, the settings (each setting the row
/// does not hold, stored by a version that had not got it yet, at its default: the value that
/// version ran with) and an external program's identity (its command, files and their hash, its
/// params; not its timeout). A label stands for one configuration.
#[derive(Debug, Clone, PartialEq)]
pub struct Configuration {
    pub strategy: String,
    pub settings: serde_json::Map<String, serde_json::Value>,
    pub program: Option<serde_json::Value>,
}

impl Configuration {
    /// The configuration of a stored row (the store has put each setting the row does not hold
    /// at its default).
    pub fn of_row(r: &StoredResult) -> Configuration {
        let program = r.summary.as_ref().and_then(|s| s.strategy_program.as_ref());
        Self::new(&r.strategy, &r.settings, program)
    }

    /// The configuration of `settings` and `program`, each as it is written (a setting by its
    /// name, the program's identity by its fields): a planned job's, for one.
    pub fn new(
        strategy: &str,
        settings: &floorcast_worker::Settings,
        program: Option<&floorcast_worker::StrategyProgram>,
    ) -> Configuration {
        let settings = match serde_json::to_value(settings) {
            Ok(serde_json::Value::Object(m)) => m,
            _ => serde_json::Map::new(),
        };
        // Its identity: all but the timeout.
        let program = program.map(|p| {
            serde_json::json!({
                "command": p.command,
                "files": p.files,
                "files_sha256": p.files_sha256,
                "params": p.params,
            })
        });
        Configuration {
            strategy: strategy.to_string(),
            settings,
            program,
        }
    }

    /// Whether `other` is the same configuration. A row without a summary (a failed job)
    /// stored no program: its program is taken as the same.
    pub fn same(&self, other: &Configuration) -> bool {
        self.strategy == other.strategy
            && self.settings == other.settings
            && (self.program.is_none() || other.program.is_none() || self.program == other.program)
    }

    /// How `other` differs from this one, in a few words ("alpha 0.5 and 0.8").
    pub fn difference(&self, other: &Configuration) -> String {
        use floorcast_worker::text::excerpt;
        if self.strategy != other.strategy {
            return format!(
                "strategy {} and {}",
                excerpt(&self.strategy),
                excerpt(&other.strategy)
            );
        }
        let mut keys: Vec<&String> = self.settings.keys().chain(other.settings.keys()).collect();
        keys.sort();
        keys.dedup();
        for k in keys {
            let (a, b) = (self.settings.get(k), other.settings.get(k));
            if a != b {
                let show = |v: Option<&serde_json::Value>| {
                    v.map_or("(none)".to_string(), |v| excerpt(&v.to_string()))
                };
                return format!("setting {} {} and {}", excerpt(k), show(a), show(b));
            }
        }
        let show = |p: &Option<serde_json::Value>| match p {
            Some(p) => excerpt(&p.to_string()),
            None => "none".into(),
        };
        format!(
            "external program {} and {}",
            show(&self.program),
            show(&other.program)
        )
    }
}

/// What to do when one label stands for two configurations.
const LABEL_REUSED: &str = "the grid's label was reused after its settings changed; give the changed configuration its own label (or use another results directory)";

/// Every label of `results` holds runs of one configuration ([`Configuration`]); else the first
/// label that does not, and how its runs differ, in one line.
pub fn check_label_configurations(results: &[StoredResult]) -> Result<(), String> {
    let mut first: BTreeMap<&str, (Configuration, &str)> = BTreeMap::new();
    for r in results {
        let c = Configuration::of_row(r);
        match first.get(r.label.as_str()) {
            None => {
                first.insert(&r.label, (c, &r.job_id));
            }
            Some((c0, job0)) if !c0.same(&c) => {
                return Err(format!(
                "label '{}' holds runs of two configurations ({}; jobs {} and {}): {LABEL_REUSED}",
                floorcast_worker::text::excerpt(&r.label),
                c0.difference(&c),
                floorcast_worker::text::excerpt(job0),
                floorcast_worker::text::excerpt(&r.job_id)
            ))
            }
            Some((c0, _)) if c0.program.is_none() && c.program.is_some() => {
                // The first row that knows the program stands for the label from here on.
                first.insert(&r.label, (c, &r.job_id));
            }
            Some(_) => {}
        }
    }
    Ok(())
}

/// The labels of a planned grid's jobs (each job's label and configuration, the first of a
/// label standing for it) have, among the stored `results`, only runs of the same configuration
/// as the grid gives them; else the first label that has others, in one line.
pub fn check_planned_labels<'a>(
    jobs: impl IntoIterator<Item = (&'a str, Configuration)>,
    results: &[StoredResult],
) -> Result<(), String> {
    let mut planned: BTreeMap<&str, Configuration> = BTreeMap::new();
    for (label, c) in jobs {
        planned.entry(label).or_insert(c);
    }
    for r in results {
        if let Some(c) = planned.get(r.label.as_str()) {
            let stored = Configuration::of_row(r);
            if !stored.same(c) {
                return Err(format!(
                    "label '{}' already has runs of another configuration in this results directory ({}, stored and in the grid; stored job {}): {LABEL_REUSED}",
                    floorcast_worker::text::excerpt(&r.label),
                    stored.difference(c),
                    floorcast_worker::text::excerpt(&r.job_id)
                ));
            }
        }
    }
    Ok(())
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
/// building under any name), seed and start pose, at `coverage` as every comparison. A positive
/// gain is faster in `results`. For grids that change one thing against a reference grid, e.g.
/// `results/paper-alpha` against `results/paper`.
pub fn gains_against(
    results: &[StoredResult],
    against: &[StoredResult],
    against_label: Option<&str>,
    coverage: f64,
) -> Vec<CrossGain> {
    let hash = |r: &StoredResult| r.building_hash.clone();
    labels_of(results)
        .into_iter()
        .map(|label| {
            let other = against_label.unwrap_or(label);
            let pairing = outcome::pair(
                outcome::outcomes(results, label, coverage, hash),
                outcome::outcomes(against, other, coverage, hash),
            );
            CrossGain {
                label: label.to_string(),
                against_label: other.to_string(),
                gain: PairedGain::of(&pairing.pairs),
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
                "mean_log_ratio": g.gain.as_ref().and_then(|p| finite(p.mean_log)),
                "mean_gain_pct": g.gain.as_ref().and_then(|p| finite(p.gain_pct())),
                "t_ci95_pct": g.gain.as_ref().and_then(|p| p.ci_pct()).map(|(a, b)| [a, b]),
                "label_only_not_achieved": g.gain.as_ref().map_or(0, |p| p.counts.label_only_not_achieved),
                "reference_only_not_achieved": g.gain.as_ref().map_or(0, |p| p.counts.reference_only_not_achieved),
                "neither_achieved": g.gain.as_ref().map_or(0, |p| p.counts.neither_achieved),
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
        "  {:<16}  {:<16}  {:>30}",
        "strategy", "over (there)", "paired gain [95% CI]"
    );
    for g in gains {
        let cell = g
            .gain
            .as_ref()
            .map_or_else(|| "no common runs".to_string(), |p| p.cell());
        let _ = writeln!(
            out,
            "  {:<16}  {:<16}  {cell:>30}",
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
    end_classes()
        .iter()
        .map(|c| (c.to_string(), counts.remove(c).unwrap_or(0)))
        .collect()
}

#[derive(Debug, Clone, PartialEq)]
pub struct Table {
    pub reference: Option<String>,
    /// The coverage level of its outcomes.
    pub coverage: f64,
    /// The time its outcomes measure.
    pub measure: outcome::Measure,
    pub overall: Vec<LabelRow>,
    /// Per building: label rows.
    pub per_building: BTreeMap<String, Vec<LabelRow>>,
}

/// Builds the table at `coverage`. `labels` gives the order (labels found only in the store
/// come after); the reference is `baseline` if present, else the first label.
pub fn table(results: &[StoredResult], labels: &[String], coverage: f64) -> Table {
    table_against(results, labels, None, coverage)
}

/// [`table`] with the gains over `reference` (default: `baseline` if present, else the first
/// label).
pub fn table_against(
    results: &[StoredResult],
    labels: &[String],
    reference: Option<&str>,
    coverage: f64,
) -> Table {
    table_by(results, labels, reference, coverage, outcome::Measure::End)
}

/// [`table_against`] with the time measured by `measure`.
pub fn table_by(
    results: &[StoredResult],
    labels: &[String],
    reference: Option<&str>,
    coverage: f64,
    measure: outcome::Measure,
) -> Table {
    let order = label_order(results, labels);
    let reference = match reference {
        Some(r) => Some(r.to_string()),
        None => order
            .iter()
            .find(|l| l.as_str() == "baseline")
            .or(order.first())
            .cloned(),
    };
    let rows_for = |subset: &[&StoredResult]| -> Vec<LabelRow> {
        order
            .iter()
            .filter_map(|label| {
                let mine: Vec<&&StoredResult> =
                    subset.iter().filter(|r| &r.label == label).collect();
                if mine.is_empty() {
                    return None;
                }
                let summaries: Vec<&RunSummary> = mine
                    .iter()
                    .filter(|r| r.status.is_ok())
                    .filter_map(|r| r.summary.as_ref())
                    .collect();
                let achieves = |s: &RunSummary| outcome::achieves(s, coverage);
                let achieved: Vec<&&&StoredResult> = mine
                    .iter()
                    .filter(|r| r.status.is_ok() && r.summary.as_ref().is_some_and(&achieves))
                    .collect();
                let times: Vec<f64> = achieved
                    .iter()
                    .filter_map(|r| {
                        outcome::outcome_by(r, coverage, &r.building, measure).achieved_s
                    })
                    .collect();
                let to = |f: f64| -> Stat {
                    Stat::of(
                        &achieved
                            .iter()
                            .filter_map(|r| time_to_fraction(r.progress.as_deref()?, f))
                            .collect::<Vec<f64>>(),
                    )
                };
                let ends: Vec<f64> = achieved
                    .iter()
                    .filter_map(|r| r.summary.as_ref().map(|s| s.exploration_time_s))
                    .collect();
                let fracs: Vec<f64> = summaries.iter().map(|s| s.explored_fraction).collect();
                let paired = reference.as_ref().and_then(|r| {
                    PairedGain::of(
                        &outcome::paired_by(subset.iter().copied(), label, r, coverage, measure)
                            .pairs,
                    )
                });
                Some(LabelRow {
                    label: label.clone(),
                    time: Stat::of(&times),
                    time_to_90: to(0.90),
                    time_to_99: to(0.99),
                    time_to_end: Stat::of(&ends),
                    explored_fraction: Stat::of(&fracs),
                    stopped_early: summaries.iter().filter(|s| s.stopped_early).count(),
                    failed: mine.len() - summaries.len(),
                    ends: count_ends(summaries.iter().copied()),
                    not_achieved: summaries.len() - times.len(),
                    not_achieved_ends: count_ends(
                        summaries.iter().copied().filter(|s| !achieves(s)),
                    )
                    .into_iter()
                    .filter(|(_, n)| *n > 0)
                    .collect(),
                    paired,
                })
            })
            .collect()
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
    let overall = rows_for(&all);
    Table {
        reference: reference.clone(),
        coverage,
        measure,
        overall,
        per_building,
    }
}

fn fmt_rows(out: &mut String, rows: &[LabelRow], reference: Option<&String>, coverage: f64) {
    let _ = writeln!(
        out,
        "  {:<16} {:>5} {:>8} {:>8} {:>8} {:>8} {:>10} {:>9} {:>32} {:>9} {:>5}",
        "strategy",
        "runs",
        format!(">={:.0}%", coverage * 100.0),
        "t90 (s)",
        "t99 (s)",
        "end (s)",
        "time (s)",
        "sd (s)",
        "paired gain [95% CI]",
        "explored",
        "ES"
    );
    for r in rows {
        let is_reference = reference.is_some_and(|reference| &r.label == reference);
        let paired = match &r.paired {
            _ if is_reference => "ref".to_string(),
            Some(p) => p.cell(),
            None => "-".into(),
        };
        let mut marks = Vec::new();
        if r.failed > 0 {
            marks.push(format!("{} failed", r.failed));
        }
        if r.not_achieved > 0 {
            let classes: Vec<String> = r
                .not_achieved_ends
                .iter()
                .map(|(c, n)| format!("{n} {c}"))
                .collect();
            marks.push(format!(
                "{} below {}: {}",
                r.not_achieved,
                coverage_text(coverage),
                classes.join(", ")
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
            "  {:<16} {:>5} {:>8} {:>8} {:>8} {:>8} {:>10} {:>9} {:>32} {:>9} {:>5}{}",
            r.label,
            r.failed + r.ends.iter().map(|(_, n)| n).sum::<usize>(),
            r.time.n,
            number(r.time_to_90.mean, 0),
            number(r.time_to_99.mean, 0),
            number(r.time_to_end.mean, 0),
            number(r.time.mean, 0),
            number(r.time.sd, 0),
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
/// one, at a coverage level: statistics of the per-pair log ratios `ln t_ref - ln t` (positive:
/// the label is faster), over every pair of runs (same building, seed and start pose), a run
/// that did not achieve the outcome charged the pair's horizon.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Comparison {
    pub label: String,
    pub reference: String,
    pub building: Option<String>,
    /// The coverage level: a run achieves the outcome with at least this fraction explored.
    pub coverage: f64,
    /// The time measured: "end" or "coverage" ([`crate::outcome::Measure`]).
    pub measure: &'static str,
    pub pairs: usize,
    /// The label's runs without a partner among the reference's.
    pub unpaired: usize,
    /// What the pairs achieved, side by side.
    #[serde(flatten)]
    pub counts: PairCounts,
    /// Mean and standard deviation of the log ratios.
    pub mean_log_ratio: Option<f64>,
    pub sd_log_ratio: Option<f64>,
    /// The mean as a gain, `100 (1 - exp(-mean_log_ratio))` (positive: the label is faster).
    pub mean_gain_pct: Option<f64>,
    /// The headline: the Hodges-Lehmann estimate of the log ratios (the median of their Walsh
    /// averages; a shortfall's charge moves it by rank only), with its Wilcoxon-based 95 %
    /// interval (at least 6 pairs), and both as gains in per cent.
    pub hl_log_ratio: Option<f64>,
    pub hl_gain_pct: Option<f64>,
    pub hl_ci95_log: Option<[f64; 2]>,
    pub hl_ci95_pct: Option<[f64; 2]>,
    /// When pairs with a run below the coverage level decide the comparison (any such pair, at
    /// a coverage level above 0.98): the Hodges-Lehmann gain and the mean gain at 0.98, in per
    /// cent, and the pairs with a shortfall there. `None` otherwise.
    pub sensitivity_98: Option<Sensitivity>,
    /// Student's t 95 % interval of the mean log ratio, and as gains in per cent.
    pub t_ci95_log: Option<[f64; 2]>,
    pub t_ci95_pct: Option<[f64; 2]>,
    /// The seeded percentile bootstrap 95 % interval of the mean log ratio
    /// ([`crate::stats::bootstrap_mean_ci95`]), and as gains.
    pub bootstrap_ci95_log: Option<[f64; 2]>,
    pub bootstrap_ci95_pct: Option<[f64; 2]>,
    /// The anytime-valid 95 % interval of the mean log ratio ([`crate::stats::confidence_sequence`]):
    /// it holds after a sequential stop, where the fixed-sample ones do not; and as gains.
    pub anytime_ci95_log: Option<[f64; 2]>,
    pub anytime_ci95_pct: Option<[f64; 2]>,
    /// Two-sided Wilcoxon signed-rank p-value of the log ratios.
    pub wilcoxon_p: Option<f64>,
    /// `wilcoxon_p` adjusted by Holm's method within its family ([`Comparison::family`]).
    pub holm_p: Option<f64>,
    /// The Holm family: "headline" (the comparisons over all buildings, one per label) or
    /// "per-building" (the per-building rows, descriptive, adjusted among themselves).
    pub family: &'static str,
    /// Cohen's d_z of the log ratios: their mean over their standard deviation.
    pub effect_size_dz: Option<f64>,
    /// The other metrics, paired the same way over the successful runs (see [`Metric`]).
    pub metrics: BTreeMap<Metric, MetricGain>,
}

/// A comparison again at a lower coverage level (0.98), to show how much the runs that fell
/// just short decide it.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Sensitivity {
    pub coverage: f64,
    pub hl_gain_pct: Option<f64>,
    pub mean_gain_pct: Option<f64>,
    /// Pairs where at least one run stayed below that level.
    pub pairs_short: usize,
}

/// A paired comparison of one metric: per pair, the log ratio `ln ref - ln x` for the metrics
/// where lower is better (shown as a gain `1 - exp(-mean)` in per cent), and `x - ref` in
/// percentage points for the explored fraction.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct MetricGain {
    pub pairs: usize,
    /// The mean: a gain in per cent, or percentage points.
    pub mean: Option<f64>,
    /// Student's t 95 % interval of the mean, in the same unit.
    pub t_ci95: Option<[f64; 2]>,
}

/// What pairs a run with the reference's for the other metrics: building, seed and start pose.
type PairKey = (String, u64, [u64; 3]);

/// `metric` of `label`'s successful runs in `subset` (those that have it), by pair key.
fn metric_by_pair(subset: &[&StoredResult], label: &str, metric: Metric) -> BTreeMap<PairKey, f64> {
    subset
        .iter()
        .filter(|r| r.label == label && r.status.is_ok())
        .filter_map(|r| {
            let s = r.summary.as_ref()?;
            let v = metric.of(s, r.progress.as_deref().unwrap_or_default())?;
            v.is_finite()
                .then(|| ((r.building.clone(), r.seed, s.start.map(f64::to_bits)), v))
        })
        .collect()
}

/// The paired comparisons of every [`Metric`] of `label` with `reference`.
fn metric_gains(
    subset: &[&StoredResult],
    label: &str,
    reference: &str,
) -> BTreeMap<Metric, MetricGain> {
    Metric::ALL
        .into_iter()
        .map(|metric| {
            let mine = metric_by_pair(subset, label, metric);
            let theirs = metric_by_pair(subset, reference, metric);
            let points = metric.in_points();
            let diffs: Vec<f64> = mine
                .iter()
                .filter_map(|(k, v)| {
                    let r = *theirs.get(k)?;
                    if points {
                        Some(v - r)
                    } else {
                        (r > 0.0 && *v > 0.0).then(|| r.ln() - v.ln())
                    }
                })
                .collect();
            let p = PairedGain::of_log_ratios(&diffs);
            let shown = |x: f64| if points { x } else { gain_pct(x) };
            let gain = MetricGain {
                pairs: diffs.len(),
                mean: p.as_ref().map(|p| shown(p.mean_log)),
                t_ci95: p.as_ref().filter(|p| p.t_half_log.is_finite()).map(|p| {
                    [
                        shown(p.mean_log - p.t_half_log),
                        shown(p.mean_log + p.t_half_log),
                    ]
                }),
            };
            (metric, gain)
        })
        .collect()
}

/// `[a, b]` of a pair.
fn span(v: Option<(f64, f64)>) -> Option<[f64; 2]> {
    v.map(|(a, b)| [a, b])
}

/// A log-space interval as gains in per cent.
fn span_pct(v: Option<[f64; 2]>) -> Option<[f64; 2]> {
    v.map(|[a, b]| [gain_pct(a), gain_pct(b)])
}

/// The coverage level of the sensitivity line ([`Comparison::sensitivity_98`]).
pub const SENSITIVITY_COVERAGE: f64 = 0.98;

/// The comparison of `label` with `reference` over `subset`.
fn compare(
    subset: &[&StoredResult],
    label: &str,
    reference: &str,
    building: Option<String>,
    coverage: f64,
    measure: outcome::Measure,
) -> Option<Comparison> {
    if !subset.iter().any(|r| r.label == label) {
        return None;
    }
    let pairing = outcome::paired_by(subset.iter().copied(), label, reference, coverage, measure);
    let xs: Vec<f64> = pairing.pairs.iter().map(Pair::log_ratio).collect();
    let paired = PairedGain::of(&pairing.pairs);
    let t_log = paired
        .as_ref()
        .filter(|p| p.t_half_log.is_finite())
        .map(|p| [p.mean_log - p.t_half_log, p.mean_log + p.t_half_log]);
    let boot = span(crate::stats::bootstrap_mean_ci95(&xs));
    let anytime = span(crate::stats::confidence_sequence(&xs));
    let hl = paired.as_ref().and_then(|p| finite(p.hl_log));
    let hl_ci = paired.as_ref().and_then(|p| span(p.hl_ci95_log));
    let family = if building.is_none() {
        "headline"
    } else {
        "per-building"
    };
    let counts = PairCounts::of(&pairing.pairs);
    let short = counts.label_only_not_achieved
        + counts.reference_only_not_achieved
        + counts.neither_achieved;
    let sensitivity_98 =
        (building.is_none() && short > 0 && coverage > SENSITIVITY_COVERAGE).then(|| {
            let p = outcome::paired_by(
                subset.iter().copied(),
                label,
                reference,
                SENSITIVITY_COVERAGE,
                measure,
            );
            let g = PairedGain::of(&p.pairs);
            Sensitivity {
                coverage: SENSITIVITY_COVERAGE,
                hl_gain_pct: g.as_ref().and_then(|g| finite(g.hl_gain_pct())),
                mean_gain_pct: g.as_ref().and_then(|g| finite(g.gain_pct())),
                pairs_short: g.as_ref().map_or(0, |g| g.pairs - g.counts.both_achieved),
            }
        });
    Some(Comparison {
        label: label.to_string(),
        reference: reference.to_string(),
        building,
        coverage,
        measure: measure.as_str(),
        pairs: xs.len(),
        unpaired: pairing.unpaired,
        counts,
        mean_log_ratio: paired.as_ref().and_then(|p| finite(p.mean_log)),
        sd_log_ratio: paired
            .as_ref()
            .filter(|p| p.pairs > 1)
            .and_then(|p| finite(p.sd_log)),
        mean_gain_pct: paired.as_ref().and_then(|p| finite(p.gain_pct())),
        hl_log_ratio: hl,
        hl_gain_pct: hl.map(gain_pct),
        hl_ci95_log: hl_ci,
        hl_ci95_pct: span_pct(hl_ci),
        sensitivity_98,
        t_ci95_log: t_log,
        t_ci95_pct: span_pct(t_log),
        bootstrap_ci95_log: boot,
        bootstrap_ci95_pct: span_pct(boot),
        anytime_ci95_log: anytime,
        anytime_ci95_pct: span_pct(anytime),
        wilcoxon_p: crate::stats::wilcoxon_signed_rank_p(&xs),
        holm_p: None,
        family,
        effect_size_dz: crate::stats::effect_size_dz(&xs),
        metrics: metric_gains(subset, label, reference),
    })
}

/// The comparisons of every label (in `order`, then as they appear) with `reference` at
/// `coverage`, over all buildings and then per building. Holm's adjustment runs within two
/// families: the comparisons over all buildings (the headline results, one per label) and,
/// apart, the per-building rows (descriptive).
pub fn comparisons(
    results: &[StoredResult],
    order: &[String],
    reference: &str,
    coverage: f64,
) -> Vec<Comparison> {
    comparisons_by(results, order, reference, coverage, outcome::Measure::End)
}

/// [`comparisons`] with the time measured by `measure`.
pub fn comparisons_by(
    results: &[StoredResult],
    order: &[String],
    reference: &str,
    coverage: f64,
    measure: outcome::Measure,
) -> Vec<Comparison> {
    let mut out = Vec::new();
    let labels: Vec<String> = label_order(results, order)
        .into_iter()
        .filter(|l| l != reference)
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
        for label in &labels {
            out.extend(compare(
                &subset,
                label,
                reference,
                building.clone(),
                coverage,
                measure,
            ));
        }
    }
    for family in ["headline", "per-building"] {
        let idx: Vec<usize> = (0..out.len())
            .filter(|&i| out[i].family == family)
            .collect();
        let ps: Vec<Option<f64>> = idx.iter().map(|&i| out[i].wilcoxon_p).collect();
        for (&i, p) in idx.iter().zip(crate::stats::holm(&ps)) {
            out[i].holm_p = p;
        }
    }
    out
}

/// Fewest pairs for a bootstrap interval shown without a warning.
pub const BOOTSTRAP_MIN_PAIRS: usize = 10;

/// The comparisons over all buildings as text: one line each. `sequential` names the labels
/// whose comparison a sequential test decided: their fixed-sample intervals are marked as
/// such and the anytime-valid interval is the one shown first.
/// A gain's interval as text (`[+6.3, +12.4]`), `-` without one. When an end falls below
/// -100 %, both ends are time ratios to the reference's (`[1.5x, 3.0x the time]`), never a
/// ratio and a percentage side by side.
pub(crate) fn gain_range_text(r: Option<[f64; 2]>) -> String {
    r.map_or("-".to_string(), |[a, b]| {
        if a < -100.0 || b < -100.0 {
            let ratio = |g: f64| 1.0 - g / 100.0;
            let (x, y) = (ratio(a).min(ratio(b)), ratio(a).max(ratio(b)));
            format!("[{x:.1}x, {y:.1}x the time]")
        } else {
            format!("[{}, {}]", gain_text(a, false), gain_text(b, false))
        }
    })
}

/// A comparison's bootstrap interval as text, said unreliable under [`BOOTSTRAP_MIN_PAIRS`].
fn bootstrap_text(c: &Comparison) -> String {
    let r = gain_range_text(c.bootstrap_ci95_pct);
    if c.pairs < BOOTSTRAP_MIN_PAIRS && c.bootstrap_ci95_pct.is_some() {
        format!("{r} (only {} pairs: unreliable)", c.pairs)
    } else {
        r
    }
}

pub(crate) fn render_comparisons(cs: &[Comparison], sequential: &[String]) -> String {
    let mut out = String::new();
    let overall: Vec<&Comparison> = cs.iter().filter(|c| c.building.is_none()).collect();
    if overall.is_empty() {
        return out;
    }
    let coverage = coverage_text(overall[0].coverage);
    let measure = overall[0]
        .measure
        .parse::<outcome::Measure>()
        .unwrap_or_default()
        .text(overall[0].coverage);
    let _ = writeln!(
        out,
        "Paired gains over {} (all buildings; measure: {measure}; per pair ln(t_ref/t), a run below {coverage} explored charged the time limit, a pair of runs both below it scored by explored fraction then time): the headline is the Hodges-Lehmann estimate (median of the Walsh averages: a charge moves it by rank only) with its Wilcoxon 95 % interval; beside it the mean gain 1 - exp(-mean) with 95 % intervals t (fixed-sample), bootstrap, anytime (valid after a sequential stop); Wilcoxon p on the log ratios, Holm-adjusted over the {} headline comparisons; d_z:",
        overall[0].reference,
        overall.len()
    );
    let range = gain_range_text;
    let num =
        |v: Option<f64>, digits: usize| v.map_or("-".to_string(), |v| format!("{v:.digits$}"));
    let pct = |v: Option<f64>| v.map_or("-".to_string(), |m| gain_text(m, true));
    for c in &overall {
        let seq = sequential.contains(&c.label);
        let n = &c.counts;
        let boot = bootstrap_text(c);
        let _ = writeln!(
            out,
            "  {:<16} HL {:>9} {:<16} mean {:>9} t {:<16} boot {:<16} anytime {:<16} p {:<7} Holm {:<7} d_z {:<6} {} pairs ({} both >= {coverage}, {} lost, {} won, {} neither), {} unpaired{}",
            c.label,
            pct(c.hl_gain_pct),
            range(c.hl_ci95_pct),
            pct(c.mean_gain_pct),
            range(c.t_ci95_pct),
            boot,
            range(c.anytime_ci95_pct),
            p_text(c.wilcoxon_p),
            p_text(c.holm_p),
            num(c.effect_size_dz, 2),
            c.pairs,
            n.both_achieved,
            n.label_only_not_achieved,
            n.reference_only_not_achieved,
            n.neither_achieved,
            c.unpaired,
            if seq {
                "; sequential: read the anytime interval (t, bootstrap and p are fixed-sample, biased after its stop)"
            } else {
                ""
            }
        );
        let metric = |m: Metric| {
            c.metrics
                .get(&m)
                .and_then(|g| g.mean)
                .map_or("-".to_string(), |g| {
                    format!("{} ({} pairs)", gain_text(g, true), c.metrics[&m].pairs)
                })
        };
        let _ = writeln!(
            out,
            "  {:<16} mean gain by time to 90 % {}, to 99 % {} (pairs of runs that reached it); by {}: {}",
            "",
            metric(Metric::TimeTo90),
            metric(Metric::TimeTo99),
            measure,
            pct(c.mean_gain_pct)
        );
        if let Some(s) = &c.sensitivity_98 {
            let _ = writeln!(
                out,
                "  {:<16} at {} instead (runs that fell short decide this comparison): HL {}, mean {}, {} pairs with a run below it",
                "",
                coverage_text(s.coverage),
                pct(s.hl_gain_pct),
                pct(s.mean_gain_pct),
                s.pairs_short
            );
        }
    }
    if overall
        .iter()
        .any(|c| c.counts.label_only_not_achieved + c.counts.reference_only_not_achieved > 0)
    {
        let _ = writeln!(
            out,
            "  (lost: pairs where only the label's run stayed below {coverage}, a loss whatever its time; won: only the reference's; neither: both below, scored by explored fraction then time)"
        );
    }
    out
}

/// The format and version of `report --json` (2: comparisons at a coverage level, symmetric
/// log-ratio gains, anytime intervals, Holm families, aggregates across buildings; 3: the
/// measure, the Hodges-Lehmann headline and its interval, the sensitivity at 98 %, the
/// sequential decision in words).
pub const REPORT_FORMAT: &str = "floorcast-report";
pub const REPORT_VERSION: u32 = 3;

/// A sequential grid's last test of a label, as `report` shows it.
#[derive(Debug, Clone, PartialEq)]
pub struct SequentialVerdict {
    pub grid: String,
    pub test: crate::sprt::LabelTest,
}

/// `report --json`: the labels' statistics, every comparison, sequential grids' decisions and
/// the aggregates across buildings (documented in `docs/report-json.md`).
pub(crate) fn report_json(
    results: &[StoredResult],
    order: &[String],
    reference: &str,
    coverage: f64,
    measure: outcome::Measure,
    verdicts: &[SequentialVerdict],
) -> serde_json::Value {
    use serde_json::json;
    let t = table_by(results, order, Some(reference), coverage, measure);
    let label_row = |r: &LabelRow, building: Option<&str>| {
        let mut v = json!({
            "label": r.label,
            "runs_achieved": r.time.n,
            "time_mean_s": finite(r.time.mean),
            "time_sd_s": finite(r.time.sd),
            "explored_fraction_mean": finite(r.explored_fraction.mean),
            "early_stops": r.stopped_early,
            "failed": r.failed,
            "not_achieved": r.not_achieved,
            "not_achieved_ends": r.not_achieved_ends.iter().map(|(c, n)| (c.clone(), *n)).collect::<BTreeMap<String, usize>>(),
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
    let comparisons: Vec<serde_json::Value> =
        comparisons_by(results, order, reference, coverage, measure)
            .into_iter()
            .map(|c| {
                let mut v = serde_json::to_value(&c).unwrap_or_default();
                let seq =
                    c.building
                        .is_none()
                        .then(|| {
                            verdicts.iter().rev().find(|s| {
                                s.test.label == c.label && s.test.reference == c.reference
                            })
                        })
                        .flatten();
                v["decision"] = seq.map_or(serde_json::Value::Null, |s| {
                    json!(s.test.state.decision.as_str())
                });
                v["decision_text"] = seq.map_or(serde_json::Value::Null, |s| {
                    let a = s
                        .test
                        .state
                        .anytime_ci95()
                        .map(|(a, b)| (gain_pct(a), gain_pct(b)));
                    json!(crate::sequential::decision_text(
                        s.test.state.decision,
                        None,
                        a
                    ))
                });
                v["sequential_pairs"] =
                    seq.map_or(serde_json::Value::Null, |s| json!(s.test.state.pairs));
                v["sequential_llr"] = seq
                    .and_then(|s| s.test.state.llr_if_any())
                    .map_or(serde_json::Value::Null, |l| json!(finite(l)));
                v["fixed_sample_intervals_biased"] = json!(seq.is_some());
                v
            })
            .collect();
    json!({
        "format": REPORT_FORMAT,
        "version": REPORT_VERSION,
        "floorcast_version": floorcast_worker::FLOORCAST_VERSION,
        "reference": reference,
        "coverage": coverage,
        "measure": measure.as_str(),
        "runs": results.len(),
        "labels": t.overall.iter().map(|r| label_row(r, None)).collect::<Vec<_>>(),
        "per_building": t.per_building.iter().map(|(b, rows)| (b.clone(), rows.iter().map(|r| label_row(r, Some(b))).collect::<Vec<_>>())).collect::<BTreeMap<String, Vec<serde_json::Value>>>(),
        "comparisons": comparisons,
        "aggregates": crate::aggregate::aggregates_json(&crate::aggregate::aggregates_by(results, order, reference, coverage, measure)),
    })
}

/// A label's other metrics, as means over its successful runs (`null` without one): times to
/// 90, 95 and 99 % explored (over the runs that reached them, with how many did), the
/// unexplored area, path length, explored fraction, rooms left unexplored, map quality.
fn label_metrics<'a>(
    results: impl Iterator<Item = &'a StoredResult>,
    label: &str,
) -> serde_json::Value {
    let runs: Vec<(&RunSummary, &[Sample])> = results
        .filter(|r| r.label == label && r.status.is_ok())
        .filter_map(|r| {
            Some((
                r.summary.as_ref()?,
                r.progress.as_deref().unwrap_or_default(),
            ))
        })
        .collect();
    let mean = |xs: Vec<f64>| finite(Stat::of(&xs).mean).filter(|_| !xs.is_empty());
    let values = |m: Metric| -> Vec<f64> { runs.iter().filter_map(|(s, p)| m.of(s, p)).collect() };
    let mut v = serde_json::json!({
        "explored_fraction_min": runs.iter().map(|(s, _)| s.explored_fraction).reduce(f64::min),
        "rooms_unexplored_total": runs.iter().filter_map(|(s, _)| s.rooms_unexplored).reduce(|a, b| a + b),
        "map_occupied_precision_aligned_mean": mean(runs.iter().map(|(s, _)| s.map_occupied_precision_aligned).collect()),
    });
    for m in [Metric::UnexploredArea, Metric::PathLength] {
        v[format!("{m}_mean")] = serde_json::json!(mean(values(m)));
    }
    for (m, pct) in [
        (Metric::TimeTo90, 90),
        (Metric::TimeTo95, 95),
        (Metric::TimeTo99, 99),
    ] {
        let times = values(m);
        v[format!("runs_reaching_{pct}")] = serde_json::json!(times.len());
        v[format!("{m}_mean")] = serde_json::json!(mean(times));
    }
    v
}

fn finite(v: f64) -> Option<f64> {
    v.is_finite().then_some(v)
}

/// The table as text.
pub fn render_text(t: &Table) -> String {
    let mut out = String::new();
    let coverage = coverage_text(t.coverage);
    let _ = writeln!(
        out,
        "Measure: {} (`time (s)`, mean and sd, and the paired gain). Times of the runs that explored at least {coverage}: to 90 %, to 99 % explored (from their progress curves) and to the end, means; the paired gain over {} (1 - exp(-mean ln(t_ref/t)); a run below {coverage} charged the time limit, a loss; a pair of runs both below it scored by explored fraction then time):",
        t.measure.text(t.coverage),
        t.reference.as_deref().unwrap_or("-")
    );
    fmt_rows(&mut out, &t.overall, t.reference.as_ref(), t.coverage);
    if t.per_building.len() > 1 {
        for (b, rows) in &t.per_building {
            let _ = writeln!(out, "{b}:");
            fmt_rows(&mut out, rows, t.reference.as_ref(), t.coverage);
        }
    }
    let below: usize = t.overall.iter().map(|r| r.not_achieved).sum();
    let failed: usize = t.overall.iter().map(|r| r.failed).sum();
    if below + failed > 0 {
        let mut classes: BTreeMap<&str, usize> = BTreeMap::new();
        for r in &t.overall {
            for (c, n) in &r.not_achieved_ends {
                *classes.entry(c.as_str()).or_default() += n;
            }
        }
        let mut listed: Vec<String> = end_classes()
            .iter()
            .filter_map(|c| classes.remove(c).map(|n| format!("{n} {c}")))
            .collect();
        listed.extend(classes.iter().map(|(c, n)| format!("{n} {c}")));
        if failed > 0 {
            listed.push(format!("{failed} failed"));
        }
        let _ = writeln!(
            out,
            "{} runs did not explore {coverage} ({}): not in `time (s)`, and each a loss in the paired gain against a run that did (against one that did not either: scored by explored fraction, then time); `>={:.0}%` counts the runs that did",
            below + failed,
            listed.join(", "),
            t.coverage * 100.0
        );
    }
    out
}

/// How the runs ended: per strategy label (overall, then per building when there are
/// several), the successful runs of each end class and those below the coverage level.
pub(crate) fn render_ends(t: &Table) -> String {
    let mut out = String::new();
    let classes = end_classes();
    let below = format!("< {}", coverage_text(t.coverage));
    let rows = |out: &mut String, rows: &[LabelRow]| {
        let mut head = format!("  {:<16}", "strategy");
        for c in &classes {
            let _ = write!(head, " {c:>10}");
        }
        let _ = writeln!(out, "{head} {below:>10} {:>7}", "failed");
        for r in rows {
            let mut line = format!("  {:<16}", r.label);
            for c in &classes {
                let n = r.ends.iter().find(|(e, _)| e == c).map_or(0, |(_, n)| *n);
                let _ = write!(line, " {:>w$}", n, w = c.len().max(10));
            }
            let _ = writeln!(
                out,
                "{line} {:>w$} {:>7}",
                r.not_achieved,
                r.failed,
                w = below.len().max(10)
            );
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
        .filter(|r| r.building == building && r.status.is_ok())
    {
        let Some(samples) = r.progress.as_deref() else {
            continue;
        };
        let curve: Vec<(f64, f64)> = samples
            .iter()
            .map(|s| (s.time_s, s.explored_fraction))
            .collect();
        if curve.is_empty() {
            continue;
        }
        let entry = curves.entry(r.label.as_str()).or_default();
        entry.0.push(curve);
        if let Some(s) = &r.summary {
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

/// One line per stored job, for pandas or R. `time_to_90_s` is the simulated time at which the
/// run had explored 90 % (the paper's point from which layout knowledge pays off), empty if it
/// never did. `rooms_never_entered` and `rooms_unexplored` are empty without ground-truth rooms.
/// `end_reason` is the end class ([`end_class`]). The start pose (`start_x_m`, `start_y_m`,
/// `start_theta_rad`, full precision) and where it came from close each line.
pub fn results_csv(results: &[StoredResult]) -> String {
    const HEADER: [&str; 28] = [
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
        Metric::TimeTo90.as_str(),
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
        "suite",
        "suite_hash",
    ];
    let mut w = csv::WriterBuilder::new()
        .terminator(csv::Terminator::Any(b'\n'))
        .from_writer(Vec::new());
    // Writing to memory fails only on a record of another length, which the arrays rule out.
    let _ = w.write_record(HEADER);
    for r in results {
        let sum = r.summary.as_ref();
        let f = |v: Option<f64>| v.map(|x| format!("{x}")).unwrap_or_default();
        let count = |v: Option<usize>| v.map(|x| x.to_string()).unwrap_or_default();
        let row: [String; HEADER.len()] = [
            r.job_id.clone(),
            r.building.clone(),
            r.building_hash.clone(),
            r.strategy.clone(),
            r.label.clone(),
            r.seed.to_string(),
            r.status.as_str().to_string(),
            f(sum.map(|s| s.exploration_time_s)),
            f(sum.map(|s| s.explored_area_m2)),
            f(sum.map(|s| s.free_area_m2)),
            f(sum.map(|s| s.explored_fraction)),
            f(r.progress.as_deref().and_then(|p| time_to_fraction(p, 0.9))),
            f(sum.map(|s| s.path_length_m)),
            sum.map(|s| s.decisions.to_string()).unwrap_or_default(),
            sum.map(|s| s.stopped_early.to_string()).unwrap_or_default(),
            sum.map(end_class).unwrap_or("").to_string(),
            f(sum.map(|s| s.unexplored_free_m2)),
            count(sum.and_then(|s| s.rooms_never_entered)),
            count(sum.and_then(|s| s.rooms_unexplored)),
            r.wall_time_s.to_string(),
            r.worker.clone(),
            r.floorcast_version.clone(),
            f(sum.map(|s| s.start[0])),
            f(sum.map(|s| s.start[1])),
            f(sum.map(|s| s.start[2])),
            sum.map(|s| s.start_source.clone()).unwrap_or_default(),
            sum.and_then(|s| s.suite.clone()).unwrap_or_default(),
            sum.and_then(|s| s.suite_hash.clone()).unwrap_or_default(),
        ];
        let _ = w.write_record(&row);
    }
    String::from_utf8(w.into_inner().unwrap_or_default()).unwrap_or_default()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fixtures::{progress, set_summary, stored, summary_value};
    use crate::metric::unexplored_area_s;

    /// Gains and their intervals as text: percentages, a time ratio below -100 %, and an
    /// interval with an end below -100 % wholly in time ratios.
    #[test]
    fn gains_and_intervals_as_text() {
        let cases: &[(f64, bool, &str)] = &[
            (9.44, true, "+9.4 %"),
            (-49.2, false, "-49.2"),
            (-120.0, true, "2.2x slower"),
            (f64::NAN, true, "-"),
        ];
        for &(g, unit, want) in cases {
            assert_eq!(gain_text(g, unit), want, "{g}");
        }
        let ranges: &[(Option<[f64; 2]>, &str)] = &[
            (Some([6.3, 12.4]), "[+6.3, +12.4]"),
            (Some([-200.0, -49.2]), "[1.5x, 3.0x the time]"),
            (Some([-200.0, 10.0]), "[0.9x, 3.0x the time]"),
            (None, "-"),
        ];
        for &(r, want) in ranges {
            assert_eq!(gain_range_text(r), want, "{r:?}");
        }
    }

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

    #[test]
    fn a_label_stands_for_one_configuration() {
        let a = stored("small", "near", 1, 100.0);
        let b = stored("small", "near", 2, 110.0);
        assert_eq!(check_label_configurations(&[a.clone(), b.clone()]), Ok(()));
        // (A setting a row lacks is at its default: the store reads it so.)
        let mut changed = b.clone();
        changed.settings.alpha = 0.123;
        let e = check_label_configurations(&[a.clone(), changed.clone()]).unwrap_err();
        for w in [
            "'near'",
            "setting alpha",
            "0.123",
            "reused",
            "its own label",
        ] {
            assert!(e.contains(w), "{w}: {e}");
        }
        assert_eq!(e.lines().count(), 1);
        let mut other = b.clone();
        other.strategy = "layout".into();
        let e = check_label_configurations(&[a.clone(), other]).unwrap_err();
        assert!(e.contains("strategy near and layout"), "{e}");
        // Another label may hold another configuration.
        changed.label = "far".into();
        assert_eq!(check_label_configurations(&[a.clone(), changed]), Ok(()));
        // An external program's identity is part of it.
        let with_program = |cmd: &str| {
            let mut r = b.clone();
            let mut v: serde_json::Value = summary_value(&r);
            v["strategy_program"] = serde_json::json!({
                "command": ["python3", cmd], "files_sha256": "ab", "timeout_s": 10.0
            });
            set_summary(&mut r, &v);
            r
        };
        let e =
            check_label_configurations(&[with_program("a.py"), with_program("b.py")]).unwrap_err();
        assert!(e.contains("external program"), "{e}");
        // A failed job stored no program: the same as any, and not the label's reference.
        let mut failed = b.clone();
        failed.summary = None;
        failed.status = floorcast_worker::wire::JobStatus::Failed;
        assert_eq!(
            check_label_configurations(&[failed.clone(), with_program("a.py")]),
            Ok(())
        );
        assert!(
            check_label_configurations(&[failed, with_program("a.py"), with_program("b.py")])
                .is_err()
        );
        let mut slower = with_program("a.py");
        if let Some(p) = slower
            .summary
            .as_mut()
            .and_then(|s| s.strategy_program.as_mut())
        {
            p.timeout_s = 20.0;
        }
        assert_eq!(
            check_label_configurations(&[with_program("a.py"), slower]),
            Ok(())
        );
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
        let t = table(&results, &["baseline".into(), "layout".into()], 0.99);
        let a = &t.per_building["a"][1];
        let p = a.paired.as_ref().unwrap();
        assert_eq!(p.pairs, 3);
        assert!((p.gain_pct() - 10.0).abs() < 1e-9, "{p:?}");
        assert!(p.sd_log.abs() < 1e-9 && p.t_half_log.abs() < 1e-9);
        let b = t.per_building["b"][1].paired.as_ref().unwrap();
        assert_eq!(b.pairs, 2);
        // Log ratios ln(1 / 0.8) and 0: their mean is the geometric gain 1 - sqrt(0.8).
        assert!((b.gain_pct() - 100.0 * (1.0 - 0.8f64.sqrt())).abs() < 1e-9);
        // sd of {ln 1.25, 0}; t(1) = 12.706; half-width = 12.706 * sd / sqrt(2).
        let sd = 1.25f64.ln() / 2f64.sqrt();
        assert!((b.t_half_log - 12.706204736174694 * sd / 2f64.sqrt()).abs() < 1e-9);
        // Overall: 5 pairs across both buildings; the reference against itself: 0.
        assert_eq!(t.overall[1].paired.as_ref().unwrap().pairs, 5);
        assert!(t.overall[0]
            .paired
            .as_ref()
            .is_some_and(|p| p.mean_log == 0.0));
        let text = render_text(&t);
        assert!(text.contains("+10.0 % [+10.0, +10.0] (n=3)"), "{text}");
        assert!(text.contains("b:"), "{text}");
        assert!(!text.contains("lost"), "{text}");
    }

    /// The other metrics are paired like the time: a label whose path is 20 % shorter on every
    /// seed and that explores 1 point less has those as its mean gains, with their pairs; times
    /// to a fraction pair only the runs that reached it.
    #[test]
    fn other_metrics_are_paired_like_the_time() {
        let run = |label: &str, seed: u64, path_m: f64, fraction: f64, curve: &str| {
            let mut r = stored("a", label, seed, 100.0);
            let mut v: serde_json::Value = summary_value(&r);
            v["path_length_m"] = serde_json::json!(path_m);
            v["explored_fraction"] = serde_json::json!(fraction);
            set_summary(&mut r, &v);
            r.progress = Some(progress(&format!(
                "time_s,explored_area_m2,explored_fraction\n{curve}"
            )));
            r
        };
        let results = vec![
            run("baseline", 1, 100.0, 1.0, "0,0,0\n50,9,0.9\n100,10,1\n"),
            run("layout", 1, 80.0, 0.99, "0,0,0\n40,9,0.9\n100,10,0.99\n"),
            run("baseline", 2, 200.0, 1.0, "0,0,0\n100,9,0.95\n"),
            run("layout", 2, 160.0, 0.99, "0,0,0\n100,9,0.85\n"),
        ];
        let c = comparisons(&results, &[], "baseline", 0.99);
        let overall = c
            .iter()
            .find(|c| c.label == "layout" && c.building.is_none())
            .unwrap();
        let m = &overall.metrics;
        let close = |a: Option<f64>, b: f64| a.is_some_and(|a| (a - b).abs() < 1e-9);
        assert_eq!(m[&Metric::PathLength].pairs, 2);
        assert!(close(m[&Metric::PathLength].mean, 20.0), "{m:?}");
        let ci = m[&Metric::PathLength].t_ci95.unwrap();
        assert!(
            close(Some(ci[0]), 20.0) && close(Some(ci[1]), 20.0),
            "{ci:?}"
        );
        assert!(
            close(m[&Metric::ExploredFractionPoints].mean, -1.0),
            "{m:?}"
        );
        // Seed 1 reaches 90 % at 40 s against 50 s; seed 2's layout never does.
        assert_eq!(m[&Metric::TimeTo90].pairs, 1);
        assert!(close(m[&Metric::TimeTo90].mean, 20.0), "{m:?}");
        assert_eq!(m[&Metric::TimeTo90].t_ci95, None);
        assert_eq!(m[&Metric::TimeTo99].pairs, 1);
        assert_eq!(m.len(), Metric::ALL.len());
        // In the JSON report, by their words.
        let v = serde_json::to_value(overall).unwrap();
        let words: Vec<&String> = v["metrics"].as_object().unwrap().keys().collect();
        assert_eq!(
            words,
            [
                "explored_fraction_points",
                "path_length_m",
                "time_to_90_s",
                "time_to_95_s",
                "time_to_99_s",
                "unexplored_area_s"
            ]
        );
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
        let mut v: serde_json::Value = summary_value(&r);
        v["end_reason"] = serde_json::json!(end_reason);
        v["explored_fraction"] = serde_json::json!(fraction);
        v["stopped_early"] = serde_json::json!(end_reason == "early stop");
        v["start"] = serde_json::json!(start);
        set_summary(&mut r, &v);
        r.job_id = format!("{label}-{seed}-{}", start[0]);
        r
    }

    #[test]
    fn every_end_class_is_counted_and_only_runs_reaching_the_coverage_are_timed() {
        let s0 = [1.0, 2.0, 0.0];
        // (seed, time_s, end_reason, explored_fraction): the baseline's runs.
        let runs = [
            (1, 100.0, "complete", 1.0),
            (2, 200.0, "no frontiers", 0.99), // written before the classes: complete
            (3, 300.0, "early stop", 0.98),
            (4, 14400.0, "time limit", 0.6),
            (5, 500.0, "stuck", 0.9),
            (6, 600.0, "frontiers unreachable", 0.95),
            (7, 700.0, "complete", 0.96), // complete, but short of 99 %
            (8, 800.0, "stuck", 0.99),    // slivers left: explored enough
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
        let t = table(&results, &["baseline".into(), "layout".into()], 0.99);
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
        // Timed: the runs that explored at least 99 %: 100, 200, 800.
        assert_eq!(base.time.n, 3);
        assert!((base.time.mean - 1100.0 / 3.0).abs() < 1e-9);
        assert_eq!(base.not_achieved, 6);
        assert_eq!(base.explored_fraction.n, 9);
        // Every pair counts: 3 where both reached 99 % (layout twice as fast), 6 where only
        // layout did (the baseline charged its time limit, 14400 s).
        let layout = &t.overall[1];
        assert_eq!(layout.not_achieved, 0);
        let p = layout.paired.as_ref().unwrap();
        assert_eq!(p.pairs, 9);
        assert_eq!(p.counts.both_achieved, 3);
        assert_eq!(p.counts.reference_only_not_achieved, 6);
        let want: f64 = [100.0, 200.0, 800.0]
            .iter()
            .map(|_| 2f64.ln())
            .chain(
                [300.0, 14400.0, 500.0, 600.0, 700.0, 900.0]
                    .iter()
                    .map(|t: &f64| 14400f64.ln() - (t / 2.0).ln()),
            )
            .sum::<f64>()
            / 9.0;
        assert!((p.mean_log - want).abs() < 1e-12, "{p:?}");
        let text = render_text(&t);
        for needle in [
            "6 below 99 %: 1 complete, 1 early stop, 1 time limit, 1 stuck, 2 frontiers unreachable",
            "6 runs did not explore 99 %",
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
        assert_eq!(line("baseline"), "3 1 1 2 2 6 0", "{ends}");
        assert_eq!(line("layout"), "9 0 0 0 0 0 0", "{ends}");
        assert!(ends.contains("frontiers unreachable"), "{ends}");
    }

    /// Swapping the reference negates every comparison's log ratios exactly (mean, t,
    /// bootstrap and anytime intervals) and keeps its p-values, with runs below the coverage
    /// level and failed jobs on both sides.
    #[test]
    fn swapping_the_reference_negates_the_gain_exactly() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let s0 = [1.0, 2.0, 0.0];
        let mut results = Vec::new();
        for building in ["x", "y", "z"] {
            for seed in 1..=9 {
                for label in ["a", "b"] {
                    let t = rng.random_range(200.0..900.0);
                    let f = if rng.random::<f64>() < 0.15 { 0.7 } else { 1.0 };
                    let mut r = stored_end(label, seed, t, "complete", f, s0);
                    r.building = building.into();
                    if rng.random::<f64>() < 0.05 {
                        r.status = floorcast_worker::wire::JobStatus::Failed;
                        r.summary = None;
                    }
                    results.push(r);
                }
            }
        }
        let pick = |reference: &str, building: Option<&str>| {
            comparisons(&results, &[], reference, 0.99)
                .into_iter()
                .find(|c| c.building.as_deref() == building)
                .unwrap()
        };
        for building in [None, Some("x"), Some("y"), Some("z")] {
            let (ab, ba) = (pick("a", building), pick("b", building));
            assert_eq!((ab.label.as_str(), ba.label.as_str()), ("b", "a"));
            assert_eq!(ab.pairs, ba.pairs);
            assert_eq!(ab.mean_log_ratio.map(|m| -m), ba.mean_log_ratio);
            let flip = |v: Option<[f64; 2]>| v.map(|[lo, hi]| [-hi, -lo]);
            assert_eq!(flip(ab.t_ci95_log), ba.t_ci95_log);
            assert_eq!(flip(ab.bootstrap_ci95_log), ba.bootstrap_ci95_log);
            assert_eq!(flip(ab.anytime_ci95_log), ba.anytime_ci95_log);
            assert_eq!(ab.wilcoxon_p, ba.wilcoxon_p);
            assert_eq!(ab.holm_p, ba.holm_p);
            assert_eq!(ab.effect_size_dz.map(|d| -d), ba.effect_size_dz);
            assert_eq!(
                ab.counts.label_only_not_achieved,
                ba.counts.reference_only_not_achieved
            );
            assert_eq!(ab.counts.neither_achieved, ba.counts.neither_achieved);
            assert!(ab.pairs > 0 && ab.mean_log_ratio.is_some());
        }
        // Some runs of each side did not achieve the outcome (the case is exercised).
        let all = pick("a", None);
        assert!(
            all.counts.label_only_not_achieved > 0 && all.counts.reference_only_not_achieved > 0
        );
    }

    /// A label that stops early, far below the coverage level, is never shown faster, however
    /// quickly it stops; nor is one whose slow runs are cut off by a short time limit (the
    /// runs it loses that way count against it, none are dropped); the sequential test says H0.
    #[test]
    fn stopping_early_or_being_cut_off_never_looks_faster() {
        let s0 = [1.0, 2.0, 0.0];
        let mut results = Vec::new();
        for seed in 1..=20u64 {
            let t = 600.0 + 10.0 * seed as f64;
            results.push(stored_end("baseline", seed, t, "complete", 1.0, s0));
            results.push(stored_end("quitter", seed, 60.0, "early stop", 0.26, s0));
            // A copy 5 % faster whose slower half hits a 580 s time limit at 90 %.
            let (time, end, f) = if seed % 2 == 0 {
                (580.0, "time limit", 0.9)
            } else {
                (t * 0.95, "complete", 1.0)
            };
            let mut r = stored_end("cut", seed, time, end, f, s0);
            let mut v: serde_json::Value = summary_value(&r);
            v["settings"]["time_limit_s"] = serde_json::json!(580.0);
            set_summary(&mut r, &v);
            results.push(r);
        }
        let cs = comparisons(&results, &[], "baseline", 0.99);
        let cfg = crate::sprt::SprtConfig::default();
        for label in ["quitter", "cut"] {
            let c = cs
                .iter()
                .find(|c| c.label == label && c.building.is_none())
                .unwrap();
            assert!(c.mean_gain_pct.unwrap() < 0.0, "{label}: {c:?}");
            assert!(c.t_ci95_pct.unwrap()[0] < 0.0, "{label}: {c:?}");
            assert_eq!(c.pairs, 20, "{label}: none dropped");
            let pairs = crate::outcome::paired(&results, label, "baseline", 0.99);
            let xs: Vec<f64> = pairs
                .pairs
                .iter()
                .map(crate::outcome::Pair::log_ratio)
                .collect();
            assert_eq!(
                cfg.state(&xs).decision,
                crate::sprt::Decision::H0,
                "{label}"
            );
        }
        let quitter = cs.iter().find(|c| c.label == "quitter").unwrap();
        assert_eq!(quitter.counts.label_only_not_achieved, 20);
        assert_eq!(quitter.counts.label_not_achieved["early stop"], 20);
        assert_eq!(quitter.counts.label_coverage_min, Some(0.26));
    }

    #[test]
    fn tables_of_runs_reaching_the_coverage_carry_no_marks() {
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
        let t = table(&results, &[], 0.99);
        let text = render_text(&t);
        assert!(
            !text.contains("did not explore") && !text.contains("failed") && !text.contains("lost"),
            "{text}"
        );
        assert!(text.contains("+10.0 %"), "{text}");
        assert_eq!(t.overall[0].time.n, 3);
        // At a coverage level above what they explored, every run is below it: both explored
        // the same fraction, so each pair compares their times to it (their end times, without
        // curves): layout 10 % faster, not a tie.
        let t = table(&results, &[], 1.0);
        let p = t.overall[1].paired.as_ref().unwrap();
        assert_eq!((p.pairs, p.counts.neither_achieved), (3, 3));
        assert!((p.mean_log - (100f64 / 90.0).ln()).abs() < 1e-12, "{p:?}");
    }

    /// Pairs where both runs fell short of the coverage level, by explored fraction then time:
    /// within half a point, their times to the lesser fraction (from the progress curves); else
    /// the one that explored more wins, timed to the other's fraction, the other charged the
    /// horizon; a failed job loses to a run that explored; swapping negates exactly.
    #[test]
    fn pairs_both_short_are_scored_by_fraction_then_time() {
        use crate::outcome::{outcome_of, Pair};
        let curve = "time_s,explored_area_m2,explored_fraction\n0,0,0\n500,50,0.5\n900,90,0.9\n1500,98,0.98\n1800,98.8,0.988\n";
        let with = |label: &str, t: f64, f: f64, curve: Option<&str>| {
            let mut r = stored_end(label, 1, t, "stuck", f, [1.0, 2.0, 0.0]);
            r.progress = curve.map(progress);
            outcome_of(&r, 0.99, "b")
        };
        let failed = || {
            let mut r = stored("b", "x", 1, 100.0);
            r.status = floorcast_worker::wire::JobStatus::Failed;
            r.summary = None;
            outcome_of(&r, 0.99, "b")
        };
        // (label's run, reference's run, (reference's charge, label's charge))
        let cases = [
            // Vipiteno1's case: 98.75 % against 98.94 %, within half a point: times to 98.75 %.
            (
                with("l", 1668.0, 0.9875, None),
                with("r", 1900.0, 0.9894, Some(curve)),
                (1800.0, 1668.0),
            ),
            (
                with("l", 1668.0, 0.9875, Some(curve)),
                with("r", 1900.0, 0.9894, None),
                (1900.0, 1800.0),
            ),
            // 90 % against 98.8 %: the reference wins, timed to 90 %; the label charged 14 400 s.
            (
                with("l", 300.0, 0.90, None),
                with("r", 1900.0, 0.988, Some(curve)),
                (900.0, 14_400.0),
            ),
            // A quitter at 26 % against a run stuck at 98.8 %.
            (
                with("l", 60.0, 0.26, None),
                with("r", 1900.0, 0.988, None),
                (1900.0, 14_400.0),
            ),
            (failed(), with("r", 1900.0, 0.988, None), (1900.0, 14_400.0)),
            (failed(), failed(), (14_400.0, 14_400.0)),
        ];
        for (i, (l, r, want)) in cases.into_iter().enumerate() {
            let p = Pair {
                label: l,
                reference: r,
            };
            assert_eq!(p.charged_s(), want, "case {i}");
            let swapped = Pair {
                label: p.reference.clone(),
                reference: p.label.clone(),
            };
            assert_eq!(swapped.log_ratio(), -p.log_ratio(), "case {i}");
        }
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
        let t = table(&results, &[], 0.99);
        let p = t.overall[1].paired.as_ref().unwrap();
        assert_eq!(p.pairs, 2);
        assert!(
            (p.gain_pct() - 100.0 * (1.0 - (0.9f64 * 0.7).sqrt())).abs() < 1e-9,
            "{p:?}"
        );
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
        let p = progress("time_s,explored_area_m2,explored_fraction\n0,0,0\n10,5,0.5\n20,10,1.0\n");
        // 10 s at 1 -> 0.5 unexplored (7.5 s), 10 s at 0.5 -> 0 (2.5 s).
        assert_eq!(unexplored_area_s(&p), Some(10.0));
        assert_eq!(
            unexplored_area_s(&progress("time_s,explored_area_m2,explored_fraction\n")),
            None
        );
    }

    #[test]
    fn time_to_a_fraction_is_the_first_sample_reaching_it() {
        let p = progress(
            "time_s,explored_area_m2,explored_fraction\n0,0,0\n2,5,0.5\n4,9,0.9\n6,10,1\n",
        );
        assert_eq!(time_to_fraction(&p, 0.9), Some(4.0));
        assert_eq!(time_to_fraction(&p, 0.4), Some(2.0));
        assert_eq!(time_to_fraction(&p, 1.1), None);
        let mut r = stored("b", "baseline", 1, 6.0);
        r.progress = Some(p);
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
        a.progress = Some(progress(
            "time_s,explored_area_m2,explored_fraction\n0,0,0\n2,5,0.5\n4,10,1\n",
        ));
        let mut b = stored("b1", "baseline", 2, 2.0);
        b.progress = Some(progress(
            "time_s,explored_area_m2,explored_fraction\n0,0,0.2\n2,8,0.8\n",
        ));
        let mut c = stored("b1", "layout", 1, 2.0);
        c.progress = Some(progress(
            "time_s,explored_area_m2,explored_fraction\n0,0,0\n2,1,1\n",
        ));
        let mut summary: serde_json::Value = summary_value(&c);
        summary["stopped_early"] = true.into();
        summary["explored_fraction"] = 0.97.into();
        set_summary(&mut c, &summary);
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
