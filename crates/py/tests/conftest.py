"""What the package's tests share: the repository, the surveyor CLI they
compare against (SURVEYOR_BIN, default <repo>/target/release/surveyor) and
a way to run it. The test files import the helpers (`from conftest import
...`: pytest puts this folder on the path, it is no package)."""

import os
import shutil
import signal
import subprocess
import tempfile
import time
import uuid
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[3]


@pytest.fixture(scope="session")
def surveyor_bin():
    path = Path(os.environ.get("SURVEYOR_BIN", REPO / "target" / "release" / "surveyor"))
    if not path.is_file():
        pytest.fail(
            f"the surveyor CLI is not at {path}: build it (cargo build --release) "
            "or point SURVEYOR_BIN at it"
        )
    return path


def run_cli(bin_path, *args):
    """Run the CLI; its standard output, or a failed assertion with its errors."""
    out = subprocess.run(
        [str(bin_path), *map(str, args)], capture_output=True, text=True, check=False
    )
    assert out.returncode == 0, f"surveyor {' '.join(map(str, args))}: {out.stderr}"
    return out.stdout


# ---------------------------------------------------------------------------
# A local Ray for the campaign and study tests

MARKER = "SURVEYOR_CAMPAIGN_TEST"


def marked_processes(tag):
    """Pids of the processes whose environment holds MARKER=tag (Ray's,
    started by these tests)."""
    needle = f"{MARKER}={tag}".encode()
    pids = []
    for entry in os.listdir("/proc"):
        if not entry.isdigit() or int(entry) == os.getpid():
            continue
        try:
            with open(f"/proc/{entry}/environ", "rb") as f:
                if needle in f.read().split(b"\0"):
                    pids.append(int(entry))
        except OSError:
            pass
    return pids


def stop_marked(tag, wait_s=15.0):
    """Wait for the marked processes to end; SIGKILL those that do not.
    Returns the pids that had to be killed."""
    deadline = time.monotonic() + wait_s
    while marked_processes(tag) and time.monotonic() < deadline:
        time.sleep(0.2)
    left = marked_processes(tag)
    for pid in left:
        try:
            os.kill(pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
    return left


@pytest.fixture(scope="module")
def ray_dir():
    """A short temporary folder for Ray (its socket paths must stay under
    107 bytes, which pytest's tmp_path can exceed)."""
    d = tempfile.mkdtemp(prefix="ray27-", dir="/tmp")
    yield Path(d)
    shutil.rmtree(d, ignore_errors=True)


@pytest.fixture(scope="module")
def local_ray(ray_dir):
    """A local Ray of 2 CPUs, shut down after the module; the campaign
    joins it. Nothing it started may outlive it."""
    tag = uuid.uuid4().hex
    os.environ[MARKER] = tag  # inherited by every process Ray starts
    import ray

    try:
        ray.init(address="local", num_cpus=2, include_dashboard=False,
                 _temp_dir=str(ray_dir / "local"))
        yield ray
    finally:
        ray.shutdown()
        del os.environ[MARKER]
        left = stop_marked(tag)
        assert not left, f"Ray processes left after ray.shutdown(), killed: {left}"
