"""What the process server of :mod:`dgraph.sweep.isolation` imports once before it forks a process
for each run: dgraph and every entity plugin of the registry (so a run starts without importing
the robotics libraries again)."""

from dgraph.registry import load_plugins

load_plugins()
