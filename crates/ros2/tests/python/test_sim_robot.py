"""`surveyor sim-robot --ros2` against Eclipse Cyclone DDS, an independent
DDS implementation (issue 26, acceptance 2): the ROS 2 types are written
here as IDL structs with ROS 2's DDS names; no ROS installation.

- /joint_states carries the scenario's joint names and start joints;
- /scan is a LaserScan with the URG-04LX's rays, intensities and ranges
  within its limits, in the `scanner` frame;
- a JointTrajectory published on the controller's topic moves the robot:
  its joint states reach the goal.

Discovery stays on loopback, without multicast; the domain is a random one
so that concurrent runs do not meet.
"""

import os
import signal
import subprocess
import time
from dataclasses import dataclass
from pathlib import Path

import pytest
import ros_domain
from cyclonedds.core import Policy, Qos
from cyclonedds.domain import DomainParticipant
from cyclonedds.idl import IdlStruct
from cyclonedds.idl.types import float32, float64, int32, sequence, uint8, uint32
from cyclonedds.pub import DataWriter
from cyclonedds.sub import DataReader
from cyclonedds.topic import Topic
from cyclonedds.util import duration

ROOT = Path(__file__).resolve().parents[4]
BINARY = os.environ.get("SURVEYOR_BIN", str(ROOT / "target/release/surveyor"))
# bridge1: the DENSO VM-6083 crouched in the channel (SPEC §4).
START = [0.0, -0.9599310885968813, 2.8797932657906435, 0.0, -1.9198621771937625, 0.0]
NAMES = ["joint1", "joint2", "joint3", "joint4", "joint5", "joint6"]


@dataclass
class Time(IdlStruct, typename="builtin_interfaces::msg::dds_::Time_"):
    sec: int32
    nanosec: uint32


@dataclass
class Duration(IdlStruct, typename="builtin_interfaces::msg::dds_::Duration_"):
    sec: int32
    nanosec: uint32


@dataclass
class Header(IdlStruct, typename="std_msgs::msg::dds_::Header_"):
    stamp: Time
    frame_id: str


@dataclass
class JointState(IdlStruct, typename="sensor_msgs::msg::dds_::JointState_"):
    header: Header
    name: sequence[str]
    position: sequence[float64]
    velocity: sequence[float64]
    effort: sequence[float64]


@dataclass
class LaserScan(IdlStruct, typename="sensor_msgs::msg::dds_::LaserScan_"):
    header: Header
    angle_min: float32
    angle_max: float32
    angle_increment: float32
    time_increment: float32
    scan_time: float32
    range_min: float32
    range_max: float32
    ranges: sequence[float32]
    intensities: sequence[float32]


@dataclass
class JointTrajectoryPoint(IdlStruct, typename="trajectory_msgs::msg::dds_::JointTrajectoryPoint_"):
    positions: sequence[float64]
    velocities: sequence[float64]
    accelerations: sequence[float64]
    effort: sequence[float64]
    time_from_start: Duration


@dataclass
class JointTrajectory(IdlStruct, typename="trajectory_msgs::msg::dds_::JointTrajectory_"):
    header: Header
    joint_names: sequence[str]
    points: sequence[JointTrajectoryPoint]


@dataclass
class Range(IdlStruct, typename="sensor_msgs::msg::dds_::Range_"):
    header: Header
    radiation_type: uint8
    field_of_view: float32
    min_range: float32
    max_range: float32
    range: float32


# ROS 2's default QoS: reliable, volatile, keep last 10.
QOS = Qos(
    Policy.Reliability.Reliable(duration(seconds=1)),
    Policy.Durability.Volatile,
    Policy.History.KeepLast(10),
)

LOOPBACK = (
    "<CycloneDDS><Domain id='any'><General><Interfaces>"
    "<NetworkInterface address='127.0.0.1'/></Interfaces>"
    "<AllowMulticast>false</AllowMulticast></General>"
    "<Discovery><ParticipantIndex>auto</ParticipantIndex><Peers>"
    "<Peer address='127.0.0.1'/></Peers></Discovery></Domain></CycloneDDS>"
)


