"""The trained linear policy: scores each frontier candidate by a weighted sum of a few of its
features (normalised, below) and drives to the best one; ties go to the lowest index, the
candidate nearest by path. Deterministic: the same observation, the same decision, in the
environment (`floorcast.ExploreEnv`) and as a strategy (`python3 -m floorcast.serve
examples/python/policy.py:policy`, in `floorcast explore` or a grid).

The weights are `linear_policy.npz` next to this file, written by `train.py`.
"""

import os

import numpy as np

#: What the policy was trained on: the environment's candidates observation, the 32 candidates
#: nearest by path (`floorcast.serve` reads this, so that the strategy sees the same).
FLOORCAST_OBSERVATION = {"observation": "candidates", "max_candidates": 32}

#: The columns of floorcast.FEATURES the policy reads.
PATH, STRAIGHT, GAIN, CELLS, BEARING = 0, 1, 2, 5, 8

#: The policy's features of a candidate, in order (`features`).
FEATURE_NAMES = (
    "path_m / 10",
    "log(1 + path_m)",
    "straight_m / 10",
    "log(1 + gain_m2) / 4",
    "log(1 + frontier_cells) / 6",
    "cos(bearing_rad)",
)

WEIGHTS_FILE = os.path.join(os.path.dirname(os.path.abspath(__file__)), "linear_policy.npz")


def features(candidates) -> np.ndarray:
    """(..., K, 10) candidates (floorcast.FEATURES columns) -> (..., K, 6) float64 features:
    lengths in tens of metres (and their log), the baseline gain (m², its log), the frontier's
    size (its cells of 5 cm, log) and how far ahead of the robot it lies (cos of its bearing)."""
    c = np.asarray(candidates, dtype=np.float64)
    path = np.maximum(c[..., PATH], 0.0)
    return np.stack(
        [
            path / 10.0,
            np.log1p(path),
            c[..., STRAIGHT] / 10.0,
            np.log1p(np.maximum(c[..., GAIN], 0.0)) / 4.0,
            np.log1p(np.maximum(c[..., CELLS], 0.0)) / 6.0,
            np.cos(c[..., BEARING]),
        ],
        axis=-1,
    )


def choose(weights, candidates, mask) -> np.ndarray:
    """The chosen index of each observation (batched or not): argmax of the masked scores,
    ties to the lowest index (0 where nothing is shown)."""
    scores = features(candidates) @ np.asarray(weights, dtype=np.float64)
    scores = np.where(np.asarray(mask) > 0, scores, -np.inf)
    return np.argmax(scores, axis=-1)


def load_weights(path: str = WEIGHTS_FILE) -> np.ndarray:
    with np.load(path) as f:
        w = np.asarray(f["weights"], dtype=np.float64)
        names = tuple(str(n) for n in f["features"])
    if names != FEATURE_NAMES or w.shape != (len(FEATURE_NAMES),):
        raise ValueError(f"{path}: weights for features {names}, expected {FEATURE_NAMES}")
    return w


WEIGHTS = load_weights() if os.path.exists(WEIGHTS_FILE) else None


def policy(obs):
    """The candidate to drive to (an index with mask 1), or None (stop) when none is shown."""
    if WEIGHTS is None:
        raise RuntimeError(f"{WEIGHTS_FILE}: no weights; train them with examples/python/train.py")
    mask = obs["mask"]
    if not np.any(mask):
        return None
    return int(choose(WEIGHTS, obs["candidates"], mask))
