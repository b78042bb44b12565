//! The report of a results set as values: what `floorcast report` prints (and `--json` writes)
//! is rendered from a [`Report`], so a program gets the same numbers without reading text.

use floorcast_worker::tour::TourRecord;

use crate::aggregate::Aggregates;
use crate::measure::Measure;
use crate::ranking::Place;
use crate::table::{Comparison, SequentialVerdict, Table};
use crate::yardstick::{LabelEfficiency, RunEfficiency};
use crate::StoredResult;

/// What a report compares: the labels in order, the reference, the coverage level and the time
/// measured.
#[derive(Debug, Clone, PartialEq)]
pub struct ReportScope {
    /// The labels in the order the report lists them (labels of the results not named come
    /// after, in the order stored: [`crate::outcome::label_order`]).
    pub order: Vec<String>,
    /// The label every other is compared with.
    pub reference: String,
    /// The coverage level a run must explore to achieve the outcome ([`crate::outcome`]).
    pub coverage: f64,
    /// The time a comparison measures.
    pub measure: Measure,
}

impl ReportScope {
    /// The scope of `results` as `floorcast report` takes it without options: their labels
    /// in the order stored, `baseline` the reference if present (else the first label), the
    /// default coverage level ([`crate::outcome::DEFAULT_COVERAGE`]) and the time to end.
    pub fn of(results: &[StoredResult]) -> ReportScope {
        let order = crate::outcome::label_order(results, &[]);
        let reference = order
            .iter()
            .find(|l| l.as_str() == "baseline")
            .or(order.first())
            .cloned()
            .unwrap_or_default();
        ReportScope {
            order,
            reference,
            coverage: crate::outcome::DEFAULT_COVERAGE,
            measure: Measure::default(),
        }
    }
}

/// A results set's report: the table of every label (overall and per building), the paired
/// comparisons with the reference, the aggregates across buildings, the efficiency against the
/// known-map tours, the ranking, and the sequential grids' last decisions. Every field is public
/// and documented where its type is; [`Report::text`] is the report as `floorcast report`
/// prints it, [`Report::json`] as `report --json` writes it.
#[derive(Debug, Clone, PartialEq)]
pub struct Report {
    pub scope: ReportScope,
    /// The runs reported (every stored job, failed ones included).
    pub runs: usize,
    /// The successful runs with a summary (those efficiency can measure).
    pub successful_runs: usize,
    /// Each label's statistics, overall and per building ([`crate::table`]).
    pub table: Table,
    /// Each label against the reference, overall then per building, with its sensitivity and
    /// other metrics.
    pub comparisons: Vec<Comparison>,
    /// Across buildings: IQM of normalized times, probability of improvement, profiles.
    pub aggregates: Aggregates,
    /// Each label's efficiency (labels without a run with a tour left out).
    pub efficiency: Vec<LabelEfficiency>,
    /// Each run's efficiency.
    pub run_efficiency: Vec<RunEfficiency>,
    /// The labels ranked by their aggregates.
    pub ranking: Vec<Place>,
    /// Sequential grids' last test of each label (by grid, then label order).
    pub verdicts: Vec<SequentialVerdict>,
}

impl Report {
    /// The report of `results`, measured against `tours` (the known-map tours stored with
    /// them), within `scope`; `verdicts` are the sequential grids' decisions stored with them
    /// (none for a grid that was not sequential).
    pub fn new(
        results: &[StoredResult],
        tours: &[TourRecord],
        scope: ReportScope,
        verdicts: Vec<SequentialVerdict>,
    ) -> Report {
        let ReportScope {
            order,
            reference,
            coverage,
            measure,
        } = &scope;
        let table = crate::table::table_by(results, order, Some(reference), *coverage, *measure);
        let comparisons =
            crate::table::comparisons_by(results, order, reference, *coverage, *measure);
        let aggregates =
            crate::aggregate::aggregates_by(results, order, reference, *coverage, *measure);
        let (run_efficiency, efficiency) =
            crate::yardstick::efficiencies(results, tours, order, *coverage);
        let ranking = crate::ranking::ranking(&aggregates, &efficiency);
        Report {
            runs: results.len(),
            successful_runs: results
                .iter()
                .filter(|r| r.status.is_ok() && r.summary.is_some())
                .count(),
            table,
            comparisons,
            aggregates,
            efficiency,
            run_efficiency,
            ranking,
            verdicts,
            scope,
        }
    }

