#!/usr/bin/env python3
"""Test strategy: nearest frontier first speaking protocol version 1 directly (no floorcast
module), as docs/strategy-protocol.md's example did before version 2: floorcast still speaks
it."""
import json
import sys


def send(obj):
    sys.stdout.write(json.dumps(obj) + "\n")
    sys.stdout.flush()


for line in sys.stdin:
    msg = json.loads(line)
    kind = msg.get("type")
    if kind == "hello":
        send({"type": "hello", "protocol": 1, "name": "nearest-plain-v1", "needs": ["layout"]})
    elif kind == "run":
        # Needs in a ready reply are protocol 2's (v1_ready_needs.py is refused for them).
        send({"type": "ready", "x": 1})
    elif kind == "decide":
        assert "map_changes" not in msg, "protocol 1: no map without the need"
        assert "robot_room" not in msg, "protocol 1: no robot_room"
        assert all("room" in c for c in msg["candidates"]), "the hello's need layout holds"
        best = min(msg["candidates"], key=lambda c: (c["path_m"], c["id"]))
        send({"type": "choose", "id": best["id"]})
