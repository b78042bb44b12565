"""Paired gains of the paper-floor runs over the paper-utility baseline (README, "A floor on the
gain"): python3 results/reference/paper-floor/paired.py (from the repository root)."""
import csv
import math
import statistics


def load(path):
    with open(path) as f:
        return {(r["building"], r["label"], int(r["seed"])): float(r["exploration_time_s"])
                for r in csv.DictReader(f)}


paper = load("results/reference/paper/results.csv")
floor = load("results/reference/paper-floor/results.csv")


def paired(ref, other):
    d = [100 * (ref[k] - other[k]) / ref[k] for k in ref if k in other]
    # 2.045: Student's t for 29 degrees of freedom, as in `floorcast report` (coordinator/src/
    # table.rs, t95); these grids pair exactly 10 buildings x 3 seeds.
    assert len(d) == 30, "expected 30 pairs, found %d" % len(d)
    ci = 2.045 * statistics.stdev(d) / math.sqrt(len(d))
    return statistics.mean(d), ci, len(d)


base = {(b, s): t for (b, l, s), t in paper.items() if l == "baseline" and s <= 3}
for label in ["baseline", "layout", "layout-es", "nearest", "nearest-es"]:
    runs = {(b, s): t for (b, l, s), t in floor.items() if l == label}
    print("%-10s vs paper-utility baseline: %+.1f +/- %.1f %% (n = %d)" % ((label,) + paired(base, runs)))
for label in ["layout", "layout-es"]:
    ref = {(b, s): t for (b, l, s), t in paper.items() if l == label and s <= 3}
    runs = {(b, s): t for (b, l, s), t in floor.items() if l == label}
    print("%-10s with the floor vs without: %+.1f +/- %.1f %% (n = %d)" % ((label,) + paired(ref, runs)))
