"""``surveyor.SurfaceModel`` against ``surveyor model`` (issue 27, part 2).

The sets are ``data/block1.jsonl.gz``: the README tour's scripted sweep of
block1, made by

    cargo build --release -p surface --example sweep_sets
    target/release/examples/sweep_sets block1 | gzip -9n > crates/py/tests/data/block1.jsonl.gz

(2221 sets of up to 26 points, 66 KB compressed; the test writes it out
uncompressed for the CLI). The a-priori table is the tour's ``table.json``.
The oracle is ``surveyor model --sets FILE --initial table.json --check
--out DIR`` (the CLI binary, ``SURVEYOR_BIN``, default
``<repo>/target/release/surveyor``): the Python model, fed the same sets
with ``check()`` after each, must write the same ``surface_model.json`` and
``surface_model.obj`` text, and its ``polygons()``, ``shared_edges()`` and
``stats`` must equal what that JSON and ``stats.json`` hold, exactly.
"""

import gzip
import json
import os
import sys
from pathlib import Path

import numpy as np
import pytest

import surveyor
from conftest import run_cli

SETS_GZ = Path(__file__).resolve().parent / "data" / "block1.jsonl.gz"
TABLE = [[-2.0, -2.0, 0.0], [2.0, -2.0, 0.0], [2.0, 2.0, 0.0], [-2.0, 2.0, 0.0]]


@pytest.fixture(scope="module")
def sets_files(tmp_path_factory):
    folder = tmp_path_factory.mktemp("sets")
    text = gzip.decompress(SETS_GZ.read_bytes()).decode()
    sets = folder / "block1.jsonl"
    sets.write_text(text)
    table = folder / "table.json"
    table.write_text(json.dumps({"segments": [TABLE]}))
    lines = [json.loads(line) for line in text.splitlines() if line.strip()]
    arrays = [
        (
            np.array(d["points"], dtype=np.float64).reshape(-1, 3),
            np.array(d["axes"], dtype=np.float64).reshape(-1, 3),
        )
        for d in lines
    ]
    return sets, table, arrays


CONFIGS = [
    (None, []),
    ({"lambda": 0.04, "mu_deg": 12.0, "merge_order": "thesis"}, ["--lambda", 0.04, "--mu-deg", 12]),
]


@pytest.mark.parametrize("config, cli_flags", CONFIGS, ids=["defaults", "lambda-mu-thesis"])
def test_model_equals_cli(surveyor_bin, sets_files, tmp_path, config, cli_flags):
    sets, table, arrays = sets_files
    cli_config = []
    if config and "merge_order" in config:
        toml_file = tmp_path / "model.toml"
        toml_file.write_text(f'merge_order = "{config["merge_order"]}"\n')
        cli_config = ["--config", toml_file]
    out = tmp_path / "cli"
    run_cli(
        surveyor_bin, "model", "--sets", sets, "--initial", table, "--check",
        *cli_config, *cli_flags, "--out", out,
    )

    model = surveyor.SurfaceModel(config)
    assert model.add_initial_segment(np.array(TABLE)) == 1
    for points, axes in arrays:
        model.add_set(points, axes)
        model.check()  # what --check runs after every set

    # The files, text for text.
    model.to_json(tmp_path / "surface_model.json")
    model.to_obj(tmp_path / "surface_model.obj")
    assert (tmp_path / "surface_model.json").read_text() == (out / "surface_model.json").read_text()
    assert (tmp_path / "surface_model.obj").read_text() == (out / "surface_model.obj").read_text()

    # polygons(), shared_edges() and stats against the CLI's JSON, exactly.
    cli = json.loads((out / "surface_model.json").read_text())
    cli_polygons = [s for s in cli["segments"] if s["kind"] == "polygon"]
    polygons = model.polygons()
    assert len(polygons) == len(cli_polygons) > 1
    for p, c in zip(polygons, cli_polygons):
        assert p["id"] == c["id"] and p["points"] == c["points"] and p["initial"] == c["initial"]
        assert p["vertices"].dtype == np.float64 and p["vertices"].shape == (len(c["vertices"]), 3)
        np.testing.assert_array_equal(p["vertices"], np.array(c["vertices"]))
        np.testing.assert_array_equal(p["normal"], np.array(c["normal"]))
        np.testing.assert_array_equal(p["centroid"], np.array(c["centroid"]))
    expected_edges = sorted(
        (c["id"], i, e["shared_with"], e["corresponding_edge"])
        for c in cli_polygons
        for i, e in enumerate(c["edges"])
        if e["shared_with"] is not None and (c["id"], i) < (e["shared_with"], e["corresponding_edge"])
    )
    edges = model.shared_edges()
    assert edges.dtype == np.int64 and edges.shape == (len(expected_edges), 4)
    assert sorted(map(tuple, edges.tolist())) == expected_edges
    cli_stats = json.loads((out / "stats.json").read_text())
    stats = model.stats
    assert stats == {k: v for k, v in cli_stats.items() if k != "update_us"}
    assert stats["updates"] == len(arrays) and stats["shared_edge_pairs"] == len(edges) > 0


def test_config_is_print_config(surveyor_bin, tmp_path):
    tomllib = pytest.importorskip("tomllib")
    config = {"lambda": 0.02, "psi": 10}
    cli = tomllib.loads(
        run_cli(surveyor_bin, "model", "--print-config", "--lambda", 0.02, "--psi", 10)
    )
    assert surveyor.SurfaceModel(config).config == cli
    assert surveyor.SurfaceModel().config["lambda"] == 0.05


