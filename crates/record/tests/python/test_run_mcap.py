"""run.mcap of an exploration and of a surface-following run, read by
independent readers (issue 26, acceptance 3).

The run folders come from SURVEYOR_EXPLORE_RUN and SURVEYOR_FOLLOW_RUN (CI
passes the README's explore run and its follow run); without them the
tests make their own with SURVEYOR_BIN (default target/release/surveyor;
conftest.py).

- Foxglove's `mcap` + `mcap-ros2-support` decode every message with the
  schemas the bag carries;
- `rosbags` reads the file too, and its built-in ROS 2 Humble definitions
  decode each message type to the same values (our layout is ROS's);
- one sweep cloud per row of viewpoints.csv, together holding every point of
  cloud.ply;
- the joint-state stream replays the executed motions: every waypoint of
  path.csv and every viewpoint's joints appear in it, in order;
- each LaserScan, placed by /tf_static and the /tf in force at its stamp,
  gives the points of the sweep clouds (the frames are right);
- (`surveyor map --bag` of the run's bag gives the run's cloud.ply and
  mesh.ply byte for byte: test_rosbags_bag.py);
- a follow run's bag: a Range per finder per step in frames on the robot,
  joint states through every step, the model's outlines; `surveyor model
  --bag` takes one set per model update of the run.
"""

import json
import subprocess

import numpy as np
import pytest
from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory

from conftest import BINARY, read_rows


