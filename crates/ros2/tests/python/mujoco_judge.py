"""What the MuJoCo tests share (issue 47): running a surveyor command
against `mujoco_robot.py` over ROS 2, and judging its output in the MuJoCo
model itself (distances to the scene's geoms, coverage of their surfaces).
"""

import json
import os
import signal
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import mujoco
import numpy as np
import ros_domain

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[3]
BINARY = os.environ.get("SURVEYOR_BIN", str(ROOT / "target/release/surveyor"))
# Robot seconds per wall second. 20 keeps up on this 2-core machine with
# the driver beside it (the robot alone runs about 35x): the robot slows its
# clock rather than race when the machine is busy.
RATE = float(os.environ.get("SURVEYOR_MUJOCO_RATE", "20"))


@dataclass
class Driven:
    """A surveyor command run against the MuJoCo robot."""
    returncode: int
    stdout: str
    stderr: str
    # What the robot printed on stopping (its figures and contact count).
    said: str
    # The arm-scene contacts it logged, as JSON objects.
    contacts: list
    # Wall seconds the command took, and from the robot's kill to its end.
    wall_s: float
    after_kill_s: float = None


def drive(tmp_path, scenario, command, robot_args=(), robot=None, kill_after_s=None,
          timeout_s=3000):
    """Run `surveyor COMMAND --ros2 --out TMP/run` against mujoco_robot.py
    serving `scenario` (name or file; `robot` for another arm) in a random
    ROS domain of their own; `kill_after_s` wall seconds in, SIGKILL the
    robot (mid-motion) and time how long the command takes to give up."""
    domain = ros_domain.pick()
    env = dict(os.environ, ROS_DOMAIN_ID=str(domain))
    contacts = tmp_path / "contacts.jsonl"
    rcmd = [sys.executable, str(HERE / "mujoco_robot.py"), "--scenario", str(scenario),
            "--rate", str(RATE), "--domain", str(domain), "--contacts", str(contacts),
            *robot_args]
    if robot:
        rcmd += ["--robot", robot]
    rproc = subprocess.Popen(rcmd, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                             text=True)
    cmd = [BINARY, *command, "--ros2", "--out", str(tmp_path / "run")]
    after_kill, proc = None, None
    try:
        wall = time.monotonic()
        proc = subprocess.Popen(cmd, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                text=True)
        if kill_after_s is not None:
            try:
                out, err = proc.communicate(timeout=kill_after_s)
            except subprocess.TimeoutExpired:
                rproc.kill()
                killed = time.monotonic()
                out, err = proc.communicate(timeout=timeout_s)
                after_kill = time.monotonic() - killed
        else:
            out, err = proc.communicate(timeout=timeout_s)
        wall = time.monotonic() - wall
    finally:
        if proc is not None and proc.poll() is None:
            proc.kill()
        if rproc.poll() is None:
            rproc.send_signal(signal.SIGTERM)
        said, rerr = rproc.communicate(timeout=60)
    print(out[-3000:], err[-3000:], said, rerr)
    if kill_after_s is None:
        assert rproc.returncode == 0, rerr
        assert "contacts: " in said, said
    text = contacts.read_text() if contacts.exists() else ""
    return Driven(proc.returncode, out, err, said + rerr,
                  [json.loads(x) for x in text.splitlines()], wall, after_kill)


def scenario_with(tmp_path, name, ros2):
    """A built-in scenario as a file, with a `[ros2]` table of `ros2`."""
    text = subprocess.run([BINARY, "scenario", "show", name], check=True, capture_output=True,
                          text=True).stdout
    table = "".join(f"{k} = {v}\n" for k, v in ros2.items())
    path = tmp_path / f"{name}.toml"
    path.write_text(f"{text}\n[ros2]\n{table}")
    return path


def read_ply(path):
    """The vertices of a binary little-endian PLY as named float64 columns."""
    data = Path(path).read_bytes()
    head, body = data.split(b"end_header\n", 1)
    lines = head.decode().splitlines()
    n = int(next(x for x in lines if x.startswith("element vertex")).split()[2])
    props = [x.split()[1:] for x in lines if x.startswith("property")]
    kinds = {"float": "<f4", "double": "<f8", "uchar": "u1", "int": "<i4", "uint": "<u4"}
    dtype = np.dtype([(name, kinds[kind]) for kind, name in props])
    v = np.frombuffer(body, dtype=dtype, count=n)
    return {k: v[k].astype(np.float64) for k in dtype.names}