# ---------------------------------------------------------------- bad input


GOOD = np.array([[0.0, 0.0, 1.0], [0.1, 0.0, 1.0]])
DOWN = np.array([[0.0, 0.0, -1.0], [0.0, 0.0, -1.0]])


@pytest.mark.parametrize(
    "points, axes, pattern",
    [
        (GOOD.astype(np.float32), DOWN, r"points: expected dtype float64"),
        (GOOD, DOWN.astype(np.int64), r"axes: expected dtype float64"),
        (GOOD[:, :2].copy(), DOWN, r"points: expected shape \(n, 3\)"),
        (GOOD, DOWN[None], r"axes: expected shape \(n, 3\)"),
        (GOOD, DOWN[:1], r"axes: 1 axes for 2 points"),
        (np.array([[0.0, np.nan, 1.0], [0.1, 0.0, 1.0]]), DOWN, r"points\[0\]: not finite"),
        (GOOD, np.array([[0.0, 0.0, -1.0], [0.0, np.inf, -1.0]]), r"axes\[1\]: not a unit"),
        (GOOD, np.array([[0.0, 0.0, -1.0], [0.0, 0.0, -2.0]]), r"axes\[1\]: not a unit vector \(norm 2\)"),
        ("abc", DOWN, r"points: expected"),
    ],
)
def test_bad_sets_raise_value_error(points, axes, pattern):
    model = surveyor.SurfaceModel()
    with pytest.raises(ValueError, match=pattern):
        model.add_set(points, axes)
    assert model.stats["updates"] == 0 and model.stats["segments"] == 0
    model.add_set(GOOD.tolist(), DOWN.tolist())  # lists are converted; the model still works
    assert model.stats["updates"] == 1


def test_too_large_set_raises_value_error():
    model = surveyor.SurfaceModel({"max_set_points": 1})
    with pytest.raises(ValueError, match=r"2 points, more than max_set_points = 1"):
        model.add_set(GOOD, DOWN)


@pytest.mark.parametrize(
    "config, pattern",
    [
        ({"lamda": 0.05}, r"config\['lamda'\]: unknown field `lamda`"),
        ({"lambda": "fine"}, r"config\['lambda'\]: invalid type"),
        ({"lambda": float("nan")}, r"config\['lambda'\]"),
        ({"lambda": -1.0}, r"`lambda` = -1 is not a length"),
        ({"mu_deg": 95}, r"`mu_deg` = 95"),
        ({"merge_order": "random"}, r"config\['merge_order'\]: unknown variant `random`"),
        ({1: 2}, r"config: keys must be field names"),
        ([("lambda", 0.05)], r"config: expected a dict"),
    ],
)
def test_bad_config_raises_value_error(config, pattern):
    with pytest.raises(ValueError, match=pattern):
        surveyor.SurfaceModel(config)


@pytest.mark.parametrize(
    "vertices, pattern",
    [
        ([[0, 0, 0], [1, 0, 0]], r"vertices: initial segment: 2 vertices"),
        ([[0, 0, 0], [1, 0, 0], [1, 1, 0.5], [0, 1, 0]], r"vertices: .*off the plane"),
        ([[0, 0, 0], [4, 0, 0], [4, 3, 0], [2, -1, 0], [0, 3, 0]], r"vertices: .*crosses itself"),
        ([[0, 0, 0], [1, 0, 0], [1, np.nan, 0]], r"vertices: .*not finite"),
        (np.zeros((3, 2)), r"vertices: expected shape \(n, 3\)"),
    ],
)
def test_bad_initial_segment_raises_value_error(vertices, pattern):
    model = surveyor.SurfaceModel()
    with pytest.raises(ValueError, match=pattern):
        model.add_initial_segment(np.asarray(vertices, dtype=np.float64))
    assert model.stats["segments"] == 0


def test_overlapping_initial_segments_raise_value_error():
    """The same table twice is one surface modelled twice: refused, naming
    the segment it overlaps and the common area (16 m²), and not added."""
    model = surveyor.SurfaceModel()
    first = model.add_initial_segment(np.array(TABLE))
    with pytest.raises(ValueError,
                       match=rf"vertices: initial segment: overlaps initial segment {first} over 1\.600e1 m²"):
        model.add_initial_segment(np.array(TABLE))
    assert model.stats["segments"] == 1
    # A second table beside the first (sharing its edge x = 2) is kept.
    beside = [[x + 4.0, y, z] for x, y, z in TABLE]
    assert model.add_initial_segment(np.array(beside)) > first


def test_unwritable_paths_raise_os_error(tmp_path):
    model = surveyor.SurfaceModel()
    model.add_initial_segment(np.array(TABLE))
    with pytest.raises(FileNotFoundError, match=r"missing.*cannot write"):
        model.to_obj(tmp_path / "missing" / "m.obj")
    with pytest.raises(OSError, match=r"cannot write"):
        model.to_json(tmp_path)  # a folder
    if hasattr(os, "geteuid") and os.geteuid() != 0 and sys.platform != "win32":
        locked = tmp_path / "locked"
        locked.mkdir(mode=0o500)
        with pytest.raises(PermissionError):
            model.to_obj(locked / "m.obj")
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(
        ["locked"] if (tmp_path / "locked").exists() else []
    ), "no temporary file is left behind"
    model.to_obj(tmp_path / "m.obj")
    assert (tmp_path / "m.obj").read_text().startswith("# surveyor surface model: 1 segments")
