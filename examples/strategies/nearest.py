#!/usr/bin/env python3
"""Nearest frontier first: every candidate ranked by planned path length (ties by id).

One parameter (a grid's `params`, or `explore --strategy-params '{"stop_below_m2": 5}'`):
stop exploring when no candidate's baseline gain reaches `stop_below_m2` square metres
(default 0: explore until no frontier is left)."""
from floorcast_strategy import Strategy, run


class Nearest(Strategy):
    name = "nearest.py"

    def decide(self, d):
        stop_below = float(self.params.get("stop_below_m2", 0.0))
        if max(c["gain_m2"] for c in d["candidates"]) < stop_below:
            return None
        ranked = sorted(d["candidates"], key=lambda c: (c["path_m"], c["id"]))
        return [c["id"] for c in ranked]


if __name__ == "__main__":
    run(Nearest())
