#!/usr/bin/env python3
"""Nearest frontier first: every candidate ranked by planned path length (ties by id)."""
from floorcast_strategy import Strategy, run


class Nearest(Strategy):
    name = "nearest.py"

    def decide(self, d):
        ranked = sorted(d["candidates"], key=lambda c: (c["path_m"], c["id"]))
        return [c["id"] for c in ranked]


if __name__ == "__main__":
    run(Nearest())
