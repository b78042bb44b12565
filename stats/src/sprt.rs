//! Sequential comparisons: a generalized sequential probability ratio test (GSPRT) on paired
//! outcomes, as fishtest decides chess engine changes (its SPRT on pentanomial outcomes and
//! M. Van den Bergh's GSPRT notes).
//!
//! The outcome of a pair (the same building and seed run with the reference label and with the
//! label under test) is the log ratio of their exploration times, `x = ln(t_ref / t_label)`:
//! positive when the label is faster, comparable across buildings of different sizes, and
//! additive (a gain of `g` per cent in every run is the same `x` on a small building and on a
//! large one). A gain of `g` per cent (`t_label = (1 - g / 100) t_ref`) is the effect
//! `e = -ln(1 - g / 100)`.
//!
//! Hypotheses: H0, the mean effect is at most `e0` (the gain is at most `h0_gain_pct`), against
//! H1, it is at least `e1` (at least `h1_gain_pct`), for approximately normal outcomes whose
//! variance is unknown. The generalized log-likelihood ratio of H1 against H0 over `n` pairs is
//! `(n / 2) ln(S0 / S1)`, with `S_k` the sum of squared distances of the outcomes to the mean
//! hypothesis `k` allows nearest to their mean `m` (`S0` about `min(m, e0)`, `S1` about
//! `max(m, e1)`: each hypothesis with its own maximum-likelihood variance); the test accepts H1
//! when it rises above `ln((1 - beta) / alpha)` and H0 when it falls below
//! `ln(beta / (1 - alpha))` (Wald's bounds). It decides on at least [`MIN_PAIRS`] pairs and looks
//! again only once [`LOOK_PAIRS`] new pairs have come (a grid's batches that add fewer are
//! pooled): with a handful of pairs the variance estimate is often far too small, and looking
//! after every 2 pairs decided wrongly 10-12 % of the time at nominal 5 % in the simulations of
//! `tests::error_rates_hold_under_repeated_looks`. Measured there (2000 simulated tests under
//! each hypothesis, at the boundaries e0 and e1 where composite hypotheses err most): both error
//! rates within `alpha` and `beta` up to simulation noise for spreads of the outcomes up to 4
//! times the gap `e1 - e0` (0.2 against 0.05: about 90 pairs under H0); at 6 times the gap they
//! reach 6-7 % (180 pairs). Against the simple hypotheses `e0` and `e1` alone (the form before),
//! a large gain decides far sooner: 30 % faster with a pair-to-pair spread of 10 % takes one
//! look, where the simple form was still undecided after 8 pairs (its variances about `e0` and
//! `e1` both absorb the distance to the true mean). Fishtest's normal approximation
//! `n (e1 - e0) (2 m - e0 - e1) / (2 s2)` with the pooled sample variance `s2` is the same test
//! for large `n`, and wrong 7-8 % of the time with a handful of pairs.
//!
//! A pair's outcome is [`crate::outcome`]'s: a run that did not achieve the outcome at the
//! grid's coverage level (an early stop short of it, the time limit, stuck, failed) is charged
//! the pair's horizon (the time limit), so it counts as a loss against a partner that achieved
//! it; a pair where neither did is scored by how much each explored, then by time
//! ([`crate::outcome::Pair::both_short_s`]); no pair is left out.
//!
//! What a decision means: accepting H0 rejects H1 (the gain is below `h1_gain_pct`), accepting H1
//! rejects H0 (above `h0_gain_pct`); neither shows the other hypothesis. The report says it that
//! way ([`crate::sequential::decision_text`]) and, when the anytime interval excludes the
//! hypothesis accepted, that the gain lies between the two.
//!
//! Several labels tested against one reference form a family: by default each label's test
//! runs at `alpha / k` for `k` labels (Bonferroni), so that the chance of any false H1 in the
//! grid stays within `alpha`; a grid may say `multiplicity = "none"`. The last batch a label
//! takes part in (at `max_seeds`) is always looked at, however few pairs it added.
//!
//! Zero variance (two labels whose runs are identical, or differ by the same factor in every
//! pair) is the limit of the ratio: outcomes all equal to `e0` decide H0 at once, all equal to
//! `e1` H1, and anything else is decided by the finite ratio; no division by zero.
//!
//! Nothing here reads a clock or a file: [`crate::sequential`] feeds it outcomes.

use serde::{Deserialize, Serialize};

