"""Robot and Scene against independent oracles (issue 27).

* ``Robot.fk`` / ``frames`` against ``surveyor fk --json`` (the CLI binary,
  ``SURVEYOR_BIN``, default ``<repo>/target/release/surveyor``), to 1e-12;
* ``Scene.raycast`` against ``surveyor raycast`` bit for bit, on the
  structure of ``surveyor raycast-fixture`` with its own rays and with rays
  this test writes in the rays-file format; the face ids against the hit
  points and a brute-force ray-triangle test in float64;
* ``Robot.jacobian`` against central differences of ``fk`` (1e-6);
* joint limits and names against the URDF read by ``xml.etree``;
* every bad input raising ``ValueError`` or ``OSError`` with a message that
  names the problem, the interpreter alive after it.

Run against an installed wheel: ``pip install ./crates/py``, then
``python -m pytest -q crates/py/tests``.
"""

import json
import math
import re
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest

import surveyor
from conftest import REPO, run_cli

UR5 = REPO / "data" / "robots" / "ur5" / "ur5_robot.urdf"
VM6083_Q_DEG = [0, -55, 165, 0, -110, 0]


def cli_fk(bin_path, robot, q, tip=None):
    args = ["fk", "--robot", robot, "--joints=" + ",".join(repr(float(v)) for v in q), "--json"]
    if tip is not None:
        args += ["--tip", tip]
    return json.loads(run_cli(bin_path, *args))


# ---------------------------------------------------------------- robots


@pytest.mark.parametrize(
    "make, cli_robot, tip, q",
    [
        (
            lambda: surveyor.Robot.builtin("denso-vm6083"),
            "denso-vm6083",
            None,
            np.radians(VM6083_Q_DEG),
        ),
        (
            lambda: surveyor.Robot.builtin("denso-vm6083"),
            "denso-vm6083",
            None,
            [0.3, -0.7, 1.9, 0.4, -1.2, 2.5],
        ),
        (
            lambda: surveyor.Robot.from_urdf(UR5, tip="tool0"),
            str(UR5),
            "tool0",
            [0.0, -1.0, 1.0, 0.0, 0.0, 0.0],
        ),
        (
            lambda: surveyor.Robot.from_urdf(str(UR5), "tool0"),
            str(UR5),
            "tool0",
            [0.7, -1.3, 1.1, -0.4, 1.6, -2.9],
        ),
    ],
)
def test_fk_and_frames_are_the_cli_s(surveyor_bin, make, cli_robot, tip, q):
    robot = make()
    want = cli_fk(surveyor_bin, cli_robot, q, tip)
    tip_pose = robot.fk(q)
    assert tip_pose.shape == (4, 4) and tip_pose.dtype == np.float64
    np.testing.assert_allclose(tip_pose, np.array(want["tip"]), rtol=0, atol=1e-12)
    frames = robot.frames(q)
    assert frames.shape == (len(want["frames"]), 4, 4) and frames.dtype == np.float64
    assert robot.link_names == [f["name"] for f in want["frames"]]
    np.testing.assert_allclose(
        frames, np.array([f["pose"] for f in want["frames"]]), rtol=0, atol=1e-12
    )


def test_the_readme_tour_runs():
    text = (REPO / "crates" / "py" / "README.md").read_text()
    blocks = re.findall(r"```python\n(.*?)```", text, re.S)
    assert blocks, "no python example in crates/py/README.md"
    # The blocks go on from one another, as a reader runs them. The campaign
    # example (20 runs into ./camp) is test_campaign.py's to check, smaller.
    namespace = {}
    for block in blocks:
        if "campaign.run(" in block or "studies." in block:
            continue
        exec(compile(block, "crates/py/README.md", "exec"), namespace)


def test_ur5_joints_and_limits_are_the_urdf_s():
    robot = surveyor.Robot.from_urdf(UR5, tip="tool0")
    urdf = ET.parse(UR5).getroot()
    chain = [
        j
        for j in urdf.findall("joint")
        if j.get("type") in ("revolute", "continuous", "prismatic")
    ]
    assert robot.dof == 6 == len(chain)
    assert robot.joint_names == [j.get("name") for j in chain]
    limits = robot.joint_limits
    assert limits.shape == (6, 2) and limits.dtype == np.float64
    want = [[float(j.find("limit").get("lower")), float(j.find("limit").get("upper"))] for j in chain]
    np.testing.assert_array_equal(limits, np.array(want))
    assert robot.name == urdf.get("name")
    assert "dof=6" in repr(robot) and "tool0" in repr(robot)


