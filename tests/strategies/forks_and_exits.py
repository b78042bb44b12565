#!/usr/bin/env python3
"""Test strategy: starts a child that keeps its stdout open (sleeping 30 s) and exits with status
5 at once, without answering the hello message: floorcast reports that exit and the stdout held
open, not a timeout."""
import os
import sys
import time

if os.fork() == 0:
    time.sleep(30)
    os._exit(0)
sys.stderr.write("leaving a child behind\n")
sys.stderr.flush()
sys.exit(5)
