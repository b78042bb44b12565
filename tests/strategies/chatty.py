#!/usr/bin/env python3
"""Test strategy: prints a debugging line to stdout (a protocol error) before its first decide
reply."""
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "python"))
from floorcast_strategy import Strategy, best_by_paper_utility, run  # noqa: E402


class Chatty(Strategy):
    name = "chatty"

    def decide(self, d):
        print("debug: deciding")
        return best_by_paper_utility(d, self.run)


run(Chatty())
