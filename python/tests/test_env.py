"""The gymnasium environment: the API, floorcast's runs reproduced, seeding, bad input."""

import math
import subprocess
import sys

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import floorcast
from conftest import REPO, explore, nearest, run_episode, same_run

SMALL = str(REPO / "buildings" / "small.toml")

# Every observation mode (and the map's two frames) passes gymnasium's checker.
MODES = [
    dict(observation="candidates"),
    dict(observation="candidates", max_candidates=4, needs=["layout_gain", "layout"]),
    dict(observation="map"),
    dict(observation="map", map_frame="global", map_size=48),
    dict(observation="graph"),
    dict(observation="graph", graph_nodes=64, graph_k=8, graph_spacing_m=1.0, graph_range_m=4.0),
]


@pytest.mark.parametrize("mode", MODES, ids=lambda m: "-".join(str(v) for v in m.values()))
def test_check_env_passes_for_every_observation_mode(mode):
    env = floorcast.ExploreEnv(buildings=SMALL, **mode)
    check_env(env, skip_render_check=True)
    obs, _ = env.reset(seed=3)
    assert env.observation_space.contains(obs)


def test_registered_and_made_with_gym_make():
    env = gym.make("floorcast/Explore-v0", buildings=SMALL, localization="ground-truth")
    obs, info = env.reset(seed=1)
    assert info["building"] == "small"
    assert env.unwrapped.floorcast_spec.settings == {"localization": "ground-truth"}
    assert obs["mask"].sum() >= 1


# `reset(seed=s)` answered by the nearest candidate is `floorcast explore --strategy nearest
# --seed s`, decision for decision: real plans with their own starts, a generated building, a
# random start, SLAM (the default) and perfect localization.
NEAREST_CASES = [
    (SMALL, 1, {}, []),
    (SMALL, 7, {"localization": "ground-truth"}, ["--localization", "ground-truth"]),
    (str(REPO / "buildings" / "paper" / "paper-03.toml"), 2, {}, []),
    (str(REPO / "maps" / "radish" / "intel_map.yaml"), 5, {"time_limit_s": 300}, ["--time-limit-s", "300"]),
]


@pytest.mark.parametrize("building,seed,settings,flags", NEAREST_CASES)
def test_nearest_answers_reproduce_floorcast_explore(tmp_path, building, seed, settings, flags):
    env = floorcast.ExploreEnv(buildings=building, settings=settings)
    actions, _, info = run_episode(env, nearest, seed)
    summary, decisions = explore(building, seed, tmp_path, "--strategy", "nearest", *flags)
    same_run(info["summary"], summary)
    assert info["summary"]["decisions"] == len(decisions.strip().splitlines()) - 1
    assert info["summary"]["strategy"] == "python-policy"
    if settings.get("time_limit_s"):
        assert info["end_reason"] == "time limit"


