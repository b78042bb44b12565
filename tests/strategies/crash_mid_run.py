#!/usr/bin/env python3
"""Test strategy: answers the first 2 decide messages (lowest id), raises at the 3rd."""
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "python"))
from floorcast_strategy import Strategy, run  # noqa: E402


class CrashMidRun(Strategy):
    name = "crash-mid-run"

    def __init__(self):
        self.decides = 0

    def decide(self, d):
        self.decides += 1
        if self.decides == 3:
            raise RuntimeError("strategy bug at decision 3")
        return min(c["id"] for c in d["candidates"])


run(CrashMidRun())
