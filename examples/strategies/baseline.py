#!/usr/bin/env python3
"""The paper's utility over the gains floorcast sends: the built-in `baseline`'s choices.

    floorcast explore --building buildings/small.toml \
        --strategy-command "python3 examples/strategies/baseline.py"

floorcast puts its module `floorcast_strategy` on the program's PYTHONPATH.
"""
from floorcast_strategy import Strategy, best_by_paper_utility, run


class Baseline(Strategy):
    name = "baseline.py"

    def decide(self, d):
        return best_by_paper_utility(d, self.run)


if __name__ == "__main__":
    run(Baseline())
