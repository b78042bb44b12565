"""The gymnasium environment `floorcast/Explore-v0` (`ExploreEnv`)."""

from __future__ import annotations

import json
import math
import numbers
from typing import Any, Callable

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from . import _native
from ._spec import EnvSpec, spec_of

#: The candidates array's features (its last axis), in order. Lengths in metres, areas in m²,
#: angles in radians; forward/left are the candidate's goal in the robot's estimated frame.
FEATURES = tuple(_native.FEATURES)
#: The map observation's channels (its first axis), in order: 255 where any map cell inside
#: the crop cell is of that kind, else 0 (free, occupied, unknown, frontier: a free cell beside
#: an unknown one; trail: the estimated positions of the decisions so far, joined by straight
#: segments; robot: the estimated position now). Outside the map counts as unknown.
CHANNELS = tuple(_native.CHANNELS)

#: Default reward weights: ``100 * explored fraction gained - 0.1 * simulated seconds
#: elapsed + 10 when the run ends complete``.
AREA_WEIGHT = 100.0
TIME_WEIGHT = 0.1
COMPLETE_BONUS = 10.0


def default_reward(terms: dict) -> float:
    """The default reward of one step from its raw terms (``info["reward_terms"]``): the
    explored share of the building's free area gained times 100, minus 0.1 per simulated
    second elapsed, plus 10 at the end of a complete run. Its sum over an episode is
    ``100 * explored_fraction - 0.1 * exploration time (s) + 10 if complete``: faster
    exploration scores more."""
    r = AREA_WEIGHT * terms["fraction_gain"] - TIME_WEIGHT * terms["elapsed_s"]
    if terms["end_reason"] == "complete":
        r += COMPLETE_BONUS
    return float(r)


def observation_space(spec: EnvSpec) -> spaces.Dict:
    """The observation space of a spec."""
    pose = spaces.Box(-np.inf, np.inf, shape=(3,), dtype=np.float32)
    time_s = spaces.Box(0.0, np.inf, shape=(1,), dtype=np.float32)
    if spec.observation == "candidates":
        k = spec.max_candidates
        return spaces.Dict(
            {
                "candidates": spaces.Box(-np.inf, np.inf, shape=(k, len(FEATURES)), dtype=np.float32),
                "mask": spaces.Box(0, 1, shape=(k,), dtype=np.int8),
                "pose": pose,
                "time_s": time_s,
            }
        )
    if spec.observation == "graph":
        n, k = spec.graph_nodes, spec.graph_k
        return spaces.Dict(
            {
                "node_inputs": spaces.Box(-np.inf, np.inf, shape=(n, 4), dtype=np.float32),
                "edge_inputs": spaces.Box(0, n - 1, shape=(1, k), dtype=np.int64),
                "current_index": spaces.Box(0, n - 1, shape=(1, 1), dtype=np.int64),
                "node_padding_mask": spaces.Box(0, 1, shape=(1, n), dtype=np.int8),
                "edge_padding_mask": spaces.Box(0, 1, shape=(1, k), dtype=np.int8),
                "edge_mask": spaces.Box(0, 1, shape=(n, n), dtype=np.int8),
                "pose": pose,
                "time_s": time_s,
            }
        )
    s = spec.map_size
    return spaces.Dict(
        {
            "map": spaces.Box(0, 255, shape=(len(CHANNELS), s, s), dtype=np.uint8),
            "pose": pose,
            "time_s": time_s,
        }
    )


class CandidateIndex(spaces.Discrete):
    """`Discrete(K)` whose ``sample()`` (without a mask of its own) draws among the candidates
    shown at the pending decision, as MaskablePPO's masked sampling does: only they are
    actions the environment takes."""

    shown: np.ndarray | None = None

    def sample(self, mask=None, probability=None):
        if mask is None and probability is None and self.shown is not None and self.shown.any():
            mask = self.shown.astype(np.int8)
        return super().sample(mask=mask, probability=probability)


def action_space(spec: EnvSpec) -> spaces.Space:
    """The action space of a spec: a candidate's index, or a point of the crop."""
    if spec.observation == "candidates":
        return CandidateIndex(spec.max_candidates)
    if spec.observation == "graph":
        return CandidateIndex(spec.graph_k)
    return spaces.Box(0.0, 1.0, shape=(2,), dtype=np.float32)


def arrays(obs_list) -> dict:
    """The native module's arrays as a dict of numpy arrays (copied)."""
    return {
        key: np.frombuffer(buf, dtype=dtype).reshape(shape)
        for key, dtype, shape, buf in obs_list
    }