def test_builtin_robots():
    vm = surveyor.Robot.builtin("denso-vm6083")
    assert vm.dof == 6 and len(vm.joint_names) == 6
    assert np.all(vm.joint_limits[:, 0] < vm.joint_limits[:, 1])
    p3 = surveyor.Robot.builtin("point3")
    assert p3.dof == 3 and p3.jacobian([0.1, 0.2, 0.3]).shape == (6, 3)
    assert surveyor.Robot.builtin("arm4").dof == 6


def numeric_jacobian(robot, q, h=1e-6):
    """Central differences of fk: the tip origin's velocity, and the angular
    velocity from R(q + h e_i) R(q - h e_i)^T (its skew part is 2 h [w])."""
    q = np.asarray(q, dtype=float)
    J = np.zeros((6, len(q)))
    for i in range(len(q)):
        dq = np.zeros_like(q)
        dq[i] = h
        plus, minus = robot.fk(q + dq), robot.fk(q - dq)
        J[:3, i] = (plus[:3, 3] - minus[:3, 3]) / (2 * h)
        M = plus[:3, :3] @ minus[:3, :3].T
        S = (M - M.T) / 2
        J[3:, i] = np.array([S[2, 1], S[0, 2], S[1, 0]]) / (2 * h)
    return J


@pytest.mark.parametrize(
    "make",
    [
        lambda: surveyor.Robot.builtin("denso-vm6083"),
        lambda: surveyor.Robot.builtin("arm4"),
        lambda: surveyor.Robot.builtin("point3"),
        lambda: surveyor.Robot.from_urdf(UR5, tip="tool0"),
    ],
)
def test_jacobian_is_the_derivative_of_fk(make):
    robot = make()
    rng = np.random.default_rng(27)
    lo, hi = robot.joint_limits.T
    lo, hi = np.maximum(lo, -3.0), np.minimum(hi, 3.0)
    for _ in range(5):
        q = rng.uniform(lo, hi)
        J = robot.jacobian(q)
        assert J.shape == (6, robot.dof) and J.dtype == np.float64
        np.testing.assert_allclose(J, numeric_jacobian(robot, q), rtol=0, atol=1e-6)


# ---------------------------------------------------------------- scenes


def read_ply_mesh(path):
    """The vertices and triangles of a binary little-endian PLY as
    `surveyor raycast-fixture` writes it (float x y z; uchar/uint lists)."""
    data = Path(path).read_bytes()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    header = data[:end].decode()
    assert "format binary_little_endian 1.0" in header
    nv = int(re.search(r"element vertex (\d+)", header).group(1))
    nf = int(re.search(r"element face (\d+)", header).group(1))
    vertices = np.frombuffer(data, dtype="<f4", count=3 * nv, offset=end).reshape(nv, 3)
    face = np.dtype([("n", "u1"), ("i", "<u4", (3,))])
    faces = np.frombuffer(data, dtype=face, count=nf, offset=end + 12 * nv)
    assert np.all(faces["n"] == 3)
    return vertices.astype(np.float64), faces["i"].astype(np.int64)


def read_rays(path):
    rays = np.fromfile(path, dtype="<f4").reshape(-1, 6).astype(np.float64)
    return np.ascontiguousarray(rays[:, :3]), np.ascontiguousarray(rays[:, 3:])


def write_rays(path, origins, directions):
    rays = np.hstack([origins, directions]).astype("<f4")
    rays.tofile(path)


@pytest.fixture(scope="session")
def fixture_dir(tmp_path_factory, surveyor_bin):
    out = tmp_path_factory.mktemp("raycast_fixture")
    run_cli(surveyor_bin, "raycast-fixture", "--out", out, "--rays", 20000, "--seed", 3)
    return out


@pytest.fixture(scope="session")
def structure(fixture_dir):
    return surveyor.Scene.from_file(fixture_dir / "structure.ply")


def cli_raycast(surveyor_bin, scene_path, rays_path, out_path):
    run_cli(
        surveyor_bin, "raycast", "--scene", scene_path, "--rays", rays_path,
        "--out", out_path, "--repeat", 1,
    )
    return np.fromfile(out_path, dtype="<f4").astype(np.float64)


