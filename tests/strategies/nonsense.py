#!/usr/bin/env python3
"""Test strategy: shakes hands, gets ready, answers the first decide message with a line that
is not JSON."""
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
        send("this is not json")
