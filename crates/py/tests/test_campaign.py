"""Campaigns on Ray (issue 27, part 3): ``surveyor.campaign.run`` runs
every (scenario, seed, config) combination as a Ray task into its own run
folder and writes summary.csv and coverage.png; it is resumable.

* (a) a campaign of bridge1 and bridge2 x seeds 0-2 on a local Ray of 2
  CPUs writes the run folders ``surveyor.explore`` writes when the six runs
  are made one after another (run.json byte for byte), and summary.csv holds
  the rows built here from those run.json files (every column but
  ``wall_s``);
* (b) called again with the same ``out`` it runs nothing (no run.json
  touched, Ray not even started);
* (c) ``python -m surveyor.campaign`` killed (SIGKILL of its process group)
  once some runs are done: called again, the campaign runs only the
  missing ones (the finished run.json files untouched) and ends with (a)'s
  summary;
* a failing run makes the campaign raise after the others, naming it; bad
  command lines exit with code 2.

Tiny runs: Stage One to 2 viewpoints, no oracle, no report (about 9 s each
on 2 cores). Ray keeps its files in a temporary folder of its own
(``_temp_dir``, ``RAY_TMPDIR``), and every process Ray starts carries a
marker in its environment, by which the tests find and stop any left over.
"""

import csv
import hashlib
import json
import os
import shutil
import signal
import subprocess
import sys
import time
import uuid

# Ray 2.60 writes an authentication token into the home folder when it
# starts a local cluster with token authentication on; the tests (and the
# campaign subprocesses they start) run without it.
os.environ.setdefault("RAY_AUTH_MODE", "disabled")

import pytest  # noqa: E402

import surveyor  # noqa: E402
from surveyor import campaign  # noqa: E402
from conftest import MARKER, stop_marked  # noqa: E402

CONFIG = {"stages": "one", "max_viewpoints": 2, "oracle": False, "report": False}
CONFIG_JSON = json.dumps(CONFIG, sort_keys=True, separators=(",", ":"))
SCENES = ["bridge1", "bridge2"]
SEEDS = [0, 1, 2]
COMBOS = [(scene, seed) for scene in SCENES for seed in SEEDS]
HEADER = ["scene", "seed", "config", "viewpoints_stage_one", "viewpoints_stage_two",
          "coverage_a1", "material_accuracy", "collisions", "folder", "wall_s"]


def folder_of(scene, seed):
    return f"{scene}/seed{seed}/cfg-{hashlib.sha256(CONFIG_JSON.encode()).hexdigest()[:8]}"


@pytest.fixture(scope="module")
def sequential(tmp_path_factory):
    """The six runs made one after another with surveyor.explore, and the
    summary rows (every column but wall_s) built from their run.json."""
    base = tmp_path_factory.mktemp("sequential")
    start = time.monotonic()
    rows = []
    for scene, seed in COMBOS:
        run = surveyor.explore(scene, seed=seed, out=base / scene / f"seed{seed}", **CONFIG)
        s = json.loads((run.dir / "run.json").read_text())
        assert s == run.summary
        cov = s.get("coverage") or {}
        rows.append({
            "scene": scene, "seed": str(seed), "config": CONFIG_JSON,
            "viewpoints_stage_one": str(s["viewpoints"]["stage_one"]),
            "viewpoints_stage_two": str(s["viewpoints"]["stage_two"]),
            "coverage_a1": "" if cov.get("A1") is None else repr(cov["A1"]),
            "material_accuracy": "" if s.get("material_accuracy") is None
            else repr(s["material_accuracy"]),
            "collisions": str(s["collisions"]),
            "folder": folder_of(scene, seed),
        })
    print(f"6 runs one after another: {time.monotonic() - start:.1f} s")
    return base, rows


def read_summary(out):
    with open(out / "summary.csv", newline="") as f:
        reader = csv.DictReader(f)
        assert reader.fieldnames == HEADER
        return list(reader)


def without_wall(rows):
    return [{k: v for k, v in r.items() if k != "wall_s"} for r in rows]


def run_json_state(out):
    """(mtime_ns, bytes) of every run.json under out, by run folder."""
    state = {}
    for scene, seed in COMBOS:
        p = out / folder_of(scene, seed) / "run.json"
        if p.is_file():
            state[(scene, seed)] = (p.stat().st_mtime_ns, p.read_bytes())
    return state


