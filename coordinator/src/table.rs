//! The grid's version of the paper's Table 1, computed from stored results: per strategy label
//! the mean and standard deviation of exploration time over all runs, and the gain over the
//! baseline in per cent; the same per building; and a CSV export.

use std::collections::BTreeMap;
use std::fmt::Write as _;

use floorcast_worker::RunSummary;

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

/// One row per strategy label.
#[derive(Debug, Clone, PartialEq)]
pub struct LabelRow {
    pub label: String,
    pub time: Stat,
    pub explored_fraction: Stat,
    pub stopped_early: usize,
    pub failed: usize,
    /// Gain of mean time over the reference label, per cent (positive = faster).
    pub gain_pct: Option<f64>,
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
    let mut order: Vec<String> = labels.to_vec();
    for r in results {
        if !order.contains(&r.label) {
            order.push(r.label.clone());
        }
    }
    let reference = order
        .iter()
        .find(|l| l.as_str() == "baseline")
        .or(order.first())
        .cloned();
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
                let times: Vec<f64> = summaries.iter().map(|s| s.exploration_time_s).collect();
                let fracs: Vec<f64> = summaries.iter().map(|s| s.explored_fraction).collect();
                Some(LabelRow {
                    label: label.clone(),
                    time: Stat::of(&times),
                    explored_fraction: Stat::of(&fracs),
                    stopped_early: summaries.iter().filter(|s| s.stopped_early).count(),
                    failed: mine.len() - summaries.len(),
                    gain_pct: None,
                })
            })
            .collect();
        let base = reference_label
            .as_ref()
            .and_then(|r| rows.iter().find(|row| &row.label == r))
            .map(|row| row.time.mean);
        for row in &mut rows {
            row.gain_pct = base
                .filter(|b| b.is_finite() && *b > 0.0)
                .map(|b| (b - row.time.mean) / b * 100.0);
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

fn fmt_rows(out: &mut String, rows: &[LabelRow], reference: Option<&String>) {
    let _ = writeln!(
        out,
        "  {:<16} {:>5} {:>10} {:>9} {:>9} {:>10} {:>6}",
        "strategy", "runs", "time (s)", "sd (s)", "gain", "explored", "ES"
    );
    for r in rows {
        let gain = match (r.gain_pct, reference) {
            (_, Some(reference)) if &r.label == reference => "ref".to_string(),
            (Some(g), _) => format!("{g:+.1} %"),
            _ => "-".into(),
        };
        let _ = writeln!(
            out,
            "  {:<16} {:>5} {:>10.0} {:>9.0} {:>9} {:>9.1}% {:>6}{}",
            r.label,
            r.time.n,
            r.time.mean,
            r.time.sd,
            gain,
            r.explored_fraction.mean * 100.0,
            r.stopped_early,
            if r.failed > 0 {
                format!("  ({} failed)", r.failed)
            } else {
                String::new()
            }
        );
    }
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
    out
}

/// One line per stored job, for pandas or R.
pub fn results_csv(results: &[StoredResult]) -> String {
    let mut s = String::from(
        "job_id,building,building_hash,strategy,label,seed,status,exploration_time_s,explored_area_m2,free_area_m2,explored_fraction,path_length_m,decisions,stopped_early,end_reason,wall_time_s,worker,floorcast_version\n",
    );
    for r in results {
        let sum = r
            .summary_json
            .as_deref()
            .and_then(|j| RunSummary::from_json(j).ok());
        let f = |v: Option<f64>| v.map(|x| format!("{x}")).unwrap_or_default();
        let _ = writeln!(
            s,
            "{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}",
            r.job_id,
            csv_field(&r.building),
            r.building_hash,
            csv_field(&r.strategy),
            csv_field(&r.label),
            r.seed,
            r.status,
            f(sum.as_ref().map(|s| s.exploration_time_s)),
            f(sum.as_ref().map(|s| s.explored_area_m2)),
            f(sum.as_ref().map(|s| s.free_area_m2)),
            f(sum.as_ref().map(|s| s.explored_fraction)),
            f(sum.as_ref().map(|s| s.path_length_m)),
            sum.as_ref()
                .map(|s| s.decisions.to_string())
                .unwrap_or_default(),
            sum.as_ref()
                .map(|s| s.stopped_early.to_string())
                .unwrap_or_default(),
            csv_field(sum.as_ref().map(|s| s.end_reason.as_str()).unwrap_or("")),
            r.wall_time_s,
            csv_field(&r.worker),
            r.floorcast_version
        );
    }
    s
}

fn csv_field(s: &str) -> String {
    if s.contains([',', '"', '\n']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
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

    #[test]
    fn csv_quotes_when_needed() {
        assert_eq!(csv_field("a,b"), "\"a,b\"");
        assert_eq!(csv_field("plain"), "plain");
    }
}