def parse_action(spec: EnvSpec, action, name: str = "action"):
    """``(index, point)`` of an action, or ValueError naming `name`."""
    if spec.observation in ("candidates", "graph"):
        a = action
        if isinstance(a, np.ndarray):
            if a.size != 1:
                raise ValueError(f"{name}: an array of shape {a.shape}; expected one index")
            a = a.reshape(()).item()
        if isinstance(a, (bool, np.bool_)):
            raise ValueError(f"{name}: {a!r}; expected an integer index, not a bool")
        if not isinstance(a, numbers.Integral):
            if isinstance(a, numbers.Real) and math.isfinite(a) and float(a).is_integer():
                a = int(a)
            else:
                raise ValueError(f"{name}: {a!r}; expected an integer index (a candidate's, or the graph's edge's)")
        return int(a), None
    try:
        p = np.asarray(action, dtype=np.float64)
    except (TypeError, ValueError):
        raise ValueError(f"{name}: {action!r}; expected a point [column, row] in [0, 1]²") from None
    if p.shape != (2,):
        raise ValueError(f"{name}: shape {p.shape}; expected (2,): a point [column, row] in [0, 1]²")
    if not np.all(np.isfinite(p)) or np.any(p < 0) or np.any(p > 1):
        raise ValueError(f"{name}: {p.tolist()}; expected two finite numbers from 0 to 1 (column, row; row 0 at the top)")
    return None, (float(p[0]), float(p[1]))


def action_mask(obs: dict) -> np.ndarray:
    """The indices an action may name: the candidates shown, or the robot node's edges (those
    not padding; batched observations give one row per environment)."""
    if "mask" in obs:
        return obs["mask"].astype(bool)
    return obs["edge_padding_mask"][..., 0, :] == 0


def reward_of(reward):
    """The reward function an argument names: ``"default"`` or a callable."""
    if isinstance(reward, str) and reward == "default":
        return default_reward
    if not callable(reward):
        raise ValueError(f"reward: {reward!r}; expected \"default\" or a callable reward(terms) -> float")
    return reward


def reward_terms(out: dict, last_fraction: float) -> dict:
    """The raw reward terms of a step's output."""
    return {
        "area_gain_m2": out["area_gain_m2"],
        "fraction_gain": out["explored_fraction"] - last_fraction,
        "elapsed_s": out["elapsed_s"],
        "driven_m": out["driven_m"],
        "explored_fraction": out["explored_fraction"],
        "end_reason": out["end_reason"],
    }


def info_of(out: dict, terms: dict) -> dict:
    info = {
        "building": out["building"],
        "seed": out["seed"],
        "decision": out["decision"],
        "attempt": out["attempt"],
        "time_s": out["time_s"],
        "explored_fraction": out["explored_fraction"],
        "explored_area_m2": out["explored_area_m2"],
        "candidates": out["candidates"],
        "reward_terms": terms,
    }
    if out["summary"] is not None:
        info["end_reason"] = out["end_reason"]
        info["summary"] = json.loads(out["summary"])
    return info


