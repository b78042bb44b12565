"""Paired gains of the true-layout oracle (`layout-truth`, `layout-truth-es`) over the paper's
strategies of results/reference/paper, and of the oracle with a floor on the gain
(`layout-truth-floor`) over the strategies of results/reference/paper-floor (README, "With the
true layout"):
python3 results/reference/paper-truth/paired.py (from the repository root)."""
import csv
import math
import statistics

# Student's t (95 %, two-sided) by degrees of freedom, as `floorcast report` uses
# (coordinator/src/table.rs, t95).
T95 = {9: 2.262, 29: 2.045, 99: 1.984}


def load(path):
    with open(path) as f:
        return {(r["building"], r["label"], int(r["seed"])): r for r in csv.DictReader(f)}


paper = load("results/reference/paper/results.csv")
floor = load("results/reference/paper-floor/results.csv")
truth = load("results/reference/paper-truth/results.csv")


def runs(table, label, field="exploration_time_s"):
    return {(b, s): float(r[field]) for (b, l, s), r in table.items() if l == label}


def paired(ref, other, n):
    keys = sorted(k for k in ref if k in other)
    d = [100 * (ref[k] - other[k]) / ref[k] for k in keys]
    assert len(d) == n, "expected %d pairs, found %d" % (n, len(d))
    ci = T95[n - 1] * statistics.stdev(d) / math.sqrt(n)
    return statistics.mean(d), ci


base = runs(paper, "baseline")
print("paired gain in exploration time (95 % CI), n = 100 each:")
for ref_label in ["baseline", "layout", "layout-es"]:
    ref = runs(paper, ref_label)
    for label in ["layout-truth", "layout-truth-es"]:
        m, ci = paired(ref, runs(truth, label), 100)
        print("  %-16s over %-10s %+6.1f +/- %.1f %%" % (label, ref_label, m, ci))
print("\nper building, over baseline (n = 10 each):")
buildings = sorted({b for (b, _) in base})
for label in ["layout-truth", "layout-truth-es"]:
    t = runs(truth, label)
    cells = []
    for b in buildings:
        m, ci = paired({k: v for k, v in base.items() if k[0] == b},
                       {k: v for k, v in t.items() if k[0] == b}, 10)
        cells.append("%s %+.1f +/- %.1f" % (b, m, ci))
    print("  %s: %s" % (label, "; ".join(cells)))
print("\nmeans over the 100 runs:")
for table, label in [(paper, "baseline"), (paper, "layout"), (paper, "layout-es"),
                     (truth, "layout-truth"), (truth, "layout-truth-es")]:
    t90 = runs(table, label, "time_to_90_s")
    path = runs(table, label, "path_length_m")
    frac = runs(table, label, "explored_fraction")
    stopped = sum(r["stopped_early"] == "true" for (_, l, _), r in table.items() if l == label)
    print("  %-16s time to 90 %% %6.0f s, path %5.0f m, explored %.4f (min %.3f), stopped early %d"
          % (label, statistics.mean(t90.values()), statistics.mean(path.values()),
             statistics.mean(frac.values()), min(frac.values()), stopped))
print("\nwith a floor of 2 m2 on the gain (seeds 1-3, n = 30 each):")
tf = {k: v for k, v in runs(truth, "layout-truth-floor").items() if k[1] <= 3}
for ref_label in ["baseline", "layout", "layout-es"]:
    m, ci = paired(runs(floor, ref_label), tf, 30)
    print("  layout-truth-floor over %-10s (floor) %+6.1f +/- %.1f %%" % (ref_label, m, ci))
