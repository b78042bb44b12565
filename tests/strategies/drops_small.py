#!/usr/bin/env python3
"""Test strategy: gives up (drops) every candidate whose baseline gain is under 4 m2, and drives
to the nearest of the others; logs how many it dropped. A dropped candidate must never be
offered again at the same place."""
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "python"))
from floorcast_strategy import Strategy, drop, run  # noqa: E402


class DropsSmall(Strategy):
    name = "drops-small"

    def new_run(self, run):
        self.run = run
        self.dropped = set()

    def decide(self, d):
        for c in d["candidates"]:
            if tuple(c["cell"]) in self.dropped:
                raise ValueError("candidate at %r offered again after it was dropped" % (c["cell"],))
        small = [c for c in d["candidates"] if c["gain_m2"] < 4.0]
        if small:
            self.dropped.update(tuple(c["cell"]) for c in small)
            return drop([c["id"] for c in small])
        return min(d["candidates"], key=lambda c: (c["path_m"], c["id"]))["id"]

    def end_run(self, end):
        print("drops_small: dropped %d" % len(self.dropped), file=sys.stderr)


run(DropsSmall())
