"""A random ROS domain for a test's processes, from a range of its own per
pytest-xdist worker: tests running side by side never share a domain (a
run would hear the other's robot)."""

import os
import random

PER_WORKER = 100


def pick():
    """A domain id (Cyclone DDS takes 0 to 232)."""
    worker = os.environ.get("PYTEST_XDIST_WORKER", "gw0")
    k = int(worker[2:]) if worker[2:].isdigit() else 0
    lo = 10 + PER_WORKER * (k % 2)
    return random.randrange(lo, lo + PER_WORKER)
