"""A policy run as a strategy (`python3 -m floorcast.serve`) makes the decisions it makes in
the environment: in `floorcast explore` and in a grid."""

import csv
import json
import subprocess
import sys
import textwrap

import numpy as np
import pytest

import floorcast
from conftest import REPO, explore, floorcast_bin, run_episode, same_run

SMALL = str(REPO / "buildings" / "small.toml")
PAPER = str(REPO / "buildings" / "paper" / "paper-05.toml")

# A policy unlike any built-in strategy: a linear score of the features (with the layout's
# gain), ties to the lowest index; and a map policy that drives to points of its own.
LINEAR = textwrap.dedent("""
    import numpy as np
    FLOORCAST_OBSERVATION = {"observation": "candidates", "max_candidates": 12, "needs": ["layout_gain"]}
    W = np.array([-1.0, 0.3, 0.05, 0.08, 0.0, 0.01, 0.2, -0.1, -0.5, 0.0], dtype=np.float32)
    def policy(obs):
        score = obs["candidates"] @ W
        return int(np.argmax(np.where(obs["mask"].astype(bool), score, -np.inf)))
""")
MAP = textwrap.dedent("""
    import numpy as np
    FLOORCAST_OBSERVATION = {"observation": "map", "map_size": 48, "map_frame": "global"}
    def policy(obs):
        # The frontier crop cell nearest to the robot but at least 3 cells from it, else the
        # farthest; the robot's own cell when there is none.
        ys, xs = np.nonzero(obs["map"][3])
        (ry,), (rx,) = np.nonzero(obs["map"][5])
        if len(xs) == 0:
            return np.array([(rx + 0.5) / 48, (ry + 0.5) / 48], dtype=np.float32)
        d = np.hypot(xs - rx, ys - ry)
        far = d >= 3
        k = int(np.argmin(np.where(far, d, np.inf))) if far.any() else int(np.argmax(d))
        return np.array([(xs[k] + 0.5) / 48, (ys[k] + 0.5) / 48], dtype=np.float32)
""")


GRAPH = textwrap.dedent("""
    import collections
    import numpy as np
    FLOORCAST_OBSERVATION = {"observation": "graph", "graph_nodes": 300, "graph_k": 16}
    def policy(obs):
        # Breadth first over the graph to the nearest node not visited that sees at least 5
        # frontier points (ARiADNE's utility floor); its first hop.
        n = int((obs["node_padding_mask"][0] == 0).sum())
        nodes, edges = obs["node_inputs"], obs["edge_inputs"][0]
        adjacent = obs["edge_mask"][:n, :n] == 0
        first, queue = {}, collections.deque()
        for i in np.flatnonzero(obs["edge_padding_mask"][0] == 0):
            j = int(edges[i])
            if j not in first:
                first[j] = int(i)
                queue.append(j)
        seen = set(first) | {0}
        while queue:
            u = queue.popleft()
            if nodes[u, 2] * 50 >= 5 and nodes[u, 3] == 0:
                return first[u]
            for v in map(int, np.flatnonzero(adjacent[u])):
                if v not in seen:
                    seen.add(v)
                    first[v] = first[u]
                    queue.append(v)
        return int(np.flatnonzero(obs["edge_padding_mask"][0] == 0)[0])
""")


def write_policy(tmp_path, text):
    path = tmp_path / "policy.py"
    path.write_text(text)
    namespace = {}
    exec(text, namespace)
    return path, namespace["policy"], namespace["FLOORCAST_OBSERVATION"]


@pytest.mark.parametrize("text,building,seed", [(LINEAR, SMALL, 3), (LINEAR, PAPER, 1), (MAP, SMALL, 2),
                                                (GRAPH, SMALL, 4)],
                         ids=["linear-small", "linear-paper", "map-small", "graph-small"])