/// Fewest pairs a test decides on.
pub const MIN_PAIRS: usize = 10;
/// Fewest new pairs between two looks: a label's test decides only when its pairs grew by this
/// much since it last looked (batches that add fewer pairs are pooled).
pub const LOOK_PAIRS: usize = 10;

/// A sequential test's parameters, as in a grid file's `[sequential]` table.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SprtConfig {
    /// H0: the gain over the reference is at most this (per cent of the reference's time).
    pub h0_gain_pct: f64,
    /// H1: the gain is at least this (per cent); greater than `h0_gain_pct`.
    pub h1_gain_pct: f64,
    /// Probability of accepting H1 when H0 holds (0 < alpha < 0.5).
    pub alpha: f64,
    /// Probability of accepting H0 when H1 holds (0 < beta < 0.5).
    pub beta: f64,
}

impl Default for SprtConfig {
    fn default() -> Self {
        Self {
            h0_gain_pct: 0.0,
            h1_gain_pct: 5.0,
            alpha: 0.05,
            beta: 0.05,
        }
    }
}

/// What a sequential test has decided so far. Its serde words are [`Decision::as_str`]'s, the
/// words the store keeps.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Decision {
    /// The gain is at most `h0_gain_pct`.
    H0,
    /// The gain is at least `h1_gain_pct`.
    H1,
    /// Not yet (or never, when the pairs ran out).
    #[serde(rename = "undecided")]
    Undecided,
}

impl Decision {
    /// The name in reports and JSON: "H0", "H1" or "undecided".
    pub fn as_str(self) -> &'static str {
        match self {
            Decision::H0 => "H0",
            Decision::H1 => "H1",
            Decision::Undecided => "undecided",
        }
    }
}

/// The state of a test after some pairs.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SprtState {
    /// Pairs seen.
    pub pairs: usize,
    /// Mean outcome (log ratio of times; positive = the label is faster).
    pub mean: f64,
    /// Maximum-likelihood variance of the outcomes.
    pub variance: f64,
    /// The log-likelihood ratio of H1 against H0 (may be infinite with zero variance).
    pub llr: f64,
    /// Wald's bounds: H0 below `lower`, H1 above `upper`.
    pub lower: f64,
    pub upper: f64,
    pub decision: Decision,
}

/// A gain in per cent of the reference's time as an effect on the log ratio of times.
pub fn effect_of_gain_pct(gain_pct: f64) -> f64 {
    -(1.0 - gain_pct / 100.0).ln()
}

/// The effect as a gain in per cent of the reference's time.
pub fn gain_pct_of_effect(effect: f64) -> f64 {
    100.0 * (1.0 - (-effect).exp())
}

impl SprtState {
    /// The log-likelihood ratio, once the test has the pairs to compute one ([`MIN_PAIRS`]).
    pub fn llr_if_any(&self) -> Option<f64> {
        (self.pairs >= MIN_PAIRS).then_some(self.llr)
    }

    /// The anytime-valid 95 % interval of the mean outcome ([`crate::stats::confidence_sequence`]),
    /// which holds where the test stopped.
    pub fn anytime_ci95(&self) -> Option<(f64, f64)> {
        let n = self.pairs;
        if n < 2 {
            return None;
        }
        let sd = (self.variance * n as f64 / (n - 1) as f64).sqrt();
        let h = crate::stats::confidence_sequence_half_width(n, sd)?;
        Some((self.mean - h, self.mean + h))
    }
}

impl SprtConfig {
    /// Checks the parameters; the error names the field and what is expected.
    pub fn validate(&self) -> Result<(), String> {
        let in_range = |v: f64| v.is_finite() && v > -100.0 && v < 100.0;
        if !in_range(self.h0_gain_pct) {
            return Err(format!(
                "h0_gain_pct: {} is not a gain in per cent (expected more than -100 and less than 100)",
                self.h0_gain_pct
            ));
        }
        if !in_range(self.h1_gain_pct) || self.h1_gain_pct <= self.h0_gain_pct {
            return Err(format!(
                "h1_gain_pct: {} must be a gain in per cent greater than h0_gain_pct ({}) and less than 100",
                self.h1_gain_pct, self.h0_gain_pct
            ));
        }
        for (name, v) in [("alpha", self.alpha), ("beta", self.beta)] {
            if !(v.is_finite() && v > 0.0 && v < 0.5) {
                return Err(format!(
                    "{name}: {v} is not an error rate (expected more than 0 and less than 0.5)"
                ));
            }
        }
        Ok(())
    }