def python_rays(n, seed, scene):
    """Rays from around the scene towards it, directions unit in float32
    (so the float64 values handed to raycast are the file's exactly)."""
    rng = np.random.default_rng(seed)
    lo, hi = scene.vertices.min(axis=0), scene.vertices.max(axis=0)
    centre, size = (lo + hi) / 2, hi - lo
    origins = (centre + rng.uniform(-0.75, 0.75, (n, 3)) * size).astype(np.float32)
    targets = centre + rng.uniform(-0.5, 0.5, (n, 3)) * size
    d = targets - origins
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    return origins.astype(np.float64), d.astype(np.float32).astype(np.float64)


def assert_same_hits(distances, faces, want):
    assert distances.dtype == np.float64 and faces.dtype == np.int64
    assert distances.shape == want.shape == faces.shape
    # Bit for bit: the same float32 values, widened.
    np.testing.assert_array_equal(distances, want)
    assert np.array_equal(np.isinf(distances), faces == -1)


def test_raycast_is_the_cli_s_on_the_fixture(surveyor_bin, fixture_dir, structure):
    origins, directions = read_rays(fixture_dir / "rays.bin")
    want = cli_raycast(
        surveyor_bin, fixture_dir / "structure.ply", fixture_dir / "rays.bin",
        fixture_dir / "d.bin",
    )
    distances, faces = structure.raycast(origins, directions, math.inf)
    assert_same_hits(distances, faces, want)
    assert 0 < np.isfinite(want).sum() < len(want)


def test_raycast_is_the_cli_s_on_rays_written_here(surveyor_bin, fixture_dir, structure, tmp_path):
    origins, directions = python_rays(5000, 11, structure)
    write_rays(tmp_path / "rays.bin", origins, directions)
    want = cli_raycast(surveyor_bin, fixture_dir / "structure.ply", tmp_path / "rays.bin", tmp_path / "d.bin")
    distances, faces = structure.raycast(origins, directions)
    assert_same_hits(distances, faces, want)
    assert np.isfinite(want).mean() > 0.3
    # Within a range: the hits beyond it become misses, the rest stay.
    r = 2.0
    near, near_faces = structure.raycast(origins, directions, r)
    np.testing.assert_array_equal(near, np.where(want <= r, want, np.inf))
    np.testing.assert_array_equal(near_faces, np.where(want <= r, faces, -1))


def test_scene_mesh_is_the_file_s(fixture_dir, structure):
    vertices, triangles = read_ply_mesh(fixture_dir / "structure.ply")
    np.testing.assert_array_equal(structure.vertices, vertices)
    np.testing.assert_array_equal(structure.triangles, triangles)
    assert structure.face_count == len(triangles)
    assert structure.triangles.dtype == np.int64


def brute_force(o, d, v0, e1, e2):
    """Möller-Trumbore in float64 against every triangle: (t, face) of the
    nearest hit, or (inf, -1)."""
    p = np.cross(d, e2)
    det = np.einsum("ij,ij->i", e1, p)
    ok = np.abs(det) > 1e-15
    inv = np.where(ok, 1.0 / np.where(ok, det, 1.0), 0.0)
    s = o - v0
    u = np.einsum("ij,ij->i", s, p) * inv
    q = np.cross(s, e1)
    v = (q @ d) * inv
    t = np.einsum("ij,ij->i", e2, q) * inv
    hit = ok & (u >= 0) & (v >= 0) & (u + v <= 1) & (t >= 0)
    if not hit.any():
        return math.inf, -1, t
    k = np.argmin(np.where(hit, t, np.inf))
    return t[k], k, np.where(hit, t, np.inf)


def test_face_ids_name_the_triangles_hit(structure):
    origins, directions = python_rays(400, 5, structure)
    distances, faces = structure.raycast(origins, directions)
    V, T = structure.vertices, structure.triangles
    v0, e1, e2 = V[T[:, 0]], V[T[:, 1]] - V[T[:, 0]], V[T[:, 2]] - V[T[:, 0]]
    hits = 0
    for o, d, dist, face in zip(origins, directions, distances, faces):
        t_best, _, t_all = brute_force(o, d, v0, e1, e2)
        if face < 0:
            assert math.isinf(dist) and (math.isinf(t_best)), (o, d, t_best)
            continue
        hits += 1
        # The reported face is hit there, and nothing is nearer (float32 casting).
        assert abs(t_all[face] - dist) < 1e-4, (face, t_all[face], dist)
        assert abs(t_best - dist) < 1e-4, (t_best, dist)
    assert hits > 100


