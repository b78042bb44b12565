#!/usr/bin/env python3
"""Test strategy (protocol 2): needs the layout only when its params say `{"rooms": true}`
(`needs_for`), checks that each decide message carries the robot's room and the candidates'
rooms exactly then, and goes to the nearest candidate. At the end it writes to stderr
`needs_by_params: rooms R, D decisions, robot_room in N, in a room M` (R: the param; D: decide
messages; N: those with `robot_room`; M: those whose `robot_room` was a room's index)."""
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "python"))
from floorcast_strategy import Strategy, run  # noqa: E402


class NeedsByParams(Strategy):
    name = "needs-by-params"

    def needs_for(self, params):
        return ("layout",) if params.get("rooms") else ()

    def new_run(self, run):
        self.rooms = bool(self.params.get("rooms"))
        self.decides = self.with_room = self.in_room = 0
        self.layout = None

    def decide(self, d):
        self.decides += 1
        if "layout" in d:
            self.layout = d["layout"]
        assert ("robot_room" in d) == self.rooms, (self.rooms, sorted(d))
        assert all(("room" in c) == self.rooms for c in d["candidates"]), self.rooms
        if "robot_room" in d:
            self.with_room += 1
            r = d["robot_room"]
            assert r is None or (self.layout is not None and 0 <= r < len(self.layout["rooms"])), r
            self.in_room += r is not None
        return min(d["candidates"], key=lambda c: (c["path_m"], c["id"]))["id"]

    def end_run(self, end):
        print(
            "needs_by_params: rooms %s, %d decisions, robot_room in %d, in a room %d"
            % (self.rooms, self.decides, self.with_room, self.in_room),
            file=sys.stderr,
        )


run(NeedsByParams())