    /// Wald's bounds `(lower, upper)` on the log-likelihood ratio.
    pub fn bounds(&self) -> (f64, f64) {
        (
            (self.beta / (1.0 - self.alpha)).ln(),
            ((1.0 - self.beta) / self.alpha).ln(),
        )
    }

    /// The test after the outcomes seen so far (in any order: only their mean and variance
    /// count). With fewer than two pairs nothing is decided.
    pub fn state(&self, outcomes: &[f64]) -> SprtState {
        let (lower, upper) = self.bounds();
        let n = outcomes.len();
        let mean = if n == 0 {
            0.0
        } else {
            outcomes.iter().sum::<f64>() / n as f64
        };
        let variance = if n == 0 {
            0.0
        } else {
            outcomes.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / n as f64
        };
        let (e0, e1) = (
            effect_of_gain_pct(self.h0_gain_pct),
            effect_of_gain_pct(self.h1_gain_pct),
        );
        // The generalized likelihood ratio with the variance unknown under each hypothesis
        // (each its own maximum-likelihood variance about its mean): (n / 2) ln(S0 / S1), with
        // S_k the sum of squared distances of the outcomes to e_k.
        // Each hypothesis is composite (H0: mean <= e0, H1: mean >= e1): its variance is taken
        // about the mean it allows nearest to the outcomes' mean.
        let ss = |mu: f64| outcomes.iter().map(|x| (x - mu).powi(2)).sum::<f64>();
        let s0: f64 = ss(mean.min(e0));
        let s1: f64 = ss(mean.max(e1));
        // Sums below rounding of the log ratios count as zero.
        let tiny = 1e-24 * n as f64;
        let llr = if n < MIN_PAIRS || (s0 <= tiny && s1 <= tiny) {
            0.0
        } else if s1 <= tiny {
            f64::INFINITY
        } else if s0 <= tiny {
            f64::NEG_INFINITY
        } else {
            n as f64 / 2.0 * (s0 / s1).ln()
        };
        let decision = if llr >= upper {
            Decision::H1
        } else if llr <= lower {
            Decision::H0
        } else {
            Decision::Undecided
        };
        SprtState {
            pairs: n,
            mean,
            variance,
            llr,
            lower,
            upper,
            decision,
        }
    }
}

/// How a sequential grid shares its error rate among the labels it tests.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Multiplicity {
    /// Each of `k` labels tested at `alpha / k`: any false H1 within `alpha` (the default).
    Bonferroni,
    /// Each label at `alpha`.
    None,
}

impl Multiplicity {
    pub fn as_str(self) -> &'static str {
        match self {
            Multiplicity::Bonferroni => "bonferroni",
            Multiplicity::None => "none",
        }
    }
}

/// A grid's sequential test: the comparisons of every label with `reference`, seeds added
/// `batch_seeds` at a time up to `max_seeds`.
#[derive(Debug, Clone, PartialEq)]
pub struct SequentialPlan {
    /// The test as the grid file gives it (its `alpha` the family's).
    pub config: SprtConfig,
    pub reference: String,
    pub batch_seeds: u64,
    pub max_seeds: u64,
    /// The coverage level of the pairs' outcomes ([`crate::outcome`]).
    pub coverage: f64,
    pub multiplicity: Multiplicity,
    /// Labels tested against the reference (the family's size).
    pub labels_tested: usize,
    /// The time the pairs' outcomes measure (the grid's `measure`; default the time to end).
    pub measure: crate::measure::Measure,
}

/// One comparison's test after the runs of seeds `1..=through_seed`.
#[derive(Debug, Clone, PartialEq)]
pub struct LabelTest {
    pub label: String,
    pub reference: String,
    pub through_seed: u64,
    pub state: SprtState,
}