def test_raycast_takes_any_layout(structure):
    origins, directions = python_rays(3000, 2, structure)
    want = structure.raycast(origins, directions)
    # A strided view, Fortran order, a reversed view, lists: the same rays.
    wide = np.zeros((len(origins), 6))
    wide[:, ::2] = origins
    strided = wide[:, ::2]
    assert not strided.flags.c_contiguous
    fortran = np.asfortranarray(directions)
    assert not fortran.flags.c_contiguous
    backwards = origins[::-1]
    assert backwards.strides[0] < 0
    for o, d, flip in [(strided, fortran, 1), (backwards, directions.tolist()[::-1], -1)]:
        got = structure.raycast(o, d)
        np.testing.assert_array_equal(got[0], want[0][::flip])
        np.testing.assert_array_equal(got[1], want[1][::flip])
    # The caller's arrays are not touched.
    np.testing.assert_array_equal(wide[:, ::2], origins)
    empty = structure.raycast(np.zeros((0, 3)), np.zeros((0, 3)))
    assert empty[0].shape == (0,) and empty[1].shape == (0,)


def test_builtin_scenes():
    cube = surveyor.Scene.builtin("cube")
    assert cube.face_count == 12 and cube.name == "cube"
    d, f = cube.raycast(np.array([[0.0, 0.0, 3.0]]), np.array([[0.0, 0.0, -1.0]]))
    assert d[0] == 2.0
    assert np.all(cube.vertices[cube.triangles[f[0]]][:, 2] == 1.0)
    bridge = surveyor.Scene.builtin("bridge1")
    d, _ = bridge.raycast(np.array([[0.0, 0.0, 0.5]]), np.array([[0.0, 0.0, 1.0]]))
    assert abs(d[0] - 1.02) < 1e-6


def test_scale_multiplies_the_mesh(fixture_dir, structure):
    half = surveyor.Scene.from_file(str(fixture_dir / "structure.ply"), scale=0.5)
    np.testing.assert_allclose(half.vertices, structure.vertices * 0.5, rtol=1e-15)


# ---------------------------------------------------------------- bad input


def expect(exc, pattern, call):
    with pytest.raises(exc) as info:
        call()
    assert type(info.value) is not BaseException
    assert re.search(pattern, str(info.value)), str(info.value)
    return info.value


@pytest.fixture(scope="module")
def cube():
    return surveyor.Scene.builtin("cube")


ORIGIN = np.array([[0.0, 0.0, 3.0]])
DOWN = np.array([[0.0, 0.0, -1.0]])


@pytest.mark.parametrize(
    "origins, directions, pattern",
    [
        (np.zeros((1, 2)), DOWN, r"origins: expected shape \(n, 3\).*got \(1, 2\)"),
        (ORIGIN, np.zeros(3), r"directions: expected shape \(n, 3\).*got \(3,\)"),
        (np.zeros((1, 1, 3)), DOWN, r"origins: expected shape \(n, 3\).*got \(1, 1, 3\)"),
        (ORIGIN.astype(np.float32), DOWN, r"origins: expected dtype float64, got float32"),
        (ORIGIN, DOWN.astype(np.int64), r"directions: expected dtype float64, got int64"),
        (ORIGIN, DOWN.astype(">f8"), r"directions: expected dtype float64, got >f8"),
        (ORIGIN, np.array([["a", "b", "c"]]), r"directions: expected dtype float64"),
        ("rays", DOWN, r"origins: expected a float64 array of shape \(n, 3\), got a str"),
        (ORIGIN, [[0, 0], [1]], r"directions: expected a float64 array"),
        (np.array([[0.0, np.nan, 3.0]]), DOWN, r"origins\[0\] is \(0, NaN, 3\).*finite"),
        (ORIGIN, np.array([[0.0, np.inf, 0.0]]), r"directions\[0\] is .*inf.*finite"),
        (
            np.vstack([ORIGIN, ORIGIN]),
            np.array([[0.0, 0.0, -1.0], [0.0, 0.0, 0.0]]),
            r"directions\[1\] is \(0, 0, 0\): a zero-length direction",
        ),
        (ORIGIN, np.array([[0.0, 0.0, -2.0]]), r"directions\[0\].*of length 2: expected a unit vector"),
        (ORIGIN, np.vstack([DOWN, DOWN]), r"origins has 1 rows and directions 2"),
        (np.array([[1e300, 0.0, 0.0]]), DOWN, r"origins\[0\].*single-precision"),
    ],
)
def test_bad_rays_raise_value_error(cube, origins, directions, pattern):
    expect(ValueError, pattern, lambda: cube.raycast(origins, directions))
    assert cube.raycast(ORIGIN, DOWN)[0][0] == 2.0  # still alive and well


