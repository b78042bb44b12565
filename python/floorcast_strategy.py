"""Write a floorcast exploration strategy in Python (protocol 2, or 1 with an older floorcast;
standard library only).

floorcast starts the strategy program once per run and talks to it in JSON lines over its
stdin and stdout (the protocol: docs/strategy-protocol.md). This module does the talking;
a strategy only decides:

    from floorcast_strategy import Strategy, run  # floorcast puts it on PYTHONPATH

    class Nearest(Strategy):
        name = "nearest"
        needs = ()  # or ("layout_gain", "layout", "map"); see also needs_for(params)

        def decide(self, d):
            if d["time_s"] > 3600:
                return None  # stop exploring
            best = min(d["candidates"], key=lambda c: (c["path_m"], c["id"]))
            return best["id"]  # or a list of ids (try them in this order), or goal(x, y)

    run(Nearest())

stdout carries the protocol: never print to it (print() included). Log to stderr
(`print(..., file=sys.stderr)`); the last stderr line is shown when the strategy crashes.
"""

import json
import math
import operator
import sys
import unicodedata

PROTOCOL = 2

_NEEDS = ("layout_gain", "layout", "map")


class Strategy:
    """Subclass it and override `decide` (and `name`, `needs`, `needs_for`, `new_run`,
    `end_run`)."""

    #: Shown in floorcast's results: non-empty, at most 100 characters, no control characters.
    name = "unnamed"
    #: What floorcast should compute and send besides the baseline: "layout_gain" (the
    #: candidates' `layout_gain_m2`), "layout" (the predicted rooms, `layout`, when new, and
    #: the candidates' `room`), "map" (the decide messages' `map_changes`).
    needs = ()
    #: The strategy's own parameters for the current run (the run message's `params`: a
    #: grid's `params` table, or `explore --strategy-params`); set before `new_run`.
    params = {}

    def needs_for(self, params):
        """The run's needs once its `params` are known (protocol 2: sent in the ready reply,
        replacing `needs`), e.g. ("layout",) only when a parameter asks for rooms. By default
        `needs`."""
        return self.needs

    def new_run(self, run):
        """The run message (building, seed, start, settings, params, map geometry)."""
        self.run = run

    def decide(self, d):
        """The decide message -> a candidate id (go there), a list of ids (try them in this
        order, take the first with a drivable path), goal(x, y) (go to a point of your own),
        drop(ids) (give those candidates up and be asked again without them) or None (stop
        exploring now)."""
        raise NotImplementedError("a Strategy must override decide()")

    def end_run(self, end):
        """The end message (reason, exploration_time_s, explored_fraction, decisions)."""


class goal(tuple):
    """A point of the strategy's own to drive to, `goal(x, y)` in metres in the map frame, as
    `decide`'s return value. When no drivable path leads there, `decide` is called again for
    the same decision with the point in the message's `unreachable_goal`."""

    def __new__(cls, x, y):
        x, y = float(x), float(y)
        if not (_finite(x) and _finite(y)):
            raise ValueError("goal(%r, %r): a goal point's coordinates must be finite" % (x, y))
        return super().__new__(cls, (x, y))


class drop(tuple):
    """Candidates to give up for the rest of the run, `drop([3, 5])`, as `decide`'s return
    value: floorcast blacklists their frontiers and calls `decide` again for the same decision
    without them."""

    def __new__(cls, ids):
        return super().__new__(cls, ids)


def _fmax(a, b):
    # f64::max: a NaN operand yields the other one; of 0.0 and -0.0, 0.0 (as floorcast's
    # build computes it; Rust leaves it unspecified, and no choice depends on it).
    if a != a:
        return b
    if b != b:
        return a
    if a == b:
        return a if math.copysign(1.0, a) > 0 else b
    return b if b > a else a


def _finite(x):
    return isinstance(x, (int, float)) and not isinstance(x, bool) and x - x == 0


def _num(x):
    # A JSON number as a float; anything else (null, missing) as NaN, i.e. not finite.
    if isinstance(x, (int, float)) and not isinstance(x, bool):
        return float(x)
    return float("nan")


def paper_utilities(candidates, alpha, gain_floor_m2=0.0, distance="distance_m", gain="gain_m2"):
    """The paper's utility u(p) = alpha * d(p) + (1 - alpha) * i(p) of each candidate, in list
    order, computed exactly as floorcast's built-in strategies do (same float operations in the
    same order, so the same bits): d(p) = (Dmax - D(p)) / Dmax, i(p) = I(p) / Imax, maxima
    over the candidates with a valid distance; each gain raised to at least `gain_floor_m2`
    first when that is > 0. `distance` and `gain` name the candidate fields used for D(p) and
    I(p). A candidate whose distance is missing, null, negative or not finite gets None; a
    missing, null or non-finite gain counts as 0 and a negative one as 0.
    """
    alpha = float(alpha) if _finite(alpha) else 0.5
    if alpha < 0.0:
        alpha = 0.0
    if alpha > 1.0:
        alpha = 1.0
    floor = _num(gain_floor_m2)

    def valid(c):
        d = c.get(distance)
        if _finite(d) and d >= 0.0:
            return float(d)
        return None

    def gain_of(c):
        g = _num(c.get(gain))
        if floor > 0.0:
            g = _fmax(g, floor)
        return _fmax(g, 0.0) if _finite(g) else 0.0

    dists = [valid(c) for c in candidates]
    d_max = 0.0
    i_max = 0.0
    for c, d in zip(candidates, dists):
        if d is not None:
            d_max = _fmax(d_max, d)
            i_max = _fmax(i_max, gain_of(c))
    out = []
    for c, d in zip(candidates, dists):
        if d is None:
            out.append(None)
            continue
        dp = (d_max - d) / d_max if d_max > 0.0 else 1.0
        ip = gain_of(c) / i_max if i_max > 0.0 else 0.0
        out.append(alpha * dp + (1.0 - alpha) * ip)
    return out


