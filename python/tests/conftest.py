"""Shared helpers of the Python tests: the repository, the floorcast binary, policies."""

import json
import os
import pathlib
import subprocess

import numpy as np
import pytest

REPO = pathlib.Path(__file__).resolve().parents[2]


def floorcast_bin() -> str:
    """The floorcast binary the tests compare with: $FLOORCAST_BIN, else the release build of
    this clone (`cargo build --release`, which the README's test command makes; in
    $CARGO_TARGET_DIR when set). Missing, the tests that need it fail: they never pass without
    it."""
    target = os.environ.get("CARGO_TARGET_DIR") or str(REPO / "target")
    path = os.environ.get("FLOORCAST_BIN") or os.path.join(target, "release", "floorcast")
    if not os.path.isfile(path):
        pytest.fail(f"no floorcast binary at {path}: run `cargo build --release` first (or set FLOORCAST_BIN)")
    return path


def explore(building, seed, out_dir, *extra):
    """`floorcast explore` of `building` with `seed`: its summary.json and decisions.csv."""
    cmd = [floorcast_bin(), "explore", "--building", str(building), "--seed", str(seed),
           "--out", str(out_dir), "--quiet", *map(str, extra)]
    p = subprocess.run(cmd, capture_output=True, text=True, cwd=REPO, timeout=900)
    assert p.returncode == 0, p.stderr
    summary = json.loads((pathlib.Path(out_dir) / "summary.json").read_text())
    decisions = (pathlib.Path(out_dir) / "decisions.csv").read_text()
    return summary, decisions


def nearest(obs):
    """The nearest candidate by path (ties: the lowest index, which the observation orders by
    id among equal paths): `nearest`'s rule."""
    m = obs["mask"].astype(bool)
    return int(np.argmin(np.where(m, obs["candidates"][:, 0], np.inf)))


def run_episode(env, policy, seed, options=None, limit=100_000):
    """Runs one episode to its end: (actions, rewards, final info)."""
    obs, info = env.reset(seed=seed, options=options)
    actions, rewards = [], []
    for _ in range(limit):
        a = policy(obs)
        actions.append(np.asarray(a).tolist())
        obs, r, term, trunc, info = env.step(a)
        rewards.append(r)
        if term or trunc:
            return actions, rewards, info
    raise AssertionError("the episode did not end")


#: Summary fields that differ between identical runs (wall time) or name the strategy.
VOLATILE = {"wall_time_s", "speedup", "strategy", "strategy_program", "strategy_name",
            "strategy_compute_s", "strategy_replies"}


def same_run(a: dict, b: dict):
    """Two summaries of the same run: every field but the volatile ones equal."""
    keys = (set(a) | set(b)) - VOLATILE
    diff = {k: (a.get(k), b.get(k)) for k in keys if a.get(k) != b.get(k)}
    assert not diff, diff
