"""The native vector environment (`VectorExplore`)."""

from __future__ import annotations

import os
import numbers
from typing import Any

import numpy as np
import gymnasium as gym
from gymnasium.vector import AutoresetMode
from gymnasium.vector.utils import batch_space

from . import _native
from ._env import (
    action_mask,
    action_space,
    arrays,
    default_reward,
    info_of,
    observation_space,
    parse_action,
    reward_of,
    reward_terms,
)
from ._spec import EnvSpec, spec_of


class VectorExplore(gym.vector.VectorEnv):
    """``num_envs`` floorcast environments of one spec, stepped together on ``threads`` Rust
    threads with the GIL released; observations, rewards and flags come back batched as numpy
    arrays. Results do not depend on ``threads``.

    Arguments: ``num_envs`` (1 to 4096), ``threads`` (1 to 256; default the machine's CPUs,
    at most ``num_envs``), ``reward`` as `ExploreEnv`'s, and the fields of `EnvSpec` (or
    ``spec=``; ``localization`` and ``strategy_settings`` as in `ExploreEnv`).

    Seeding: after ``reset(seed=s)``, episode k of environment i has seed ``s + i + k *
    num_envs`` (its building ``seed % len(buildings)``). Autoreset: gymnasium's next-step mode
    (an environment whose episode ended is reset by the next ``step``, which ignores its
    action and returns the new episode's first observation with reward 0).

    ``infos`` holds per-environment arrays (gymnasium's vector convention, each key with a
    ``_key`` mask): ``explored_fraction``, ``time_s``, ``decision``, ``seed``; at an episode's
    end ``end_reason`` and ``summary`` (summary.json as a dict).
    """

    metadata = {"autoreset_mode": AutoresetMode.NEXT_STEP, "render_modes": []}

    def __init__(self, num_envs: int, threads: int | None = None, *, spec: EnvSpec | None = None,
                 reward="default", localization=None, strategy_settings=None, **kwargs: Any):
        spec = spec_of(spec, localization, strategy_settings, kwargs)
        if isinstance(num_envs, bool) or not isinstance(num_envs, numbers.Integral) or not 1 <= num_envs <= 4096:
            raise ValueError(f"num_envs: {num_envs!r}; expected an integer from 1 to 4096")
        if threads is None:
            threads = max(1, min(int(num_envs), os.cpu_count() or 1))
        if isinstance(threads, bool) or not isinstance(threads, numbers.Integral) or not 1 <= threads <= 256:
            raise ValueError(f"threads: {threads!r}; expected an integer from 1 to 256")
        self.floorcast_spec = spec
        self._reward = reward_of(reward)
        self.num_envs = int(num_envs)
        self.threads = int(threads)
        self._native = _native.VecEnv(spec.to_json(), self.num_envs, self.threads)
        self.single_observation_space = observation_space(spec)
        self.single_action_space = action_space(spec)
        self.observation_space = batch_space(self.single_observation_space, self.num_envs)
        self.action_space = batch_space(self.single_action_space, self.num_envs)
        self.building_names = tuple(self._native.building_names())
        self._fractions = np.zeros(self.num_envs)
        self._obs = None

    def __reduce__(self):
        return (_rebuild, (self.num_envs, self.threads, self.floorcast_spec, self._reward))

    def _batch(self, outs):
        each = [arrays(o["obs"]) for o in outs]
        obs = {k: np.stack([e[k] for e in each]) for k in self.single_observation_space.spaces}
        infos: dict = {}
        for key in ("explored_fraction", "time_s", "decision", "seed"):
            infos[key] = np.array([o[key] for o in outs])
            infos["_" + key] = np.ones(self.num_envs, dtype=bool)
        ended = np.array([o["summary"] is not None for o in outs])
        if ended.any():
            infos["end_reason"] = np.array([o["end_reason"] for o in outs], dtype=object)
            infos["_end_reason"] = ended
            infos["summary"] = np.array([info_of(o, {}).get("summary") for o in outs], dtype=object)
            infos["_summary"] = ended
        self._obs = obs
        return obs, infos

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        """Resets every environment: environment i gets seed ``seed + i``."""
        if options:
            raise ValueError(f"options: {sorted(options)}; the vector environment takes none")
        if seed is None:
            seed = int(np.random.default_rng().integers(0, 2**63))
        elif isinstance(seed, bool) or not isinstance(seed, numbers.Integral) or not 0 <= seed < 2**64:
            raise ValueError(f"seed: {seed!r}; expected one integer from 0 to 2**64 - 1 (environment i gets seed + i)")
        outs = self._native.reset(int(seed))
        self._fractions = np.array([o["explored_fraction"] for o in outs])
        return self._batch(outs)

    def step(self, actions):
        """One decision of every environment: ``actions`` of shape (num_envs,) (candidates) or
        (num_envs, 2) (map)."""
        spec = self.floorcast_spec
        try:
            a = np.asarray(actions)
        except (TypeError, ValueError):
            raise ValueError(f"actions: {actions!r}; expected an array of one action per environment") from None
        if a.ndim == 0 or len(a) != self.num_envs:
            raise ValueError(f"actions: shape {a.shape}; expected one action per environment ({self.num_envs})")
        parsed = [parse_action(spec, a[i], name=f"actions[{i}]") for i in range(self.num_envs)]
        if spec.observation != "map":
            outs = self._native.step([p[0] for p in parsed], None)
        else:
            outs = self._native.step(None, [p[1] for p in parsed])
        rewards = np.zeros(self.num_envs)
        terminations = np.zeros(self.num_envs, dtype=bool)
        truncations = np.zeros(self.num_envs, dtype=bool)
        for i, o in enumerate(outs):
            if o.get("autoreset"):
                self._fractions[i] = o["explored_fraction"]
                continue
            terms = reward_terms(o, self._fractions[i])
            self._fractions[i] = o["explored_fraction"]
            rewards[i] = float(self._reward(terms))
            terminations[i] = o["terminated"]
            truncations[i] = o["truncated"]
        obs, infos = self._batch(outs)
        return obs, rewards, terminations, truncations, infos

    def action_masks(self) -> np.ndarray:
        """(num_envs, K) bool: the indices each environment's action may name."""
        if self.floorcast_spec.observation == "map":
            raise ValueError("action_masks: the map observation's action is a point, not an index")
        if self._obs is None:
            raise ValueError("action_masks: call reset() first")
        return action_mask(self._obs)


def _rebuild(num_envs, threads, spec, reward):
    return VectorExplore(num_envs, threads, spec=spec, reward="default" if reward is default_reward else reward)
