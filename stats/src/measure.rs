//! The time a comparison measures (`--measure`, a grid's `[sequential] measure`) and the
//! coverage level as text: what the outcomes ([`crate::outcome`]), the sequential test
//! ([`crate::sprt`]) and the tables name, in a module of their own that uses none of them.

/// The time a comparison measures ([`crate::outcome::outcome_by`]): the time until the run ended (its
/// exploration time, the paper's measure, the default) or the time at which it first had the
/// coverage level explored (from its stored progress curve; Explore-Bench's T_90 at 0.9).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Measure {
    /// Time to the end: the exploration time of a run that ended with the coverage level
    /// explored.
    #[default]
    End,
    /// Time to the coverage level: the first time the run's progress curve reached it.
    Coverage,
}

impl Measure {
    /// The word of `--measure` and of a grid's `measure`: "end" or "coverage".
    pub fn as_str(self) -> &'static str {
        match self {
            Measure::End => "end",
            Measure::Coverage => "coverage",
        }
    }

    /// What the measure is, in words: "time to end" or "time to 99 % explored".
    pub fn text(self, coverage: f64) -> String {
        match self {
            Measure::End => "time to end".to_string(),
            Measure::Coverage => format!("time to {} explored", coverage_text(coverage)),
        }
    }
}

impl std::str::FromStr for Measure {
    type Err = String;

    fn from_str(word: &str) -> Result<Measure, String> {
        match word {
            "end" => Ok(Measure::End),
            "coverage" => Ok(Measure::Coverage),
            _ => Err(format!(
                "unknown measure '{}', expected end (the time until the run ended, having explored the coverage level) or coverage (the time at which it first had the coverage level explored)",
                floorcast_worker::text::excerpt(word)
            )),
        }
    }
}

/// `99 %`: a coverage level as text.
pub fn coverage_text(coverage: f64) -> String {
    let pct = coverage * 100.0;
    if (pct - pct.round()).abs() < 1e-9 {
        format!("{pct:.0} %")
    } else {
        format!("{pct} %")
    }
}
