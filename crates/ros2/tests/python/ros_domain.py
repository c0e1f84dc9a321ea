"""A random ROS domain for a test's processes, from a range of its own per
pytest-xdist worker and never one this process picked before: tests
running side by side, or a module's robot still serving while another test
starts one, never share a domain (a run would hear the other's robot)."""

import os
import random

LOW, HIGH = 10, 230  # Cyclone DDS takes 0 to 232
_taken = set()


def pick():
    """A domain id of this worker's range that this process has not used."""
    worker = os.environ.get("PYTEST_XDIST_WORKER", "gw0")
    k = int(worker[2:]) if worker[2:].isdigit() else 0
    count = max(1, int(os.environ.get("PYTEST_XDIST_WORKER_COUNT", "1")))
    size = (HIGH - LOW) // count
    lo = LOW + size * (k % count)
    free = [d for d in range(lo, lo + size) if d not in _taken]
    domain = random.choice(free)
    _taken.add(domain)
    return domain
