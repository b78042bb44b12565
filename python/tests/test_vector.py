"""The native vector environment, and the spec that rebuilds an environment elsewhere."""

import concurrent.futures
import multiprocessing
import pickle

import gymnasium as gym
import numpy as np
import pytest

import floorcast
from conftest import REPO, nearest, run_episode

BUILDINGS = [str(REPO / "buildings" / "small.toml"), "generate:school:400:3"]


def batched_nearest(obs):
    m = obs["mask"].astype(bool)
    return np.argmin(np.where(m, obs["candidates"][..., 0], np.inf), axis=-1)


def roll(vec, seed, steps):
    """`steps` steps of nearest answers: observations, rewards, flags and summaries."""
    obs, _ = vec.reset(seed=seed)
    trace = [obs]
    ends = []
    for _ in range(steps):
        obs, rew, term, trunc, infos = vec.step(batched_nearest(obs))
        trace.append((obs, rew, term, trunc))
        if "summary" in infos:
            ends += [(i, s) for i, s in enumerate(infos["summary"]) if infos["_summary"][i]]
    return trace, ends


def same_trace(a, b):
    assert len(a) == len(b)
    for x, y in zip(a, b):
        if isinstance(x, dict):
            x, y = (x,), (y,)
        for u, v in zip(x, y):
            if isinstance(u, dict):
                for k in u:
                    np.testing.assert_array_equal(u[k], v[k], err_msg=k)
            else:
                np.testing.assert_array_equal(u, v)


def test_the_same_results_whatever_the_thread_count():
    one = floorcast.VectorExplore(3, threads=1, buildings=BUILDINGS)
    two = floorcast.VectorExplore(3, threads=2, buildings=BUILDINGS)
    t1, e1 = roll(one, 5, 150)
    t2, e2 = roll(two, 5, 150)
    same_trace(t1, t2)
    assert [(i, s["exploration_time_s"]) for i, s in e1] == [(i, s["exploration_time_s"]) for i, s in e2]
    assert e1, "an episode ended within the steps (autoreset exercised)"


def test_the_vector_env_steps_the_single_envs_episodes():
    # Environment i's first episode is a single environment's reset(seed + i).
    vec = floorcast.VectorExplore(2, threads=2, buildings=BUILDINGS)
    trace, ends = roll(vec, 10, 400)
    single = floorcast.ExploreEnv(buildings=BUILDINGS)
    for i in range(2):
        actions, rewards, info = run_episode(single, nearest, 10 + i)
        first = [s for j, s in ends if j == i][0]
        assert first["exploration_time_s"] == info["summary"]["exploration_time_s"]
        assert first["decisions"] == info["summary"]["decisions"]
        assert first["building"] == info["summary"]["building"]
        # Its rewards, step for step, until the end.
        vec_rewards = [t[1][i] for t in trace[1:len(rewards) + 1]]
        assert vec_rewards == pytest.approx(rewards, rel=0, abs=0)


def test_autoreset_is_next_step_with_the_next_seed():
    vec = floorcast.VectorExplore(2, threads=2, buildings=[BUILDINGS[0]])
    obs, _ = vec.reset(seed=0)
    seeds = []
    ended = np.zeros(2, dtype=bool)
    for _ in range(400):
        obs, rew, term, trunc, infos = vec.step(batched_nearest(obs))
        for i in np.flatnonzero(ended):
            # The step after an end: the new episode's first observation, reward 0.
            assert rew[i] == 0 and not term[i] and not trunc[i]
            seeds.append((i, int(infos["seed"][i])))
        ended = term | trunc
        if len(seeds) >= 2:
            break
    assert sorted(seeds)[:2] == [(0, 2), (1, 3)]


def test_make_vec_uses_the_native_vector_env():
    vec = gym.make_vec("floorcast/Explore-v0", num_envs=2, vectorization_mode="vector_entry_point",
                       buildings=BUILDINGS[0])
    assert isinstance(vec, floorcast.VectorExplore)
    obs, _ = vec.reset(seed=1)
    assert obs["candidates"].shape == (2, 32, len(floorcast.FEATURES))
    assert vec.action_masks().shape == (2, 32)


@pytest.mark.parametrize("actions", [[0], [0, 99], [0.5, 0], np.zeros((2, 2)), "ab", [0, float("nan")]], ids=repr)
def test_bad_vector_actions_raise_before_any_env_moves(actions):
    vec = floorcast.VectorExplore(2, threads=2, buildings=BUILDINGS[0])
    obs, _ = vec.reset(seed=1)
    with pytest.raises(ValueError, match="actions"):
        vec.step(actions)
    obs2, *_ = vec.step(batched_nearest(obs))
    # Both moved exactly one decision from the reset: the bad call changed nothing.
    ref = floorcast.VectorExplore(2, threads=1, buildings=BUILDINGS[0])
    o, _ = ref.reset(seed=1)
    o2, *_ = ref.step(batched_nearest(o))
    np.testing.assert_array_equal(obs2["candidates"], o2["candidates"])


@pytest.mark.parametrize("kwargs,argument", [
    (dict(num_envs=0), "num_envs"), (dict(num_envs=2, threads=0), "threads"),
    (dict(num_envs=2, threads=1.5), "threads"),
])
def test_bad_vector_arguments_raise(kwargs, argument):
    with pytest.raises(ValueError, match=argument):
        floorcast.VectorExplore(buildings=BUILDINGS[0], **kwargs)


def _episode_of_pickled_spec(blob):
    """In another process: the environment rebuilt from its pickled spec, one episode."""
    import pickle
    import numpy as np

    spec = pickle.loads(blob)
    env = spec.make()
    obs, _ = env.reset(seed=21)
    actions = []
    while True:
        m = obs["mask"].astype(bool)
        a = int(np.argmin(np.where(m, obs["candidates"][:, 0], np.inf)))
        actions.append(a)
        obs, r, term, trunc, info = env.step(a)
        if term or trunc:
            return actions, info["summary"]


def test_an_environment_rebuilt_from_its_pickled_spec_in_another_process_runs_the_same_episode():
    spec = floorcast.EnvSpec(buildings=BUILDINGS, settings={"time_limit_s": 900}, max_candidates=16)
    blob = pickle.dumps(spec)
    assert len(blob) < 2000, "the spec is small"
    ctx = multiprocessing.get_context("spawn")
    with concurrent.futures.ProcessPoolExecutor(1, mp_context=ctx) as pool:
        there = pool.submit(_episode_of_pickled_spec, blob).result(timeout=600)
    here = _episode_of_pickled_spec(blob)
    assert there[0] == here[0]
    for k in ("exploration_time_s", "explored_fraction", "path_length_m", "decisions", "building"):
        assert there[1][k] == here[1][k], k
    # The environments themselves pickle as their spec.
    env = pickle.loads(pickle.dumps(spec.make()))
    assert env.floorcast_spec == spec


def test_a_pickled_spec_of_another_layout_is_refused_by_name():
    import floorcast._spec as spec_module

    blob = pickle.dumps(floorcast.EnvSpec(buildings="x.toml"))
    assert pickle.loads(blob) == floorcast.EnvSpec(buildings="x.toml")
    with pytest.raises(ValueError, match="EnvSpec: pickled with spec layout 99"):
        spec_module._load(99, {"buildings": "x.toml"})
    with pytest.raises(ValueError, match="unknown fields"):
        spec_module._load(spec_module.SPEC_VERSION, {"buildings": "x.toml", "colour": 1})