def geom_distances(m, points):
    """Signed distance from each point to each scene geom of model `m`
    (negative inside): exact for boxes; for a convex mesh the largest
    distance beyond its face planes (exact off its edges, less near them).
    A dict from geom id to distances."""
    d = mujoco.MjData(m)
    mujoco.mj_forward(m, d)
    out = {}
    for g in range(m.ngeom):
        if not m.geom(g).name.startswith("scene/"):
            continue
        rot = d.geom_xmat[g].reshape(3, 3)
        local = (points - d.geom_xpos[g]) @ rot  # into the geom frame
        if m.geom_type[g] == mujoco.mjtGeom.mjGEOM_BOX:
            q = np.abs(local) - m.geom_size[g]
            out[g] = np.linalg.norm(np.maximum(q, 0.0), axis=1) + np.minimum(q.max(axis=1), 0.0)
        elif m.geom_type[g] == mujoco.mjtGeom.mjGEOM_MESH:
            nrm, off = mesh_planes(m, g)
            dist = np.full(len(points), -np.inf)
            for k in range(0, len(nrm), 64):
                dist = np.maximum(dist, (local @ nrm[k:k + 64].T - off[k:k + 64]).max(axis=1))
            out[g] = dist
    return out


def mesh_planes(m, g):
    """Outward unit normals and offsets of a convex mesh geom's faces, in
    its frame."""
    mid = m.geom_dataid[g]
    va, vn = m.mesh_vertadr[mid], m.mesh_vertnum[mid]
    fa, fn = m.mesh_faceadr[mid], m.mesh_facenum[mid]
    verts = m.mesh_vert[va:va + vn]
    faces = m.mesh_face[fa:fa + fn]
    a, b, c = verts[faces[:, 0]], verts[faces[:, 1]], verts[faces[:, 2]]
    nrm = np.cross(b - a, c - a)
    nrm /= np.linalg.norm(nrm, axis=1, keepdims=True)
    flip = np.einsum("ij,ij->i", nrm, a - verts.mean(axis=0)) < 0
    nrm[flip] *= -1
    return nrm, np.einsum("ij,ij->i", nrm, a)


def scene_distance(m, points):
    """Distance from each point to the nearest scene solid."""
    return np.min(np.abs(np.stack(list(geom_distances(m, points).values()))), axis=0)


def surface_samples(m, spacing=0.02, seed=0, normals=False):
    """Points on the scene geoms' surfaces, about one per `spacing`² (a grid
    on each box face, uniform on each mesh triangle), those inside or on
    another geom (hidden faces) left out; with `normals`, also the outward
    unit normal of the face each lies on."""
    d = mujoco.MjData(m)
    mujoco.mj_forward(m, d)
    rng = np.random.default_rng(seed)
    samples, owner, normal = [], [], []
    for g in range(m.ngeom):
        if not m.geom(g).name.startswith("scene/"):
            continue
        rot = d.geom_xmat[g].reshape(3, 3)
        if m.geom_type[g] == mujoco.mjtGeom.mjGEOM_BOX:
            h = m.geom_size[g]
            for axis in range(3):
                u, v = [a for a in range(3) if a != axis]
                nu = max(1, int(round(2 * h[u] / spacing)))
                nv = max(1, int(round(2 * h[v] / spacing)))
                gu = (np.arange(nu) + 0.5) / nu * 2 * h[u] - h[u]
                gv = (np.arange(nv) + 0.5) / nv * 2 * h[v] - h[v]
                uu, vv = np.meshgrid(gu, gv)
                for sign in (-1, 1):
                    local = np.zeros((uu.size, 3))
                    local[:, u], local[:, v], local[:, axis] = uu.ravel(), vv.ravel(), sign * h[axis]
                    samples.append(local @ rot.T + d.geom_xpos[g])
                    owner.append(np.full(uu.size, g))
                    normal.append(np.tile(sign * rot[:, axis], (uu.size, 1)))
        elif m.geom_type[g] == mujoco.mjtGeom.mjGEOM_MESH:
            mid = m.geom_dataid[g]
            va, fa, fn = m.mesh_vertadr[mid], m.mesh_faceadr[mid], m.mesh_facenum[mid]
            verts = m.mesh_vert[va:va + m.mesh_vertnum[mid]]
            nrm, _ = mesh_planes(m, g)
            for f, n in zip(m.mesh_face[fa:fa + fn], nrm):
                a, b, c = verts[f]
                area = 0.5 * np.linalg.norm(np.cross(b - a, c - a))
                k = rng.poisson(area / spacing**2)
                r1, r2 = rng.random(k), rng.random(k)
                s1 = np.sqrt(r1)
                local = (1 - s1)[:, None] * a + (s1 * (1 - r2))[:, None] * b + (s1 * r2)[:, None] * c
                samples.append(local @ rot.T + d.geom_xpos[g])
                owner.append(np.full(k, g))
                normal.append(np.tile(rot @ n, (k, 1)))
    pts, owner, normal = np.concatenate(samples), np.concatenate(owner), np.concatenate(normal)
    dist = geom_distances(m, pts)
    hidden = np.zeros(len(pts), dtype=bool)
    for g, dg in dist.items():
        hidden |= (owner != g) & (dg <= 1e-6)
    if normals:
        return pts[~hidden], normal[~hidden]
    return pts[~hidden]


