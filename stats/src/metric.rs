//! The metrics `report` compares besides the exploration time (a comparison's `metrics`,
//! [`crate::table::Comparison`]): one enum, whose words (the keys of `report --json`) are
//! written and read here only ([`Metric::as_str`], its `FromStr`).

use floorcast_worker::RunSummary;

use crate::progress::Sample;

/// A metric of a successful run, paired between labels as the exploration time is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Metric {
    /// The simulated time at which the run had explored 90 % (its progress curve).
    TimeTo90,
    /// The same at 95 %.
    TimeTo95,
    /// The same at 99 %.
    TimeTo99,
    /// The area above the explored-fraction curve ([`unexplored_area_s`]).
    UnexploredArea,
    /// The path length (m).
    PathLength,
    /// The explored fraction at the end, in percentage points.
    ExploredFractionPoints,
}

impl Metric {
    /// Every metric, in the order comparisons compute them.
    pub const ALL: [Metric; 6] = [
        Metric::TimeTo90,
        Metric::TimeTo95,
        Metric::TimeTo99,
        Metric::UnexploredArea,
        Metric::PathLength,
        Metric::ExploredFractionPoints,
    ];

    /// The metric's word.
    pub const fn as_str(self) -> &'static str {
        match self {
            Metric::TimeTo90 => "time_to_90_s",
            Metric::TimeTo95 => "time_to_95_s",
            Metric::TimeTo99 => "time_to_99_s",
            Metric::UnexploredArea => "unexplored_area_s",
            Metric::PathLength => "path_length_m",
            Metric::ExploredFractionPoints => "explored_fraction_points",
        }
    }

    /// Whether the metric is compared by differences in percentage points (the explored
    /// fraction); every other by log ratios, lower being better.
    pub fn in_points(self) -> bool {
        self == Metric::ExploredFractionPoints
    }

    /// The metric's value of a successful run: its summary and stored progress curve (`None`
    /// when the run has none, e.g. never reached 90 %).
    pub fn of(self, s: &RunSummary, progress: &[Sample]) -> Option<f64> {
        match self {
            Metric::TimeTo90 => time_to_fraction(progress, 0.90),
            Metric::TimeTo95 => time_to_fraction(progress, 0.95),
            Metric::TimeTo99 => time_to_fraction(progress, 0.99),
            Metric::UnexploredArea => unexplored_area_s(progress),
            Metric::PathLength => Some(s.path_length_m),
            Metric::ExploredFractionPoints => Some(s.explored_fraction * 100.0),
        }
    }
}

impl std::str::FromStr for Metric {
    type Err = String;

    fn from_str(word: &str) -> Result<Metric, String> {
        Metric::ALL
            .into_iter()
            .find(|m| m.as_str() == word)
            .ok_or_else(|| {
                format!(
                    "unknown metric '{}', expected one of {}",
                    floorcast_worker::text::excerpt(word),
                    Metric::ALL.map(Metric::as_str).join(", ")
                )
            })
    }
}

impl std::fmt::Display for Metric {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.as_str())
    }
}

/// Ordered by word, as `report --json` lists them.
impl Ord for Metric {
    fn cmp(&self, other: &Metric) -> std::cmp::Ordering {
        self.as_str().cmp(other.as_str())
    }
}

impl PartialOrd for Metric {
    fn partial_cmp(&self, other: &Metric) -> Option<std::cmp::Ordering> {
        Some(self.cmp(other))
    }
}

impl serde::Serialize for Metric {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(self.as_str())
    }
}

/// The first simulated time at which a stored progress curve reaches `fraction` explored.
pub fn time_to_fraction(progress: &[Sample], fraction: f64) -> Option<f64> {
    progress
        .iter()
        .find_map(|s| (s.explored_fraction >= fraction).then_some(s.time_s))
}

/// The area above a run's explored-fraction curve up to its end, `∫ (1 - f(t)) dt` in seconds
/// (trapezoids between the samples): how long the building stays unseen on average, lower is
/// better; it weighs early progress, where the exploration time sees only the end.
pub fn unexplored_area_s(progress: &[Sample]) -> Option<f64> {
    let mut prev: Option<(f64, f64)> = None;
    let mut area = 0.0;
    for s in progress {
        let (t, f) = (s.time_s, s.explored_fraction);
        if let Some((t0, f0)) = prev {
            area += (t - t0) * (2.0 - f0 - f) / 2.0;
        }
        prev = Some((t, f));
    }
    prev.map(|_| area)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Each metric's word reads back as it; the words are ordered as `report --json` lists them.
    #[test]
    fn words_read_back_and_order_as_listed() {
        for m in Metric::ALL {
            assert_eq!(m.as_str().parse::<Metric>(), Ok(m));
            assert_eq!(serde_json::to_string(&m).unwrap(), format!("\"{m}\""));
        }
        let e = "time_to_50_s".parse::<Metric>().unwrap_err();
        assert!(e.contains("unknown metric 'time_to_50_s'"), "{e}");
        let mut sorted = Metric::ALL;
        sorted.sort();
        let mut words = Metric::ALL.map(Metric::as_str);
        words.sort_unstable();
        assert_eq!(sorted.map(Metric::as_str), words);
    }
}
