"""What the tests of our bags share: the binary, the run folders they read,
and the reader of a run's CSV files.

The run folders come from SURVEYOR_EXPLORE_RUN and SURVEYOR_FOLLOW_RUN (CI
passes the README's explore run and its follow run); without them they are
made once per session with SURVEYOR_BIN (default target/release/surveyor).
The test files import the helpers (`from conftest import ...`: pytest puts
this folder on the path, it is no package).
"""

import csv
import os
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[4]
BINARY = os.environ.get("SURVEYOR_BIN", str(ROOT / "target/release/surveyor"))


def made(tmp_path_factory, env, name, args):
    given = os.environ.get(env)
    if given:
        return Path(given)
    out = tmp_path_factory.mktemp(name) / name
    subprocess.run([BINARY, *args, "--out", str(out), "--no-timings"], check=True,
                   stdout=subprocess.DEVNULL)
    return out


@pytest.fixture(scope="session")
def run_dir(tmp_path_factory):
    return made(tmp_path_factory, "SURVEYOR_EXPLORE_RUN", "bridge1",
                ["explore", "--scenario", "bridge1"])


@pytest.fixture(scope="session")
def follow_dir(tmp_path_factory):
    return made(tmp_path_factory, "SURVEYOR_FOLLOW_RUN", "block1",
                ["follow", "--scenario", "block1", "--robot", "arm4"])


def read_rows(path):
    with open(path) as f:
        return list(csv.DictReader(f))
