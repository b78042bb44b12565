#!/usr/bin/env python3
"""Test strategy: shakes hands, gets ready, chooses candidate 99999 (never offered) at every
decide message."""
import json
import sys


def send(obj):
    sys.stdout.write(json.dumps(obj) + "\n")
    sys.stdout.flush()


for line in sys.stdin:
    msg = json.loads(line)
    if msg["type"] == "hello":
        send({"type": "hello", "protocol": 1, "name": "illegal-id"})
    elif msg["type"] == "run":
        send({"type": "ready"})
    elif msg["type"] == "decide":
        send({"type": "choose", "id": 99999})
