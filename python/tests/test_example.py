"""The example that learns (examples/python): its training runs, its committed policy makes the
same decisions as a strategy as in the environment, and its grid holds out the test split."""

import pathlib
import subprocess
import sys
import tomllib

import numpy as np

import floorcast
from conftest import REPO, explore, run_episode, same_run

EXAMPLE = REPO / "examples" / "python"


def test_quick_training_runs_and_writes_weights(tmp_path):
    out = tmp_path / "w.npz"
    p = subprocess.run([sys.executable, str(EXAMPLE / "train.py"), "--quick", "--out", str(out)],
                       cwd=REPO, capture_output=True, text=True, timeout=900)
    assert p.returncode == 0, p.stderr
    with np.load(out) as f:
        assert f["weights"].shape == (6,) and np.isfinite(f["weights"]).all()


def test_the_committed_policy_makes_the_same_run_in_the_env_and_as_a_strategy(tmp_path):
    sys.path.insert(0, str(EXAMPLE))
    try:
        import policy
    finally:
        sys.path.remove(str(EXAMPLE))
    building = REPO / "maps" / "plans" / "scuola_secondaria_i_grado_mera__updated.xml"
    env = floorcast.ExploreEnv(buildings=str(building), label="policy", **policy.FLOORCAST_OBSERVATION)
    _, _, info = run_episode(env, policy.policy, 3)
    command = f"{sys.executable} -m floorcast.serve {EXAMPLE / 'policy.py'}"
    summary, _ = explore(building, 3, tmp_path / "out", "--strategy-command", command)
    same_run(info["summary"], summary)


def test_the_example_grid_holds_out_exactly_the_test_split():
    grid = tomllib.loads((EXAMPLE / "grid.toml").read_text())
    files = [(EXAMPLE / b).resolve() for b in grid["buildings"]]
    assert all(f.is_file() for f in files)
    test = floorcast.ExploreEnv(buildings=str(REPO / "maps" / "plans" / "*.xml"), split="test").building_names
    assert sorted(f.stem for f in files) == sorted(test)
    labels = {s.get("label", s.get("name")) for s in grid["strategies"]}
    assert {"random-frontier", "linear-policy"} <= labels
    assert grid["sequential"]["reference"] == "random-frontier"
