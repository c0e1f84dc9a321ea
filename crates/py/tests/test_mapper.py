"""``surveyor.Mapper`` against ``surveyor map``, ``sld`` and ``segment``
(issue 27, part 2).

Two sweeps of bridge1 are made by the CLI (``SURVEYOR_BIN``, default
``<repo>/target/release/surveyor``), as in the README tour::

    surveyor scan --scenario bridge1 --out a.ply
    surveyor scan --scenario bridge1 --deg --joints 60,-55,165,0,-110,0 --out b.ply
    surveyor map --scans a.ply b.ply --scenario bridge1 --out maps

read here (the scan-file PLY of crates/sensor/src/scan_file.rs) and fed to a
``Mapper(scenario="bridge1")``. Oracles, all exact:

* ``report()`` and ``entropy()`` against ``maps/occupancy.json``;
* ``mesh()`` against ``maps/mesh.ply`` (its float32 vertices are the
  float64 vertices rounded; the faces are equal);
* ``discs()`` and ``segments()`` against ``surveyor sld`` and ``surveyor
  segment`` run on the float64 mesh, which the test writes as a PLY of
  doubles. (The tour's ``sld --input maps/mesh.ply`` reads the float32
  mesh: the same number of discs here, but normals a few 1e-3 apart.)

The same without the (scan, ray) cells against ``map --scans`` on scan files
without the ``scan ray`` columns, and with ``voxel`` against ``--voxel``.
"""

import csv
import json
from pathlib import Path

import numpy as np
import pytest

import surveyor
from conftest import run_cli

PLY_TYPES = {"float": "<f4", "double": "<f8", "uchar": "u1", "uint": "<u4", "int": "<i4"}


def read_ply(path):
    """The elements of a binary little-endian PLY: {name: structured array};
    a face element (a list of three indices) as an int64 (k, 3) array."""
    data = Path(path).read_bytes()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    header = data[:end].decode("ascii").splitlines()
    assert header[:2] == ["ply", "format binary_little_endian 1.0"], header[:2]
    elements = []
    for line in header:
        words = line.split()
        if words[0] == "element":
            elements.append((words[1], int(words[2]), []))
        elif words[0] == "property":
            elements[-1][2].append(words[1:])
    offset, out = end, {}
    for name, count, props in elements:
        if props[0][0] == "list":
            _, count_type, index_type, _ = props[0]
            dtype = np.dtype([("n", PLY_TYPES[count_type]), ("i", PLY_TYPES[index_type], (3,))])
            rows = np.frombuffer(data, dtype=dtype, count=count, offset=offset)
            assert (rows["n"] == 3).all()
            out[name] = rows["i"].astype(np.int64)
        else:
            dtype = np.dtype([(p[1], PLY_TYPES[p[0]]) for p in props])
            out[name] = np.frombuffer(data, dtype=dtype, count=count, offset=offset)
        offset += dtype.itemsize * count
    assert offset == len(data)
    return out


def write_ply(path, columns, faces=None):
    """A binary little-endian PLY: vertex columns {name: array} (float32 or
    float64), optionally triangles."""
    dtype = np.dtype([(k, "<f8" if v.dtype == np.float64 else "<f4") for k, v in columns.items()])
    n = len(next(iter(columns.values())))
    vertices = np.zeros(n, dtype=dtype)
    for k, v in columns.items():
        vertices[k] = v
    head = ["ply", "format binary_little_endian 1.0", f"element vertex {n}"]
    head += [f"property {'double' if dtype[k] == np.float64 else 'float'} {k}" for k in columns]
    body = vertices.tobytes()
    if faces is not None:
        head += [f"element face {len(faces)}", "property list uchar uint vertex_indices"]
        rows = np.zeros(len(faces), dtype=[("n", "u1"), ("i", "<u4", (3,))])
        rows["n"], rows["i"] = 3, faces
        body += rows.tobytes()
    Path(path).write_bytes(("\n".join(head + ["end_header"]) + "\n").encode() + body)


def sweep_arrays(vertex, cells=True):
    """insert_sweep's arguments from a scan file's vertex table."""
    stack = lambda *names: np.stack([vertex[k] for k in names], axis=1).astype(np.float64)
    args = {
        "points": stack("x", "y", "z"),
        "origins": stack("ox", "oy", "oz"),
        "intensities": vertex["intensity"].astype(np.float64),
    }
    if cells:
        args["cells"] = stack("scan", "ray").astype(np.int64)
    return args


