"""Hostile inputs for every command: a fixed corpus of malformed and extreme runs,
files and flags, hypothesis strategies drawing more, and a forking runner that
runs each case under a time bound and judges its exit code, stderr and JSON."""
