#!/usr/bin/env python3
"""Test strategy: stops exploring at the first decision (an early stop)."""
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "python"))
from floorcast_strategy import Strategy, run  # noqa: E402


class StopsAtOnce(Strategy):
    name = "stops-at-once"

    def decide(self, d):
        return None


run(StopsAtOnce())
