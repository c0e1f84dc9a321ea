"""`surveyor explore --ros2` and `surveyor follow --ros2` driving
`surveyor sim-robot --ros2` (two processes talking DDS on loopback) make the
in-process runs of the same seed (issue 26, acceptance 1):

- explore on bridge1: viewpoints.csv and discs.csv equal the in-process
  run's, but for what only a ground truth gives (A1 coverage, the discs'
  true material) and the wall-clock columns; path.csv, cloud.ply and
  mesh.ply byte for byte;
- follow on block1 with arm4: steps.csv (but for its time columns) and
  surface_model.json.

The robot runs in lockstep (`--lockstep` on both sides: each scan, reading
and noise seed is asked for, so its noise is drawn in the in-process order;
each motion ends exactly on its goal). The simulated scanner reports what
its LaserScan carries (float32 ranges and intensities, float32 angles), so
nothing is lost on the way; the range finders' readings also go at full
precision on /surveyor/ranges, checked against their float32 Range.

Both runs also publish their live view (/tf, sweeps, markers): the runs
say how many messages it sent.

The in-process runs come from SURVEYOR_EXPLORE_RUN and SURVEYOR_FOLLOW_RUN
(CI passes the README's explore run and its follow run), else they are made
here with SURVEYOR_BIN (default target/release/surveyor).
"""

import csv
import os
import signal
import subprocess
from pathlib import Path

import ros_domain


ROOT = Path(__file__).resolve().parents[4]
BINARY = os.environ.get("SURVEYOR_BIN", str(ROOT / "target/release/surveyor"))

EXPLORE = ["explore", "--scenario", "bridge1"]
FOLLOW = ["follow", "--scenario", "block1", "--robot", "arm4"]


def in_process(tmp_path_factory, env, name, args):
    given = os.environ.get(env)
    if given:
        return Path(given)
    out = tmp_path_factory.mktemp(name) / name
    subprocess.run([BINARY, *args, "--no-timings", "--out", str(out)], check=True,
                   stdout=subprocess.DEVNULL)
    return out


def over_ros2(out, robot_args, run_args):
    """Run `run_args` with --ros2 against `sim-robot robot_args`, in a
    domain of their own; returns the robot's summary line."""
    env = dict(os.environ, ROS_DOMAIN_ID=str(ros_domain.pick()))
    robot = subprocess.Popen(
        [BINARY, "sim-robot", *robot_args, "--ros2", "--lockstep", "--joint-speed", "10",
         "--for", "1200"],
        env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        run = subprocess.run(
            [BINARY, *run_args, "--ros2", "--lockstep", "--no-timings", "--out", str(out)],
            env=env, capture_output=True, text=True, timeout=1200)
    finally:
        robot.send_signal(signal.SIGINT)  # Ctrl-C: a clean stop with a summary
        said, err = robot.communicate(timeout=30)
    print(run.stdout, run.stderr, said, err)
    assert run.returncode == 0, run.stderr
    assert robot.returncode == 0, err
    live = [line for line in run.stdout.splitlines() if line.startswith("live view:")]
    assert live and int(live[0].split()[2]) > 0, run.stdout
    assert "could not send" not in run.stderr, run.stderr
    return [line for line in said.splitlines() if line.startswith("served:")][0]


def rows(path):
    with open(path) as f:
        return list(csv.DictReader(f))


def same_rows(ours, theirs, skip):
    """Equal row for row, every column but those `skip` accepts."""
    a, b = rows(ours), rows(theirs)
    assert len(a) == len(b), (ours, len(a), len(b))
    assert list(a[0]) == list(b[0])
    kept = [k for k in a[0] if not skip(k)]
    for i, (x, y) in enumerate(zip(a, b)):
        for k in kept:
            assert x[k] == y[k], f"{ours.name} row {i}, {k}: {x[k]} against {y[k]}"


def test_explore_over_ros2_is_the_in_process_run(tmp_path_factory):
    ref = in_process(tmp_path_factory, "SURVEYOR_EXPLORE_RUN", "bridge1", EXPLORE)
    out = tmp_path_factory.mktemp("ros2") / "bridge1"
    served = over_ros2(out, ["--scenario", "bridge1"], EXPLORE)
    # Ground truth (coverage_a1) and wall-clock times (*_ms, and the robot
    # time's deciding, which is wall time when the reference run is timed)
    # aside: the robot clock's motions and sweeps are the in-process run's.
    same_rows(out / "viewpoints.csv", ref / "viewpoints.csv",
              lambda k: k == "coverage_a1" or k.endswith("_ms")
              or k in ("robot_time_s", "robot_deciding_s"))
    same_rows(out / "discs.csv", ref / "discs.csv", lambda k: k == "true_material")
    # No ground truth over ROS 2: no coverage, no true materials.
    assert {r["coverage_a1"] for r in rows(out / "viewpoints.csv")} == {""}
    assert {r["true_material"] for r in rows(out / "discs.csv")} == {"-1"}
    for name in ["path.csv", "cloud.ply", "mesh.ply"]:
        assert (out / name).read_bytes() == (ref / name).read_bytes(), name
    # The scans came over DDS: every sweep's.
    scans = int(served.split(" scans")[0].rsplit(" ", 1)[1])
    assert scans >= len(rows(out / "viewpoints.csv")), served


def test_follow_over_ros2_is_the_in_process_run(tmp_path_factory):
    ref = in_process(tmp_path_factory, "SURVEYOR_FOLLOW_RUN", "block1", FOLLOW)
    out = tmp_path_factory.mktemp("ros2") / "block1"
    served = over_ros2(out, ["--scenario", "block1", "--robot", "arm4"], FOLLOW)
    # The step's robot time holds its decision's wall time in a timed run.
    same_rows(out / "steps.csv", ref / "steps.csv",
              lambda k: k.endswith("_us") or k == "robot_time_s")
    model = "surface_model.json"
    assert (out / model).read_bytes() == (ref / model).read_bytes()
    # One reading of the 133 finders per step, asked for over DDS.
    readings = int(served.split(" readings")[0].rsplit(" ", 1)[1])
    assert readings == len(rows(out / "steps.csv")), served
