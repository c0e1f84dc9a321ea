#!/usr/bin/env python3
"""A physics robot for surveyor's ROS 2 driver (issue 47): a scenario's arm
simulated by MuJoCo, served over ROS 2 (Eclipse Cyclone DDS, no ROS
installation), in place of `surveyor sim-robot`.

    python mujoco_robot.py --scenario bridge1 [--robot R] --rate 20 \
        --domain 42 --contacts contacts.jsonl

The model comes from `surveyor scenario mjcf` (SURVEYOR_BIN, default
target/release/surveyor) with its JSON sidecar. The physics steps every
2 ms on its own clock, `--rate` sim seconds per wall second (0: as fast as
it can; fallen more than 1 ms of wall time behind, it does not race to
catch up, its clock runs slower for a moment), and the robot publishes,
stamped on that clock (`start` + sim
time, as sim-robot stamps):

- /clock (rosgraph_msgs/Clock, best effort, keep last 1) every 5 ms (and
  at most every 0.5 ms of wall time);
- /joint_states every 10 ms (100 Hz): the joints' ROS names, the measured
  positions and velocities, the motor torques as efforts;
- /scan (sensor_msgs/LaserScan) every scan time (0.1 s): a free-running
  scanner whose beam i is cast at its own moment, `stamp + i *
  time_increment`, with mj_multiRay from the scanner site as the arm stands
  at the physics step nearest it (the arm's own geoms left out); a ray
  beyond the range is a miss; the range noise, material range bias and
  intensities of our sensor model (sensor::Scanner, sensor::ReflectionModel)
  from the hit geom's material (`--no-noise` for exact ranges);
- /range/finder_K (sensor_msgs/Range) every 0.1 s when the robot has range
  finders (mj_ray along each finder site's z axis, the range noise σ).

It executes each trajectory_msgs/JointTrajectory sent to
/joint_trajectory_controller/joint_trajectory as ros2_control's joint
trajectory controller does: the points on their time_from_start counted
from the header stamp (from now when the stamp is zero; a stamp already
past still counts, so the path jumps ahead: the summary says how many came
late and by how much), linearly interpolated, from where the arm is due
when the trajectory begins; a new
trajectory replaces the one under way from its start on; a single point
without a time runs at --joint-speed. A PD controller with gravity and
Coriolis compensation (MuJoCo's qfrc_bias) tracks the interpolated
positions and velocities, its gains weighted by the mass matrix (armature
included: each joint a critically damped loop of 50 rad/s), its torques
clipped to the model's limits: the arm lags, overshoots and settles as a
real one.

Every contact MuJoCo finds between an arm geom and a scene geom (`arm/...`
and `scene/...`) is logged to --contacts as a JSON line (sim time, the two
geoms, penetration depth). On SIGINT or SIGTERM it stops, and prints the
largest tracking error (while a trajectory runs and while the arm holds
still) and the number of contacts.

Faults for the driver to cope with (the tests' fault cases): the torque
limits scaled (`--torque-scale 0.25`: the DENSO cannot hold its wrist
against gravity; at 0.5 it still keeps up), a share
of the scans dropped (`--drop-scans 0.05`), Gaussian noise on the joint
positions reported (`--joint-noise 0.001`, rad).
"""

import argparse
import json
import math
import os
import signal
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

import mujoco
import numpy as np
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


# --- ROS 2 message types, by their DDS names (as test_sim_robot.py) ---

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
class Clock(IdlStruct, typename="rosgraph_msgs::msg::dds_::Clock_"):
    clock: Time


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


# ROS 2's default QoS (reliable, volatile, keep last 10), and its clock's.
QOS = Qos(Policy.Reliability.Reliable(duration(seconds=1)), Policy.Durability.Volatile,
          Policy.History.KeepLast(10))
# The driver keeps a motion's every joint state and scan: keep more here too,
# so a burst at a high rate is not overwritten before it is sent.
STREAM_QOS = Qos(Policy.Reliability.Reliable(duration(seconds=1)), Policy.Durability.Volatile,
                 Policy.History.KeepLast(1000))