def test_a_generated_building_with_a_random_start_reproduces_explore(tmp_path):
    gen = tmp_path / "gen.toml"
    p = subprocess.run([__import__("conftest").floorcast_bin(), "building", "generate", "--seed", "4",
                        "--area-m2", "500", "--out", str(gen)], capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    env = floorcast.ExploreEnv(buildings=str(gen), start="random")
    _, _, info = run_episode(env, nearest, 9)
    summary, _ = explore(gen, 9, tmp_path / "out", "--strategy", "nearest", "--start", "random")
    same_run(info["summary"], summary)


def test_the_same_seed_is_the_same_episode_and_another_seed_another():
    env = floorcast.ExploreEnv(buildings=SMALL)
    rng_policy = lambda seed: (lambda obs, r=np.random.default_rng(seed): int(r.choice(np.flatnonzero(obs["mask"]))))
    a1, r1, i1 = run_episode(env, rng_policy(0), 11)
    a2, r2, i2 = run_episode(env, rng_policy(0), 11)
    assert (a1, r1) == (a2, r2)
    same_run(i1["summary"], i2["summary"])
    _, _, i3 = run_episode(env, rng_policy(0), 12)
    assert i3["summary"]["seed"] == 12
    assert i3["summary"]["exploration_time_s"] != i1["summary"]["exploration_time_s"]


def test_rewards_sum_to_the_documented_total():
    env = floorcast.ExploreEnv(buildings=SMALL)
    _, rewards, info = run_episode(env, nearest, 2)
    s = info["summary"]
    obs, first = env.reset(seed=2)
    expected = (100 * (s["explored_fraction"] - first["explored_fraction"])
                - 0.1 * s["total_time_s"] + (10 if s["end_reason"] == "complete" else 0))
    assert math.isclose(sum(rewards), expected, rel_tol=1e-9, abs_tol=1e-9)


def test_a_callable_reward_sees_the_raw_terms():
    seen = []
    env = floorcast.ExploreEnv(buildings=SMALL, reward=lambda t: seen.append(t) or t["area_gain_m2"])
    _, first = env.reset(seed=1)
    _, rewards, info = run_episode(env, nearest, 1)
    assert set(seen[0]) == {"area_gain_m2", "fraction_gain", "elapsed_s", "driven_m", "explored_fraction", "end_reason"}
    gained = info["summary"]["explored_area_m2"] - first["explored_area_m2"]
    assert math.isclose(sum(rewards), gained, rel_tol=1e-9)
    assert seen[-1]["end_reason"] == info["end_reason"] and all(t["end_reason"] is None for t in seen[:-1])


def test_candidates_are_ordered_by_path_and_masked():
    env = floorcast.ExploreEnv(buildings=str(REPO / "buildings" / "paper" / "paper-01.toml"), max_candidates=8)
    obs, info = env.reset(seed=1)
    for _ in range(20):
        n = int(obs["mask"].sum())
        assert n == min(8, info["candidates"])
        assert list(obs["mask"][:n]) == [1] * n and not obs["mask"][n:].any()
        paths = obs["candidates"][:n, 0]
        assert (np.diff(paths) >= 0).all()
        assert not obs["candidates"][n:].any()
        assert (env.action_masks() == obs["mask"].astype(bool)).all()
        obs, _, term, trunc, info = env.step(n - 1)
        if term or trunc:
            break


# Bad input raises a ValueError naming the argument; the interpreter goes on.
BAD_MAKE = [
    (dict(buildings="no/such/file.toml"), "buildings"),
    (dict(buildings="no-such-suite"), "buildings"),
    (dict(buildings="maps/none/*.xml"), "buildings"),
    (dict(buildings="/**/*.xml"), "whole file system"),  # bounded, as a grid's patterns
    (dict(buildings="generate:castle:900:1"), "buildings"),
    (dict(buildings="generate:school:12:1"), "buildings"),
    (dict(buildings=[]), "buildings"),
    (dict(buildings=SMALL, observation="pixels"), "observation"),
    (dict(buildings=SMALL, max_candidates=0), "max_candidates"),
    (dict(buildings=SMALL, settings={"alpha": "x"}), "settings"),
    (dict(buildings=SMALL, settings={"no_such_setting": 1}), "settings"),
    (dict(buildings=SMALL, localization="gps"), "settings"),
    (dict(buildings=SMALL, needs=["map"]), "needs"),
    (dict(buildings=SMALL, start="anywhere"), "start"),
    (dict(buildings=SMALL, split="validation"), "split"),
    (dict(buildings=SMALL, base="no-such-strategy"), "base"),
    (dict(buildings=SMALL, reward="fast"), "reward"),
    (dict(buildings=SMALL, map_cell_m=float("nan")), "map_cell_m"),
    (dict(buildings=SMALL, settings={"charge_compute": True}), "settings"),
]


@pytest.mark.parametrize("kwargs,argument", BAD_MAKE)
def test_bad_arguments_raise_a_value_error_naming_them(kwargs, argument):
    with pytest.raises(ValueError, match=argument):
        floorcast.ExploreEnv(**kwargs)


BAD_ACTIONS = [-1, 32, 3.5, float("nan"), "0", None, np.array([0, 1]), True]


@pytest.mark.parametrize("action", BAD_ACTIONS, ids=repr)
def test_bad_actions_raise_and_leave_the_episode_as_it_was(action):
    env = floorcast.ExploreEnv(buildings=SMALL)
    obs, info = env.reset(seed=1)
    with pytest.raises(ValueError, match="action"):
        env.step(action)
    # The decision is still pending: a good action goes on.
    env.step(nearest(obs))


BAD_POINTS = [[0.5], [0.5, float("nan")], [1.5, 0.2], [[0.1, 0.2]], "a", 3]


@pytest.mark.parametrize("action", BAD_POINTS, ids=repr)
def test_bad_points_raise(action):
    env = floorcast.ExploreEnv(buildings=SMALL, observation="map")
    env.reset(seed=1)
    with pytest.raises(ValueError, match="action"):
        env.step(action)


def test_step_before_reset_and_after_the_end_raise():
    env = floorcast.ExploreEnv(buildings=SMALL)
    with pytest.raises(ValueError, match="reset"):
        env.step(0)
    run_episode(env, nearest, 1)
    with pytest.raises(ValueError, match="over"):
        env.step(0)


BAD_RESETS = [
    (dict(seed=-1), "seed"),
    (dict(seed=2**64), "seed"),
    (dict(seed=1, options={"building": 5}), "building"),
    (dict(seed=1, options={"building": "nowhere"}), "building"),
    (dict(seed=1, options={"start": [1.0, 2.0]}), "start"),
    (dict(seed=1, options={"start": [float("nan"), 0, 0]}), "start"),
    (dict(seed=1, options={"start": [-500.0, -500.0, 0.0]}), "start"),
    (dict(seed=1, options={"colour": "red"}), "options"),
]


@pytest.mark.parametrize("kwargs,argument", BAD_RESETS)
def test_bad_resets_raise_a_value_error_naming_the_argument(kwargs, argument):
    env = floorcast.ExploreEnv(buildings=SMALL)
    with pytest.raises(ValueError, match=argument):
        env.reset(**kwargs)


def test_bad_input_never_aborts_the_interpreter():
    # In a child interpreter: every bad call raises, and the interpreter exits normally.
    code = f"""
import floorcast, numpy as np
bad = 0
for kw in [dict(buildings="nope"), dict(buildings={SMALL!r}, observation="x")]:
    try: floorcast.ExploreEnv(**kw)
    except ValueError: bad += 1
env = floorcast.ExploreEnv(buildings={SMALL!r})
for a in [-5, 10**30, float("nan"), np.zeros((3, 3))]:
    try: env.step(a)
    except (ValueError, OverflowError): bad += 1
env.reset(seed=1)
for a in [-5, 10**30, float("inf")]:
    try: env.step(a)
    except (ValueError, OverflowError): bad += 1
print(bad)
"""
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stderr
    assert p.stdout.strip() == "9"


def test_buildings_from_a_glob_a_suite_and_a_generator():
    env = floorcast.ExploreEnv(buildings=["generate:office:300:1-3", str(REPO / "buildings" / "paper" / "paper-0[12].toml")])
    assert env.building_names == ("gen-office-300-1", "gen-office-300-2", "gen-office-300-3", "paper-01", "paper-02")
    obs, info = env.reset(seed=4)
    assert info["building"] == "paper-02"  # seed % 5
    suite = floorcast.ExploreEnv(buildings=str(REPO / "suites" / "paper-set.toml"))
    assert len(suite.building_names) == 10


def test_the_split_is_fixed_disjoint_and_whole():
    glob = str(REPO / "maps" / "plans" / "*.xml")
    every = set(floorcast.ExploreEnv(buildings=glob).building_names)
    train = set(floorcast.ExploreEnv(buildings=glob, split="train").building_names)
    test = set(floorcast.ExploreEnv(buildings=glob, split="test").building_names)
    assert train | test == every and not train & test
    # About TEST_SHARE of them: within four standard deviations of the binomial.
    n, p = len(every), floorcast.TEST_SHARE
    assert abs(len(test) - n * p) <= 4 * (n * p * (1 - p)) ** 0.5
    # The same buildings under other names are on the same side (the split is by content).
    again = floorcast.ExploreEnv(buildings=sorted(str(REPO / "maps" / "plans" / f"{b}.xml") for b in test), split="test")
    assert set(again.building_names) == test


def test_the_graph_has_ariadnes_shapes_and_its_rules():
    env = floorcast.ExploreEnv(buildings=str(REPO / "buildings" / "paper" / "paper-02.toml"), observation="graph",
                               graph_nodes=200, graph_k=12)
    obs, info = env.reset(seed=1)
    for step in range(30):
        n = int((obs["node_padding_mask"][0] == 0).sum())
        assert 1 < n <= 200 and not obs["node_padding_mask"][0, :n].any() and obs["node_padding_mask"][0, n:].all()
        nodes = obs["node_inputs"]
        assert not nodes[n:].any()
        assert nodes[0, 3] == 1, "the robot's node is visited"
        assert (nodes[:n, 2] >= 0).all() and set(np.unique(nodes[:n, 3])) <= {0.0, 1.0}
        assert obs["current_index"][0, 0] == 0
        edges = obs["edge_inputs"][0]
        # The robot node's edges are its row of the edge mask; 0 (itself) pads.
        assert set(np.flatnonzero(obs["edge_mask"][0] == 0)) == set(edges[edges != 0]) | {0}
        assert (obs["edge_padding_mask"][0] == (edges == 0)).all()
        assert (obs["edge_mask"][n:] == 1).all() and (obs["edge_mask"][:, n:] == 1).all()
        # Neighbours by distance, the nearest first.
        d = np.hypot(*(nodes[edges[edges != 0], :2] - nodes[0, :2]).T)
        assert (np.diff(d) >= -1e-6).all()
        mask = env.action_masks()
        obs, _, term, trunc, info = env.step(int(np.flatnonzero(mask)[-1]))
        if term or trunc:
            break


def test_a_graph_policy_explores_a_building():
    from test_serve import GRAPH
    namespace = {}
    exec(GRAPH, namespace)
    env = floorcast.ExploreEnv(buildings=SMALL, **namespace["FLOORCAST_OBSERVATION"])
    _, _, info = run_episode(env, namespace["policy"], 1)
    assert info["end_reason"] == "complete" and info["explored_fraction"] > 0.99
