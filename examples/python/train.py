#!/usr/bin/env python3
"""Trains the linear policy of policy.py (numpy only) in floorcast's vector environment.

The policy scores each frontier candidate by a weighted sum of six normalised features
(policy.FEATURE_NAMES) and drives to the best. The weights are found by the cross-entropy
method: each iteration draws a population of weight vectors around the current mean (the mean
itself is member 0), runs each, deterministically (argmax), once on every training building
(the same buildings and seeds for every member: a paired comparison), and moves the mean to the
best few. An episode's return is floorcast's default reward: 100 x the explored fraction -
0.1 per simulated second + 10 if complete, so faster exploration scores more.

Training buildings: small real floor plans of maps/plans/ from the fixed train split
(`split="train"`; the test split's plans are held out for grid.toml). Deterministic given
--seed (floorcast's results do not depend on the threads).

    python3 examples/python/train.py                 # about 5 minutes on 2 cores
    python3 examples/python/train.py --quick         # a few seconds (a smoke test)

Run it from the repository's root (the plans' paths are relative to it), or give --maps.
"""

import argparse
import os
import sys
import tempfile
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
from policy import FEATURE_NAMES, FLOORCAST_OBSERVATION, features  # noqa: E402

import floorcast  # noqa: E402

#: Small real plans of the train split (330-1020 m²; each a second or less to explore).
TRAIN_PLANS = (
    "Lamuniere1_updated",
    "chewlane",
    "Franch1_updated",
    "Sabadell3_updated",
    "Liselotte1_updated",
    "Milano-1",
)
QUICK_PLANS = ("Lamuniere1_updated", "chewlane")


def rollout(env, weights, seed):
    """Runs member j's weights on envs j*L .. j*L+L-1 (L = buildings) until each has ended one
    episode: (returns, exploration times, explored fractions), each of shape (members, L), and
    the buildings of member 0's episodes."""
    n, members = env.num_envs, len(weights)
    per = n // members
    w_env = np.repeat(weights, per, axis=0)  # (n, F)
    obs, infos = env.reset(seed=seed)
    returns = np.zeros(n)
    times = np.zeros(n)
    fractions = np.zeros(n)
    done = np.zeros(n, dtype=bool)
    buildings = [None] * n
    while not done.all():
        scores = np.einsum("nkf,nf->nk", features(obs["candidates"]), w_env)
        actions = np.argmax(np.where(obs["mask"] > 0, scores, -np.inf), axis=1)
        obs, rewards, terminated, truncated, infos = env.step(actions)
        returns += np.where(done, 0.0, rewards)
        ended = (terminated | truncated) & ~done
        for i in np.flatnonzero(ended):
            s = infos["summary"][i]
            times[i] = s["exploration_time_s"]
            fractions[i] = s["explored_fraction"]
            buildings[i] = s["building"]
        done |= ended
    shape = (members, per)
    return returns.reshape(shape), times.reshape(shape), fractions.reshape(shape), buildings[:per]