CLOCK_QOS = Qos(Policy.Reliability.BestEffort, Policy.Durability.Volatile,
                Policy.History.KeepLast(1))
LOOPBACK = (
    "<CycloneDDS><Domain id='any'><General><Interfaces>"
    "<NetworkInterface address='127.0.0.1'/></Interfaces>"
    "<AllowMulticast>false</AllowMulticast></General>"
    "<Discovery><ParticipantIndex>auto</ParticipantIndex><Peers>"
    "<Peer address='127.0.0.1'/></Peers></Discovery></Domain></CycloneDDS>"
)

DT_S = 0.002           # physics step
CLOCK_PERIOD_S = 0.005  # as sim-robot
STATE_PERIOD_S = 0.01   # 100 Hz
RANGE_PERIOD_S = 0.1
OMEGA = 50.0           # the PD loop's natural frequency, rad/s (critically damped)
STILL_AFTER_S = 0.5    # the arm holds still this long after a trajectory's end and arrival
MAX_BEHIND_S = 0.001   # wall seconds the sim may fall behind its rate before it stops catching up


def as_slice(index):
    """Indices as a slice when they are consecutive (a view, not a copy, of
    the arrays they index), else as an array."""
    index = [int(i) for i in index]
    if index == list(range(index[0], index[0] + len(index))):
        return slice(index[0], index[0] + len(index))
    return np.array(index)