class ExploreEnv(gym.Env):
    """floorcast's exploration as a gymnasium environment: one step is one decision of the
    robot (where to drive next); between decisions floorcast simulates the robot, its laser,
    odometry, SLAM, mapping, frontiers and path following (about a thousand times faster than
    real time). ``reset(seed=s)`` on a building reproduces ``floorcast explore --seed s`` on
    it bit for bit when the policy answers as a strategy would.

    Arguments (all keyword): those of `EnvSpec` (``buildings`` required; ``settings``, alias
    ``strategy_settings``; ``observation``, ``max_candidates``, ``needs``, ``map_size``,
    ``map_cell_m``, ``map_frame``, ``start``, ``split``, ``base``, ``label``), or ``spec=`` an
    `EnvSpec`; ``localization`` (``"slam"``, ``"odometry"`` or ``"ground-truth"``: shorthand for
    ``settings["localization"]``); ``reward``: ``"default"`` (see `default_reward`) or a
    callable ``reward(terms) -> float`` of the raw terms (``info["reward_terms"]``:
    ``area_gain_m2``, ``fraction_gain``, ``elapsed_s``, ``driven_m``, ``explored_fraction``,
    ``end_reason``).

    Observation ``"candidates"``: ``candidates`` (K, 10) float32, the reachable frontier
    candidates nearest by path first, their features in `FEATURES`; ``mask`` (K,) int8, 1 for a
    candidate shown; ``pose`` (3,) the estimated pose (x m, y m, θ rad, map frame);
    ``time_s`` (1,) simulated time. Action: the index of a candidate with mask 1
    (`action_masks()`).

    Observation ``"map"``: ``map`` (6, S, S) uint8 (channels `CHANNELS`, row 0 the top);
    ``pose``; ``time_s``. Action: a point [column, row] in [0, 1]² of the crop: the robot
    drives there (the nearest traversable cell within 0.5 m), or when no path leads there to
    the candidate whose goal is nearest to it.

    Observation ``"graph"``: the known free space as a graph in ARiADNE's shapes and order
    (without its batch axis): ``node_inputs`` (N, 4) float32 ``[x, y, utility / 50,
    guidepost]``, x and y from the map's lower-left corner over its longer side, node 0 the
    robot's estimated position, the others a lattice over the known free cells;
    ``edge_inputs`` (1, K) int64, the robot node's K nearest nodes in sight (itself first; 0
    pads); ``current_index`` (1, 1) int64 (0); ``node_padding_mask`` (1, N) int8;
    ``edge_padding_mask`` (1, K) int8 (1 where ``edge_inputs`` is 0); ``edge_mask`` (N, N)
    int8 (0 where an edge joins two nodes); ``pose``; ``time_s``. Action: an index into
    ``edge_inputs`` whose ``edge_padding_mask`` is 0: the robot drives to that node (or, when
    no path leads there, to the candidate whose goal is nearest to it).

    Episodes end (``terminated``) as floorcast's runs end: complete, early stop, stuck,
    frontiers unreachable; ``truncated`` at the settings' ``time_limit_s``. ``info`` holds the
    building, seed, decision, simulated time, explored fraction and the reward terms; at the
    end also ``end_reason`` and ``summary`` (the run's summary.json).
    """

    metadata = {"render_modes": []}

    def __init__(self, *, spec: EnvSpec | None = None, reward: str | Callable[[dict], float] = "default",
                 localization: str | None = None, strategy_settings=None, render_mode=None, **kwargs: Any):
        spec = spec_of(spec, localization, strategy_settings, kwargs)
        if render_mode is not None:
            raise ValueError(f"render_mode: {render_mode!r}; this environment does not render (write figures with `floorcast explore`)")
        self.floorcast_spec = spec
        self._reward = reward_of(reward)
        self._native = _native.Env(spec.to_json())
        self.observation_space = observation_space(spec)
        self.action_space = action_space(spec)
        self.building_names = tuple(self._native.building_names())
        self._obs = None
        self._fraction = 0.0

    def __reduce__(self):
        return (_rebuild, (self.floorcast_spec, self._reward))

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        """A new episode. ``seed`` (0 to 2**64 - 1): the run's seed (laser and odometry noise,
        random starts); without one, drawn from the environment's generator. ``options``:
        ``building`` (an index into `building_names` or a name; default ``seed % len``),
        ``start`` ([x m, y m, θ rad]; default: the spec's ``start``)."""
        if seed is not None and (isinstance(seed, bool) or not isinstance(seed, numbers.Integral) or not 0 <= seed < 2**64):
            raise ValueError(f"seed: {seed!r}; expected an integer from 0 to 2**64 - 1")
        super().reset(seed=seed)
        if seed is None:
            seed = int(self.np_random.integers(0, 2**63))
        options = dict(options or {})
        building = options.pop("building", None)
        if isinstance(building, str):
            if building not in self.building_names:
                raise ValueError(f"options['building']: {building!r} is not one of the environment's buildings")
            building = self.building_names.index(building)
        elif building is not None and (isinstance(building, bool) or not isinstance(building, numbers.Integral) or building < 0):
            raise ValueError(f"options['building']: {building!r}; expected an index or a name")
        start = options.pop("start", None)
        if start is not None:
            try:
                start = tuple(float(v) for v in start)
            except (TypeError, ValueError):
                raise ValueError(f"options['start']: {start!r}; expected [x m, y m, theta rad]") from None
            if len(start) != 3:
                raise ValueError(f"options['start']: {start!r}; expected [x m, y m, theta rad]")
        if options:
            raise ValueError(f"options: unknown keys {sorted(options)}; expected 'building', 'start'")
        out = self._native.reset(int(seed), building, start)
        self._fraction = out["explored_fraction"]
        self._set_obs(out)
        terms = reward_terms(out, self._fraction)
        return self._obs, info_of(out, terms)

    def _set_obs(self, out):
        self._obs = arrays(out["obs"])
        if isinstance(self.action_space, CandidateIndex):
            self.action_space.shown = action_mask(self._obs)

    def step(self, action):
        """Answers the pending decision and runs to the next one: ``(obs, reward, terminated,
        truncated, info)``."""
        index, point = parse_action(self.floorcast_spec, action)
        out = self._native.step(index, point)
        terms = reward_terms(out, self._fraction)
        self._fraction = out["explored_fraction"]
        self._set_obs(out)
        reward = float(self._reward(terms))
        return self._obs, reward, out["terminated"], out["truncated"], info_of(out, terms)

    def action_masks(self) -> np.ndarray:
        """The indices an action may name (bool, shape (K,)): the candidates shown, or the
        graph's edges of the robot's node; not in the map mode."""
        if self.floorcast_spec.observation == "map":
            raise ValueError("action_masks: the map observation's action is a point, not an index")
        if self._obs is None:
            raise ValueError("action_masks: call reset() first")
        return action_mask(self._obs)


def _rebuild(spec, reward):
    return ExploreEnv(spec=spec, reward="default" if reward is default_reward else reward)
