#!/usr/bin/env python3
"""Test strategy: shakes hands, gets ready, then never answers the first decide message."""
import json
import sys
import time


def send(obj):
    sys.stdout.write(json.dumps(obj) + "\n")
    sys.stdout.flush()


for line in sys.stdin:
    msg = json.loads(line)
    if msg["type"] == "hello":
        send({"type": "hello", "protocol": 1, "name": "hang"})
    elif msg["type"] == "run":
        send({"type": "ready"})
    elif msg["type"] == "decide":
        while True:
            time.sleep(60)
