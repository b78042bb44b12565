#!/usr/bin/env python3
"""Test strategy: needs the layout gain, the layout and the map, keeps a local copy of the map
from the decide messages' map_changes and the latest layout, and checks every decide message
against the contract; chooses as the built-in baseline does. At the end it writes to stderr
`needs_everything: N decisions, K known cells, L layouts, R rooms` (N: decide messages answered;
L: layouts received; R: rooms in the last one)."""
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "python"))
from floorcast_strategy import Strategy, best_by_paper_utility, run  # noqa: E402

UNKNOWN, FREE, OCCUPIED = 0, 1, 2


class NeedsEverything(Strategy):
    name = "needs-everything"
    needs = ("layout_gain", "layout", "map")

    def new_run(self, run):
        self.run = run
        m = run["map"]
        self.width, self.height = m["width"], m["height"]
        assert isinstance(self.width, int) and self.width > 0, m
        assert isinstance(self.height, int) and self.height > 0, m
        assert isinstance(m["resolution_m"], float) and m["resolution_m"] > 0, m
        assert len(m["origin"]) == 2, m
        self.cells = bytearray(self.width * self.height)  # every cell starts unknown
        self.decides = 0
        self.layouts = 0
        self.layout = None

    def decide(self, d):
        assert d["candidates"], "an empty candidate list was sent"
        if "layout" in d:
            layout = d["layout"]
            # A layout is sent once, when it is new.
            assert self.layout is None or layout["number"] > self.layout["number"], layout["number"]
            for r in layout["rooms"]:
                assert len(r["polygon"]) >= 3 and all(len(p) == 2 for p in r["polygon"]), r
                assert r["state"] in ("full", "partial", "open"), r
                assert isinstance(r["predicted"], bool), r
                assert r["area_m2"] > 0 and 0 <= r["unknown_area_m2"] <= r["area_m2"] + 1e-9, r
            self.layout = layout
            self.layouts += 1
        for c in d["candidates"]:
            assert "layout_gain_m2" in c, c
            g = c["layout_gain_m2"]
            assert g is None or isinstance(g, float), c
            room = c["room"]
            assert room is None or (self.layout is not None and 0 <= room < len(self.layout["rooms"])), c
        # The local map has the dimensions the run message announced.
        assert len(self.cells) == self.width * self.height == (
            self.run["map"]["width"] * self.run["map"]["height"]
        )
        changes = d["map_changes"]
        seen = set()
        for key, state in (("free", FREE), ("occupied", OCCUPIED), ("unknown", UNKNOWN)):
            for i in changes[key]:
                assert isinstance(i, int) and 0 <= i < len(self.cells), (key, i)
                assert i not in seen, "cell %d listed twice in one map_changes" % i
                seen.add(i)
                assert self.cells[i] != state, "cell %d listed as %s but was already" % (i, key)
                self.cells[i] = state
        if self.decides == 0:
            assert not changes["unknown"], "the first map_changes lists unknown cells"
            assert changes["free"], "the first map_changes lists no free cell"
        self.decides += 1
        return best_by_paper_utility(d, self.run)

    def end_run(self, end):
        known = len(self.cells) - self.cells.count(UNKNOWN)
        rooms = len(self.layout["rooms"]) if self.layout else 0
        sys.stderr.write(
            "needs_everything: %d decisions, %d known cells, %d layouts, %d rooms\n"
            % (self.decides, known, self.layouts, rooms)
        )
        sys.stderr.flush()


run(NeedsEverything())