def stamp(ns):
    return Time(int(ns // 1_000_000_000), int(ns % 1_000_000_000))


def to_ns(t):
    return t.sec * 1_000_000_000 + t.nanosec


def load_model(scenario, robot, workdir):
    """The scenario's MJCF and sidecar, written by surveyor."""
    xml = Path(workdir) / "model.xml"
    cmd = [BINARY, "scenario", "mjcf", scenario, "--out", str(xml)]
    if robot:
        cmd += ["--robot", robot]
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
    model = mujoco.MjModel.from_xml_path(str(xml))
    sidecar = json.loads(xml.with_suffix(".json").read_text())
    return model, sidecar


class Trajectory:
    """The path the controller tracks: timed knots (sim seconds, joints),
    linear between them, as a joint trajectory controller samples it."""

    def __init__(self, t, q):
        self.knots = [(t, np.array(q, dtype=float))]
        self.still = np.zeros(len(q))
        self.seg = 0  # the segment sampled last: the next sample is most often in it

    def end_s(self):
        return self.knots[-1][0]

    def at(self, t):
        """Desired positions and velocities at sim time `t`."""
        k = self.knots
        if t <= k[0][0]:
            return k[0][1], self.still
        if t >= k[-1][0]:
            return k[-1][1], self.still
        lo = self.seg
        if not (lo + 1 < len(k) and k[lo][0] <= t < k[lo + 1][0]):
            lo, hi = 0, len(k) - 1
            while hi - lo > 1:
                mid = (lo + hi) // 2
                if k[mid][0] <= t:
                    lo = mid
                else:
                    hi = mid
            self.seg = lo
        (t0, q0), (t1, q1) = k[lo], k[lo + 1]
        v = (q1 - q0) / (t1 - t0)
        return q0 + v * (t - t0), v

    def replace(self, points, times, now, begin, joint_speed):
        """Take a new trajectory received at `now`, beginning at `begin`
        (now when None). A `begin` already past counts the points' times
        from it all the same, as ros2_control's controller does: the path
        jumps to where the new trajectory has the arm now."""
        begin = now if begin is None else begin
        here, _ = self.at(begin)
        kept = [k for k in self.knots if k[0] < begin]
        kept.append((begin, here))
        t, at = begin, here
        for p, after in zip(points, times):
            far = float(np.max(np.abs(p - at))) if len(p) else 0.0
            t = begin + after if begin + after > t else t + far / joint_speed
            kept.append((t, p))
            at = p
        # Forget what is long past.
        while len(kept) > 2 and kept[1][0] < now - 1.0:
            kept.pop(0)
        self.knots = kept
        self.seg = 0


class Robot:
    def __init__(self, args):
        self.args = args
        self.workdir = tempfile.TemporaryDirectory(prefix="mujoco_robot_")
        self.m, self.side = load_model(args.scenario, args.robot, self.workdir.name)
        m = self.m
        m.opt.timestep = DT_S
        self.d = mujoco.MjData(m)
        mujoco.mj_resetDataKeyframe(m, self.d, 0)
        mujoco.mj_forward(m, self.d)
        joints = self.side["joints"]
        self.names = [j["ros_name"] for j in joints]
        self.qadr = as_slice([m.jnt_qposadr[m.joint(j["name"]).id] for j in joints])
        self.vadr = as_slice([m.jnt_dofadr[m.joint(j["name"]).id] for j in joints])
        self.act = as_slice([m.actuator(j["name"]).id for j in joints])
        self.tau_max = args.torque_scale * np.array([j["torque_limit"] for j in joints])
        self.err = np.zeros(len(joints))
        self.abs_err = np.zeros(len(joints))
        self.tau = np.zeros(len(joints))
        self.accj = np.zeros(len(joints))
        self.acc = np.zeros(m.nv)
        self.weighted = np.zeros(m.nv)
        self.rng = np.random.default_rng(args.seed)
        self.traj = Trajectory(0.0, self.q())
        # Geoms: arm and scene, by id; the scene geoms' materials.
        self.arm_geom = np.array([m.geom(i).name.startswith("arm/") for i in range(m.ngeom)])
        self.scene_geom = np.array([m.geom(i).name.startswith("scene/") for i in range(m.ngeom)])
        materials = {mat["name"]: mat for mat in self.side["materials"]}
        self.refl = np.zeros(m.ngeom)
        self.rough = np.zeros(m.ngeom)
        for name, mat in self.side["scene_geoms"]:
            gid = m.geom(name).id
            self.refl[gid] = materials[mat]["reflectance"]
            self.rough[gid] = materials[mat]["roughness"]
        self.scene_only = np.array([1, 0, 0, 0, 0, 0], dtype=np.uint8)  # geom group 0
        # The scanner.
        sc = self.side["scanner"]
        self.scanner = sc
        if sc:
            self.scan_site = m.site(sc["site"]).id
            b = np.array(sc["bearings_rad"])
            self.bearings = b
            self.dirs = np.stack([np.zeros_like(b), -np.sin(b), np.cos(b)], axis=1)
            self.inc = sc["time_increment_s"]
            self.cfg = sc["config"]
            self.scan_period = self.cfg["scan_time_s"]
        self.finders = [(m.site(f["site"]).id, f["max_range_m"]) for f in self.side["range_finders"]]
        self.sigma_range = self.side["range_noise_sigma_m"]
        self.contacts_file = open(args.contacts, "w") if args.contacts else None
        # Figures for the summary.
        self.contacts = 0
        self.pairs = set()
        self.deepest = 0.0
        self.worst_moving = (0.0, None, 0.0)
        self.worst_still = (0.0, None, 0.0)
        self.trajectories = 0
        self.taken_s = 0.0  # when the last trajectory came, sim seconds
        self.refused = 0
        self.late = 0     # trajectories whose stamp had passed when they came
        self.latest = 0.0  # by how much, the most, sim seconds
        self.states = 0
        self.scans = 0
        self.dropped = 0
        self.readings = 0

    def q(self):
        return self.d.qpos[self.qadr].copy()

    # --- control ---

    def control(self, t):
        d = self.d
        q_des, v_des = self.traj.at(t)
        err, tau = self.err, self.tau
        np.subtract(q_des, d.qpos[self.qadr], out=err)
        # The PD's accelerations, weighted by the mass matrix (armature
        # included): every joint, coupled or not, a critically damped loop
        # of OMEGA while the torques stay within their limits.
        acc = self.accj
        np.subtract(v_des, d.qvel[self.vadr], out=acc)
        acc *= 2.0 * OMEGA
        acc += OMEGA * OMEGA * err
        self.acc[self.vadr] = acc
        mujoco.mj_mulM(self.m, d, self.weighted, self.acc)
        np.add(d.qfrc_bias[self.vadr], self.weighted[self.vadr], out=tau)
        np.maximum(tau, -self.tau_max, out=tau)
        np.minimum(tau, self.tau_max, out=tau)
        d.ctrl[self.act] = tau
        np.abs(err, out=self.abs_err)
        j = int(self.abs_err.argmax())
        e = float(self.abs_err[j])
        if t > max(self.traj.end_s(), self.taken_s) + STILL_AFTER_S:
            if e > self.worst_still[0]:
                self.worst_still = (e, self.names[j], t)
        elif e > self.worst_moving[0]:
            self.worst_moving = (e, self.names[j], t)

    def take(self, msg, now, start_ns):
        names = list(msg.joint_names)
        unknown = [n for n in names if n not in self.names]
        if unknown:
            self.refused += 1
            print(f"trajectory refused: joint {unknown[0]} is not one of {self.names}", file=sys.stderr)
            return
        index = [names.index(n) if n in names else None for n in self.names]
        due, _ = self.traj.at(now)
        points, times = [], []
        for k, p in enumerate(msg.points):
            if len(p.positions) != len(names):
                self.refused += 1
                print(f"trajectory refused: point {k} has {len(p.positions)} positions "
                      f"for {len(names)} joints", file=sys.stderr)
                return
            points.append(np.array([p.positions[i] if i is not None else due[j]
                                    for j, i in enumerate(index)]))
            times.append(to_ns(p.time_from_start) * 1e-9)
        ns = to_ns(msg.header.stamp)
        begin = (ns - start_ns) * 1e-9 if ns > 0 else None
        if begin is not None and begin < now:
            self.late += 1
            self.latest = max(self.latest, now - begin)
        self.traj.replace(points, times, now, begin, self.args.joint_speed)
        self.trajectories += 1
        self.taken_s = now

    # --- contacts ---

    def check_contacts(self, t):
        d = self.d
        for i in range(d.ncon):
            c = d.contact[i]
            g1, g2 = c.geom1, c.geom2
            if (self.arm_geom[g1] and self.scene_geom[g2]) or (self.arm_geom[g2] and self.scene_geom[g1]):
                if c.dist > 0:
                    continue  # within the margin, not touching
                a, s = (g1, g2) if self.arm_geom[g1] else (g2, g1)
                self.contacts += 1
                pair = (self.m.geom(a).name, self.m.geom(s).name)
                self.pairs.add(pair)
                self.deepest = max(self.deepest, -c.dist)
                if self.contacts_file:
                    self.contacts_file.write(json.dumps(
                        {"t": round(t, 6), "arm": pair[0], "scene": pair[1],
                         "depth_m": -c.dist}) + "\n")

    # --- sensing ---

    def cast(self, idx, raw):
        """Cast beams `idx` from where the scanner stands now into `raw`
        (distance, -1 for a miss; geom; normal; direction)."""
        d = self.d
        pnt = d.site_xpos[self.scan_site].copy()
        rot = d.site_xmat[self.scan_site].reshape(3, 3)
        vec = (self.dirs[idx] @ rot.T).reshape(-1)
        n = len(idx)
        geomid = np.zeros(n, dtype=np.int32)
        dist = np.zeros(n)
        normal = np.zeros(3 * n)
        mujoco.mj_multiRay(self.m, d, pnt, vec, self.scene_only, True, -1, geomid, dist, normal,
                           n, self.cfg["max_range_m"])
        raw["dist"][idx] = dist
        raw["geom"][idx] = geomid
        raw["normal"][idx] = normal.reshape(n, 3)
        raw["dir"][idx] = vec.reshape(n, 3)

    def scan_readings(self, raw):
        """A scan's ranges (inf for a miss) and intensities from its raw
        hits, with the sensor model's bias and noise (sensor::Scanner)."""
        dist, geomid, nrm, dirs = raw["dist"], raw["geom"], raw["normal"], raw["dir"]
        n = len(dist)
        cfg = self.cfg
        refl_model = cfg["reflection"]
        noise = cfg["noise"]
        # Both normals drawn for every ray, hit or not (as sensor::Scanner).
        n_range = self.rng.standard_normal(n)
        n_int = self.rng.standard_normal(n)
        hit = (geomid >= 0) & (dist >= cfg["min_range_m"]) & (dist <= cfg["max_range_m"])
        ranges = np.full(n, np.inf)
        intens = np.zeros(n)
        if not hit.any():
            return ranges, intens
        cos_inc = np.clip(np.einsum("ij,ij->i", nrm, -dirs), -1.0, 1.0)
        phi = np.minimum(np.abs(np.arccos(cos_inc)), math.pi / 2)
        g = np.where(hit, geomid, 0)
        cr, psi = self.refl[g], self.rough[g]
        width = refl_model["lobe_min_rad"] + refl_model["lobe_per_roughness_rad"] * psi
        lobe = np.exp(-0.5 * (phi / width) ** 2)
        bias = np.zeros(n)
        sigma = np.zeros(n)
        if not self.args.no_noise:
            if cfg["material_range_bias"]:
                bias = (-refl_model["specular_range_bias_m"] * cr * lobe
                        + refl_model["roughness_range_bias_m"] * psi * (1.0 - np.cos(phi)))
            if noise["enabled"]:
                sigma = np.where(dist <= noise["near_limit_m"], noise["sigma_near_m"],
                                 noise["relative_far"] * dist)
        r = dist + bias + sigma * n_range
        ok = hit & (r >= cfg["min_range_m"]) & (r <= cfg["max_range_m"])
        spec = cr * lobe
        diffuse = (1.0 - cr) * refl_model["diffuse_weight"] * np.cos(phi)
        expected = (refl_model["peak_intensity"] * (spec + diffuse)
                    * (refl_model["reference_range_m"] / np.maximum(dist, 0.05)) ** 2)
        rel = 0.0 if self.args.no_noise else refl_model["intensity_noise_rel"]
        ranges[ok] = r[ok]
        intens[ok] = np.maximum(expected * (1.0 + rel * n_int), 0.0)[ok]
        return ranges, intens

    def read_finder(self, site, max_range):
        d = self.d
        pnt = d.site_xpos[site].copy()
        vec = d.site_xmat[site].reshape(3, 3)[:, 2].copy()
        geomid = np.zeros(1, dtype=np.int32)
        dist = mujoco.mj_ray(self.m, d, pnt, vec, self.scene_only, True, -1, geomid)
        if dist < 0 or dist > max_range:
            return math.inf
        if self.sigma_range > 0 and not self.args.no_noise:
            dist += self.sigma_range * self.rng.standard_normal()
        return dist

    # --- the loop ---

    def run(self, stop):
        args, side, m, d = self.args, self.side, self.m, self.d
        ros2 = side["ros2"]
        os.environ.setdefault("CYCLONEDDS_URI", LOOPBACK)
        dp = DomainParticipant(args.domain)
        writer = lambda topic, typ, qos=QOS: DataWriter(dp, Topic(dp, "rt" + topic, typ), qos=qos)
        clock_w = writer("/clock", Clock, CLOCK_QOS)
        state_w = writer(ros2["joint_states_topic"], JointState, STREAM_QOS)
        scan_w = writer(ros2["scan_topic"], LaserScan, STREAM_QOS) if self.scanner else None
        range_w = [writer(f"{ros2['range_topic_prefix']}{k}", Range)
                   for k in range(len(self.finders))]
        traj_r = DataReader(dp, Topic(dp, "rt" + ros2["trajectory_topic"], JointTrajectory),
                            qos=Qos(Policy.Reliability.Reliable(duration(seconds=1)),
                                    Policy.Durability.Volatile, Policy.History.KeepLast(100)))
        start_ns = time.time_ns()
        wall0 = time.monotonic()
        t = 0.0
        step = 0
        next_clock = next_state = next_range = 0.0
        # /clock every 5 ms of sim time, and no more often than every
        # 0.5 ms of wall time: faster than real time, a message of every
        # 5 ms would cost more than the physics.
        clock_period = max(CLOCK_PERIOD_S, 0.0005 * args.rate)
        # Faults asked for: noise on the joint positions reported, scans
        # dropped (their own generator, so the sensor noise stays as without).
        faults = np.random.default_rng(args.seed + 1)
        # The scan under way: its beginning, its ranges so far.
        scan_begin, scan_next_beam = 0.0, 0
        if self.scanner:
            nb = len(self.bearings)
            new_raw = lambda: {"dist": np.full(nb, -1.0), "geom": np.full(nb, -1, dtype=np.int32),
                               "normal": np.zeros((nb, 3)), "dir": np.zeros((nb, 3))}
            raw = new_raw()
            b0 = float(np.float32(self.bearings[0]))
            binc = float(np.float32((self.bearings[-1] - self.bearings[0]) / max(nb - 1, 1)))
        print(f"{side['scenario']} ({side['robot']}, {len(self.names)} joints, "
              f"{len(self.finders)} range finders{', a scanner' if self.scanner else ''}) "
              f"in MuJoCo {mujoco.__version__} on ROS 2 domain {args.domain}, "
              f"rate {args.rate or 'as fast as it can'}", flush=True)
        while not stop["now"]:
            if args.rate > 0:
                ahead = wall0 + t / args.rate - time.monotonic()
                if ahead > 0:
                    time.sleep(ahead)
                elif ahead < -MAX_BEHIND_S:
                    # Fallen behind (the machine busy): the clock runs on
                    # from here, slower for a moment, rather than racing to
                    # catch up (a burst of sim time the driver cannot follow).
                    wall0 -= ahead + MAX_BEHIND_S
            now_ns = start_ns + int(round(t * 1e9))
            if step % 2 == 0:
                for msg in traj_r.take(N=100):
                    if isinstance(msg, JointTrajectory):  # not a writer's disposal
                        self.take(msg, t, start_ns)
            if t >= next_clock - 1e-9:
                next_clock += clock_period
                clock_w.write(Clock(stamp(now_ns)))
            if t >= next_state - 1e-9:
                next_state += STATE_PERIOD_S
                q = d.qpos[self.qadr]
                if args.joint_noise > 0:
                    q = q + args.joint_noise * faults.standard_normal(len(self.names))
                state_w.write(JointState(Header(stamp(now_ns), ""), self.names, q.tolist(),
                                         d.qvel[self.vadr].tolist(), d.ctrl[self.act].tolist()))
                self.states += 1
            if self.scanner:
                # Beams whose moment is nearest this step.
                while True:
                    hi = scan_next_beam
                    while hi < nb and scan_begin + hi * self.inc < t + DT_S / 2:
                        hi += 1
                    if hi > scan_next_beam:
                        self.cast(np.arange(scan_next_beam, hi), raw)
                        scan_next_beam = hi
                    if scan_next_beam < nb:
                        break
                    ranges, intens = self.scan_readings(raw)
                    if args.drop_scans > 0 and faults.random() < args.drop_scans:
                        self.dropped += 1
                    else:
                        scan_w.write(LaserScan(
                            Header(stamp(start_ns + int(round(scan_begin * 1e9))), "scanner"),
                            b0, float(np.float32(self.bearings[-1])), binc, self.inc,
                            self.scan_period, self.cfg["min_range_m"], self.cfg["max_range_m"],
                            ranges.astype(np.float32).tolist(),
                            intens.astype(np.float32).tolist()))
                        self.scans += 1
                    scan_begin += self.scan_period
                    scan_next_beam = 0
                    raw = new_raw()
                    if scan_begin >= t + DT_S / 2:
                        break
            if self.finders and t >= next_range - 1e-9:
                next_range += RANGE_PERIOD_S
                for k, ((site, max_range), w) in enumerate(zip(self.finders, range_w)):
                    r = self.read_finder(site, max_range)
                    w.write(Range(Header(stamp(now_ns), f"range_finder_{k}"), 1, 0.0, 0.0,
                                  max_range + 10 * self.sigma_range, r))
                self.readings += 1
            self.control(t)
            mujoco.mj_step(m, d)
            step += 1
            t = step * DT_S
            if d.ncon:
                self.check_contacts(t)
        wall = time.monotonic() - wall0
        if self.contacts_file:
            self.contacts_file.close()
        e, j, at = self.worst_moving
        es, js, ats = self.worst_still
        print(f"ran {t:.3f} s of sim time in {wall:.3f} s of wall time ({t / max(wall, 1e-9):.1f}x); "
              f"{self.states} joint states, {self.scans} scans ({self.dropped} dropped), "
              f"{self.readings} readings, "
              f"{self.trajectories} trajectories ({self.refused} refused, {self.late} came after "
              f"their stamp, by at most {1000 * self.latest:.1f} ms)")
        print(f"largest tracking error: {e:.3e} rad ({j} at {at:.3f} s) while moving; "
              f"{es:.3e} rad ({js} at {ats:.3f} s) holding still")
        print(f"contacts: {self.contacts} (pairs {sorted(self.pairs)}, deepest {self.deepest:.6f} m)",
              flush=True)


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--scenario", required=True)
    p.add_argument("--robot")
    p.add_argument("--rate", type=float, default=1.0,
                   help="sim seconds per wall second (0: as fast as it can)")
    p.add_argument("--domain", type=int, default=int(os.environ.get("ROS_DOMAIN_ID", "0")))
    p.add_argument("--contacts", help="log arm-scene contacts here (JSON lines)")
    p.add_argument("--seed", type=int, default=0, help="seed of the sensor noise")
    p.add_argument("--no-noise", action="store_true", help="exact ranges and intensities")
    p.add_argument("--joint-speed", type=float, default=1.0,
                   help="rad/s of a one-point trajectory without a time")
    p.add_argument("--for", dest="duration_s", type=float,
                   help="stop after this many wall seconds")
    faults = p.add_argument_group("faults")
    faults.add_argument("--torque-scale", type=float, default=1.0,
                        help="the model's torque limits times this (0.5: half as strong)")
    faults.add_argument("--drop-scans", type=float, default=0.0,
                        help="the share of /scan messages not sent (0.05: one in twenty)")
    faults.add_argument("--joint-noise", type=float, default=0.0,
                        help="σ of Gaussian noise on the joint positions reported, rad")
    args = p.parse_args()
    if not (0 < args.torque_scale <= 10):
        p.error(f"--torque-scale {args.torque_scale}: expected more than 0, at most 10")
    if not (0 <= args.drop_scans < 1):
        p.error(f"--drop-scans {args.drop_scans}: expected a share from 0 to below 1")
    if not (0 <= args.joint_noise <= 0.1):
        p.error(f"--joint-noise {args.joint_noise}: expected 0 to 0.1 rad")
    if args.rate < 0 or not math.isfinite(args.rate):
        p.error(f"--rate {args.rate}: expected sim seconds per wall second ≥ 0")
    if not 0 <= args.domain <= 232:
        p.error(f"--domain {args.domain}: expected a ROS domain id from 0 to 232")
    if not (args.joint_speed > 0 and math.isfinite(args.joint_speed)):
        p.error(f"--joint-speed {args.joint_speed}: expected more than 0")
    stop = {"now": False}

    def on_signal(signum, frame):
        stop["now"] = True

    signal.signal(signal.SIGINT, on_signal)
    signal.signal(signal.SIGTERM, on_signal)
    if args.duration_s:
        signal.signal(signal.SIGALRM, on_signal)
        signal.setitimer(signal.ITIMER_REAL, args.duration_s)
    robot = Robot(args)
    robot.run(stop)
    return 0


if __name__ == "__main__":
    sys.exit(main())
