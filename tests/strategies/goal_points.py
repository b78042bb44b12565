#!/usr/bin/env python3
"""Test strategy: drives to points of its own (goal replies). At the first decision it asks
for a point off the map, and checks that it is asked again with that point as
`unreachable_goal`; then it drives to the nearest candidate's goal point, or chooses the
candidate itself (to face its frontier) once it stands within 0.5 m of that point."""
import math
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "python"))
from floorcast_strategy import Strategy, goal, run  # noqa: E402

OFF_MAP = (1.0e6, -1.0e6)


class GoalPoints(Strategy):
    name = "goal-points"

    def new_run(self, run):
        self.run = run
        self.points = 0
        self.told_unreachable = False

    def decide(self, d):
        if d["decision"] == 0 and d["attempt"] == 0:
            return goal(*OFF_MAP)
        if d["decision"] == 0 and d["attempt"] == 1:
            if d.get("unreachable_goal") != list(OFF_MAP):
                raise ValueError("expected unreachable_goal %r, got %r" % (OFF_MAP, d.get("unreachable_goal")))
            self.told_unreachable = True
        x, y = d["pose"][0], d["pose"][1]
        best = min(d["candidates"], key=lambda c: (c["path_m"], c["id"]))
        gx, gy = best["goal"]
        if math.hypot(gx - x, gy - y) < 0.5:
            return best["id"]
        self.points += 1
        return goal(gx, gy)

    def end_run(self, end):
        print(
            "goal_points: %d goal points, told unreachable: %s" % (self.points, self.told_unreachable),
            file=sys.stderr,
        )


run(GoalPoints())
