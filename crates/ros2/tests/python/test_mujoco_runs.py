"""surveyor's loops against a MuJoCo arm (issue 47): a scenario's arm
simulated with real dynamics by `mujoco_robot.py` (PD + gravity
compensation, torques clipped, 2 ms steps) at well above real time, served
over Cyclone DDS, surveyor's driver taking it for a robot. MuJoCo's own
contact detection judges safety: no arm geom may touch a scene geom.

- `explore --ros2`, Stage One with four viewpoints, on bridge1's DENSO: the
  cloud lies on the true surfaces (95 % of its points within 30 mm of the
  scene's solids, measured in the MuJoCo model itself) as the in-process
  run's does, and covers A1 (SPEC §6, on samples of the model's surfaces,
  which give the in-process run's judged A1 within a point) within 5
  points of it.
- Both stages on bridge1 (acceptance 1): each stage ends by its own rule;
  A1 coverage and the share of discs identified within 5 points of the
  in-process run's; each stage's robot time per viewpoint within 20 % of
  it (SURVEYOR_MUJOCO_LONG=1: five minutes).
- `follow --ros2` on block1 with arm4 (acceptance 2): ends by the
  algorithm's own rule, its model's vertices within λ of the true surface
  as in process (each face's share within λ is printed: see the test;
  SURVEYOR_MUJOCO_LONG=1: one to three minutes).

SURVEYOR_MUJOCO_RATE sets the robot's rate (robot seconds per wall second);
SURVEYOR_EXPLORE_RUN may name the in-process run of bridge1's README command
(`.ci/run` makes it) rather than running it again.
"""

import csv
import json
import os
import subprocess
from pathlib import Path

import numpy as np
import pytest
from mujoco_judge import (BINARY, RATE, ROOT, coverage, drive, face_scores, model,
                          scene_distance, within)

A1 = ([-1.1, -1.1, -0.625], [1.1, 1.1, 1.575])  # bridge1's [regions.a1]


def in_process(tmp_path, args):
    out = tmp_path / "in_process"
    subprocess.run([BINARY, "explore", "--scenario", "bridge1", *args, "--out", str(out)],
                   check=True, stdout=subprocess.DEVNULL)
    return out


def test_explore_drives_a_mujoco_arm(tmp_path):
    args = ["--stages", "one", "--max-viewpoints", "4"]
    run = drive(tmp_path, "bridge1", ["explore", "--scenario", "bridge1", *args])
    assert run.returncode == 0, run.stderr
    assert run.contacts == [], run.contacts[:20]
    assert "contacts: 0 " in run.said, run.said
    out, ref = tmp_path / "run", in_process(tmp_path, args)
    m = model(tmp_path)
    ours, n = within(m, out / "cloud.ply", 0.03)
    theirs, n_ref = within(m, ref / "cloud.ply", 0.03)
    a1_ours, a1_theirs = coverage(m, out / "cloud.ply", A1), coverage(m, ref / "cloud.ply", A1)
    robot_s = json.loads((out / "run.json").read_text())["robot_time_s"]["total"]
    ref_json = json.loads((ref / "run.json").read_text())
    print(f"over ROS 2, MuJoCo at rate {RATE}: {n} points, {100 * ours:.2f} % within 30 mm, "
          f"A1 {100 * a1_ours:.1f} % (our samples), wall {run.wall_s:.0f} s, robot {robot_s:.0f} s; "
          f"in process: {n_ref} points, {100 * theirs:.2f} %, A1 {100 * a1_theirs:.1f} % "
          f"(our samples; the judge's {100 * ref_json['coverage']['A1']:.1f} %), "
          f"robot {ref_json['robot_time_s']['total']:.0f} s")
    assert ours >= 0.95, ours
    assert ours >= theirs - 0.02, (ours, theirs)
    # Our samples give the judge's A1 (within a point), and the run over
    # MuJoCo covers about as much as the run in process.
    assert abs(a1_theirs - ref_json["coverage"]["A1"]) < 0.01, (a1_theirs, ref_json["coverage"])
    assert a1_ours >= a1_theirs - 0.05, (a1_ours, a1_theirs)