def test_the_first_bad_ray_of_many_is_named(cube):
    # Rays are checked a chunk of 1024 at a time on several threads: whichever
    # chunk fails first, the message names the first bad ray of them all.
    n = 50_000
    origins = np.tile(ORIGIN, (n, 1))
    directions = np.tile(DOWN, (n, 1))
    origins[40_000, 1] = np.nan
    directions[7_777] = [0.0, 0.0, -3.0]
    directions[30_000] = 0.0
    expect(ValueError, r"^directions\[7777\] is \(0, 0, -3\), of length 3", lambda: cube.raycast(origins, directions))
    directions[7_777] = DOWN
    expect(ValueError, r"^directions\[30000\] is \(0, 0, 0\)", lambda: cube.raycast(origins, directions))
    directions[30_000] = DOWN
    expect(ValueError, r"^origins\[40000\] is \(0, NaN, 3\)", lambda: cube.raycast(origins, directions))
    origins[40_000, 1] = 0.0
    distances, faces = cube.raycast(origins, directions)
    assert np.all(distances == 2.0) and np.all(faces >= 0)


@pytest.mark.parametrize("max_range", [-1.0, math.nan])
def test_bad_max_range_raises_value_error(cube, max_range):
    expect(ValueError, r"max_range is .*expected a distance", lambda: cube.raycast(ORIGIN, DOWN, max_range))


@pytest.mark.parametrize(
    "q, pattern",
    [
        ([0.0] * 5, r"expected 6 joint values .*got 5"),
        ([0.0] * 7, r"expected 6 joint values .*got 7"),
        ([0.0, math.nan, 0, 0, 0, 0], r"joint joint2 \(q\[1\]\) is NaN: joint values must be finite"),
        ([0.0, 0, 0, 0, 0, math.inf], r"joint joint6 \(q\[5\]\) is inf"),
        ("abcdef", r"q: expected a sequence of 6 joint values"),
        (np.zeros((2, 6)), r"q: expected a sequence of 6 joint values"),
        (None, r"q: expected a sequence of 6 joint values"),
        # Issue 48: a complex array was cast to its real part.
        (np.zeros(6, dtype=complex), r"q: complex values"),
        ([0.0, 0, 0, np.complex128(1 + 2j), 0, 0], r"q: complex values"),
        ([0.0, 0, 0, 0, 0, 1j], r"q: complex values"),
    ],
)
def test_bad_joints_raise_value_error(q, pattern):
    robot = surveyor.Robot.builtin("denso-vm6083")
    for method in (robot.fk, robot.frames, robot.jacobian):
        expect(ValueError, pattern, lambda: method(q))
    assert robot.fk(np.zeros(6)).shape == (4, 4)


def test_joint_vectors_of_any_kind():
    robot = surveyor.Robot.builtin("denso-vm6083")
    q = np.radians(VM6083_Q_DEG)
    want = robot.fk(q)
    for same in (list(q), tuple(q), q.astype(np.float32).astype(np.float64)):
        np.testing.assert_array_equal(robot.fk(same), robot.fk(np.asarray(same, dtype=float)))
    np.testing.assert_array_equal(robot.fk(list(q)), want)
    np.testing.assert_array_equal(robot.fk([0, 0, 0, 0, 0, 0]), robot.fk(np.zeros(6)))


