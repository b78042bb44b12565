"""Paired gain of one label of one results CSV over one label of another, by (building, seed).

Run from the repository root, e.g. the baseline with alpha = 0.75 against the paper's baseline:

    python3 results/reference/robustness/paired.py \
        results/reference/robustness/paper-alpha/results.csv baseline \
        results/reference/paper/results.csv baseline

Prints the mean gain in exploration time (positive: the first is faster) with its Student-t
95 % interval over the pairs both files hold, and the number of pairs.
"""

import csv
import math
import statistics
import sys

# Two-sided 95 % Student-t quantiles by degrees of freedom (the pairings used here).
T95 = {9: 2.262, 19: 2.093, 26: 2.056, 27: 2.052, 28: 2.048, 29: 2.045, 32: 2.037, 99: 1.984}


def times(path, label):
    with open(path, newline="") as f:
        return {
            (r["building"], r["seed"]): float(r["exploration_time_s"])
            for r in csv.DictReader(f)
            if r["label"] == label and r["status"] == "ok"
        }


def main(a_csv, a_label, b_csv, b_label):
    a, b = times(a_csv, a_label), times(b_csv, b_label)
    gains = [100.0 * (b[k] - a[k]) / b[k] for k in sorted(a.keys() & b.keys())]
    n = len(gains)
    if n - 1 not in T95:
        sys.exit(f"{n} pairs: no t quantile for {n - 1} degrees of freedom here")
    half = T95[n - 1] * statistics.stdev(gains) / math.sqrt(n)
    print(f"{a_label} ({a_csv}) over {b_label} ({b_csv}): "
          f"{statistics.mean(gains):+.1f} ± {half:.1f} % (n = {n})")


if __name__ == "__main__":
    if len(sys.argv) != 5:
        sys.exit(__doc__)
    main(*sys.argv[1:])
