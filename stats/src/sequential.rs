//! A sequential grid's progress: the seeds added batch by batch while the labels' tests
//! ([`crate::sprt`], the GSPRT) are undecided, and its text.
//!
//! Nothing here reads a clock or a file: the grid runner feeds it stored results, plans each
//! batch's jobs and replays a grid from its store (`floorcast_coordinator::sequential`).

use std::collections::BTreeSet;

use crate::sprt::{gain_pct_of_effect, Decision, LabelTest, SequentialPlan, LOOK_PAIRS};
use crate::StoredResult;

/// Where a sequential grid stands: the seeds planned so far, the labels still undecided, and
/// the path of every test (one [`LabelTest`] per label per batch while it was open).
#[derive(Debug, Clone, PartialEq)]
pub struct Progress {
    /// Seeds `1..=through_seed` are planned for the labels open at each batch.
    pub through_seed: u64,
    pub open: BTreeSet<String>,
    pub path: Vec<LabelTest>,
    /// Every comparison decided, or `max_seeds` reached.
    pub finished: bool,
    /// The ids of the jobs planned so far (the runs the tests may use).
    pub planned: BTreeSet<String>,
    /// Pairs of each label's test when it last looked.
    looked_at: std::collections::BTreeMap<String, usize>,
}

/// The next batch of a sequential grid: its seeds, for these labels (the reference and the
/// labels still undecided).
#[derive(Debug, Clone, PartialEq)]
pub struct Batch {
    pub seeds: Vec<u64>,
    pub labels: BTreeSet<String>,
}

impl Progress {
    /// The first batch of a grid: `sequential` its test (`None`: not sequential, finished from
    /// the start), `labels` its labels in order, `planned` the ids of its first batch's jobs.
    pub fn start(
        sequential: Option<&SequentialPlan>,
        labels: &[String],
        planned: impl IntoIterator<Item = String>,
    ) -> Self {
        let seq = sequential;
        Self {
            through_seed: seq.map_or(0, |q| q.batch_seeds),
            open: labels
                .iter()
                .filter(|l| seq.is_some_and(|q| **l != q.reference))
                .cloned()
                .collect(),
            path: Vec::new(),
            finished: seq.is_none(),
            planned: planned.into_iter().collect(),
            looked_at: Default::default(),
        }
    }

    /// Every job planned so far is stored (in `results`): tests the batch just completed, and
    /// returns the next batch (the next seeds, for the reference and the labels still
    /// undecided), or none when the grid is finished. `sequential` and `labels` are the grid's,
    /// as [`Progress::start`] was given them; the caller plans the batch's jobs and adds their
    /// ids with [`Progress::plan`].
    pub fn advance(
        &mut self,
        sequential: Option<&SequentialPlan>,
        labels: &[String],
        results: &[StoredResult],
    ) -> Option<Batch> {
        let Some(seq) = sequential else {
            self.finished = true;
            return None;
        };
        if self.finished {
            return None;
        }
        let ours: Vec<StoredResult> = results
            .iter()
            .filter(|r| self.planned.contains(&r.job_id))
            .cloned()
            .collect();
        let labels: Vec<String> = labels
            .iter()
            .filter(|l| self.open.contains(*l) || **l == seq.reference)
            .cloned()
            .collect();
        let final_batch = self.through_seed >= seq.max_seeds;
        for mut t in seq.tests(&labels, &ours, self.through_seed) {
            // A look needs LOOK_PAIRS new pairs: fewer are pooled with the next batch's, except
            // at the last batch, which is always looked at.
            let last = self.looked_at.get(&t.label).copied().unwrap_or(0);
            if t.state.pairs >= last + LOOK_PAIRS || (final_batch && t.state.pairs > last) {
                self.looked_at.insert(t.label.clone(), t.state.pairs);
            } else {
                t.state.decision = Decision::Undecided;
            }
            if t.state.decision != Decision::Undecided {
                self.open.remove(&t.label);
            }
            self.path.push(t);
        }
        if self.open.is_empty() || self.through_seed >= seq.max_seeds {
            self.finished = true;
            return None;
        }
        let next = (self.through_seed + seq.batch_seeds).min(seq.max_seeds);
        let seeds: Vec<u64> = (self.through_seed + 1..=next).collect();
        self.through_seed = next;
        let mut labels = self.open.clone();
        labels.insert(seq.reference.clone());
        Some(Batch { seeds, labels })
    }

    /// The ids of a batch's jobs, as planned: the runs the tests may use.
    pub fn plan(&mut self, ids: impl IntoIterator<Item = String>) {
        self.planned.extend(ids);
    }

    /// The tests of the last batch each label took part in, in the plan's label order.
    pub fn latest(&self) -> Vec<&LabelTest> {
        let mut by_label: std::collections::BTreeMap<&str, &LabelTest> = Default::default();
        for t in &self.path {
            by_label.insert(&t.label, t);
        }
        let mut v: Vec<&LabelTest> = by_label.into_values().collect();
        v.sort_by_key(|t| self.path.iter().position(|p| p.label == t.label));
        v
    }
}