def unit(w):
    return w / np.linalg.norm(w, axis=-1, keepdims=True)


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--seed", type=int, default=1, help="the training seed (default 1)")
    p.add_argument("--iterations", type=int, help="CEM iterations (default 10; --quick: 2)")
    p.add_argument("--population", type=int, help="members per iteration, the mean included (default 8; --quick: 4)")
    p.add_argument("--elites", type=int, help="members the mean moves to (default 3; --quick: 2)")
    p.add_argument("--out", help="the weights file (default examples/python/linear_policy.npz; --quick: a file in the temporary directory)")
    p.add_argument("--maps", default="maps/plans", help="the directory of the plans (default maps/plans, from the repository's root)")
    p.add_argument("--threads", type=int, default=2, help="Rust threads stepping the environments (default 2)")
    p.add_argument("--time-limit-s", type=float, default=1500.0, help="simulated time limit of a training run (default 1500 s, 2-5 x a good policy's)")
    p.add_argument("--localization", default="ground-truth", help="floorcast's localization setting while training (default ground-truth, for speed)")
    p.add_argument("--quick", action="store_true", help="a tiny run (2 plans, 2 iterations of 4 members): a smoke test")
    a = p.parse_args(argv)
    plans = QUICK_PLANS if a.quick else TRAIN_PLANS
    iterations = a.iterations if a.iterations is not None else (2 if a.quick else 10)
    population = a.population if a.population is not None else (4 if a.quick else 8)
    elites = a.elites if a.elites is not None else (2 if a.quick else 3)
    if a.out:
        out = a.out
    elif a.quick:
        out = os.path.join(tempfile.gettempdir(), "floorcast_quick_policy.npz")
    else:
        out = os.path.join(HERE, "linear_policy.npz")
    if not 1 <= elites < population:
        p.error("--elites: from 1 to --population - 1")

    files = [os.path.join(a.maps, name + ".xml") for name in plans]
    settings = {"localization": a.localization, "time_limit_s": a.time_limit_s}
    start = time.time()
    env = floorcast.VectorExplore(
        population * len(files),
        a.threads,
        buildings=files,
        split="train",
        settings=settings,
        reward="default",
        **FLOORCAST_OBSERVATION,
    )
    if len(env.building_names) != len(files):
        sys.exit(f"train.py: some of {plans} are not in the train split: {env.building_names}")
    print(f"training on {len(files)} plans of the train split: {', '.join(env.building_names)}")
    print(f"features: {', '.join(FEATURE_NAMES)}")
    print(f"CEM: {iterations} iterations of {population} members (the mean first), {elites} elites, "
          f"{population * len(files)} episodes each; settings {settings}")

    rng = np.random.default_rng(a.seed)
    dim = len(FEATURE_NAMES)
    mean = unit(rng.normal(size=dim))  # a random start: the policy knows nothing
    sigma = np.full(dim, 0.5)
    print(f"{'iter':>4} {'return':>8} {'time_s':>7} {'mean-policy return':>18} {'time_s':>7} "
          f"{'best':>8} {'sigma':>6} {'wall_s':>6}")
    for it in range(iterations + 1):
        last = it == iterations
        if last:  # the final mean, once more on the same plans (new seeds)
            members = mean[None, :]
        else:
            members = np.vstack([mean, unit(mean + sigma * rng.normal(size=(population - 1, dim)))])
        seed = a.seed * 1_000_003 + it * 10_007
        if last:
            env_last = floorcast.VectorExplore(len(files), a.threads, buildings=files, split="train",
                                               settings=settings, **FLOORCAST_OBSERVATION)
            returns, times, fractions, names = rollout(env_last, members, seed)
        else:
            returns, times, fractions, names = rollout(env, members, seed)
        fitness = returns.mean(axis=1)
        if last:
            print(f"final mean policy on the training plans: return {fitness[0]:.1f}, "
                  f"exploration time {times.mean():.0f} s, explored {100 * fractions.mean():.1f} %, "
                  f"per plan: {', '.join(f'{b} {t:.0f} s' for b, t in zip(names, times[0]))}")
            break
        print(f"{it:>4} {fitness.mean():>8.1f} {times.mean():>7.0f} {fitness[0]:>18.1f} {times[0].mean():>7.0f} "
              f"{fitness.max():>8.1f} {sigma.mean():>6.3f} {time.time() - start:>6.0f}", flush=True)
        order = np.argsort(-fitness, kind="stable")  # ties: the lower member
        best = members[order[:elites]]
        mean = unit(best.mean(axis=0))
        sigma = np.maximum(0.6 * sigma + 0.4 * best.std(axis=0), 0.05)

    np.savez(out, weights=mean, features=np.array(FEATURE_NAMES),
             seed=a.seed, iterations=iterations, population=population,
             plans=np.array(env.building_names), settings=str(settings))
    print(f"weights: {np.array2string(mean, precision=3)} ({', '.join(FEATURE_NAMES)})")
    print(f"wrote {out} in {time.time() - start:.0f} s")


if __name__ == "__main__":
    main()
