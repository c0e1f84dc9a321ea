"""What the package's tests share: the repository, the surveyor CLI they
compare against (SURVEYOR_BIN, default <repo>/target/release/surveyor) and
a way to run it. The test files import the helpers (`from conftest import
...`: pytest puts this folder on the path, it is no package)."""

import os
import subprocess
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
