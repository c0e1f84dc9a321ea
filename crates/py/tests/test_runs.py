"""Whole runs from Python against the command line (issue 27, acceptance 1):
``surveyor.explore`` and ``surveyor.follow`` write the run folders
``surveyor explore`` and ``surveyor follow`` write for the same scenario,
seed and options (``--no-timings``): the same run.json (``Run.summary``),
the same CSV tables (``Run.viewpoints``, ``Run.steps``), the same cloud and
mesh. Scenario overrides go through the scenario's own checks; bad options,
scenarios and folders raise ``ValueError`` or ``OSError``.

The CLI is ``SURVEYOR_BIN`` (conftest.py).
Short runs: Stage One of bridge1 to 3 viewpoints without the oracle, 300
sets of block1 with arm4.
"""

import json

import numpy as np
import pytest

import surveyor
from conftest import run_cli

@pytest.fixture(scope="module")
def cli(surveyor_bin):
    return lambda *args: run_cli(surveyor_bin, *args, "--no-timings")


@pytest.fixture(scope="module")
def explored(tmp_path_factory, cli):
    base = tmp_path_factory.mktemp("explore")
    cli("explore", "--scenario", "bridge1", "--stages", "one", "--max-viewpoints", "3",
        "--no-oracle", "--out", str(base / "cli"))
    run = surveyor.explore("bridge1", seed=0, out=base / "py", stages="one",
                           max_viewpoints=3, oracle=False)
    return base / "cli", run


def test_explore_is_the_cli_s_run(explored):
    cli_dir, run = explored
    assert run.kind == "explore"
    assert run.summary == json.loads((cli_dir / "run.json").read_text())
    for name in ["viewpoints.csv", "discs.csv", "path.csv", "cloud.ply", "mesh.ply", "run.json"]:
        assert (run.dir / name).read_bytes() == (cli_dir / name).read_bytes(), name
    assert len(run.viewpoints) == 3
    assert list(run.viewpoints["k"]) == [0, 1, 2]
    assert run.viewpoints["stage"].dtype == np.int64
    # Empty cells are NaN: no Stage Two target without Stage Two.
    assert np.isnan(run.viewpoints["target_disc"]).all()
    assert (run.dir / "report.html").is_file()


def test_a_run_s_cloud_and_mesh(explored):
    cli_dir, run = explored
    cloud = run.cloud()
    assert cloud.shape[1] == 3 and len(cloud) > 100_000
    # cloud.ply holds float32 x, y, z (then the ray origin): read it here.
    with open(cli_dir / "cloud.ply", "rb") as f:
        head, _, body = f.read().partition(b"end_header\n")
    props = [line for line in head.split(b"\n") if line.startswith(b"property")]
    rows = np.frombuffer(body, dtype=np.float32).reshape(-1, len(props))
    assert np.array_equal(cloud, rows[:, :3].astype(np.float64))
    vertices, triangles = run.mesh()
    assert vertices.shape[1] == 3 and triangles.shape[1] == 3
    assert triangles.min() >= 0 and triangles.max() < len(vertices)


def test_follow_is_the_cli_s_run(tmp_path, cli):
    cli("follow", "--scenario", "block1", "--robot", "arm4", "--max-sets", "300",
        "--out", str(tmp_path / "cli"))
    run = surveyor.follow("block1", robot="arm4", max_sets=300, out=tmp_path / "py")
    assert run.kind == "follow"
    assert run.summary == json.loads((tmp_path / "cli" / "run.json").read_text())
    for name in ["steps.csv", "surface_model.json", "run.json"]:
        assert (run.dir / name).read_bytes() == (tmp_path / "cli" / name).read_bytes(), name
    assert len(run.steps) == run.summary["steps"] == 300
    assert run.steps["q1"].dtype == np.float64


def test_a_run_without_out_lives_as_long_as_its_run():
    run = surveyor.follow("block1", robot="arm4", max_sets=20)
    folder = run.dir
    assert (folder / "run.json").is_file() and len(run.steps) == 20
    del run
    assert not folder.exists()