def check_against_sequential(out, sequential):
    base, expected = sequential
    rows = read_summary(out)
    assert without_wall(rows) == expected
    for r in rows:
        # Unknown (empty) only for a run killed between its run.json and
        # the campaign's campaign.json.
        if r["wall_s"] or (out / r["folder"] / "campaign.json").exists():
            assert float(r["wall_s"]) > 0
    for scene, seed in COMBOS:
        ours, theirs = out / folder_of(scene, seed), base / scene / f"seed{seed}"
        for name in ["run.json", "viewpoints.csv", "discs.csv", "path.csv"]:
            assert (ours / name).read_bytes() == (theirs / name).read_bytes(), (scene, seed, name)
        # The run folder and campaign.json, nothing else (no staging left).
        assert set(os.listdir(ours)) - {"campaign.json"} == set(os.listdir(theirs))
        if (ours / "campaign.json").exists():
            info = json.loads((ours / "campaign.json").read_text())
            assert (info["scene"], info["seed"], info["config"]) == (scene, seed, CONFIG_JSON)
    png = (out / "coverage.png").read_bytes()
    assert png.startswith(b"\x89PNG\r\n\x1a\n") and len(png) > 10_000
    return rows


@pytest.fixture(scope="module")
def campaign_a(tmp_path_factory, local_ray):
    out = tmp_path_factory.mktemp("campaign") / "out"
    start = time.monotonic()
    result = campaign.run(SCENES, range(3), CONFIG, out=out)
    return out, result, time.monotonic() - start


def test_a_campaign_writes_the_runs_made_one_after_another(campaign_a, sequential):
    out, result, seconds = campaign_a
    print(f"campaign of 6 runs: {seconds:.1f} s")
    assert len(result.ran) == 6 and result.skipped == [] and result.failed == []
    rows = check_against_sequential(out, sequential)
    # The returned rows are summary.csv's, typed.
    assert [r["folder"] for r in result.rows] == [r["folder"] for r in rows]
    assert [str(r["seed"]) for r in result.rows] == [r["seed"] for r in rows]
    assert [repr(r["wall_s"]) for r in result.rows] == [r["wall_s"] for r in rows]
    assert result.summary == out / "summary.csv" and result.plot == out / "coverage.png"


def test_a_second_call_runs_nothing(campaign_a, monkeypatch):
    out, first, _ = campaign_a
    before = run_json_state(out)
    rows_before = read_summary(out)
    assert len(before) == 6

    def no_ray(*args, **kwargs):
        raise AssertionError("Ray started with nothing to run")

    monkeypatch.setattr(campaign, "_start_ray", no_ray)
    again = campaign.run(SCENES, [0, 1, 2], [CONFIG], out=out)
    assert again.ran == [] and len(again.skipped) == 6
    assert run_json_state(out) == before
    # The same rows, wall_s included (read back from each campaign.json).
    assert read_summary(out) == rows_before
    assert again.rows == first.rows


def test_a_failed_run_is_named_after_the_others_finish(campaign_a, local_ray, tmp_path):
    out_a, _, _ = campaign_a
    out = tmp_path / "out"
    done = folder_of("bridge1", 0)
    shutil.copytree(out_a / done, out / done)  # a finished run: skipped
    # Seed 2's run cannot make its folder (a file stands where it goes): it
    # fails as it runs (a bad config is refused before Ray starts).
    blocked = (out / folder_of("bridge1", 2)).parent
    blocked.write_text("in the way")
    with pytest.raises(campaign.CampaignError, match="bridge1 seed 2") as info:
        campaign.run("bridge1", [0, 1, 2], [CONFIG], out=out)
    err = info.value
    assert len(err.failures) == 1
    assert all(c.seed == 2 for c, _ in err.failures)
    # The good run finished; summary.csv holds the two finished rows.
    assert len(err.result.ran) == 1 and len(err.result.skipped) == 1
    rows = read_summary(out)
    assert [(r["seed"], r["config"]) for r in rows] == [("0", CONFIG_JSON), ("1", CONFIG_JSON)]
    assert (out / "coverage.png").is_file()