def coverage(m, cloud, box, within_m=0.01):
    """The share of the exposed true surface in `box` (min, max) with a
    cloud point within `within_m`: the A1 coverage of SPEC §6, on samples
    of our own (a 2 cm grid) where surveyor's judge samples 40 000 per m²."""
    from scipy.spatial import cKDTree
    s = surface_samples(m)
    lo, hi = np.array(box[0]), np.array(box[1])
    s = s[np.all((s >= lo) & (s <= hi), axis=1)]
    c = read_ply(cloud)
    tree = cKDTree(np.stack([c["x"], c["y"], c["z"]], axis=1))
    dist, _ = tree.query(s, distance_upper_bound=within_m)
    return float(np.mean(dist <= within_m))


def within(m, cloud, metres):
    c = read_ply(cloud)
    pts = np.stack([c["x"], c["y"], c["z"]], axis=1)
    return float(np.mean(scene_distance(m, pts) <= metres)), len(pts)


def model(tmp, scenario="bridge1", robot=None):
    """The MuJoCo model `surveyor scenario mjcf` writes of `scenario`."""
    xml = Path(tmp) / "model.xml"
    cmd = [BINARY, "scenario", "mjcf", str(scenario), "--out", str(xml)]
    subprocess.run(cmd + (["--robot", robot] if robot else []), check=True,
                   stdout=subprocess.DEVNULL)
    return mujoco.MjModel.from_xml_path(str(xml))


def polygon_distances(points, vertices):
    """Distance from each point to a planar convex or concave polygon (its
    vertices in order): to its plane over its inside, else to its nearest
    edge. Also the polygon's unit normal."""
    v = np.asarray(vertices, dtype=float)
    # Newell's normal: right for concave polygons too (anticlockwise
    # vertices give the outward normal).
    w = np.roll(v, -1, axis=0)
    n = np.array([np.sum((v[:, 1] - w[:, 1]) * (v[:, 2] + w[:, 2])),
                  np.sum((v[:, 2] - w[:, 2]) * (v[:, 0] + w[:, 0])),
                  np.sum((v[:, 0] - w[:, 0]) * (v[:, 1] + w[:, 1]))])
    n /= np.linalg.norm(n)
    e1 = v[1] - v[0]
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(n, e1)
    rel = points - v[0]
    height = rel @ n
    p2 = np.stack([rel @ e1, rel @ e2], axis=1)
    q2 = np.stack([(v - v[0]) @ e1, (v - v[0]) @ e2], axis=1)
    inside = np.zeros(len(points), dtype=bool)
    edge = np.full(len(points), np.inf)
    for a, b, a3, b3 in zip(q2, np.roll(q2, -1, axis=0), v, np.roll(v, -1, axis=0)):
        # Crossings of a ray along +u (even-odd rule).
        crosses = (a[1] > p2[:, 1]) != (b[1] > p2[:, 1])
        t = (p2[:, 1] - a[1]) / np.where(b[1] != a[1], b[1] - a[1], 1.0)
        inside ^= crosses & (p2[:, 0] < a[0] + t * (b[0] - a[0]))
        ab = b3 - a3
        s = np.clip(((points - a3) @ ab) / max(ab @ ab, 1e-24), 0.0, 1.0)
        edge = np.minimum(edge, np.linalg.norm(points - (a3 + s[:, None] * ab), axis=1))
    return np.where(inside, np.abs(height), edge), n


def face_scores(m, model_json, skip_normals=(), lam=0.05, mu_deg=10.0, spacing=0.01):
    """Pudney's acceptance on faces (SPEC §6), judged here on the MuJoCo
    model: for each true face (the exposed samples of one plane), the share
    of its samples within λ of a model polygon whose normal is within μ of
    the face's. Faces resting on the table (normal down at z = 0) and those
    whose normal is in `skip_normals` (given a priori) do not count. A list
    of (normal, plane offset, samples, share within λ)."""
    pts, nrm = surface_samples(m, spacing=spacing, normals=True)
    cos_mu = np.cos(np.radians(mu_deg))
    keep = ~((nrm[:, 2] < -cos_mu) & (np.abs(pts[:, 2]) < 1e-6))
    for a in skip_normals:
        keep &= nrm @ np.asarray(a, dtype=float) <= cos_mu
    pts, nrm = pts[keep], nrm[keep]
    ok = np.zeros(len(pts), dtype=bool)
    for seg in model_json["segments"]:
        if seg.get("kind") != "polygon" or len(seg["vertices"]) < 3:
            continue
        dist, n = polygon_distances(pts, seg["vertices"])
        ok |= (dist <= lam) & (nrm @ n > cos_mu)
    keys = np.round(np.concatenate([nrm, np.einsum("ij,ij->i", nrm, pts)[:, None]], axis=1), 3)
    faces, index = np.unique(keys, axis=0, return_inverse=True)
    index = index.ravel()
    return [(tuple(float(x) for x in f[:3]), float(f[3]), int(np.sum(index == k)),
             float(np.mean(ok[index == k]))) for k, f in enumerate(faces)]
