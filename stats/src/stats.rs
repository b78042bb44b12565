//! The statistics of a paired comparison beyond the t interval: the Wilcoxon signed-rank test,
//! a seeded percentile bootstrap of the mean, Holm's adjustment across the comparisons of one
//! report, and the paired effect size. Pure functions of the per-pair differences.

use rand::{Rng, SeedableRng};
use statrs::distribution::{ContinuousCDF, Normal};

/// Two-sided p-value of the Wilcoxon signed-rank test that the differences are centred on 0,
/// as `scipy.stats.wilcoxon(d)` gives it with its defaults (scipy 1.17: zero differences
/// dropped, ties sharing their average rank, `method="auto"`): for at most 50 differences
/// without ties or zeros the exact distribution of the positive rank sum; with ties or zeros and
/// at most 13 differences every sign pattern of the non-zero ones (the exact permutation test);
/// else the normal approximation with the tie correction and without a continuity correction.
/// `None` without a non-zero difference.
pub fn wilcoxon_signed_rank_p(differences: &[f64]) -> Option<f64> {
    let finite: Vec<f64> = differences
        .iter()
        .copied()
        .filter(|x| x.is_finite())
        .collect();
    let zeros = finite.iter().filter(|x| **x == 0.0).count();
    let mut d: Vec<f64> = finite.iter().copied().filter(|x| *x != 0.0).collect();
    let n = d.len();
    if n == 0 {
        return None;
    }
    d.sort_by(|a, b| a.abs().total_cmp(&b.abs()));
    // Average ranks of equal magnitudes.
    let mut ranks = vec![0.0; n];
    let mut ties_term = 0.0;
    let mut i = 0;
    while i < n {
        let mut j = i;
        while j + 1 < n && d[j + 1].abs() == d[i].abs() {
            j += 1;
        }
        let t = (j - i + 1) as f64;
        let rank = (i + j) as f64 / 2.0 + 1.0;
        for r in &mut ranks[i..=j] {
            *r = rank;
        }
        ties_term += t * t * t - t;
        i = j + 1;
    }
    let w_plus: f64 = d
        .iter()
        .zip(&ranks)
        .filter(|(x, _)| **x > 0.0)
        .map(|(_, r)| r)
        .sum();
    let (ties, samples) = (ties_term > 0.0 || zeros > 0, finite.len());
    if !ties && samples <= 50 {
        // counts[s]: sign patterns whose positive ranks sum to s.
        let max = n * (n + 1) / 2;
        let mut counts = vec![0.0f64; max + 1];
        counts[0] = 1.0;
        for k in 1..=n {
            for s in (k..=max).rev() {
                counts[s] += counts[s - k];
            }
        }
        let total = 2f64.powi(n as i32);
        let w = w_plus.round() as usize;
        let lower: f64 = counts[..=w].iter().sum::<f64>() / total;
        let upper: f64 = counts[w..].iter().sum::<f64>() / total;
        return Some((2.0 * lower.min(upper)).min(1.0));
    }
    if samples <= 13 {
        // Every sign pattern of the non-zero differences (at most 2^13), their ranks fixed.
        let patterns = 1u32 << n;
        let tolerance = 1e-14 * w_plus.abs().max(1.0);
        let (mut lower, mut upper) = (0u32, 0u32);
        for pattern in 0..patterns {
            let w: f64 = (0..n)
                .filter(|k| pattern & (1 << k) != 0)
                .map(|k| ranks[k])
                .sum();
            lower += u32::from(w <= w_plus + tolerance);
            upper += u32::from(w >= w_plus - tolerance);
        }
        let p = 2.0 * lower.min(upper) as f64 / patterns as f64;
        return Some(p.min(1.0));
    }
    let nf = n as f64;
    let mean = nf * (nf + 1.0) / 4.0;
    let var = nf * (nf + 1.0) * (2.0 * nf + 1.0) / 24.0 - ties_term / 48.0;
    if var <= 0.0 {
        return Some(1.0);
    }
    let z = (w_plus - mean).abs() / var.sqrt();
    let normal = Normal::new(0.0, 1.0).expect("the standard normal");
    Some((2.0 * normal.sf(z)).min(1.0))
}