def test_a_policy_makes_the_same_run_in_the_env_and_in_explore(tmp_path, text, building, seed):
    path, policy, fields = write_policy(tmp_path, text)
    env = floorcast.ExploreEnv(buildings=building, label="policy", **fields)
    _, _, info = run_episode(env, policy, seed)
    command = f"{sys.executable} -m floorcast.serve {path}:policy"
    summary, _ = explore(building, seed, tmp_path / "out", "--strategy-command", command)
    same_run(info["summary"], summary)
    assert summary["strategy"] == "policy"


def test_a_policy_makes_the_same_runs_in_a_grid(tmp_path):
    path, policy, fields = write_policy(tmp_path, LINEAR)
    grid = tmp_path / "grid.toml"
    grid.write_text(textwrap.dedent(f"""
        format = "floorcast-grid"
        version = 1
        name = "python-policy"
        buildings = ["{SMALL}"]
        seed_range = [1, 2]

        [[strategies]]
        label = "linear"
        command = ["{sys.executable}", "-m", "floorcast.serve", "policy.py"]
    """))
    results = tmp_path / "results"
    p = subprocess.run([floorcast_bin(), "run", str(grid), "--results", str(results), "--quiet"],
                       capture_output=True, text=True, cwd=REPO, timeout=900)
    assert p.returncode == 0, p.stderr
    table = tmp_path / "runs.csv"
    p = subprocess.run([floorcast_bin(), "report", str(results), "--csv", str(table)],
                       capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stderr
    rows = {int(r["seed"]): r for r in csv.DictReader(table.open())}
    assert sorted(rows) == [1, 2]
    env = floorcast.ExploreEnv(buildings=SMALL, **fields)
    for seed, row in rows.items():
        _, _, info = run_episode(env, policy, seed)
        s = info["summary"]
        assert float(row["exploration_time_s"]) == pytest.approx(s["exploration_time_s"], abs=1e-9)
        assert float(row["explored_area_m2"]) == pytest.approx(s["explored_area_m2"], abs=1e-9)
        assert row["end_reason"] == s["end_reason"]


def test_serve_refuses_a_bad_policy_with_a_clear_message(tmp_path):
    for target, words in [("nowhere.py:policy", "no such file"), ("json:nothing", "no callable"),
                          ("justaname", "expected FILE.py")]:
        p = subprocess.run([sys.executable, "-m", "floorcast.serve", target], input="",
                           capture_output=True, text=True, timeout=60)
        assert p.returncode != 0
        assert words in p.stderr, p.stderr


def test_the_observer_refuses_malformed_messages():
    obs = floorcast._native.Observer(json.dumps({"observation": "candidates"}))
    for bad in ["{", '{"map": 3}', '{"map": {"origin": [0, 0], "width": -1, "height": 2, "resolution_m": 0.05}}']:
        with pytest.raises(ValueError, match="run message"):
            obs.begin(bad)
    obs.begin(json.dumps({"map": {"origin": [0, 0], "width": 4, "height": 4, "resolution_m": 0.05}}))
    for bad in ['{"pose": [0, 0]}', '{"pose": [0, 0, 0], "time_s": 0}',
                '{"pose": [0, 0, 0], "time_s": 0, "candidates": [{"id": 0}]}',
                '{"pose": [0, 0, 0], "time_s": 0, "candidates": [], "map_changes": {"free": [99]}}']:
        with pytest.raises(ValueError, match="decide message|field"):
            obs.decide(bad)
    graph = floorcast._native.Observer(json.dumps({"observation": "graph"}))
    with pytest.raises(ValueError, match="settings.laser_range_m"):
        graph.begin(json.dumps({"map": {"origin": [0, 0], "width": 4, "height": 4, "resolution_m": 0.05}}))


@pytest.mark.parametrize("text", [LINEAR, MAP, GRAPH], ids=["candidates", "map", "graph"])
def test_serve_passes_floorcasts_protocol_checker(tmp_path, text):
    path, _, _ = write_policy(tmp_path, text)
    p = subprocess.run([floorcast_bin(), "strategy", "check", f"{sys.executable} -m floorcast.serve {path}"],
                       capture_output=True, text=True, timeout=600)
    assert p.returncode == 0, p.stdout + p.stderr
    assert "keeps to the strategy protocol version 2" in p.stdout + p.stderr