def test_a_killed_campaign_finishes_only_what_is_missing(
        campaign_a, sequential, local_ray, ray_dir, tmp_path):
    out = tmp_path / "out"
    tag = uuid.uuid4().hex
    env = {**os.environ, MARKER: tag, "RAY_TMPDIR": str(ray_dir / "cli")}
    (ray_dir / "cli").mkdir()
    cmd = [sys.executable, "-m", "surveyor.campaign", "--scenarios", ",".join(SCENES),
           "--seeds", "0-2", "--config", json.dumps(CONFIG), "--out", str(out), "--num-cpus", "2"]
    proc = subprocess.Popen(cmd, env=env, start_new_session=True,
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT)
    try:
        deadline = time.monotonic() + 150
        while time.monotonic() < deadline:
            # A run is done (its campaign.json written after run.json).
            if list(out.glob("*/seed*/cfg-*/campaign.json")) or proc.poll() is not None:
                break
            time.sleep(0.1)
        # Ray workers are children of Ray's daemons: the whole group goes.
        os.killpg(proc.pid, signal.SIGKILL)
        proc.wait(timeout=30)
        log = proc.stdout.read().decode(errors="replace")
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
        left = stop_marked(tag)
    assert not left, f"Ray processes outlived the killed campaign, killed: {left}\n{log}"
    before = run_json_state(out)
    assert 1 <= len(before) < 6, f"killed too late or too early: {sorted(before)}\n{log}"
    missing = sorted(set(COMBOS) - set(before))
    print(f"killed with {len(before)} runs done; the campaign's output:\n{log}")

    result = campaign.run(SCENES, SEEDS, CONFIG, out=out)
    assert sorted((c.scenario, c.seed) for c in result.ran) == missing
    assert sorted((c.scenario, c.seed) for c in result.skipped) == sorted(before)
    after = run_json_state(out)
    for key, state in before.items():
        assert after[key] == state, f"{key}: run.json rewritten"
    rows = check_against_sequential(out, sequential)
    assert without_wall(rows) == without_wall(read_summary(campaign_a[0]))


@pytest.mark.parametrize("seeds, message", [
    ("9-0", "ends before it starts"),
    ("x", "not a seed"),
    ("1-", "not a seed"),
    ("-1", "not a seed"),
])
def test_bad_seed_ranges_exit_2(tmp_path, seeds, message):
    out = subprocess.run(
        [sys.executable, "-m", "surveyor.campaign", "--scenarios", "bridge1", "--seeds", seeds,
         "--out", str(tmp_path / "out")], capture_output=True, text=True)
    assert out.returncode == 2
    assert "--seeds" in out.stderr and message in out.stderr
    assert not (tmp_path / "out").exists()


def test_bad_arguments_raise_before_running(tmp_path):
    with pytest.raises(ValueError, match="seed"):
        campaign.run("bridge1", [-1], out=tmp_path / "a")
    with pytest.raises(ValueError, match="configs"):
        campaign.run("bridge1", [0], ["stages=one"], out=tmp_path / "a")
    with pytest.raises(ValueError, match="'seed' is set by the campaign"):
        campaign.run("bridge1", [0], {"seed": 3}, out=tmp_path / "a")
    with pytest.raises(ValueError, match="not JSON"):
        campaign.run("bridge1", [0], {"noise": float("nan")}, out=tmp_path / "a")
    # Issue 48: raw TypeErrors, and a bad scenario or option found only
    # after Ray had started.
    with pytest.raises(ValueError, match="scenarios=5"):
        campaign.run(5, [0], out=tmp_path / "a")
    with pytest.raises(ValueError, match=r"scenarios=\[None\]"):
        campaign.run([None], [0], out=tmp_path / "a")
    with pytest.raises(ValueError, match="no_such_scene"):
        campaign.run("no_such_scene", [0], out=tmp_path / "a")
    with pytest.raises(ValueError, match="stages"):
        campaign.run("bridge1", [0], [{}, {"stages": "two"}], out=tmp_path / "a")
    with pytest.raises(ValueError, match="local_candidates"):
        campaign.run("bridge1", [0], {"explore": {"local_candidates": -1}}, out=tmp_path / "a")
    assert not (tmp_path / "a").exists()
    bad = subprocess.run(
        [sys.executable, "-m", "surveyor.campaign", "--scenarios", "bridge1", "--seeds", "0",
         "--config", "[1]", "--out", str(tmp_path / "b")], capture_output=True, text=True)
    assert bad.returncode == 2 and "--config" in bad.stderr


def test_folder_names_are_stable():
    c = campaign.Combination("bridge1", 3, CONFIG_JSON)
    assert c.folder.as_posix() == folder_of("bridge1", 3)
    assert campaign.canonical_json({"b": 1, "a": {"y": 2, "x": 1}}) == '{"a":{"x":1,"y":2},"b":1}'
    # A scenario file: its sanitised stem and a hash of the whole path.
    name = campaign.scene_folder_name("/data/my scenes/bridge 4.toml")
    assert name.startswith("bridge_4-") and len(name) == len("bridge_4-") + 8
    assert name != campaign.scene_folder_name("/other/bridge 4.toml")
    assert campaign.parse_seeds("0-2,5, 7-8") == [0, 1, 2, 5, 7, 8]