/// The Walsh averages `(x_i + x_j) / 2` for `i <= j` of the finite `xs`, sorted.
fn walsh_averages(xs: &[f64]) -> Vec<f64> {
    let v: Vec<f64> = xs.iter().copied().filter(|x| x.is_finite()).collect();
    let mut w = Vec::with_capacity(v.len() * (v.len() + 1) / 2);
    for i in 0..v.len() {
        for j in i..v.len() {
            w.push((v[i] + v[j]) / 2.0);
        }
    }
    w.sort_by(f64::total_cmp);
    w
}

/// The Hodges-Lehmann estimate of the centre of `xs`: the median of their Walsh averages
/// (Hodges and Lehmann, *Annals of Mathematical Statistics* 1963), the estimate that goes with
/// Wilcoxon's signed-rank test. A value far out (a run charged the time limit) moves it only by
/// its rank: how large the charge is does not swing it. `None` without a finite value.
pub fn hodges_lehmann(xs: &[f64]) -> Option<f64> {
    median(&walsh_averages(xs))
}

/// The 95 % confidence interval of the Hodges-Lehmann estimate from the signed-rank
/// distribution (Lehmann, *Nonparametrics*, 1975; R's `wilcox.test(x, conf.int = TRUE)`):
/// `[W_(k), W_(M + 1 - k)]` of the `M` sorted Walsh averages, `k` the largest with
/// `P(T+ <= k - 1) <= 0.025` under the null (exact for at most 50 values, else the normal
/// approximation). `None` for fewer than 6 values (no such `k`: the interval would be
/// everything).
pub fn hodges_lehmann_ci95(xs: &[f64]) -> Option<(f64, f64)> {
    let w = walsh_averages(xs);
    let m = w.len();
    let n = ((((8 * m + 1) as f64).sqrt() - 1.0) / 2.0).round() as usize;
    if n < 6 {
        return None;
    }
    let k = if n <= 50 {
        let max = n * (n + 1) / 2;
        let mut counts = vec![0.0f64; max + 1];
        counts[0] = 1.0;
        for r in 1..=n {
            for s in (r..=max).rev() {
                counts[s] += counts[s - r];
            }
        }
        let total = 2f64.powi(n as i32);
        // cdf[j] = P(T+ <= j); k - 1 the largest j with cdf <= 0.025.
        let mut cdf = 0.0;
        let mut k = 0;
        for (j, c) in counts.iter().enumerate() {
            cdf += c / total;
            if cdf <= 0.025 + 1e-12 {
                k = j + 1;
            } else {
                break;
            }
        }
        k
    } else {
        let nf = n as f64;
        let mean = nf * (nf + 1.0) / 4.0;
        let sd = (nf * (nf + 1.0) * (2.0 * nf + 1.0) / 24.0).sqrt();
        (mean - 1.959_963_984_540_054 * sd).floor().max(0.0) as usize
    };
    (1..=m).contains(&k).then(|| (w[k - 1], w[m - k]))
}

/// The seed of every bootstrap: a report is reproducible.
pub const BOOTSTRAP_SEED: u64 = 20_261_125;
/// Resamples per bootstrap interval.
pub const BOOTSTRAP_RESAMPLES: usize = 10_000;

