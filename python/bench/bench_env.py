"""Throughput of the Python environment (a benchmark, not a test): decision steps, explored area
and robot travel per CPU second of the single and vector environments, beside the same runs made
by `floorcast explore` (the binding's overhead as a ratio).

    python3 python/bench/bench_env.py            # about 3 minutes on 2 cores
    python3 python/bench/bench_env.py --quick    # one seed, a smaller plan

One step of this environment is one decision of the robot: where to drive next, then the
simulation (motion, laser, SLAM, mapping, frontiers, planning) until the next decision. The
policy here is the nearest candidate (numpy), so the runs are `floorcast explore --strategy
nearest`'s and the two can be compared run for run.

Run it on a quiet machine: the figures are CPU seconds of this process (and of `explore` as it
reports its own run's wall time, single-threaded), the vector figures wall seconds.
"""

import argparse
import json
import os
import pathlib
import subprocess
import sys
import tempfile
import time

import numpy as np

import floorcast

REPO = pathlib.Path(__file__).resolve().parents[2]
PLAN = "maps/plans/130604_Floor_Plan_with_Furniture_small.xml"  # 2124 m² of offices
SMALL_PLAN = "maps/plans/324-Elm-Furn-Plan.xml"  # 1308 m²


def nearest(obs):
    m = obs["mask"] == 1
    return np.argmin(np.where(m, obs["candidates"][..., 0], np.inf), axis=-1)


def env_runs(building, settings, seeds):
    """The single environment's runs: steps, CPU s, wall s, explored m², travel m, summaries."""
    env = floorcast.ExploreEnv(buildings=str(REPO / building), settings=settings)
    steps = 0
    cpu0, wall0 = time.process_time(), time.perf_counter()
    summaries = []
    for seed in seeds:
        obs, info = env.reset(seed=seed)
        while True:
            obs, r, term, trunc, info = env.step(int(nearest(obs)))
            steps += 1
            if term or trunc:
                summaries.append(info["summary"])
                break
    cpu, wall = time.process_time() - cpu0, time.perf_counter() - wall0
    return steps, cpu, wall, summaries


def explore_runs(building, settings, seeds, floorcast_bin):
    """`floorcast explore --strategy nearest` of the same runs: their summaries (each with the
    run's own wall time, `wall_time_s`: the simulation alone, no start-up or output)."""
    out = []
    with tempfile.TemporaryDirectory() as d:
        settings_file = pathlib.Path(d) / "settings.json"
        settings_file.write_text(json.dumps(settings))
        for seed in seeds:
            o = pathlib.Path(d) / f"run-{seed}"
            subprocess.run([floorcast_bin, "explore", "--building", str(REPO / building), "--strategy", "nearest",
                            "--seed", str(seed), "--settings", str(settings_file), "--out", str(o), "--quiet"],
                           check=True, capture_output=True)
            out.append(json.loads((o / "summary.json").read_text()))
    return out


def vector_rate(building, settings, num_envs, threads, steps):
    """Decision steps per wall second of the vector environment (next-step autoreset)."""
    vec = floorcast.VectorExplore(num_envs, threads=threads, buildings=str(REPO / building), settings=settings)
    obs, _ = vec.reset(seed=0)
    t0 = time.perf_counter()
    for _ in range(steps):
        obs, *_ = vec.step(nearest(obs))
    return num_envs * steps / (time.perf_counter() - t0)


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--quick", action="store_true", help="one seed on a smaller plan, fewer vector steps")
    p.add_argument("--seeds", type=int, default=3, help="runs per localization (default 3)")
    target = os.environ.get("CARGO_TARGET_DIR") or str(REPO / "target")
    p.add_argument("--floorcast", default=os.path.join(target, "release", "floorcast"),
                   help="the floorcast binary to compare with (default: this clone's release build)")
    a = p.parse_args()
    if not os.path.isfile(a.floorcast):
        sys.exit(f"bench_env: no floorcast binary at {a.floorcast}: run `cargo build --release` first (or give --floorcast)")
    building = SMALL_PLAN if a.quick else PLAN
    seeds = list(range(1, 2 if a.quick else a.seeds + 1))
    print(f"floorcast {floorcast.__version__}, {building}, seeds {seeds}, policy: the nearest candidate")
    print("one step = one decision (where to drive next, then the simulation to the next decision)\n")
    header = f"{'localization':<13}{'steps/CPU s':>12}{'m² expl./CPU s':>16}{'m travel/CPU s':>16}{'explore (same runs)':>21}{'overhead':>10}"
    print(header)
    for loc in ("slam", "ground-truth"):
        settings = {"localization": loc}
        # Seed by seed, the environment's run then explore's, so that the machine's drift falls
        # on both alike.
        steps, cpu, envs, runs = 0, 0.0, [], []
        for seed in seeds:
            n, c, _, e = env_runs(building, settings, [seed])
            steps, cpu, envs = steps + n, cpu + c, envs + e
            runs += explore_runs(building, settings, [seed], a.floorcast)
        for e, x in zip(envs, runs):
            for k in ("decisions", "exploration_time_s", "explored_area_m2", "path_length_m"):
                assert e[k] == x[k], f"the environment's run differs from explore's in {k}: {e[k]} != {x[k]}"
        area = sum(s["explored_area_m2"] for s in envs)
        travel = sum(s["path_length_m"] for s in envs)
        explore_s = sum(s["wall_time_s"] for s in runs)
        print(f"{loc:<13}{steps / cpu:>12.0f}{area / cpu:>16.0f}{travel / cpu:>16.0f}"
              f"{f'{explore_s:.2f} s vs {cpu:.2f} s':>21}{cpu / explore_s:>9.2f}x")
    print("\n(overhead: CPU seconds of the environment's episodes, policy included, over explore's own run time)")
    print("the environments researchers use today, one core of this machine (measured once, 2026, quoted in issue 80):")
    print("  HouseExpo's gym env: 300 steps/s (one step = a 1 m move or a 30° turn), 100 m travel and 70 m² explored per CPU s")
    print("  ARiADNE: 3.4 steps/s (one step = a move to a neighbouring graph node); Explore-Bench's grid env: 0.8 steps/s,")
    print("  7 m and 10 m² per s (one step = a trip to a frontier). Goals here: >= 700 m² and >= 500 m per CPU s with SLAM,")
    print("  >= 100 decisions per CPU s on a 2000 m² plan.")
    n_steps = 20 if a.quick else 60
    one = vector_rate(building, {"localization": "slam"}, 8, 1, n_steps)
    two = vector_rate(building, {"localization": "slam"}, 8, 2, n_steps)
    print(f"\nvector environment, 8 environments, SLAM, {n_steps} steps each (one step = one decision of every environment):")
    print(f"  1 thread : {one:7.1f} decisions per wall second")
    print(f"  2 threads: {two:7.1f} decisions per wall second ({two / one:.2f}x; {os.cpu_count()} CPUs)")


if __name__ == "__main__":
    main()