@pytest.fixture(scope="module")
def scans(surveyor_bin, tmp_path_factory):
    folder = tmp_path_factory.mktemp("scans")
    a, b = folder / "a.ply", folder / "b.ply"
    run_cli(surveyor_bin, "scan", "--scenario", "bridge1", "--out", a)
    run_cli(
        surveyor_bin, "scan", "--scenario", "bridge1", "--deg",
        "--joints", "60,-55,165,0,-110,0", "--out", b,
    )
    return folder, [a, b]


def cli_map(surveyor_bin, files, out, *flags):
    run_cli(surveyor_bin, "map", "--scans", *files, "--scenario", "bridge1", *flags, "--out", out)
    mesh = read_ply(out / "mesh.ply")
    return json.loads((out / "occupancy.json").read_text()), mesh


@pytest.fixture(scope="module")
def mapped(surveyor_bin, scans):
    folder, files = scans
    mapper = surveyor.Mapper(scenario="bridge1")
    summaries = [mapper.insert_sweep(**sweep_arrays(read_ply(f)["vertex"])) for f in files]
    return mapper, summaries, cli_map(surveyor_bin, files, folder / "maps")


def test_occupancy_equals_cli(mapped):
    mapper, summaries, (occupancy, _) = mapped
    assert mapper.report() == occupancy
    entropy = mapper.entropy()
    assert entropy == {k: occupancy[k] for k in ("h1_unweighted", "h1_weighted", "h2")}
    assert entropy["h1_unweighted"] > entropy["h1_weighted"] > 0
    # `surveyor map` prints these per scan: 0 and 3 occlusion segments on the scan grid.
    assert [s["occupancy"]["range_jumps"] for s in summaries] == [0, 3]
    assert all(s["occupancy"]["rays_outside"] == 0 and s["tsdf"]["points"] > 50000 for s in summaries)


def test_mesh_equals_cli(mapped):
    mapper, _, (_, mesh) = mapped
    vertices, triangles = mapper.mesh()
    assert vertices.dtype == np.float64 and triangles.dtype == np.int64
    v = mesh["vertex"]
    expected = np.stack([v["x"], v["y"], v["z"]], axis=1)
    assert vertices.shape == expected.shape and vertices.shape[0] > 10000
    np.testing.assert_array_equal(vertices.astype(np.float32), expected)
    np.testing.assert_array_equal(triangles, mesh["face"])


def test_discs_and_segments_equal_cli(mapped, surveyor_bin, tmp_path):
    mapper, _, _ = mapped
    vertices, triangles = mapper.mesh()
    write_ply(
        tmp_path / "mesh64.ply",
        {"x": vertices[:, 0], "y": vertices[:, 1], "z": vertices[:, 2]},
        triangles,
    )
    run_cli(surveyor_bin, "sld", "--input", tmp_path / "mesh64.ply", "--out", tmp_path / "discs.csv")
    run_cli(surveyor_bin, "segment", "--discs", tmp_path / "discs.csv", "--out", tmp_path / "s.json")
    with open(tmp_path / "discs.csv", newline="") as f:
        rows = list(csv.reader(f))
    header, rows = rows[0], rows[1:]
    assert header == ["cx", "cy", "cz", "nx", "ny", "nz", "radius", "points"]

    discs = mapper.discs()
    assert discs.dtype.names == (*header, "segment")
    assert len(discs) == len(rows) > 1000
    for name in header[:7]:
        assert discs.dtype[name] == np.float64
        np.testing.assert_array_equal(discs[name], [float(r[header.index(name)]) for r in rows])
    np.testing.assert_array_equal(discs["points"], [int(r[7]) for r in rows])

    cli_segments = json.loads((tmp_path / "s.json").read_text())["segments"]
    segments = mapper.segments()
    assert all(s.dtype == np.int64 for s in segments)
    assert [s.tolist() for s in segments] == cli_segments
    for k, members in enumerate(cli_segments):
        assert (discs["segment"][members] == k).all()


def test_without_cells_and_other_voxel_equals_cli(scans, surveyor_bin, tmp_path):
    """No (scan, ray) cells: occlusions between list neighbours, as `map`
    reads a scan file without `scan ray` columns; 2 cm voxels as --voxel."""
    _, files = scans
    mapper = surveyor.Mapper(scenario="bridge1", voxel=0.02)
    stripped = []
    for k, f in enumerate(files):
        vertex = read_ply(f)["vertex"]
        mapper.insert_sweep(**sweep_arrays(vertex, cells=False))
        stripped.append(tmp_path / f"nogrid{k}.ply")
        write_ply(stripped[-1], {n: vertex[n] for n in ("x", "y", "z", "intensity", "ox", "oy", "oz")})
    occupancy, mesh = cli_map(surveyor_bin, stripped, tmp_path / "maps", "--voxel", 0.02)
    assert mapper.report() == occupancy and occupancy["voxel_m"] == 0.02
    vertices, triangles = mapper.mesh()
    v = mesh["vertex"]
    np.testing.assert_array_equal(vertices.astype(np.float32), np.stack([v["x"], v["y"], v["z"]], 1))
    np.testing.assert_array_equal(triangles, mesh["face"])