def best_by_paper_utility(d, run, gain="gain_m2"):
    """The id of the candidate of highest paper utility (ties to the first in list order), with
    the run's `alpha` and `gain_floor_m2` and the candidates' `distance_m`: the built-in
    `baseline`'s choice. None if no candidate has a utility."""
    settings = run["settings"]
    cands = d["candidates"]
    utils = paper_utilities(
        cands, settings.get("alpha"), settings.get("gain_floor_m2", 0.0), "distance_m", gain
    )
    best = None
    for c, u in zip(cands, utils):
        if u is not None and (best is None or u > best[1]):
            best = (c["id"], u)
    return None if best is None else best[0]


def _as_id(x, ids):
    if isinstance(x, bool):
        raise TypeError("decide() returned %r: a candidate id is an integer" % (x,))
    try:
        i = operator.index(x)
    except TypeError:
        raise TypeError(
            "decide() returned %r: expected a candidate id (int), a list of ids, goal(x, y), "
            "drop(ids) or None" % (x,)
        ) from None
    if i not in ids:
        raise ValueError("decide() returned id %d, not a candidate of this decide message" % i)
    return i


def _id_list(result, ids, what):
    listed = [_as_id(x, ids) for x in result]
    if not listed:
        raise ValueError("decide() returned %s without ids (return None to stop)" % what)
    if len(set(listed)) != len(listed):
        raise ValueError("decide() returned %s with a repeated id: %r" % (what, listed))
    return listed


def _reply_to_decide(result, d):
    ids = {c["id"] for c in d["candidates"]}
    if result is None:
        return {"type": "stop"}
    if isinstance(result, goal):
        return {"type": "goal", "point": [result[0], result[1]]}
    if isinstance(result, drop):
        return {"type": "drop", "ids": _id_list(result, ids, "a drop")}
    if isinstance(result, (list, tuple)):
        return {"type": "rank", "ids": _id_list(result, ids, "a ranking")}
    return {"type": "choose", "id": _as_id(result, ids)}


def _check_needs(needs, where):
    if isinstance(needs, str):
        raise ValueError("%s must be a tuple of strings, e.g. (%r,)" % (where, needs))
    needs = list(needs)
    for n in needs:
        if n not in _NEEDS:
            raise ValueError("unknown need %r in %s (known: %s)" % (n, where, ", ".join(_NEEDS)))
    return needs


def _check_hello(strategy, protocol):
    name = strategy.name
    if not isinstance(name, str) or not name.strip() or len(name) > 100:
        raise ValueError("Strategy.name must be a non-empty string of at most 100 characters")
    if any(unicodedata.category(ch) == "Cc" for ch in name):
        raise ValueError("Strategy.name must not contain control characters")
    needs = _check_needs(strategy.needs, "Strategy.needs")
    return {"type": "hello", "protocol": protocol, "name": name, "needs": needs}


def run(strategy):
    """Serve one floorcast run on stdin/stdout until stdin ends. Exceptions raised by the
    strategy propagate (the process exits non-zero; floorcast reports the last stderr line)."""
    inp = sys.stdin.buffer
    out = sys.__stdout__

    def send(obj):
        # Whatever the strategy printed goes out first (and fails the run, as it should).
        out.flush()
        line = json.dumps(obj, separators=(",", ":"), allow_nan=False) + "\n"
        out.buffer.write(line.encode("ascii"))
        out.buffer.flush()

    # The version spoken: this module's, or an older floorcast's.
    protocol = PROTOCOL
    while True:
        raw = inp.readline()
        if not raw:
            return
        text = raw.decode("utf-8").strip()
        if not text:
            continue
        msg = json.loads(text)
        kind = msg.get("type") if isinstance(msg, dict) else None
        if kind == "hello":
            theirs = msg.get("protocol")
            if theirs == 1:
                protocol = 1
            elif theirs != PROTOCOL:
                sys.stderr.write(
                    "floorcast_strategy: floorcast speaks protocol %r, this module %d\n"
                    % (theirs, PROTOCOL)
                )
                sys.stderr.flush()
            send(_check_hello(strategy, protocol))
        elif kind == "run":
            params = msg.get("params")
            strategy.params = params if isinstance(params, dict) else {}
            strategy.new_run(msg)
            ready = {"type": "ready"}
            if protocol >= 2:
                ready["needs"] = _check_needs(strategy.needs_for(strategy.params), "needs_for()")
            send(ready)
        elif kind == "decide":
            send(_reply_to_decide(strategy.decide(msg), msg))
        elif kind == "end":
            strategy.end_run(msg)
        # Any other type: a later protocol's message this strategy does not know; ignored.