def identified_share(run):
    """The share of a run's discs identified (their most probable material
    at p >= 0.8, Paul §5.4; discs.csv), which needs no ground truth."""
    with open(run / "discs.csv") as f:
        rows = list(csv.DictReader(f))
    best = [max(float(v) for k, v in r.items() if k.startswith("p_")) for r in rows]
    return sum(p >= 0.8 for p in best) / len(best)


@pytest.mark.skipif(not os.environ.get("SURVEYOR_MUJOCO_LONG"),
                    reason="both stages take 5 minutes: SURVEYOR_MUJOCO_LONG=1 runs them")
def test_both_stages_on_a_mujoco_denso(tmp_path):
    run = drive(tmp_path, "bridge1", ["explore", "--scenario", "bridge1"])
    assert run.returncode == 0, run.stderr
    assert run.contacts == [], run.contacts[:20]
    assert "contacts: 0 " in run.said, run.said
    given = os.environ.get("SURVEYOR_EXPLORE_RUN")
    out, ref = tmp_path / "run", Path(given) if given else in_process(tmp_path, [])
    ours = json.loads((out / "run.json").read_text())
    theirs = json.loads((ref / "run.json").read_text())
    m = model(tmp_path)
    a1 = [coverage(m, r / "cloud.ply", A1) for r in (out, ref)]
    ident = [identified_share(r) for r in (out, ref)]
    robot = [r["robot_time_s"] for r in (ours, theirs)]
    views = [r["viewpoints"] for r in (ours, theirs)]
    per_view = [[r[f"stage_{s}"] / max(v[f"stage_{s}"], 1) for s in ("one", "two")]
                for r, v in zip(robot, views)]
    print(f"both stages over MuJoCo at rate {RATE}: wall {run.wall_s:.0f} s; "
          f"viewpoints {views[0]} against {views[1]} in process; "
          f"ends {ours['termination']}/{ours['stage_two_termination']} against "
          f"{theirs['termination']}/{theirs['stage_two_termination']}; "
          f"A1 {100 * a1[0]:.1f} % against {100 * a1[1]:.1f} % (our samples; the judge's "
          f"{100 * theirs['coverage']['A1']:.1f} % in process); "
          f"discs identified {100 * ident[0]:.1f} % against {100 * ident[1]:.1f} %; "
          f"robot time {robot[0]['total']:.0f} s against {robot[1]['total']:.0f} s, "
          f"per viewpoint {per_view[0][0]:.0f} and {per_view[0][1]:.0f} s against "
          f"{per_view[1][0]:.0f} and {per_view[1][1]:.0f} s")
    # Each stage ends by its own rule (A§3.2, §3.3): Stage One as the
    # in-process run's (its information measures converged), Stage Two on
    # its viewpoint budget or with no disc left to target.
    assert ours["termination"] == theirs["termination"], ours["termination"]
    assert ours["stage_two_termination"] in ("viewpoint_budget", "no_targetable_disc"), \
        ours["stage_two_termination"]
    assert abs(a1[0] - a1[1]) <= 0.05, a1
    assert abs(ident[0] - ident[1]) <= 0.05, ident
    # The robot's time for the same work: each stage's per viewpoint within
    # 20 % of the in-process clock model's. The total also counts how many
    # viewpoints Stage One took before its information converged, which
    # follows what the scans happened to see (10 to 14 over MuJoCo, 14 in
    # process): printed above, not asserted.
    for stage in (0, 1):
        assert abs(per_view[0][stage] - per_view[1][stage]) <= 0.2 * per_view[1][stage], per_view


@pytest.mark.skipif(not os.environ.get("SURVEYOR_MUJOCO_LONG"),
                    reason="the follow takes 1-3 minutes: SURVEYOR_MUJOCO_LONG=1 runs it")