/// The 95 % percentile bootstrap interval of the mean of `xs` (resampling the pairs with
/// replacement, [`BOOTSTRAP_RESAMPLES`] times from [`BOOTSTRAP_SEED`]). `None` for fewer than two
/// values.
pub fn bootstrap_mean_ci95(xs: &[f64]) -> Option<(f64, f64)> {
    let n = xs.len();
    if n < 2 {
        return None;
    }
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(BOOTSTRAP_SEED);
    let mut means: Vec<f64> = (0..BOOTSTRAP_RESAMPLES)
        .map(|_| (0..n).map(|_| xs[rng.random_range(0..n)]).sum::<f64>() / n as f64)
        .collect();
    means.sort_by(f64::total_cmp);
    let at = |q: f64| means[((q * (BOOTSTRAP_RESAMPLES - 1) as f64).round()) as usize];
    Some((at(0.025), at(0.975)))
}

/// Holm's step-down adjustment of p-values (one family: the comparisons of one report), in
/// the order given; `None` stays `None` and does not count.
pub fn holm(ps: &[Option<f64>]) -> Vec<Option<f64>> {
    let mut order: Vec<usize> = (0..ps.len()).filter(|&i| ps[i].is_some()).collect();
    order.sort_by(|&a, &b| ps[a].unwrap_or(1.0).total_cmp(&ps[b].unwrap_or(1.0)));
    let m = order.len();
    let mut out = vec![None; ps.len()];
    let mut running: f64 = 0.0;
    for (k, &i) in order.iter().enumerate() {
        let adjusted = ((m - k) as f64 * ps[i].unwrap_or(1.0)).min(1.0);
        running = running.max(adjusted);
        out[i] = Some(running);
    }
    out
}

/// The paired effect size (Cohen's d_z): the mean difference over its standard deviation.
/// `None` for fewer than two pairs or no spread.
pub fn effect_size_dz(xs: &[f64]) -> Option<f64> {
    let n = xs.len();
    if n < 2 {
        return None;
    }
    let mean = xs.iter().sum::<f64>() / n as f64;
    let sd = (xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1) as f64).sqrt();
    (sd > 0.0).then(|| mean / sd)
}

/// The error rate of [`confidence_sequence`]'s intervals: 95 % at every number of pairs at once.
pub const CS_ALPHA: f64 = 0.05;
/// The number of pairs at which [`confidence_sequence`] is tightest (its mixture's tuning):
/// about where sequential grids decide.
pub const CS_TUNED_PAIRS: f64 = 30.0;

/// The half-width of a two-sided, time-uniform (anytime-valid) 95 % confidence sequence for
/// the mean of `n` outcomes with sample standard deviation `sd`: the asymptotic confidence
/// sequence of Waudby-Smith, Arnold, Wu, Wang and Ramdas ("Time-uniform central limit theory
/// and asymptotic confidence sequences", Annals of Statistics, 2024; Howard, Ramdas,
/// McAuliffe and Sekhon's normal-mixture boundary, Annals of Statistics 49(2), 2021, with the
/// variance estimated), in units of the sample standard deviation:
/// `sd / n · sqrt(2 (n ρ² + 1) / ρ² · ln(sqrt(n ρ² + 1) / α))`, with
/// `ρ² = (-2 ln α + ln(1 - 2 ln α)) / n*` (`n*` = [`CS_TUNED_PAIRS`]). It holds at once for
/// every `n`, so also where a sequential test stopped, which a fixed-sample interval does not
/// (its coverage after a data-dependent stop is measured in
/// `tests::confidence_sequence_covers_after_sequential_stops`). `None` below two outcomes.
pub fn confidence_sequence_half_width(n: usize, sd: f64) -> Option<f64> {
    if n < 2 || !sd.is_finite() {
        return None;
    }
    let a = CS_ALPHA;
    let rho2 = (-2.0 * a.ln() + (1.0 - 2.0 * a.ln()).ln()) / CS_TUNED_PAIRS;
    let nf = n as f64;
    let v = nf * rho2 + 1.0;
    Some(sd / nf * (2.0 * v / rho2 * (v.sqrt() / a).ln()).sqrt())
}

