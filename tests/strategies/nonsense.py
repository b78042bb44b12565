#!/usr/bin/env python3
"""Test strategy: shakes hands, gets ready, answers the first decide message with a line that
is not JSON, or with the line given as its argument."""
import json
import sys


def send(text):
    sys.stdout.write(text + "\n")
    sys.stdout.flush()


for line in sys.stdin:
    msg = json.loads(line)
    if msg["type"] == "hello":
        send(json.dumps({"type": "hello", "protocol": 1, "name": "nonsense"}))
    elif msg["type"] == "run":
        send(json.dumps({"type": "ready"}))
    elif msg["type"] == "decide":
        send(sys.argv[1] if len(sys.argv) > 1 else "this is not json")
