//! The paper's utility `u(p) = alpha * d(p) + (1 - alpha) * i(p)` and the choice of the best
//! candidate.
//!
//! `d(p) = (Dmax - D(p)) / Dmax` and `i(p) = I(p) / Imax`, maxima over the reachable candidates.
//! When `Dmax = 0` every `d(p)` is 1 (all equally close); when `Imax = 0` every `i(p)` is 0.

/// What the distance `D(p)` of the utility measures.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum UtilityDistance {
    /// The length of the planned path from the robot to the candidate (floorcast's default: a
    /// candidate behind a wall is as far as the way around it).
    #[default]
    Path,
    /// The straight-line distance from the robot to the candidate, as the paper defines
    /// `D(p, p_R)`. Candidates must still be reachable to be chosen.
    Euclidean,
}

impl UtilityDistance {
    pub fn as_str(self) -> &'static str {
        match self {
            Self::Path => "path",
            Self::Euclidean => "euclidean",
        }
    }

    pub fn from_name(name: &str) -> Option<Self> {
        match name {
            "path" => Some(Self::Path),
            "euclidean" => Some(Self::Euclidean),
            _ => None,
        }
    }
}

/// What the utility needs to know about one candidate.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CandidateScore {
    /// Distance from the robot (m; see [`UtilityDistance`]); `None` = unreachable (never
    /// chosen).
    pub distance_m: Option<f64>,
    /// Expected information gain `I(p)` (m2).
    pub gain_m2: f64,
}

/// `u(p)` per candidate (`None` for unreachable ones). `alpha` is clamped to `[0, 1]`.
pub(crate) fn utilities(candidates: &[CandidateScore], alpha: f64) -> Vec<Option<f64>> {
    let alpha = if alpha.is_finite() {
        alpha.clamp(0.0, 1.0)
    } else {
        0.5
    };
    let valid = |c: &CandidateScore| c.distance_m.filter(|d| d.is_finite() && *d >= 0.0);
    let gain = |c: &CandidateScore| {
        if c.gain_m2.is_finite() {
            c.gain_m2.max(0.0)
        } else {
            0.0
        }
    };
    let d_max = candidates.iter().filter_map(valid).fold(0.0, f64::max);
    let i_max = candidates
        .iter()
        .filter(|c| valid(c).is_some())
        .map(gain)
        .fold(0.0, f64::max);
    candidates
        .iter()
        .map(|c| {
            let d = valid(c)?;
            let dp = if d_max > 0.0 {
                (d_max - d) / d_max
            } else {
                1.0
            };
            let ip = if i_max > 0.0 { gain(c) / i_max } else { 0.0 };
            Some(alpha * dp + (1.0 - alpha) * ip)
        })
        .collect()
}

/// The candidates with every gain raised to at least `floor_m2` (an option, not the paper's
/// utility). Near the end of an exploration every candidate is a small residual frontier (a
/// corner, a strip along a wall), and `i(p) = I(p) / Imax` turns a difference between 0.1 and
/// 2.5 m2, both within the error of the estimate, into a reason to cross the building, only to
/// come back later for what was left behind. With a floor, gains below it count as equal and
/// distance decides among them; large gains still dominate.
pub(crate) fn with_gain_floor(candidates: &[CandidateScore], floor_m2: f64) -> Vec<CandidateScore> {
    candidates
        .iter()
        .map(|c| CandidateScore {
            gain_m2: if floor_m2 > 0.0 {
                c.gain_m2.max(floor_m2)
            } else {
                c.gain_m2
            },
            ..*c
        })
        .collect()
}

/// Index of the reachable candidate of highest utility; ties go to the lowest index.
pub fn best_candidate(candidates: &[CandidateScore], alpha: f64) -> Option<usize> {
    let mut best: Option<(usize, f64)> = None;
    for (i, u) in utilities(candidates, alpha).into_iter().enumerate() {
        if let Some(u) = u {
            if best.is_none_or(|(_, b)| u > b) {
                best = Some((i, u));
            }
        }
    }
    best.map(|(i, _)| i)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn c(d: Option<f64>, g: f64) -> CandidateScore {
        CandidateScore {
            distance_m: d,
            gain_m2: g,
        }
    }

    #[test]
    fn alpha_trades_distance_for_gain() {
        let cands = [c(Some(2.0), 5.0), c(Some(10.0), 40.0), c(None, 100.0)];
        assert_eq!(best_candidate(&cands, 1.0), Some(0));
        assert_eq!(best_candidate(&cands, 0.0), Some(1));
        let u = utilities(&cands, 0.5);
        assert!((u[0].unwrap() - (0.5 * 0.8 + 0.5 * 0.125)).abs() < 1e-12);
        assert!((u[1].unwrap() - 0.5).abs() < 1e-12);
        assert_eq!(u[2], None);
    }

    #[test]
    fn degenerate_maxima_and_ties() {
        let same = [c(Some(0.0), 0.0), c(Some(0.0), 0.0)];
        assert_eq!(utilities(&same, 0.5), vec![Some(0.5), Some(0.5)]);
        assert_eq!(best_candidate(&same, 0.5), Some(0));
        assert_eq!(best_candidate(&[], 0.5), None);
        assert_eq!(best_candidate(&[c(None, 1.0)], 0.5), None);
        assert_eq!(
            best_candidate(&[c(Some(1.0), f64::NAN), c(Some(1.0), 2.0)], 0.0),
            Some(1)
        );
    }

    #[test]
    fn a_gain_floor_lets_distance_decide_among_small_gains() {
        // The end of an exploration: a residual corner next to the robot, another across the
        // building with a larger but still small gain.
        let cands = [c(Some(5.0), 0.1), c(Some(80.0), 2.5), c(None, 50.0)];
        assert_eq!(best_candidate(&cands, 0.5), Some(1));
        let floored = with_gain_floor(&cands, 2.0);
        assert_eq!(floored[0].gain_m2, 2.0);
        assert_eq!(floored[1].gain_m2, 2.5);
        assert_eq!(floored[0].distance_m, Some(5.0));
        assert_eq!(best_candidate(&floored, 0.5), Some(0));
        // A large gain still wins over a near small one.
        let cands = [c(Some(5.0), 0.1), c(Some(30.0), 40.0)];
        assert_eq!(best_candidate(&with_gain_floor(&cands, 2.0), 0.5), Some(1));
        // No floor: unchanged.
        assert_eq!(with_gain_floor(&cands, 0.0), cands.to_vec());
    }
}