def decode_all(path):
    """Every message, decoded by mcap-ros2-support: (topic, log_time, msg)."""
    out = []
    with open(path, "rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        stats = reader.get_summary().statistics
        for _schema, channel, message, msg in reader.iter_decoded_messages(log_time_order=False):
            out.append((channel.topic, message.log_time, msg))
    assert len(out) == stats.message_count
    return out


@pytest.fixture(scope="module")
def decoded(run_dir):
    return decode_all(run_dir / "run.mcap")


def topic(decoded, name):
    return [(t, m) for (c, t, m) in decoded if c == name]


def joints_of(row):
    return np.array([float(v) for k, v in row.items() if k[0] == "q" and k[1:].isdigit()])


def passes_through(states, wanted):
    """Every joint vector of `wanted` is one of `states`, in order."""
    i = 0
    for w in wanted:
        while i < len(states) and not np.allclose(states[i], w, atol=1e-9, rtol=0):
            i += 1
        assert i < len(states), f"joints {w} not reached in order"


def test_every_message_decodes_and_topics_are_there(decoded):
    topics = {c for (c, _, _) in decoded}
    for want in ["/tf_static", "/tf", "/joint_states", "/scan", "/surveyor/sweep",
                 "/surveyor/viewpoints", "/surveyor/discs"]:
        assert want in topics, want


def test_rosbags_reads_it_with_rosbags_own_humble_types(run_dir, decoded):
    from rosbags.highlevel import AnyReader
    from rosbags.typesys import Stores, get_typestore

    humble = get_typestore(Stores.ROS2_HUMBLE)
    n = 0
    first = {}
    with AnyReader([run_dir / "run.mcap"]) as reader:
        for conn, _t, raw in reader.messages():
            reader.deserialize(raw, conn.msgtype)
            if conn.topic not in first:
                first[conn.topic] = humble.deserialize_cdr(raw, conn.msgtype)
            n += 1
    assert n == len(decoded)
    js = first["/joint_states"]
    ours = topic(decoded, "/joint_states")[0][1]
    assert list(js.name) == list(ours.name)
    assert np.array_equal(js.position, np.array(ours.position))
    scan = first["/scan"]
    ours = topic(decoded, "/scan")[0][1]
    assert scan.angle_increment == pytest.approx(ours.angle_increment)
    assert np.array_equal(scan.ranges, np.array(ours.ranges, dtype=np.float32))
    assert np.array_equal(scan.intensities, np.array(ours.intensities, dtype=np.float32))
    discs = first["/surveyor/discs"]
    assert len(discs.markers) == len(topic(decoded, "/surveyor/discs")[0][1].markers)
    assert len(discs.markers) == len(read_rows(run_dir / "discs.csv"))


def cloud_ply_count(path):
    with open(path, "rb") as f:
        for line in f:
            if line.startswith(b"element vertex"):
                return int(line.split()[2])
    raise AssertionError("no vertex count")


def cloud_points(msg):
    data = np.frombuffer(bytes(msg.data), dtype=np.float32).reshape(-1, 4)
    assert data.shape[0] == msg.width * msg.height
    return data


def test_one_sweep_cloud_per_viewpoint_holding_the_cloud(run_dir, decoded):
    rows = read_rows(run_dir / "viewpoints.csv")
    sweeps = topic(decoded, "/surveyor/sweep")
    assert len(sweeps) == len(rows)
    total = sum(m.width * m.height for (_, m) in sweeps)
    assert total == cloud_ply_count(run_dir / "cloud.ply")
    stamps = [t for (t, _) in sweeps]
    assert stamps == sorted(stamps)
    viewpoints = topic(decoded, "/surveyor/viewpoints")[0][1]
    assert len(viewpoints.markers) == len(rows)


def test_joint_states_replay_the_executed_motions(run_dir, decoded):
    states = topic(decoded, "/joint_states")
    times = [t for (t, _) in states]
    assert times == sorted(times)
    q = np.array([m.position for (_, m) in states])
    # The waypoints of every viewpoint's path, then the viewpoint itself.
    wanted = []
    path = read_rows(run_dir / "path.csv")
    for row in read_rows(run_dir / "viewpoints.csv"):
        wanted += [joints_of(p) for p in path if p["k"] == row["k"]]
        wanted.append(joints_of(row))
    passes_through(q, wanted)


def test_the_bag_s_clock_spans_the_run_s_robot_time(run_dir, follow_dir, decoded):
    """run.mcap is stamped on the robot clock: its messages span run.json's
    robot_time_s (within 1 %), which is the sum of the viewpoints' (or the
    steps') robot times; a scan lasts its scan_time."""
    for folder, rows, msgs in [
        (run_dir, read_rows(run_dir / "viewpoints.csv"), decoded),
        (follow_dir, read_rows(follow_dir / "steps.csv"), decode_all(follow_dir / "run.mcap")),
    ]:
        total = json.load(open(folder / "run.json"))["robot_time_s"]["total"]
        assert total > 0, folder
        assert abs(sum(float(r["robot_time_s"]) for r in rows) - total) <= 1e-5 * len(rows), folder
        span = (max(t for (_, t, _) in msgs) - min(t for (_, t, _) in msgs)) * 1e-9
        assert abs(span - total) <= 0.01 * total, (folder, span, total)
    scans = topic(decoded, "/scan")
    assert all(abs(m.scan_time - 0.1) < 1e-6 for (_, m) in scans)
    times = [t for (t, _) in scans]
    assert all(b - a >= 0.1e9 - 1 for a, b in zip(times, times[1:]))


def rotation(qx, qy, qz, qw):
    return np.array([
        [1 - 2 * (qy * qy + qz * qz), 2 * (qx * qy - qz * qw), 2 * (qx * qz + qy * qw)],
        [2 * (qx * qy + qz * qw), 1 - 2 * (qx * qx + qz * qz), 2 * (qy * qz - qx * qw)],
        [2 * (qx * qz - qy * qw), 2 * (qy * qz + qx * qw), 1 - 2 * (qx * qx + qy * qy)],
    ])


def matrix(tf):
    m = np.eye(4)
    r = tf.transform.rotation
    t = tf.transform.translation
    m[:3, :3] = rotation(r.x, r.y, r.z, r.w)
    m[:3, 3] = [t.x, t.y, t.z]
    return m


def test_scans_placed_by_tf_give_the_sweep_points(decoded):
    static = topic(decoded, "/tf_static")[0][1].transforms
    parent = {s.child_frame_id: (s.header.frame_id, matrix(s)) for s in static}
    tfs = topic(decoded, "/tf")
    tf_times = np.array([t for (t, _) in tfs])
    placed = []
    for t, scan in topic(decoded, "/scan"):
        k = np.searchsorted(tf_times, t, side="right") - 1
        assert k >= 0
        frames = dict(parent)
        frames.update({s.child_frame_id: (s.header.frame_id, matrix(s))
                       for s in tfs[k][1].transforms})
        m, frame = np.eye(4), "scanner"
        while frame != "map":
            up, link = frames[frame]
            m = link @ m
            frame = up
        r = np.array(scan.ranges, dtype=np.float64)
        a = scan.angle_min + scan.angle_increment * np.arange(len(r))
        ok = np.isfinite(r)
        local = np.stack([r * np.cos(a), r * np.sin(a), np.zeros_like(r)], axis=1)[ok]
        placed.append(local @ m[:3, :3].T + m[:3, 3])
    placed = np.concatenate(placed)
    swept = np.concatenate([cloud_points(m)[:, :3] for (_, m) in topic(decoded, "/surveyor/sweep")])
    assert placed.shape == swept.shape
    # Sweeps are stored in the order the scans were taken; ranges are
    # 32-bit floats (a few µm at 5 m), the angle increment too.
    err = np.linalg.norm(placed.astype(np.float32) - swept, axis=1)
    print("max error", err.max(), "points", len(err))
    assert err.max() < 1e-3, err.max()


def test_a_follow_run_s_bag(follow_dir):
    """Every message decodes (both readers); one Range per finder per step,
    in the finder's frame on its link; the joint states pass through every
    step's joints in order and end at the run's end joints; one outline
    marker per polygon of the model."""
    from rosbags.highlevel import AnyReader

    msgs = decode_all(follow_dir / "run.mcap")
    with AnyReader([follow_dir / "run.mcap"]) as r:
        assert sum(1 for _ in r.messages()) == len(msgs)
    steps = read_rows(follow_dir / "steps.csv")
    run = json.load(open(follow_dir / "run.json"))
    # The messages by topic, in bag order, in one pass (the bag holds a
    # Range per finder per step: a pass per finder took 7 s).
    by_topic = {}
    for (c, _, m) in msgs:
        by_topic.setdefault(c, []).append(m)
    finders = sorted((c for c in by_topic if c.startswith("/range/")),
                     key=lambda n: int(n.rsplit("_", 1)[1]))
    assert finders
    static = by_topic["/tf_static"][0].transforms
    placed = {s.child_frame_id for s in static}
    for k, name in enumerate(finders):
        readings = by_topic[name]
        assert len(readings) == len(steps), name
        assert readings[0].header.frame_id == f"range_finder_{k}"
        assert f"range_finder_{k}" in placed
    q = np.array([m.position for m in by_topic["/joint_states"]])
    passes_through(q, [joints_of(row) for row in steps])
    assert np.allclose(q[-1], run["end_joints"], atol=1e-12, rtol=0)
    model = by_topic["/surveyor/surface_model"][0]
    outlines = [m for m in model.markers if m.ns == "polygons"]
    assert len(outlines) == run["model"]["polygons"]


def test_model_from_a_follow_bag_takes_the_run_s_sets(follow_dir, tmp_path):
    """`surveyor model --bag` of a follow run: one sensor set per model
    update of the run, holding the readings of every step (the points
    themselves are checked against the rig's in crates/sim/tests/it/bag.rs)."""
    out = tmp_path / "model"
    done = subprocess.run(
        [BINARY, "model", "--bag", str(follow_dir / "run.mcap"), "--out", str(out)],
        check=True,
        capture_output=True,
        text=True,
    )
    run = json.load(open(follow_dir / "run.json"))
    points = sum(int(r["set_size"]) for r in read_rows(follow_dir / "steps.csv"))
    assert f"{run['model']['updates']} sets from" in done.stdout, done.stdout
    assert f"({points} readings with a return" in done.stdout, done.stdout
    stats = json.load(open(out / "stats.json"))
    assert stats["updates"] == run["model"]["updates"]