def serve(scenario, domain):
    env = dict(os.environ, ROS_DOMAIN_ID=str(domain))
    return subprocess.Popen(
        [BINARY, "sim-robot", "--scenario", scenario, "--ros2", "--for", "120"],
        env=env,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )


def stop(proc):
    proc.send_signal(signal.SIGINT)  # Ctrl-C: a clean stop with a summary
    out, err = proc.communicate(timeout=20)
    print(out, err)
    assert proc.returncode == 0, err
    return out


@pytest.fixture(scope="module")
def robot():
    domain = ros_domain.pick()
    proc = serve("bridge1", domain)
    os.environ["CYCLONEDDS_URI"] = LOOPBACK
    participant = DomainParticipant(domain)
    yield participant, proc
    out = stop(proc)
    served = [line for line in out.splitlines() if line.startswith("served:")]
    assert served and " 0 trajectories" not in served[0], out


def first(reader, timeout_s=30.0, accept=lambda m: True):
    end = time.monotonic() + timeout_s
    while time.monotonic() < end:
        for m in reader.take(N=100):
            if accept(m):
                return m
        time.sleep(0.02)
    raise AssertionError(f"nothing accepted within {timeout_s} s")


def test_joint_states_carry_the_scenario_s_joints(robot):
    participant, _ = robot
    reader = DataReader(participant, Topic(participant, "rt/joint_states", JointState), qos=QOS)
    js = first(reader)
    assert list(js.name) == NAMES
    assert js.position == pytest.approx(START, abs=1e-12)
    assert js.header.stamp.sec > 1_700_000_000  # wall-clock stamps


def test_scans_are_the_urg_s(robot):
    participant, _ = robot
    reader = DataReader(participant, Topic(participant, "rt/scan", LaserScan), qos=QOS)
    scan = first(reader)
    assert scan.header.frame_id == "scanner"
    assert len(scan.ranges) == 342 == len(scan.intensities)
    assert scan.angle_increment == pytest.approx(0.36 * 3.141592653589793 / 180, rel=1e-5)
    assert scan.angle_min == pytest.approx(-scan.angle_max)
    hits = [(r, i) for r, i in zip(scan.ranges, scan.intensities) if r != float("inf")]
    assert len(hits) > 100
    assert all(scan.range_min <= r <= scan.range_max and i > 0 for r, i in hits)


def test_a_trajectory_moves_the_robot(robot):
    participant, proc = robot
    goal = list(START)
    goal[0] += 0.3
    goal[4] += 0.2
    writer = DataWriter(
        participant,
        Topic(participant, "rt/joint_trajectory_controller/joint_trajectory", JointTrajectory),
        qos=QOS,
    )
    reader = DataReader(participant, Topic(participant, "rt/joint_states", JointState), qos=QOS)
    first(reader)  # discovery done both ways once states flow
    point = JointTrajectoryPoint(goal, [], [], [], Duration(1, 0))
    end = time.monotonic() + 30
    reached = None
    while reached is None and time.monotonic() < end:
        writer.write(JointTrajectory(Header(Time(0, 0), ""), NAMES, [point]))
        for m in reader.take(N=100):
            if m.position == pytest.approx(goal, abs=1e-9):
                reached = m
        time.sleep(0.2)
    assert reached is not None, "the joint states never reached the goal"
    assert proc.poll() is None, "sim-robot ended"


def test_range_finders_publish_ranges():
    """block1's point robot: a Range per range finder, in its frame, within
    its range or +inf (REP 117)."""
    domain = ros_domain.pick()
    proc = serve("block1", domain)
    os.environ["CYCLONEDDS_URI"] = LOOPBACK
    participant = DomainParticipant(domain)
    try:
        readers = [
            DataReader(participant, Topic(participant, f"rt/range/finder_{k}", Range), qos=QOS)
            for k in range(26)  # point3 carries 26 range finders
        ]
        got = [first(r) for r in readers]
    finally:
        stop(proc)
    for k, r in enumerate(got):
        assert r.header.frame_id == f"range_finder_{k}"
        assert r.radiation_type == 1
        assert r.range == float("inf") or 0.0 <= r.range <= r.max_range
    # The start pose is δ = 0.2 m over block1's top: the downward sensors see it.
    assert sum(r.range != float("inf") for r in got) >= 5
