//! The statistics of a paired comparison beyond the t interval: the Wilcoxon signed-rank test,
//! a seeded percentile bootstrap of the mean, Holm's adjustment across the comparisons of one
//! report, and the paired effect size. Pure functions of the per-pair differences.

use rand::{Rng, SeedableRng};
use statrs::distribution::{ContinuousCDF, Normal};

/// Two-sided p-value of the Wilcoxon signed-rank test that the differences are centred on 0.
/// Zero differences are dropped (Wilcoxon's rule); ties share their average rank. Exact (the
/// distribution of the positive rank sum over all sign patterns) for up to 30 non-zero
/// differences without ties, else the normal approximation with the tie correction and a
/// continuity correction. `None` without a non-zero difference.
pub fn wilcoxon_signed_rank_p(differences: &[f64]) -> Option<f64> {
    let mut d: Vec<f64> = differences
        .iter()
        .copied()
        .filter(|x| x.is_finite() && *x != 0.0)
        .collect();
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
    let nf = n as f64;
    if ties_term == 0.0 && n <= 30 {
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
    let mean = nf * (nf + 1.0) / 4.0;
    let var = nf * (nf + 1.0) * (2.0 * nf + 1.0) / 24.0 - ties_term / 48.0;
    if var <= 0.0 {
        return Some(1.0);
    }
    let z = ((w_plus - mean).abs() - 0.5).max(0.0) / var.sqrt();
    let normal = Normal::new(0.0, 1.0).expect("the standard normal");
    Some((2.0 * (1.0 - normal.cdf(z))).min(1.0))
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

#[cfg(test)]
mod tests {
    use super::*;

    /// Published values: exact p for small samples (as R's `wilcox.test(x, exact = TRUE)`
    /// gives), the normal approximation with ties.
    #[test]
    fn wilcoxon_matches_published_values() {
        // (differences, p)
        let cases: [(&[f64], f64); 4] = [
            // All five positive: W+ = 15, P = 2 / 32.
            (&[1.0, 2.0, 3.0, 4.0, 5.0], 0.0625),
            // R: wilcox.test(c(1.83, 0.50, 1.62, 2.48, 1.68, 1.88, 1.55, 3.06, 1.30) -
            //   c(0.878, 0.647, 0.598, 2.05, 1.06, 1.29, 1.06, 3.14, 1.29)): V = 40, p = 0.03906.
            (
                &[0.952, -0.147, 1.022, 0.43, 0.62, 0.59, 0.49, -0.08, 0.01],
                0.039_062_5,
            ),
            // W+ = 2 + 4 = 6 of n = 4: P(W+ >= 6) = 7/16, p = 14/16.
            (&[-1.0, 1.5, -2.0, 2.5], 0.875),
            // Ties (normal approximation with tie and continuity corrections): ranks 1.5 1.5 3
            // 4, W+ = 10, mean 5, var 7.5 - 6/48 = 7.375, z = 4.5 / 2.7157 = 1.657.
            (&[1.0, 1.0, 2.0, 3.0], 0.097_513),
        ];
        for (d, want) in cases {
            let p = wilcoxon_signed_rank_p(d).unwrap();
            assert!((p - want).abs() < 1e-4, "{d:?}: {p} against {want}");
        }
        assert_eq!(wilcoxon_signed_rank_p(&[0.0, 0.0]), None);
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
}