/// The anytime-valid 95 % interval of the mean of `xs` ([`confidence_sequence_half_width`]
/// about their mean, with the sample standard deviation). `None` below two values.
pub fn confidence_sequence(xs: &[f64]) -> Option<(f64, f64)> {
    let n = xs.len();
    if n < 2 {
        return None;
    }
    let mean = xs.iter().sum::<f64>() / n as f64;
    let sd = (xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1) as f64).sqrt();
    let h = confidence_sequence_half_width(n, sd)?;
    Some((mean - h, mean + h))
}

/// The interquartile mean: the mean of the middle half of `xs` once sorted, as
/// `scipy.stats.trim_mean(xs, 0.25)` (`floor(n / 4)` values cut from each end), the robust
/// aggregate of Agarwal et al., "Deep reinforcement learning at the edge of the statistical
/// precipice" (NeurIPS 2021). `None` for no values or a NaN.
pub fn interquartile_mean(xs: &[f64]) -> Option<f64> {
    if xs.is_empty() || xs.iter().any(|x| x.is_nan()) {
        return None;
    }
    let mut v = xs.to_vec();
    v.sort_by(f64::total_cmp);
    let cut = v.len() / 4;
    let mid = &v[cut..v.len() - cut];
    Some(mid.iter().sum::<f64>() / mid.len() as f64)
}

/// The probability that a run drawn from `xs` is better (lower) than one drawn from `ys`, ties
/// counting half: the Mann-Whitney statistic over `|xs| · |ys|` (Agarwal et al.'s probability
/// of improvement on one task). `None` if either is empty.
pub fn probability_lower(xs: &[f64], ys: &[f64]) -> Option<f64> {
    if xs.is_empty() || ys.is_empty() {
        return None;
    }
    let mut score = 0.0;
    for x in xs {
        for y in ys {
            score += if x < y {
                1.0
            } else if x == y {
                0.5
            } else {
                0.0
            };
        }
    }
    Some(score / (xs.len() * ys.len()) as f64)
}

/// Resamples for the two-level bootstrap of the aggregates across buildings.
pub const STRATIFIED_RESAMPLES: usize = 2_000;

/// The 95 % percentile interval of `statistic` under the two-level (hierarchical) bootstrap:
/// each resample draws the strata (buildings) with replacement, then resamples each drawn
/// stratum's vectors (a building's runs of the label and of the reference, say) within
/// themselves, [`STRATIFIED_RESAMPLES`] times from [`BOOTSTRAP_SEED`]. A statistic that
/// normalizes by a stratum's vector (the reference's median per building) so sees its
/// normalizer vary with the resampled runs, and the interval counts the spread between
/// buildings as well as within them (Davison and Hinkley, *Bootstrap methods and their
/// application*, 1997, section 3.8: resampling at both levels). `statistic` gets the resampled
/// strata; resamples where it gives `None` or a NaN are skipped. `None` when there is nothing
/// to resample (one stratum whose vectors hold at most one value each) or no resample gives a
/// value.
pub fn hierarchical_bootstrap_ci95<const K: usize>(
    strata: &[[Vec<f64>; K]],
    statistic: impl Fn(&[[Vec<f64>; K]]) -> Option<f64>,
) -> Option<(f64, f64)> {
    let n = strata.len();
    if n == 0 || (n == 1 && !strata[0].iter().any(|v| v.len() > 1)) {
        return None;
    }
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(BOOTSTRAP_SEED);
    let mut values = Vec::with_capacity(STRATIFIED_RESAMPLES);
    let mut resampled: Vec<[Vec<f64>; K]> = strata.to_vec();
    for _ in 0..STRATIFIED_RESAMPLES {
        for to in resampled.iter_mut() {
            let from = &strata[rng.random_range(0..n)];
            for (t, f) in to.iter_mut().zip(from) {
                t.clear();
                for _ in 0..f.len() {
                    t.push(f[rng.random_range(0..f.len())]);
                }
            }
        }
        if let Some(v) = statistic(&resampled).filter(|v| !v.is_nan()) {
            values.push(v);
        }
    }
    percentile_ci95(values)
}

