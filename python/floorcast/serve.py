"""Run a policy as a floorcast strategy (protocol 2), in ``floorcast explore``, grids,
sequential tests and the leaderboard, making the decisions it makes in the environment:

    floorcast explore --building buildings/small.toml \\
        --strategy-command "python3 -m floorcast.serve examples/python/policy.py"

In a grid file::

    [[strategies]]
    label = "linear-policy"
    command = ["python3", "-m", "floorcast.serve", "policy.py"]
    files = ["linear_policy.npz"]

POLICY is ``FILE.py`` (its callable ``policy``, or ``--callable NAME``), ``FILE.py:NAME`` or
``MODULE:NAME`` (in a grid, give the file as a word of its own, ``policy.py``: floorcast
then hashes it into the runs' identity and sends it to remote workers). NAME is a callable ``policy(obs) -> action``,
given the observation the environment gives (numpy arrays) and answering as the
environment's action (a candidate index, or a point [column, row]; ``None`` stops the
exploration early). A module may set ``FLOORCAST_OBSERVATION``, a dict of `EnvSpec`'s
observation fields (``observation``, ``max_candidates``, ``needs``, ``map_size``,
``map_cell_m``, ``map_frame``, ``graph_*``), so that the policy sees what it was trained on; the options
below override it. If the callable has a method ``new_run(run)``, it is called with each run
message (building, seed, start, settings, params).

stdout carries the protocol; the policy must not print to it (``print`` goes to stderr
while the policy runs).
"""

from __future__ import annotations

import argparse
import contextlib
import importlib
import importlib.util
import json
import os
import sys

from . import _native
from ._env import arrays, parse_action
from ._spec import EnvSpec

PROTOCOL = 2


def load_policy(target: str, default_name: str = "policy"):
    """The callable ``FILE.py``, ``FILE.py:NAME`` or ``MODULE:NAME`` names (NAME by default
    `default_name`), its module and its name."""
    if target.endswith(".py"):
        where, name = target, default_name
    elif ":" in target:
        where, name = target.rsplit(":", 1)
    else:
        raise SystemExit(f"floorcast.serve: POLICY: {target!r}; expected FILE.py, FILE.py:NAME or MODULE:NAME")
    if where.endswith(".py"):
        if not os.path.isfile(where):
            raise SystemExit(f"floorcast.serve: POLICY: no such file: {where}")
        spec = importlib.util.spec_from_file_location(os.path.splitext(os.path.basename(where))[0], where)
        module = importlib.util.module_from_spec(spec)
        sys.path.insert(0, os.path.dirname(os.path.abspath(where)))
        spec.loader.exec_module(module)
    else:
        module = importlib.import_module(where)
    policy = getattr(module, name, None)
    if not callable(policy):
        raise SystemExit(f"floorcast.serve: POLICY: {where} has no callable {name!r}")
    return policy, module, name


def observation_spec(module, args) -> EnvSpec:
    """The observation fields: the module's ``FLOORCAST_OBSERVATION``, then the options."""
    fields = dict(getattr(module, "FLOORCAST_OBSERVATION", {}) or {})
    for key in ("observation", "max_candidates", "map_size", "map_cell_m", "map_frame", "graph_nodes", "graph_k",
                "graph_spacing_m", "graph_range_m"):
        v = getattr(args, key)
        if v is not None:
            fields[key] = v
    if args.needs is not None:
        fields["needs"] = [n for n in args.needs.split(",") if n]
    return EnvSpec(buildings="-", **fields)


def serve(policy, spec: EnvSpec, name: str, stdin, stdout) -> None:
    """The protocol session: hello, run, decisions, end."""
    observer = _native.Observer(spec.to_json())
    needs = list(spec.needs) + (["map"] if spec.observation in ("map", "graph") else [])

    def send(obj_or_line):
        line = obj_or_line if isinstance(obj_or_line, str) else json.dumps(obj_or_line)
        stdout.write(line + "\n")
        stdout.flush()

    for line in stdin:
        msg = json.loads(line)
        kind = msg.get("type")
        if kind == "hello":
            send({"type": "hello", "protocol": PROTOCOL, "name": name, "needs": needs})
        elif kind == "run":
            observer.begin(line)
            if hasattr(policy, "new_run"):
                with contextlib.redirect_stdout(sys.stderr):
                    policy.new_run(msg)
            send({"type": "ready"})
        elif kind == "decide":
            reply, obs = observer.decide(line)
            if reply is None:
                with contextlib.redirect_stdout(sys.stderr):
                    action = policy(arrays(obs))
                if action is None:
                    reply = json.dumps({"type": "stop"})
                else:
                    index, point = parse_action(spec, action)
                    reply = observer.reply(index, point)
            send(reply)
        elif kind == "end":
            pass


def main(argv=None) -> None:
    p = argparse.ArgumentParser(
        prog="python3 -m floorcast.serve",
        description="Run a policy (a Python callable) as a floorcast strategy over the strategy protocol.",
    )
    p.add_argument("policy", help="FILE.py (its callable `policy`, or --callable's), FILE.py:NAME or MODULE:NAME: a callable policy(obs) -> action")
    p.add_argument("--callable", dest="callable_name", default="policy", help="with a FILE.py alone: the callable's name (default: policy)")
    p.add_argument("--name", help="the strategy's name in results (default: the callable's name)")
    p.add_argument("--observation", choices=["candidates", "map", "graph"], help="as EnvSpec (default: the module's FLOORCAST_OBSERVATION, else candidates)")
    p.add_argument("--max-candidates", dest="max_candidates", type=int, help="candidates mode: K (1 to 4096, default 32)")
    p.add_argument("--needs", help="comma-separated: layout_gain, layout (default: none)")
    p.add_argument("--map-size", dest="map_size", type=int, help="map mode: the crop's side in cells (8 to 1024, default 64)")
    p.add_argument("--map-cell-m", dest="map_cell_m", type=float, help="map mode: a crop cell's side in m (default 0.5)")
    p.add_argument("--map-frame", dest="map_frame", choices=["egocentric", "global"], help="map mode (default egocentric)")
    p.add_argument("--graph-nodes", dest="graph_nodes", type=int, help="graph mode: N (2 to 4096, default 360)")
    p.add_argument("--graph-k", dest="graph_k", type=int, help="graph mode: K (2 to 64, default 20)")
    p.add_argument("--graph-spacing-m", dest="graph_spacing_m", type=float, help="graph mode: the lattice's spacing in m (default 1.5)")
    p.add_argument("--graph-range-m", dest="graph_range_m", type=float, help="graph mode: a node's sensing range in m (default: 7/8 of the laser's)")
    args = p.parse_args(argv)
    stdout = sys.stdout
    # Only the protocol goes to stdout: what the policy's module prints on import goes to stderr.
    with contextlib.redirect_stdout(sys.stderr):
        policy, module, callable_name = load_policy(args.policy, args.callable_name)
        try:
            spec = observation_spec(module, args)
        except ValueError as e:
            raise SystemExit(f"floorcast.serve: {e}") from None
    name = args.name or callable_name
    serve(policy, spec, name, sys.stdin, stdout)


if __name__ == "__main__":
    main()