/// What a decision says, in words: the GSPRT accepting H0 rejected H1 ("rejected H1 (gain
/// below 15 %)"), accepting H1 rejected H0 ("rejected H0 (gain above 5 %)"). When the anytime
/// interval `anytime` (as gains in per cent) excludes the value of the hypothesis accepted (H0
/// accepted with the whole interval above `h0`, or H1 with it below `h1`), the gain lies between
/// the two: that, the interval first. `hypotheses` are `(h0_gain_pct, h1_gain_pct)`, unknown for
/// a test read from a store alone.
pub fn decision_text(
    decision: Decision,
    hypotheses: Option<(f64, f64)>,
    anytime: Option<(f64, f64)>,
) -> String {
    let num = |v: f64| format!("{}", (v * 1e6).round() / 1e6);
    match (decision, hypotheses) {
        (Decision::Undecided, _) => "undecided".to_string(),
        (Decision::H0, None) => "rejected H1 (H0 accepted)".to_string(),
        (Decision::H1, None) => "rejected H0 (H1 accepted)".to_string(),
        (d, Some((h0, h1))) => {
            let rejected = if d == Decision::H0 {
                format!("rejected H1 (gain below {} %)", num(h1))
            } else {
                format!("rejected H0 (gain above {} %)", num(h0))
            };
            match anytime {
                Some((lo, hi))
                    if (d == Decision::H0 && lo > h0) || (d == Decision::H1 && hi < h1) =>
                {
                    format!(
                        "gain between {} % and {} % (anytime 95 % [{lo:+.1}, {hi:+.1}] excludes {} %): {rejected}",
                        num(h0),
                        num(h1),
                        num(if d == Decision::H0 { h0 } else { h1 })
                    )
                }
                _ => rejected,
            }
        }
    }
}

/// A test's line: its decision in words ([`decision_text`]; `config` gives the hypotheses,
/// unknown for a test read from a store alone), pairs, mean gain with its anytime-valid
/// interval, and the LLR with its bounds (a dash before the test has
/// [`MIN_PAIRS`](crate::sprt::MIN_PAIRS) pairs).
pub fn render_test(t: &LabelTest, config: Option<&crate::sprt::SprtConfig>) -> String {
    let s = &t.state;
    let anytime_pct = s
        .anytime_ci95()
        .map(|(a, b)| (gain_pct_of_effect(a), gain_pct_of_effect(b)));
    let anytime = anytime_pct.map_or("-".to_string(), |(a, b)| format!("[{a:+.1}, {b:+.1}]"));
    let llr = s
        .llr_if_any()
        .map_or("-".to_string(), |l| format!("{l:.2}"));
    format!(
        "{:<16} vs {:<12} {} after {:>3} pairs (seeds 1-{}), mean gain {:+.1} % (anytime 95 % {anytime}), LLR {llr} in [{:.2}, {:.2}]",
        t.label,
        t.reference,
        decision_text(
            s.decision,
            config.map(|c| (c.h0_gain_pct, c.h1_gain_pct)),
            anytime_pct
        ),
        s.pairs,
        t.through_seed,
        gain_pct_of_effect(s.mean),
        s.lower,
        s.upper
    )
}

/// One line per comparison: its decision, pairs, statistic and bounds.
pub fn render(progress: &Progress, seq: &SequentialPlan) -> String {
    use std::fmt::Write as _;
    let label_alpha = seq.label_config().alpha;
    let mut out = format!(
        "Sequential test (GSPRT on ln(t_ref / t), {} at {} coverage, a run below it a loss, a pair of runs both below it scored by explored fraction then time; H0: gain <= {} %, H1: gain >= {} %, alpha {} ({} over {} labels: {} each), beta {}; accepting H0 rejects H1, accepting H1 rejects H0):\n",
        seq.measure.text(seq.coverage),
        crate::outcome::coverage_text(seq.coverage),
        seq.config.h0_gain_pct,
        seq.config.h1_gain_pct,
        seq.config.alpha,
        seq.multiplicity.as_str(),
        seq.labels_tested,
        label_alpha,
        seq.config.beta
    );
    for t in progress.latest() {
        let _ = writeln!(out, "  {}", render_test(t, Some(&seq.config)));
    }
    if !progress.finished {
        let _ = writeln!(out, "  (not finished: run the same command again to go on)");
    }
    out
}

impl SequentialPlan {
    /// The test of each label (in `labels` order, the reference left out) on the stored runs of
    /// seeds up to `through_seed`: pairs of a label's run and the reference's run on the same
    /// building, seed and start pose ([`crate::outcome::paired`] at the grid's coverage level:
    /// a run that did not achieve it is a loss; two that did not are scored by explored fraction,
    /// then time, [`crate::outcome::Pair::both_short_s`]), timed by the grid's `measure`.
    pub fn tests(
        &self,
        labels: &[String],
        results: &[StoredResult],
        through_seed: u64,
    ) -> Vec<LabelTest> {
        let within: Vec<&StoredResult> =
            results.iter().filter(|r| r.seed <= through_seed).collect();
        let config = self.label_config();
        labels
            .iter()
            .filter(|l| **l != self.reference)
            .map(|label| {
                let outcomes: Vec<f64> = crate::outcome::paired_by(
                    within.iter().copied(),
                    label,
                    &self.reference,
                    self.coverage,
                    self.measure,
                )
                .pairs
                .iter()
                .map(crate::outcome::Pair::log_ratio)
                .collect();
                LabelTest {
                    label: label.clone(),
                    reference: self.reference.clone(),
                    through_seed,
                    state: config.state(&outcomes),
                }
            })
            .collect()
    }
}