/// The 2.5 % and 97.5 % percentiles of bootstrap `values` (`None` for none).
fn percentile_ci95(mut values: Vec<f64>) -> Option<(f64, f64)> {
    if values.is_empty() {
        return None;
    }
    values.sort_by(f64::total_cmp);
    let at = |q: f64| values[((q * (values.len() - 1) as f64).round()) as usize];
    Some((at(0.025), at(0.975)))
}

/// The median of `xs` (`None` for none).
pub fn median(xs: &[f64]) -> Option<f64> {
    if xs.is_empty() {
        return None;
    }
    let mut v = xs.to_vec();
    v.sort_by(f64::total_cmp);
    let n = v.len();
    Some(if n % 2 == 1 {
        v[n / 2]
    } else {
        (v[n / 2 - 1] + v[n / 2]) / 2.0
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The p-values of `scipy.stats.wilcoxon(d)` with its defaults (scipy 1.17.1), through each
    /// of its methods: exact, the permutation test (ties or zeros, at most 13), the normal
    /// approximation (ties or zeros beyond 13, or more than 50).
    #[test]
    #[allow(clippy::too_many_lines)] // a table of cases
    fn wilcoxon_matches_scipy() {
        let cases: &[(&str, &[f64], f64)] = &[
            ("all five positive", &[1.0, 2.0, 3.0, 4.0, 5.0], 0.0625),
            (
                "R's example",
                &[0.952, -0.147, 1.022, 0.43, 0.62, 0.59, 0.49, -0.08, 0.01],
                0.0390625,
            ),
            ("n4", &[-1.0, 1.5, -2.0, 2.5], 0.875),
            ("n4 ties: permutation", &[1.0, 1.0, 2.0, 3.0], 0.125),
            ("n5 exact", &[1.5, -0.25, 3.0, 2.25, 4.5], 0.125),
            (
                "n12 ties: permutation",
                &[
                    1.0, -1.0, 2.0, 2.0, 3.5, -0.5, 4.0, 1.0, 5.0, -2.0, 6.5, 3.0,
                ],
                0.02197265625,
            ),
            (
                "n10 a zero: permutation",
                &[0.0, 1.25, -2.5, 3.0, 4.25, 5.5, -6.0, 7.0, 8.5, 9.0],
                0.09765625,
            ),
            (
                "n20 exact",
                &[
                    0.802, 1.397, 0.252, -0.981, -0.109, -1.183, 0.92, 3.48, -0.184, -0.441, 1.78,
                    1.514, 1.011, -1.061, 0.741, 2.191, -1.888, -0.115, -3.002, -1.779,
                ],
                0.7011814117431641,
            ),
            (
                "n40 exact",
                &[
                    -3.283, -0.07, -2.135, 0.943, 0.714, 0.026, -4.634, -0.677, 0.303, 0.627,
                    -2.66, -0.556, -1.557, -1.218, 2.522, -1.215, 0.335, 2.169, -0.767, 0.177,
                    0.621, 0.528, -2.05, 0.552, 3.118, -2.694, 2.119, 0.639, -0.883, 4.401, 1.925,
                    -1.999, 0.549, 1.553, 0.022, 1.766, 0.267, 1.734, 3.277, -0.951,
                ],
                0.7546940826050559,
            ),
            (
                "n50 exact",
                &[
                    0.106, -1.227, -0.045, -2.674, -1.459, -0.692, 1.498, 1.99, -2.947, -1.889,
                    0.994, -4.285, -1.226, -0.495, 2.214, 1.079, -0.954, -1.037, -0.8, 2.747,
                    -1.156, -0.907, 0.405, -0.542, -0.695, -2.528, -0.323, -1.187, 2.032, 1.006,
                    -0.348, 1.037, -0.98, 1.804, -0.311, 0.867, -2.882, 0.393, -3.676, -4.371,
                    -0.909, -2.1, 0.028, 4.19, -1.963, -1.548, 0.111, 0.686, -0.653, -0.712,
                ],
                0.048920909954075616,
            ),
            (
                "n20 ties: asymptotic",
                &[
                    2.0, 2.0, -2.0, 0.0, 1.0, -2.0, 1.0, -1.0, 2.0, 1.0, 1.0, -1.0, 0.0, -3.0,
                    -2.0, 1.0, -4.0, 2.0, -3.0, 2.0,
                ],
                0.7230569207887818,
            ),
            (
                "n30 zeros: asymptotic",
                &[
                    -1.0, 1.0, 0.0, -1.0, 1.0, 2.0, 0.0, -0.0, 0.0, -1.0, 1.0, -0.0, 0.0, -1.0,
                    -0.0, -1.0, 1.0, 0.0, 1.0, 0.0, -0.0, -0.0, -0.0, 0.0, -0.0, -0.0, -1.0, -1.0,
                    2.0, -0.0,
                ],
                0.6353317636247899,
            ),
            (
                "n51 asymptotic",
                &[
                    -1.808, 0.975, 3.115, -2.608, -0.117, -0.964, -3.222, 1.77, 0.253, 0.443,
                    -1.205, 1.21, -0.779, 0.014, -1.917, -2.132, 2.971, -0.714, 0.883, 0.232,
                    -0.582, -0.716, 1.56, -0.304, -0.003, 0.344, 2.653, 1.661, 1.065, -0.827,
                    -2.464, 2.199, 2.233, 0.019, 1.384, 1.863, 1.962, 2.143, -0.611, 3.33, -2.193,
                    2.023, 1.288, 2.047, 4.058, 3.269, -1.99, -3.077, 1.934, -1.73, 0.275,
                ],
                0.148875760400945,
            ),
            (
                "n100 asymptotic",
                &[
                    1.879, -3.088, -4.02, 0.719, 0.289, -0.292, 0.277, -1.521, -2.827, -0.133,
                    -1.743, -3.087, 1.211, 0.077, 1.013, -1.779, -1.116, -1.798, -1.573, 0.591,
                    -1.366, 0.912, 0.88, 4.25, -2.586, 1.976, 0.021, 0.172, -2.7, -0.72, 1.686,
                    0.035, 0.362, -0.381, 2.509, 0.157, -4.201, -1.184, -3.738, -6.303, -0.86,
                    2.867, 0.294, -2.145, -1.681, 2.461, 0.515, 0.296, 0.093, 0.277, 1.811, 1.305,
                    0.631, -1.886, 1.222, -1.168, 2.388, -2.342, -0.075, 0.185, -2.449, 3.644,
                    3.121, -0.727, 1.743, 0.957, -5.027, 0.701, 0.077, 0.366, -1.954, -0.339,
                    -0.157, 2.576, 0.869, 0.189, 3.258, -0.91, -0.579, -3.434, 3.338, 2.129, 2.034,
                    1.538, 0.42, 0.631, -0.304, -0.207, 0.309, 3.224, 1.311, 0.083, -0.959, -1.07,
                    3.405, 1.213, 0.335, -0.492, -2.018, 0.066,
                ],
                0.8527033773278186,
            ),
        ];
        for (what, d, want) in cases {
            let p = wilcoxon_signed_rank_p(d).unwrap();
            assert!(
                (p - want).abs() < 1e-9 * want.max(1e-3),
                "{what}: {p} against {want}"
            );
        }
        assert_eq!(wilcoxon_signed_rank_p(&[0.0, 0.0]), None);
    }

    /// The Hodges-Lehmann estimate and its interval as R's `wilcox.test(x, conf.int = TRUE)`
    /// forms them (exact: `qu = qsignrank(0.025, n)`, `[W_(qu), W_(M + 1 - qu)]`; the null
    /// distribution of n = 9 enumerated over its 512 sign patterns), and the size of an
    /// outlier's charge does not move the estimate.
    #[test]
    fn hodges_lehmann_matches_r_and_ignores_the_size_of_an_outlier() {
        let x = [1.83, 0.50, 1.62, 2.48, 1.68, 1.88, 1.55, 3.06, 1.30];
        // The median of the 45 Walsh averages: the 23rd of them.
        let mut w = Vec::new();
        for i in 0..x.len() {
            for j in i..x.len() {
                w.push((x[i] + x[j]) / 2.0);
            }
        }
        w.sort_by(f64::total_cmp);
        assert_eq!(hodges_lehmann(&x), Some(w[22]));
        // n = 9: P(T+ <= 5) = 0.0195, P(T+ <= 6) = 0.0273: k = 6, [W_(6), W_(40)].
        assert_eq!(hodges_lehmann_ci95(&x), Some((w[5], w[39])));
        // A shortfall charged 10 or 1000: the estimate moves the same (by rank only).
        let with = |charge: f64| {
            let mut v = x.to_vec();
            v.push(-charge);
            hodges_lehmann(&v).unwrap()
        };
        assert_eq!(with(10.0), with(1000.0));
        assert!(hodges_lehmann_ci95(&x[..5]).is_none());
        assert!(hodges_lehmann(&[]).is_none());
    }

    #[test]
    fn holm_adjusts_step_down_and_keeps_order() {
        let adj = holm(&[Some(0.01), Some(0.04), None, Some(0.03)]);
        // Sorted 0.01, 0.03, 0.04 with m = 3: 0.03, 0.06, max(0.06, 0.04) = 0.06.
        let want = [Some(0.03), Some(0.06), None, Some(0.06)];
        for (a, w) in adj.iter().zip(want) {
            assert_eq!(
                a.map(|x| (x * 1e9).round()),
                w.map(|x: f64| (x * 1e9).round())
            );
        }
    }

    #[test]
    fn bootstrap_interval_holds_the_mean_and_is_reproducible() {
        let xs: Vec<f64> = (0..20)
            .map(|i| (i as f64 * 0.37).sin() * 5.0 + 2.0)
            .collect();
        let mean = xs.iter().sum::<f64>() / xs.len() as f64;
        let (lo, hi) = bootstrap_mean_ci95(&xs).unwrap();
        assert!(lo < mean && mean < hi, "{lo} {mean} {hi}");
        assert_eq!(bootstrap_mean_ci95(&xs), Some((lo, hi)));
        // About the t interval's width for a sample this size.
        let sd = (xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / 19.0).sqrt();
        let t_half = 2.093 * sd / 20f64.sqrt();
        assert!(
            ((hi - lo) / 2.0 - t_half).abs() < 0.25 * t_half,
            "{lo} {hi} {t_half}"
        );
        assert_eq!(bootstrap_mean_ci95(&[1.0]), None);
        assert_eq!(effect_size_dz(&[1.0, 1.0]), None);
        assert!((effect_size_dz(&[1.0, 3.0]).unwrap() - 2.0 / 2f64.sqrt()).abs() < 1e-12);
    }

    /// The robust aggregates against their definitions: `median`, `interquartile_mean` as
    /// `scipy.stats.trim_mean(xs, 0.25)` (an outlier among eight values cut away) and
    /// `probability_lower` as the Mann-Whitney statistic over all pairs, ties counting half.
    #[test]
    fn robust_aggregates_match_their_definitions() {
        assert_eq!(median(&[3.0, 1.0, 2.0]), Some(2.0));
        assert_eq!(median(&[4.0, 1.0, 3.0, 2.0]), Some(2.5));
        assert_eq!(median(&[]), None);
        let eight = [7.0, 1.0, 100.0, 3.0, 5.0, 2.0, 6.0, 4.0];
        assert_eq!(interquartile_mean(&eight), Some(4.5));
        // Five values: one cut from each end (floor(5 / 4)).
        assert_eq!(interquartile_mean(&[9.0, 1.0, 2.0, 3.0, 4.0]), Some(3.0));
        assert_eq!(interquartile_mean(&[1.0, f64::NAN]), None);
        assert_eq!(interquartile_mean(&[]), None);
        // (1<2) + (1<3) + (2=2)/2 + (2<3) over four pairs.
        assert_eq!(probability_lower(&[1.0, 2.0], &[2.0, 3.0]), Some(0.875));
        assert_eq!(probability_lower(&[5.0], &[1.0, 2.0]), Some(0.0));
        assert_eq!(probability_lower(&[], &[1.0]), None);
    }

    /// The confidence sequence's half-width against its formula computed independently (in
    /// Python's `math`, to the last digits): 0.554150810257185 at 30 pairs and sd 1 (where it is
    /// tuned), 1.00193569207303 at 10; wider than the fixed-sample 95 % interval (1.96 / sqrt(n))
    /// and narrowing with `n`; the interval is centred on the mean.
    #[test]
    fn confidence_sequence_matches_its_formula() {
        let h30 = confidence_sequence_half_width(30, 1.0).unwrap();
        assert!((h30 - 0.554_150_810_257_185).abs() < 1e-12, "{h30}");
        let h10 = confidence_sequence_half_width(10, 1.0).unwrap();
        assert!((h10 - 1.001_935_692_073_03).abs() < 1e-12, "{h10}");
        assert!(h30 > 1.96 / 30f64.sqrt() && h10 > h30);
        assert_eq!(confidence_sequence_half_width(30, 2.0), Some(2.0 * h30));
        assert_eq!(confidence_sequence_half_width(1, 1.0), None);
        assert_eq!(confidence_sequence_half_width(5, f64::NAN), None);
        let xs = [1.0, 2.0, 3.0, 4.0];
        let (lo, hi) = confidence_sequence(&xs).unwrap();
        assert!(((lo + hi) / 2.0 - 2.5).abs() < 1e-12);
        let sd = (5.0f64 / 3.0).sqrt();
        let h = confidence_sequence_half_width(4, sd).unwrap();
        assert!((hi - lo - 2.0 * h).abs() < 1e-12);
        assert_eq!(confidence_sequence(&[1.0]), None);
    }

    /// The two-level bootstrap: a constant statistic gives a point, nothing to resample gives
    /// none, the same call gives the same interval (its seed), and a mean's interval holds the
    /// mean of the data.
    #[test]
    fn hierarchical_bootstrap_is_seeded_and_sensible() {
        let mean = |s: &[[Vec<f64>; 1]]| {
            let all: Vec<f64> = s.iter().flat_map(|[v]| v.iter().copied()).collect();
            (!all.is_empty()).then(|| all.iter().sum::<f64>() / all.len() as f64)
        };
        let constant = [[vec![2.0, 2.0]], [vec![2.0]]];
        assert_eq!(
            hierarchical_bootstrap_ci95(&constant, mean),
            Some((2.0, 2.0))
        );
        assert_eq!(hierarchical_bootstrap_ci95(&[[vec![1.0]]], mean), None);
        assert_eq!(hierarchical_bootstrap_ci95::<1>(&[], mean), None);
        let strata = [
            [vec![1.0, 2.0, 3.0]],
            [vec![4.0, 5.0]],
            [vec![2.0, 8.0, 3.0, 1.0]],
        ];
        let a = hierarchical_bootstrap_ci95(&strata, mean).unwrap();
        assert_eq!(hierarchical_bootstrap_ci95(&strata, mean), Some(a));
        let m = mean(&strata).unwrap();
        assert!(a.0 < m && m < a.1, "{a:?} around {m}");
        assert_eq!(hierarchical_bootstrap_ci95(&strata, |_| None), None);
    }
}