    /// The labels whose comparison with the reference a sequential grid decided (the fixed-sample
    /// intervals of theirs are marked as biased).
    pub fn sequential_labels(&self) -> Vec<String> {
        self.verdicts
            .iter()
            .filter(|v| v.test.reference == self.scope.reference)
            .map(|v| v.test.label.clone())
            .collect()
    }

    /// The report as `floorcast report` prints it: the table, how runs ended, the comparisons,
    /// the aggregates, the efficiency and the ranking (the sequential decisions are printed
    /// after it, one line each: [`crate::sequential::render_test`]).
    pub fn text(&self) -> String {
        format!(
            "{}{}{}{}{}{}",
            crate::table::render_text(&self.table),
            crate::table::render_ends(&self.table),
            crate::table::render_comparisons(&self.comparisons, &self.sequential_labels()),
            crate::aggregate::render(&self.aggregates),
            crate::yardstick::render(&self.efficiency, self.successful_runs, self.scope.coverage),
            crate::ranking::render(&self.ranking, &self.scope.reference)
        )
    }

    /// The report as `report --json` writes it (docs/report-json.md) from the same `results`:
    /// the labels' statistics, the comparisons with the sequential decisions, the aggregates,
    /// the efficiency (`labels`, `runs`) and the ranking.
    pub fn json(&self, results: &[StoredResult]) -> serde_json::Value {
        let s = &self.scope;
        let mut v = crate::table::report_json(
            results,
            &s.order,
            &s.reference,
            s.coverage,
            s.measure,
            &self.verdicts,
        );
        v["efficiency"] =
            serde_json::json!({"labels": self.efficiency, "runs": self.run_efficiency});
        v["ranking"] = serde_json::to_value(&self.ranking).unwrap_or_default();
        v
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fixtures::stored;

    /// Three labels on two buildings: `fast` 20 % faster than `baseline`, `slow` 25 % slower.
    fn results() -> Vec<StoredResult> {
        let mut out = Vec::new();
        for building in ["a", "b"] {
            for seed in 1..=4 {
                let t = 500.0 + 10.0 * seed as f64;
                out.push(stored(building, "slow", seed, t * 1.25));
                out.push(stored(building, "baseline", seed, t));
                out.push(stored(building, "fast", seed, t * 0.8));
            }
        }
        out
    }

    #[test]
    fn the_default_scope_takes_baseline_as_reference() {
        let scope = ReportScope::of(&results());
        assert_eq!(scope.order, ["slow", "baseline", "fast"]);
        assert_eq!(scope.reference, "baseline");
        assert_eq!(scope.coverage, crate::outcome::DEFAULT_COVERAGE);
        assert_eq!(ReportScope::of(&[]).reference, "");
    }

    #[test]
    fn the_report_holds_the_numbers_its_text_shows() {
        let results = results();
        let report = Report::new(&results, &[], ReportScope::of(&results), Vec::new());
        assert_eq!((report.runs, report.successful_runs), (24, 24));
        let ranked: Vec<&str> = report.ranking.iter().map(|p| p.label.as_str()).collect();
        assert_eq!(ranked, ["fast", "baseline", "slow"]);
        let fast = report
            .comparisons
            .iter()
            .find(|c| c.label == "fast" && c.building.is_none())
            .unwrap();
        let gain = fast.hl_gain_pct.unwrap();
        assert!((gain - 20.0).abs() < 1e-9, "{gain}");
        let text = report.text();
        assert!(text.contains("Ranking by IQM"), "{text}");
        assert!(text.contains("+20.0 %"), "{text}");
        // No tours: no efficiency, and the text says why.
        assert!(report.efficiency.is_empty());
        assert!(text.contains("no efficiency: 24 successful runs"), "{text}");
        let json = report.json(&results);
        assert_eq!(json["ranking"][0]["label"], "fast");
        assert_eq!(json["reference"], "baseline");
    }
}