def test_config_is_print_config(surveyor_bin, tmp_path):
    tomllib = pytest.importorskip("tomllib")
    cli = tomllib.loads(run_cli(surveyor_bin, "map", "--print-config", "--scenario", "bridge1"))
    ours = surveyor.Mapper(scenario="bridge1").config
    # TOML has no null: the fields left unset (None) are absent there.
    assert ours["occupancy"].pop("free_misses_m") is None
    assert ours == cli
    config = {"occupancy": {"voxel_m": 0.05, "weights": [0.5, 0.3, 0.2]}, "tsdf": {"voxel_m": 0.05, "truncation_m": 0.2}}
    mapper = surveyor.Mapper(config)
    assert mapper.config["occupancy"]["weights"] == [0.5, 0.3, 0.2]
    assert mapper.report()["voxel_m"] == 0.05 and mapper.entropy()["h2"] == 0.0
    assert mapper.mesh()[0].shape == (0, 3) and len(mapper.discs()) == 0 and mapper.segments() == []


# ---------------------------------------------------------------- bad input


P = np.array([[1.0, 0.0, 1.0], [1.0, 0.1, 1.0]])
O = np.zeros((2, 3))


@pytest.mark.parametrize(
    "args, pattern",
    [
        ({"points": P.astype(np.float32), "origins": O}, r"points: expected dtype float64"),
        ({"points": P, "origins": O[:, :2].copy()}, r"origins: expected shape \(n, 3\)"),
        ({"points": P, "origins": O[:1]}, r"origins: 1 rows for 2 points"),
        ({"points": np.array([[1.0, np.nan, 1.0], [1, 0, 1]]), "origins": O}, r"points: row 0 is not finite"),
        ({"points": P, "origins": np.array([[0, 0, 0], [0, 0, np.inf]])}, r"origins: row 1 is not finite"),
        ({"points": P, "origins": O, "intensities": np.zeros(3)}, r"intensities: expected shape \(2,\)"),
        ({"points": P, "origins": O, "intensities": np.zeros(2, np.float32)}, r"intensities: expected dtype float64"),
        ({"points": P, "origins": O, "intensities": np.array([0.0, np.nan])}, r"intensities: value 1 is not finite"),
        ({"points": P, "origins": O, "cells": np.zeros((2, 2))}, r"cells: expected an integer dtype"),
        ({"points": P, "origins": O, "cells": np.zeros((2, 3), np.int64)}, r"cells: expected shape \(2, 2\)"),
        ({"points": P, "origins": O, "cells": np.array([[0, 1], [0, -1]])}, r"cells: row 1 is \(0, -1\)"),
        ({"points": P, "origins": O, "cells": np.array([[0, 1], [0, 0]])}, r"cells: .*strictly increasing"),
    ],
)
def test_bad_sweeps_raise_value_error(args, pattern):
    mapper = surveyor.Mapper(voxel=0.05)
    with pytest.raises(ValueError, match=pattern):
        mapper.insert_sweep(**args)
    assert mapper.report()["regions"][2]["occupied"] == 0
    summary = mapper.insert_sweep(P.tolist(), O, [0.0, 1.0], [[0, 0], [0, 1]])
    assert summary["occupancy"]["rays"] == 2


@pytest.mark.parametrize(
    "kwargs, exc, pattern",
    [
        ({"config": {"occupancy": {"voxel": 0.1}}}, ValueError, r"config\['occupancy'\]: unknown field `voxel`"),
        ({"config": {"tsfd": {}}}, ValueError, r"config\['tsfd'\]: unknown field `tsfd`"),
        ({"config": {"occupancy": {"voxel_m": -1.0}}}, ValueError, r"occupancy.voxel_m"),
        ({"voxel": 0.0}, ValueError, r"voxel_m"),
        ({"scenario": "bridge9"}, ValueError, r"bridge9"),
        ({"scenario": "/nonexistent/s.toml"}, FileNotFoundError, r"scenario /nonexistent/s.toml"),
    ],
)
def test_bad_config_raises(kwargs, exc, pattern):
    with pytest.raises(exc, match=pattern):
        surveyor.Mapper(**kwargs)
