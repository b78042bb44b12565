#!/usr/bin/env python3
"""Test strategy: speaks protocol version 1 but lists needs in its ready reply, which version 2
added: floorcast refuses it (ignored, the run would go without the map it asks for)."""
import json
import sys


def send(obj):
    sys.stdout.write(json.dumps(obj) + "\n")
    sys.stdout.flush()


for line in sys.stdin:
    msg = json.loads(line)
    kind = msg.get("type")
    if kind == "hello":
        send({"type": "hello", "protocol": 1, "name": "v1-ready-needs"})
    elif kind == "run":
        send({"type": "ready", "needs": ["map"]})
    elif kind == "decide":
        best = min(msg["candidates"], key=lambda c: (c["path_m"], c["id"]))
        send({"type": "choose", "id": best["id"]})
