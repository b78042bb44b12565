#!/usr/bin/env python3
"""Test strategy: crashes at start-up, before reading anything (exit status 3)."""
import sys

sys.stderr.write("something went wrong\n")
sys.stderr.flush()
sys.exit(3)
