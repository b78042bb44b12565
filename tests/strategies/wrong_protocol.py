#!/usr/bin/env python3
"""Test strategy: claims protocol version 99 in its hello reply."""
import json
import sys

for line in sys.stdin:
    msg = json.loads(line)
    if msg["type"] == "hello":
        sys.stdout.write(json.dumps({"type": "hello", "protocol": 99, "name": "future"}) + "\n")
        sys.stdout.flush()
