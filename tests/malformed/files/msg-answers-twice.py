#!/usr/bin/env python3
"""Test strategy: answers decision 0 twice (the second answer unasked), then every decision once."""
import json
import sys


def send(text):
    sys.stdout.write(text)
    sys.stdout.flush()


for line in sys.stdin:
    msg = json.loads(line)
    if msg["type"] == "hello":
        send(json.dumps({"type": "hello", "protocol": 1, "name": "answers-twice"}) + "\n")
    elif msg["type"] == "run":
        send(json.dumps({"type": "ready"}) + "\n")
    elif msg["type"] == "decide":
        choice = json.dumps({"type": "choose", "id": msg["candidates"][0]["id"]}) + "\n"
        send(choice * 2 if msg["decision"] == 0 and msg["attempt"] == 0 else choice)