def test_scenario_overrides_are_checked_by_the_scenario(tmp_path):
    run = surveyor.explore("bridge1", out=tmp_path / "a", stages="one", max_viewpoints=1,
                           oracle=False, report=False, explore={"local_candidates": 0})
    assert len(run.viewpoints) == 1
    assert not (run.dir / "report.html").exists()
    with pytest.raises(ValueError, match="local_candidate"):
        surveyor.explore("bridge1", out=tmp_path / "b", explore={"local_candidate": 0})
    with pytest.raises(ValueError, match="scenario key `robot`"):
        surveyor.explore("bridge1", out=tmp_path / "c", robot=None)
    assert not (tmp_path / "b").exists() and not (tmp_path / "c").exists()


@pytest.mark.parametrize("call, exc, pattern", [
    (lambda d: surveyor.explore("no_such_scene", out=d), ValueError, "no_such_scene"),
    (lambda d: surveyor.explore("bridge1", out=d, stages="two"), ValueError, "stages"),
    (lambda d: surveyor.explore("bridge1", out=d, stage_one="greedy"), ValueError, "stage_one"),
    (lambda d: surveyor.explore("bridge1", out=d, max_viewpoints=0), ValueError, "max_viewpoints"),
    (lambda d: surveyor.explore("bridge1", out=d, max_viewpoints=-1), ValueError, "max_viewpoints"),
    (lambda d: surveyor.explore("bridge1", seed=-1, out=d), ValueError, "seed"),
    (lambda d: surveyor.explore("bridge1", seed=1.5, out=d), ValueError, "seed"),
    # Issue 48: the keyword was not named.
    (lambda d: surveyor.explore("bridge1", out=d, oracle="yes"), ValueError, "oracle='yes'"),
    (lambda d: surveyor.follow("block1", out=d, report=1), ValueError, "report=1"),
    (lambda d: surveyor.follow("block1", out=d, max_sets=0), ValueError, "max_sets"),
    (lambda d: surveyor.follow("block1", out=d, speed=2), ValueError, "speed"),
    (lambda d: surveyor.follow("block1", out=d, robot="elbow"), ValueError, "elbow"),
    (lambda d: surveyor.follow("block1", out=d, noise_m=float("nan")), ValueError, "noise"),
])
def test_bad_runs_raise_and_write_nothing(tmp_path, call, exc, pattern):
    with pytest.raises(exc, match=pattern):
        call(tmp_path / "run")
    assert not (tmp_path / "run").exists()


def test_a_run_folder_is_checked_when_loaded(tmp_path):
    with pytest.raises(FileNotFoundError, match="no such run folder"):
        surveyor.Run.load(tmp_path / "missing")
    (tmp_path / "empty").mkdir()
    with pytest.raises((ValueError, OSError)):
        surveyor.Run.load(tmp_path / "empty")
    # A file where the run folder should be.
    (tmp_path / "file").write_text("x")
    with pytest.raises(FileNotFoundError):
        surveyor.Run.load(tmp_path / "file")
    # An output path that is a file: the job refuses it.
    with pytest.raises((ValueError, OSError)):
        surveyor.follow("block1", max_sets=5, out=tmp_path / "file")


def test_a_damaged_table_is_named_by_file_and_line(tmp_path):
    """Issue 48: a truncated, empty or binary steps.csv raised a raw
    IndexError or UnicodeDecodeError."""
    surveyor.follow("block1", max_sets=5, out=tmp_path / "run")
    steps = tmp_path / "run" / "steps.csv"
    text = steps.read_text()
    lines = text.splitlines(keepends=True)
    cut = "".join(lines[:2]) + lines[2][: lines[2].index(",") + 1]
    for data, pattern in [
        (b"", r"steps\.csv, line 1: empty"),
        (b"\xff\xfe\x00\x81junk\n", r"steps\.csv: not UTF-8"),
        (cut.encode(), r"steps\.csv, line 3: 2 fields, expected"),
    ]:
        steps.write_bytes(data)
        with pytest.raises(ValueError, match=pattern):
            surveyor.Run.load(tmp_path / "run")
