"""`surveyor scenario mjcf` against MuJoCo as an oracle (issue 47, step 3):
the model MuJoCo compiles from our MJCF is our robot and our scene.

- MuJoCo's forward kinematics of every link body, the scanner site and the
  tool site, at several joint vectors, is `surveyor fk`'s within 1e-9 m
  (and 1e-9 in each rotation matrix entry);
- MuJoCo's ray distances from the scanner's ray origins are the distances
  of our simulated sweep (`surveyor scan` with the noise and range bias off,
  written as float32 PLY) within 1e-6 m, on every ray that meets its
  surface less than 80 degrees from the normal (a float32 direction moves a
  grazing hit by more);
- the arm at its start joints touches nothing: MuJoCo finds no contact.
"""

import json
import os
import subprocess
from pathlib import Path

import mujoco
import numpy as np
import pytest
from mujoco_judge import read_ply

ROOT = Path(__file__).resolve().parents[4]
BINARY = os.environ.get("SURVEYOR_BIN", str(ROOT / "target/release/surveyor"))


def mjcf(tmp_path, scenario, robot=None):
    out = tmp_path / "model.xml"
    cmd = [BINARY, "scenario", "mjcf", scenario, "--out", str(out)]
    if robot:
        cmd += ["--robot", robot]
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
    model = mujoco.MjModel.from_xml_path(str(out))
    return model, json.loads(out.with_suffix(".json").read_text())


def fk(robot, q):
    tip = ["--tip", "tool0"] if robot.endswith(".urdf") else []  # the UR5's, as ur5_bridge's
    out = subprocess.run(
        [BINARY, "fk", "--robot", robot, *tip, "--joints", ",".join(repr(float(v)) for v in q),
         "--json"], check=True, capture_output=True, text=True).stdout
    return json.loads(out)


def joint_vectors(side, count=4, seed=7):
    """The start joints, zeros, and `count` random vectors within the limits."""
    rng = np.random.default_rng(seed)
    start = [j["start"] for j in side["joints"]]
    lo = np.array([j["min"] if j["min"] is not None else -np.pi for j in side["joints"]])
    hi = np.array([j["max"] if j["max"] is not None else np.pi for j in side["joints"]])
    return [start, [0.0] * len(start)] + [list(rng.uniform(lo, hi)) for _ in range(count)]


def pose(m, d, kind, name):
    """World pose of a body or site as a 4x4 matrix."""
    if kind == "site":
        x, r = d.site(name).xpos, d.site(name).xmat
    else:
        x, r = d.body(name).xpos, d.body(name).xmat
    t = np.eye(4)
    t[:3, :3] = np.asarray(r).reshape(3, 3)
    t[:3, 3] = x
    return t


UR5_BRIDGE = str(ROOT / "data/scenarios/ur5_bridge.toml")
UR5 = str(ROOT / "data/robots/ur5/ur5_robot.urdf")


@pytest.mark.parametrize("scenario,robot", [("bridge1", "denso-vm6083"),
                                            ("block1", "arm4"), (UR5_BRIDGE, UR5)])
def test_mujoco_s_kinematics_are_surveyor_fk_s(tmp_path, scenario, robot):
    m, side = mjcf(tmp_path, scenario, robot if scenario == "block1" else None)
    d = mujoco.MjData(m)
    mujoco.mj_kinematics(m, d)
    world_from_base = pose(m, d, "body", m.body(1).name)  # the base link's body
    checked, worst = 0, 0.0
    for q in joint_vectors(side):
        d.qpos[:] = q
        mujoco.mj_kinematics(m, d)
        ours = fk(robot, q)
        pairs = [(ours["tip"], pose(m, d, "site", "tool"))]
        if ours.get("sensor"):
            pairs.append((ours["sensor"], pose(m, d, "site", "scanner")))
        for f in ours["frames"]:
            name = f["name"] if f["name"] != "world" else "world_link"
            pairs.append((f["pose"], pose(m, d, "body", name)))
        for want, got in pairs:
            want = world_from_base @ np.array(want)
            worst = max(worst, np.max(np.abs(got[:3, 3] - want[:3, 3])))
            assert np.max(np.abs(got[:3, 3] - want[:3, 3])) < 1e-9, (q, want, got)
            assert np.max(np.abs(got[:3, :3] - want[:3, :3])) < 1e-9, (q, want, got)
            checked += 1
    print(f"{scenario}: {checked} frames, largest position difference {worst:.3e} m")
    assert checked >= 6 * 3


def test_mujoco_s_rays_are_our_sweep_s(tmp_path):
    # bridge1 with the scanner's noise and range bias off: exact ranges.
    text = subprocess.run([BINARY, "scenario", "show", "bridge1"], check=True,
                          capture_output=True, text=True).stdout
    text = text.replace("material_range_bias = true", "material_range_bias = false")
    section = text.index("[scanner.config.noise]")
    text = text[:section] + text[section:].replace("enabled = true", "enabled = false", 1)
    scenario = tmp_path / "exact.toml"
    scenario.write_text(text)
    m, side = mjcf(tmp_path, str(scenario))
    d = mujoco.MjData(m)
    mujoco.mj_resetDataKeyframe(m, d, 0)
    mujoco.mj_forward(m, d)
    compared = 0
    for q in joint_vectors(side, count=0)[:1] + [[0.3, -0.6, 2.2, 0.4, -1.2, 0.5]]:
        ply = tmp_path / "scan.ply"
        subprocess.run([BINARY, "scan", "--scenario", str(scenario), "--joints",
                        ",".join(repr(float(v)) for v in q), "--out", str(ply)],
                       check=True, stdout=subprocess.DEVNULL)
        s = read_ply(ply)
        assert len(s["x"]) > 10_000
        origin = np.stack([s["ox"], s["oy"], s["oz"]], axis=1)
        point = np.stack([s["x"], s["y"], s["z"]], axis=1)
        ours = np.linalg.norm(point - origin, axis=1)
        scene_only = np.array([1, 0, 0, 0, 0, 0], dtype=np.uint8)
        geomid = np.zeros(1, dtype=np.int32)
        normal = np.zeros(3)
        far, worst = 0, 0.0
        for o, p, r in zip(origin, point, ours):
            u = (p - o) / r
            got = mujoco.mj_ray(m, d, o, u, scene_only, True, -1, geomid, normal)
            assert got >= 0, f"MuJoCo misses the ray from {o} to {p}"
            if abs(np.dot(normal, u)) < np.cos(np.radians(80)):
                far += 1  # grazing
                continue
            worst = max(worst, abs(got - r))
            compared += 1
        print(f"{len(ours)} rays, {far} grazing, largest difference {worst:.3e} m")
        assert worst < 1e-6, worst
        assert far < 0.05 * len(ours), far
    assert compared > 20_000


@pytest.mark.parametrize("scenario,robot", [("bridge1", None), ("bridge3", None),
                                            ("block1", "arm4"), ("cube", None),
                                            (UR5_BRIDGE, None)])
def test_the_arm_at_its_start_touches_nothing(tmp_path, scenario, robot):
    m, _ = mjcf(tmp_path, scenario, robot)
    d = mujoco.MjData(m)
    mujoco.mj_resetDataKeyframe(m, d, 0)
    mujoco.mj_forward(m, d)
    touching = [(m.geom(c.geom1).name, m.geom(c.geom2).name, c.dist) for c in d.contact[:d.ncon]]
    assert touching == []
    # The names tell arm from scene: every geom is one or the other.
    names = [m.geom(i).name for i in range(m.ngeom)]
    assert all(n.startswith(("arm/", "scene/")) for n in names), names