def test_missing_and_unreadable_files_raise_os_error(tmp_path):
    missing = tmp_path / "nowhere.urdf"
    err = expect(FileNotFoundError, re.escape(str(missing)) + r": cannot read", lambda: surveyor.Robot.from_urdf(missing))
    assert isinstance(err, OSError)
    expect(FileNotFoundError, r"nowhere\.ply", lambda: surveyor.Scene.from_file(tmp_path / "nowhere.ply"))
    folder = tmp_path / "folder.ply"
    folder.mkdir()
    expect(OSError, r"folder\.ply: cannot read", lambda: surveyor.Scene.from_file(folder))
    # A URDF whose collision mesh is missing.
    urdf = tmp_path / "arm.urdf"
    urdf.write_text(
        '<robot name="r"><link name="a"><collision><geometry><mesh filename="gone.stl"/>'
        '</geometry></collision></link><link name="b"/>'
        '<joint name="j" type="revolute"><parent link="a"/><child link="b"/>'
        '<axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint></robot>'
    )
    expect(FileNotFoundError, r"gone\.stl", lambda: surveyor.Robot.from_urdf(urdf))


def test_bad_files_and_names_raise_value_error(tmp_path):
    expect(ValueError, r"unknown built-in robot 'puma': valid names are denso-vm6083, point3, arm4",
           lambda: surveyor.Robot.builtin("puma"))
    expect(ValueError, r"unknown built-in scene 'moon': valid names are bridge1, .*cylinder",
           lambda: surveyor.Scene.builtin("moon"))
    expect(ValueError, r"tool9", lambda: surveyor.Robot.from_urdf(UR5, tip="tool9"))
    bad = tmp_path / "bad.urdf"
    bad.write_text("<robot name='r'>\n<link name='a'>\n</robot>\n")
    expect(ValueError, re.escape(str(bad)) + r":\d+:\d+: malformed XML", lambda: surveyor.Robot.from_urdf(bad))
    text = tmp_path / "mesh.xyz"
    text.write_text("0 0 0\n")
    expect(ValueError, r"unsupported file type", lambda: surveyor.Scene.from_file(text))
    garbage = tmp_path / "mesh.ply"
    garbage.write_bytes(b"ply\nformat ascii 1.0\nelement vertex 1\nend_header\nnot numbers\n")
    expect(ValueError, r"mesh\.ply", lambda: surveyor.Scene.from_file(garbage))
    cube_obj = tmp_path / "cube.obj"
    cube_obj.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    for scale in (0.0, -1.0, math.nan, math.inf):
        expect(ValueError, r"scale factor must be finite and positive", lambda: surveyor.Scene.from_file(cube_obj, scale))
    assert surveyor.Scene.from_file(cube_obj).face_count == 1


def test_the_api_is_documented():
    """help(surveyor) lists the API: every public name of the package has a
    docstring and a stub entry."""
    import pydoc

    page = pydoc.render_doc(surveyor, renderer=pydoc.plaintext)
    for name in surveyor.__all__:
        assert name in page, f"help(surveyor) does not list {name}"
        if name != "__version__":
            assert getattr(surveyor, name).__doc__, f"surveyor.{name} has no docstring"
    for fn in (surveyor.explore, surveyor.follow, surveyor.Run.load):
        assert fn.__doc__
    for cls in (surveyor.Robot, surveyor.Scene, surveyor.SurfaceModel, surveyor.Mapper):
        assert cls.__doc__ and cls.__module__ == "surveyor"
        for name in dir(cls):
            if not name.startswith("_"):
                assert getattr(cls, name).__doc__, f"{cls.__name__}.{name} has no docstring"
    assert surveyor.__doc__ and "Robot" in surveyor.__doc__
    stub = Path(surveyor.__file__).with_name("__init__.pyi")
    assert stub.is_file() and stub.with_name("py.typed").is_file()
    # The stub names every public member.
    text = stub.read_text()
    for fn in (surveyor.scale_like_discs, surveyor.candidate_coverage):
        assert re.search(rf"def {fn.__name__}\b", text), f"{fn.__name__} is not in the stub"
    for cls in (surveyor.Robot, surveyor.Scene, surveyor.SurfaceModel, surveyor.Mapper):
        for name in dir(cls):
            if not name.startswith("_"):
                assert re.search(rf"def {name}\b", text), f"{cls.__name__}.{name} is not in the stub"
    for name in ("explore", "follow", "class Run", "def load", "def cloud", "def mesh"):
        assert name in text, f"{name} is not in the stub"