def test_follow_drives_a_mujoco_arm4(tmp_path):
    cmd = ["follow", "--scenario", "block1", "--robot", "arm4"]
    run = drive(tmp_path, "block1", cmd, robot="arm4")
    assert run.returncode == 0, run.stderr
    assert run.contacts == [], run.contacts[:20]
    assert "contacts: 0 " in run.said, run.said
    ours = json.loads((tmp_path / "run" / "run.json").read_text())
    assert ours["completed"] and ours["termination"] == "surface_complete", ours["termination"]
    # Over ROS 2 the run knows no truth: the faces are judged here, in the
    # MuJoCo model (face_scores), a judge checked first against surveyor's
    # own on the in-process run (the same faces, within a point).
    ref = tmp_path / "in_process"
    subprocess.run([BINARY, *cmd, "--out", str(ref)], check=True, stdout=subprocess.DEVNULL)
    theirs = json.loads((ref / "run.json").read_text())
    m = model(tmp_path, "block1", "arm4")
    judged = face_scores(m, json.loads((ref / "surface_model.json").read_text()),
                         theirs["a_priori_faces"])
    scored = sorted((tuple(f["normal"]), f["within_lambda_fraction"])
                    for f in theirs["score"]["faces"])
    assert len(judged) == len(scored), (judged, scored)
    for (n, _, _, share), (n_ref, share_ref) in zip(
            sorted(judged, key=lambda f: (f[0], f[3])), scored):
        assert n == n_ref and abs(share - share_ref) < 0.01, (judged, scored)
    faces = face_scores(m, json.loads((tmp_path / "run" / "surface_model.json").read_text()),
                        ours["a_priori_faces"])
    print(f"follow over MuJoCo at rate {RATE}: wall {run.wall_s:.0f} s, {ours['sets']} sets "
          f"(in process {theirs['sets']}), robot time {ours['robot_time_s']['total']:.0f} s "
          f"(in process {theirs['robot_time_s']['total']:.0f} s), faces within λ "
          + ", ".join(f"{n} at {off:.2f}: {100 * share:.1f} %" for n, off, _, share in faces))
    assert len(faces) == len(scored)
    # The model's vertices lie on the true surface as the in-process runs'
    # do from starts 1 cm apart (97.8-100 % within λ, the farthest up to
    # 65 mm: a polygon reaching past an edge). That every face is also
    # 90 % modelled (issue 47, acceptance 2) is the follower's to hold, not
    # the robot's: from those starts, in process, 3 of 6 runs end "surface
    # complete" with faces at 9-52 % (see the README), so it is printed
    # above, not asserted.
    model_json = json.loads((tmp_path / "run" / "surface_model.json").read_text())
    vertices = np.array([v for s in model_json["segments"]
                         if s["kind"] == "polygon" and not s["initial"] for v in s["vertices"]])
    dist = scene_distance(m, vertices)
    print(f"{len(vertices)} model vertices, {100 * np.mean(dist <= 0.05):.1f} % within λ, "
          f"the farthest {1000 * dist.max():.1f} mm from the scene")
    assert len(vertices) >= 20 and np.mean(dist <= 0.05) >= 0.95, dist


@pytest.mark.skipif(not os.environ.get("SURVEYOR_MUJOCO_LONG"),
                    reason="the UR5's Stage One takes minutes: SURVEYOR_MUJOCO_LONG=1 runs it")
def test_stage_one_on_a_mujoco_ur5_from_its_urdf(tmp_path):
    # Acceptance 3: the UR5 of data/robots/ur5 (its URDF inertials, its STL
    # collision meshes as MuJoCo sees them: their convex hulls, which hold
    # the meshes, so a contact of a hull is at worst a false alarm).
    scenario = ROOT / "data/scenarios/ur5_bridge.toml"
    run = drive(tmp_path, scenario, ["explore", "--scenario", str(scenario), "--stages", "one"])
    assert run.returncode == 0, run.stderr
    assert run.contacts == [], run.contacts[:20]
    assert "contacts: 0 " in run.said, run.said
    ours = json.loads((tmp_path / "run" / "run.json").read_text())
    share, n = within(model(tmp_path, scenario), tmp_path / "run" / "cloud.ply", 0.03)
    print(f"UR5 Stage One over MuJoCo at rate {RATE}: wall {run.wall_s:.0f} s, "
          f"{ours['viewpoints']['stage_one']} viewpoints, ends {ours['termination']}, "
          f"robot time {ours['robot_time_s']['total']:.0f} s, {n} points, "
          f"{100 * share:.2f} % within 30 mm")
    assert ours["termination"] == "information_converged", ours["termination"]
    assert share >= 0.95, share