impl SequentialPlan {
    /// The test each label runs: the grid's, with `alpha` shared by the family.
    pub fn label_config(&self) -> SprtConfig {
        let k = match self.multiplicity {
            Multiplicity::Bonferroni => self.labels_tested.max(1) as f64,
            Multiplicity::None => 1.0,
        };
        SprtConfig {
            alpha: self.config.alpha / k,
            ..self.config.clone()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_distr::{Distribution, Normal};

    #[test]
    fn gains_and_effects_convert_both_ways() {
        for g in [-50.0, -5.0, 0.0, 5.0, 34.0, 90.0] {
            assert!((gain_pct_of_effect(effect_of_gain_pct(g)) - g).abs() < 1e-9);
        }
        assert_eq!(effect_of_gain_pct(0.0), 0.0);
        // 10 % faster: 0.9 of the time.
        assert!(((100f64).ln() - (90f64).ln() - effect_of_gain_pct(10.0)).abs() < 1e-12);
    }

    #[test]
    fn bad_parameters_name_the_field() {
        let cases = [
            (
                SprtConfig {
                    h1_gain_pct: 0.0,
                    ..SprtConfig::default()
                },
                "h1_gain_pct",
            ),
            (
                SprtConfig {
                    h0_gain_pct: f64::NAN,
                    ..SprtConfig::default()
                },
                "h0_gain_pct",
            ),
            (
                SprtConfig {
                    alpha: 0.0,
                    ..SprtConfig::default()
                },
                "alpha",
            ),
            (
                SprtConfig {
                    beta: 0.7,
                    ..SprtConfig::default()
                },
                "beta",
            ),
            (
                SprtConfig {
                    h1_gain_pct: 100.0,
                    ..SprtConfig::default()
                },
                "h1_gain_pct",
            ),
        ];
        for (cfg, field) in cases {
            let e = cfg.validate().unwrap_err();
            assert!(e.starts_with(field), "{e}");
        }
        assert!(SprtConfig::default().validate().is_ok());
    }

    /// Two labels whose runs are identical: zero variance, mean 0 = e0, decided H0 at the first
    /// look, no NaN; a label 10 % faster in every pair: H1; a large gain with a spread: H1 at
    /// the first look (the composite hypotheses measure it from its own mean).
    #[test]
    fn zero_variance_decides_without_numeric_trouble() {
        let cfg = SprtConfig::default();
        let same = cfg.state(&[0.0; MIN_PAIRS]);
        assert_eq!(same.decision, Decision::H0);
        assert_eq!(same.llr, f64::NEG_INFINITY);
        assert!(!same.mean.is_nan() && !same.variance.is_nan());
        let faster = cfg.state(&[effect_of_gain_pct(10.0); MIN_PAIRS]);
        assert_eq!(faster.decision, Decision::H1);
        assert!(!faster.llr.is_nan());
        // About 30 % faster, pair to pair between 20 and 40 %.
        let spread: Vec<f64> = (0..MIN_PAIRS)
            .map(|i| effect_of_gain_pct(20.0 + 20.0 * i as f64 / (MIN_PAIRS - 1) as f64))
            .collect();
        assert_eq!(cfg.state(&spread).decision, Decision::H1);
        // Exactly between the hypotheses: the data say nothing.
        let mid = (effect_of_gain_pct(0.0) + effect_of_gain_pct(5.0)) / 2.0;
        assert_eq!(cfg.state(&[mid; MIN_PAIRS]).decision, Decision::Undecided);
        // Nothing is decided on fewer than MIN_PAIRS pairs.
        assert_eq!(
            cfg.state(&[0.0; MIN_PAIRS - 1]).decision,
            Decision::Undecided
        );
        assert_eq!(cfg.state(&[]).decision, Decision::Undecided);
    }

    /// Runs one sequential test on simulated normal outcomes of mean `effect` and standard
    /// deviation `sd`, looking after each batch, up to `max_pairs`.
    fn simulate(
        cfg: &SprtConfig,
        effect: f64,
        sd: f64,
        batch: usize,
        max_pairs: usize,
        rng: &mut rand_chacha::ChaCha8Rng,
    ) -> (Decision, usize) {
        let noise = Normal::new(effect, sd).unwrap();
        let mut xs = Vec::with_capacity(max_pairs);
        while xs.len() < max_pairs {
            for _ in 0..batch {
                xs.push(noise.sample(rng));
            }
            let s = cfg.state(&xs);
            if s.decision != Decision::Undecided {
                return (s.decision, xs.len());
            }
        }
        (Decision::Undecided, xs.len())
    }

    /// 2000 simulated sequential tests at each hypothesis (and at a few spreads of the outcomes,
    /// batch sizes as grids use them: a batch of 2 seeds on 3 to 10 buildings): the rate of
    /// wrong decisions stays within the nominal alpha and beta up to simulation noise (three
    /// standard errors of a rate of 0.05 over 2000 tests: 0.015).
    #[test]
    fn error_rates_hold_under_repeated_looks() {
        let cfg = SprtConfig::default();
        let (e0, e1) = (
            effect_of_gain_pct(cfg.h0_gain_pct),
            effect_of_gain_pct(cfg.h1_gain_pct),
        );
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(20261125);
        let runs = 2000;
        for (sd, batch) in [(0.02, 10), (0.05, 10), (0.1, 10), (0.1, 20), (0.2, 10)] {
            let mut false_h1 = 0;
            let mut false_h0 = 0;
            let mut pairs = 0;
            for _ in 0..runs {
                let (d, n) = simulate(&cfg, e0, sd, batch, 4000, &mut rng);
                false_h1 += (d == Decision::H1) as usize;
                pairs += n;
                let (d, _) = simulate(&cfg, e1, sd, batch, 4000, &mut rng);
                false_h0 += (d == Decision::H0) as usize;
            }
            let (a, b) = (false_h1 as f64 / runs as f64, false_h0 as f64 / runs as f64);
            eprintln!(
                "sd {sd}, batch {batch}: false H1 {a:.4}, false H0 {b:.4}, mean pairs under H0 {:.1}",
                pairs as f64 / runs as f64
            );
            assert!(
                a <= cfg.alpha + 0.015,
                "sd {sd} batch {batch}: false H1 rate {a}"
            );
            assert!(
                b <= cfg.beta + 0.015,
                "sd {sd} batch {batch}: false H0 rate {b}"
            );
        }
    }

    /// The sequential test's error rates when runs fall short of the coverage level and pairs
    /// are scored by [`crate::outcome::Pair::charged_s`] (a shortfall against a run that
    /// achieved is a loss charged the horizon; two shortfalls by explored fraction, then time):
    /// 1000 simulated tests per setting, log-normal times (sd 0.3 between pairs), the label's
    /// log ratio at e0 or e1 with spread `sd`, each run falling short with probability `q`
    /// (stalled at 97.5-99 % explored, its end time its own), looks every 10 pairs up to 400.
    /// Printed with `cargo test --release -p floorcast-coordinator --lib shortfall_error_rates
    /// -- --nocapture`; asserted within alpha and beta plus 0.02.
    #[test]
    fn shortfall_error_rates_hold() {
        use crate::outcome::{Pair, RunOutcome};
        use rand::Rng;
        let cfg = SprtConfig::default();
        let (e0, e1) = (
            effect_of_gain_pct(cfg.h0_gain_pct),
            effect_of_gain_pct(cfg.h1_gain_pct),
        );
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(20261207);
        let outcome = |t: f64, short: Option<f64>| RunOutcome {
            building: "b".into(),
            seed: 1,
            start: None,
            achieved_s: short.is_none().then_some(t),
            not_achieved: short.map(|_| "stuck".to_string()),
            explored_fraction: Some(short.unwrap_or(0.995)),
            horizon_s: 14_400.0,
            end_s: Some(t),
            curve: None,
        };
        let runs = 1000;
        for (sd, q) in [(0.05, 0.02), (0.05, 0.1), (0.1, 0.05), (0.1, 0.2)] {
            let mut wrong = [0usize; 2];
            for (k, effect) in [e0, e1].into_iter().enumerate() {
                let spread = Normal::new(effect, sd).unwrap();
                let between = Normal::new(7.0f64, 0.3).unwrap();
                for _ in 0..runs {
                    let mut xs = Vec::new();
                    let d = loop {
                        for _ in 0..10 {
                            let tr = f64::exp(between.sample(&mut rng));
                            let tl = tr * (-spread.sample(&mut rng)).exp();
                            let mut side =
                                || (rng.random::<f64>() < q).then(|| rng.random_range(0.975..0.99));
                            let (sr, sl) = (side(), side());
                            let p = Pair {
                                label: outcome(tl, sl),
                                reference: outcome(tr, sr),
                            };
                            xs.push(p.log_ratio());
                        }
                        let s = cfg.state(&xs);
                        if s.decision != Decision::Undecided || xs.len() >= 400 {
                            break s.decision;
                        }
                    };
                    let bad = if k == 0 { Decision::H1 } else { Decision::H0 };
                    wrong[k] += usize::from(d == bad);
                }
            }
            let (a, b) = (wrong[0] as f64 / runs as f64, wrong[1] as f64 / runs as f64);
            eprintln!("sd {sd}, shortfall {q}: false H1 {a:.3}, false H0 {b:.3}");
            assert!(a <= cfg.alpha + 0.02, "sd {sd} q {q}: false H1 {a}");
            assert!(b <= cfg.beta + 0.02, "sd {sd} q {q}: false H0 {b}");
        }
    }

    /// The outcome noise of the coverage simulation: normal, Student's t with 3 degrees of
    /// freedom (heavy tails) scaled to the same standard deviation, or normal with 5 % of the
    /// label's runs taking twice as long (`x - ln 2`).
    #[derive(Debug, Clone, Copy)]
    enum Noise {
        Normal,
        T3,
        Doubled5,
    }

    impl Noise {
        fn sample(self, centre: f64, sd: f64, rng: &mut rand_chacha::ChaCha8Rng) -> f64 {
            use rand::Rng;
            match self {
                Noise::Normal => Normal::new(centre, sd).unwrap().sample(rng),
                Noise::T3 => {
                    centre + sd / 3f64.sqrt() * rand_distr::StudentT::new(3.0).unwrap().sample(rng)
                }
                Noise::Doubled5 => {
                    // Each run of the pair, the label's and the reference's, takes twice as
                    // long with probability 0.05.
                    let mut x = Normal::new(centre, sd).unwrap().sample(rng);
                    if rng.random::<f64>() < 0.05 {
                        x -= 2f64.ln();
                    }
                    if rng.random::<f64>() < 0.05 {
                        x += 2f64.ln();
                    }
                    x
                }
            }
        }

        /// The true mean of the outcomes around `centre` (every noise is symmetric about it).
        fn mean(self, centre: f64) -> f64 {
            centre
        }
    }

    /// Thousands of simulated sequential tests, each stopped where the GSPRT decided (looking
    /// every 10 pairs, as grids do) or at 400 pairs: the anytime-valid interval at the stop holds
    /// the true mean in at least 94 % of them at nominal 95 %, for spreads up to 4 times the gap
    /// between the hypotheses (0.2 against 0.051), with normal, heavy-tailed (t, 3 degrees of
    /// freedom) and contaminated (5 % of runs twice as long) outcomes, true means at H0, between the
    /// hypotheses and at H1. The fixed-sample t interval at the same stops is measured too: it
    /// falls below its nominal coverage (what the anytime interval is for).
    #[test]
    fn confidence_sequence_covers_after_sequential_stops() {
        let cfg = SprtConfig::default();
        let (e0, e1) = (
            effect_of_gain_pct(cfg.h0_gain_pct),
            effect_of_gain_pct(cfg.h1_gain_pct),
        );
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(20261128);
        let runs = 1000;
        let mut worst_t: f64 = 1.0;
        for noise in [Noise::Normal, Noise::T3, Noise::Doubled5] {
            for sd in [0.02, 0.05, 0.1, 0.2] {
                for centre in [e0, (e0 + e1) / 2.0, e1] {
                    let truth = noise.mean(centre);
                    let (mut covered, mut t_covered) = (0, 0);
                    for _ in 0..runs {
                        let mut xs: Vec<f64> = Vec::new();
                        let state = loop {
                            for _ in 0..10 {
                                xs.push(noise.sample(centre, sd, &mut rng));
                            }
                            let s = cfg.state(&xs);
                            if s.decision != Decision::Undecided || xs.len() >= 400 {
                                break s;
                            }
                        };
                        let (lo, hi) = state.anytime_ci95().unwrap();
                        covered += usize::from(lo <= truth && truth <= hi);
                        let t = crate::table::PairedGain::of_log_ratios(&xs).unwrap();
                        t_covered += usize::from((t.mean_log - truth).abs() <= t.t_half_log);
                    }
                    let rate = covered as f64 / runs as f64;
                    let t_rate = t_covered as f64 / runs as f64;
                    worst_t = worst_t.min(t_rate);
                    eprintln!(
                        "{noise:?} sd {sd} mean {truth:.4}: anytime {rate:.3}, fixed-sample t {t_rate:.3}"
                    );
                    assert!(
                        rate >= 0.94,
                        "{noise:?} sd {sd} mean {truth}: the anytime interval covered {rate}"
                    );
                }
            }
        }
        // The reason for it: somewhere the fixed-sample interval does not hold after the stop.
        assert!(worst_t < 0.93, "fixed-sample t coverage at worst {worst_t}");
    }
}
