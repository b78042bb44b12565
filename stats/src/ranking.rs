//! The report's ranking (a leaderboard): labels in order of their interquartile mean of
//! normalized times across buildings ([`crate::aggregate`]), each with its interval, its
//! probability of being faster than the reference, the share of its runs that reached the
//! coverage level and its median efficiency ([`crate::yardstick`]).

use crate::aggregate::Aggregates;
use crate::yardstick::LabelEfficiency;

/// One place of the ranking.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Place {
    /// 1 for the fastest; labels whose intervals overlap the one above share nothing but the
    /// order (read the intervals).
    pub rank: usize,
    pub label: String,
    pub iqm_normalized_time: Option<f64>,
    pub iqm_ci95: Option<[f64; 2]>,
    /// Against the reference (`None` for the reference).
    pub probability_of_improvement: Option<f64>,
    pub achieved_fraction: f64,
    pub median_efficiency: Option<f64>,
    pub runs: usize,
}

/// The labels of `aggregates` ranked by their IQM of normalized times (lower first; a label
/// without one last), ties by name.
pub fn ranking(aggregates: &Aggregates, efficiency: &[LabelEfficiency]) -> Vec<Place> {
    let mut places: Vec<Place> = aggregates
        .labels
        .iter()
        .map(|l| Place {
            rank: 0,
            label: l.label.clone(),
            iqm_normalized_time: l.iqm_normalized_time.filter(|v| v.is_finite()),
            iqm_ci95: l.iqm_ci95,
            probability_of_improvement: l.probability_of_improvement,
            achieved_fraction: l.achieved_fraction,
            median_efficiency: efficiency
                .iter()
                .find(|e| e.label == l.label)
                .map(|e| e.median),
            runs: l.runs,
        })
        .collect();
    places.sort_by(|a, b| {
        let key = |p: &Place| p.iqm_normalized_time.unwrap_or(f64::INFINITY);
        key(a)
            .total_cmp(&key(b))
            .then_with(|| a.label.cmp(&b.label))
    });
    for (i, p) in places.iter_mut().enumerate() {
        p.rank = i + 1;
    }
    places
}

/// The ranking as the report prints it (nothing for fewer than three labels: the comparisons
/// say it all).
pub fn render(places: &[Place], reference: &str) -> String {
    use std::fmt::Write as _;
    if places.len() < 3 {
        return String::new();
    }
    let width = places
        .iter()
        .map(|p| p.label.len())
        .max()
        .unwrap_or(5)
        .max(5);
    let mut out = format!(
        "\nRanking by IQM of normalized time (lower is faster; P(faster) against {reference}; efficiency: median yardstick time / exploration time, the yardstick the faster of the known-map tour and the fastest run):\n"
    );
    let _ = writeln!(
        out,
        "{:>4}  {:<width$}  {:>6}  {:>17}  {:>9}  {:>7}  {:>10}  {:>5}",
        "rank", "label", "IQM", "95 % interval", "P(faster)", "reached", "efficiency", "runs"
    );
    let num = |v: Option<f64>| v.map_or("-".to_string(), |v| format!("{v:.3}"));
    for p in places {
        let _ = writeln!(
            out,
            "{:>4}  {:<width$}  {:>6}  {:>17}  {:>9}  {:>6.0}%  {:>10}  {:>5}",
            p.rank,
            p.label,
            num(p.iqm_normalized_time),
            p.iqm_ci95
                .map_or("-".to_string(), |[a, b]| format!("[{a:.3}, {b:.3}]")),
            if p.label == reference {
                "ref".to_string()
            } else {
                num(p.probability_of_improvement)
            },
            p.achieved_fraction * 100.0,
            num(p.median_efficiency),
            p.runs
        );
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::aggregate::LabelAggregate;

    fn label(name: &str, iqm: Option<f64>) -> LabelAggregate {
        LabelAggregate {
            label: name.into(),
            runs: 4,
            buildings: 2,
            achieved_fraction: 1.0,
            iqm_normalized_time: iqm,
            iqm_ci95: iqm.map(|v| [v - 0.1, v + 0.1]),
            probability_of_improvement: Some(0.5),
            probability_of_improvement_ci95: None,
            profile: Vec::new(),
        }
    }

    #[test]
    fn labels_rank_by_their_iqm_and_those_without_one_come_last() {
        let a = Aggregates {
            reference: "b".into(),
            coverage: 0.99,
            measure: "end",
            reference_median_s: Default::default(),
            labels: vec![
                label("b", Some(1.0)),
                label("none", None),
                label("nan", Some(f64::NAN)),
                label("fast", Some(0.6)),
                label("a", Some(1.0)),
            ],
        };
        let places = ranking(&a, &[]);
        let order: Vec<&str> = places.iter().map(|p| p.label.as_str()).collect();
        assert_eq!(order, ["fast", "a", "b", "nan", "none"]);
        assert_eq!(places[0].rank, 1);
        assert_eq!(places[4].rank, 5);
        let text = render(&places, "b");
        assert!(text.contains("Ranking by IQM"), "{text}");
        assert!(render(&places[..2], "b").is_empty());
    }
}
