"""The theses' parameter studies (issue 27, acceptance 6) and the library
calls behind them.

* ``scale_like_discs`` on a run's fused mesh gives ``surveyor sld``'s discs
  of that mesh.ply (the same rows of discs.csv, the same share of points
  registered), and refuses bad input with a ``ValueError`` naming it;
* ``candidate_coverage``: with no candidate it is the coverage of the run's
  first sweep (viewpoints.csv's ``coverage_a1`` of a run of the same seed);
  the first n of a draw are the draw of n; coverage never falls as n grows;
* ``studies.fit_exponential`` recovers a known curve;
* ``studies.sld`` and ``studies.candidates`` as campaigns on a local Ray:
  their CSV rows are the library calls' answers, their PNG is written, and
  called again they compute nothing;
* ``studies.strategies`` as a campaign on a local Ray: a row per run, each
  what its run folder's run.json and viewpoints.csv say, its table and
  plots written, and called again it runs nothing.
"""

import csv
import json
import os

os.environ.setdefault("RAY_AUTH_MODE", "disabled")

import numpy as np  # noqa: E402
import pytest  # noqa: E402

import surveyor  # noqa: E402
from surveyor import studies  # noqa: E402
from conftest import run_cli  # noqa: E402


@pytest.fixture(scope="module")
def small_run(tmp_path_factory):
    """A one-viewpoint bridge1 run of seed 0 (its start sweep alone)."""
    out = tmp_path_factory.mktemp("run") / "bridge1"
    return surveyor.explore("bridge1", seed=0, out=out, stages="one", max_viewpoints=1,
                            oracle=False, report=False)


def read_csv(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


@pytest.mark.parametrize("mu, n_min", [(0.025, 8), (0.04, 20), (0.012, 3)])
def test_discs_of_a_run_s_mesh_are_the_cli_s(small_run, surveyor_bin, tmp_path, mu, n_min):
    out = tmp_path / "discs.csv"
    said = run_cli(surveyor_bin, "sld", "--input", small_run.dir / "mesh.ply", "--radius", mu,
                   "--min-points", n_min, "--out", out)
    vertices, triangles = small_run.mesh()
    discs, info = surveyor.scale_like_discs(
        vertices, triangles=triangles, config={"radius_m": mu, "min_points": n_min})
    cli = read_csv(out)
    assert len(discs) == len(cli) > 10
    for name in ("cx", "cy", "cz", "nx", "ny", "nz", "radius"):
        np.testing.assert_allclose(discs[name], [float(r[name]) for r in cli], rtol=0, atol=1e-9)
    assert list(discs["points"]) == [int(r["points"]) for r in cli]
    assert f"({100 * info['registered_fraction']:.2f} % registered)" in said
    assert info["points"] == len(vertices) and 0 <= info["registered"] <= info["points"]
    assert info["seconds"] > 0 and info["occupied_voxels"] > 0


def test_discs_face_the_sensor_given_origins():
    # A plane z = 0 seen from above: every disc's normal points up, whatever
    # the canonical sign would say; seen from below, down.
    g = np.linspace(0.0, 1.0, 41)
    x, y = np.meshgrid(g, g)
    points = np.column_stack([x.ravel(), y.ravel(), np.zeros(x.size)])
    for z, sign in ((2.0, 1.0), (-2.0, -1.0)):
        origins = np.tile([0.5, 0.5, z], (len(points), 1))
        discs, info = surveyor.scale_like_discs(points, origins=origins)
        assert len(discs) > 100 and info["registered_fraction"] > 0.9
        np.testing.assert_allclose(discs["nz"], sign, atol=1e-9)


@pytest.mark.parametrize(
    "kwargs, pattern",
    [
        ({"triangles": np.array([[0, 1, 9]])}, r"triangles: row 0 is \(0, 1, 9\), expected vertex indices in \[0, 3\)"),
        ({"triangles": np.array([[0.0, 1.0, 2.0]])}, r"triangles: expected an integer dtype"),
        ({"triangles": np.array([0, 1, 2])}, r"triangles: expected shape \(m, 3\)"),
        ({"origins": np.zeros((2, 3))}, r"origins has 2 rows and points 3"),
        ({"origins": np.full((3, 3), np.nan)}, r"origins: row 0 is not finite"),
        ({"config": {"radius": 0.1}}, r"radius"),
        ({"config": {"radius_m": -0.1}}, r"radius_m"),
        ({"config": {"min_points": 0}}, r"min_points"),
    ],
)
def test_bad_disc_input_raises_value_error(kwargs, pattern):
    points = np.eye(3)
    with pytest.raises(ValueError, match=pattern):
        surveyor.scale_like_discs(points, **kwargs)
    with pytest.raises(ValueError, match=r"points: row 1 is not finite"):
        surveyor.scale_like_discs(np.array([[0.0, 0, 0], [np.inf, 0, 0]]))
    with pytest.raises(ValueError, match=r"points: expected dtype float64"):
        surveyor.scale_like_discs(points.astype(np.float32))


def test_no_candidate_is_the_run_s_first_sweep(small_run):
    table = surveyor.candidate_coverage("bridge1", [0], seed=0)
    assert list(table["n_q"]) == [0]
    assert table["coverage_run"][0] == small_run.viewpoints["coverage_a1"][0]
    assert table["coverage_contact"][0] == table["coverage_run"][0]


def test_candidates_are_one_draw_of_the_largest_size():
    many = surveyor.candidate_coverage("bridge1", [12, 0, 4, 8, 8], seed=3)
    assert list(many["n_q"]) == [0, 4, 8, 12]
    few = surveyor.candidate_coverage("bridge1", [8], seed=3)
    for key in few:
        assert few[key][0] == many[key][2], key
    for key in ("coverage_run", "coverage_contact", "clear_run", "clear_contact"):
        assert np.all(np.diff(many[key]) >= 0), key
    assert np.all(many["clear_run"] <= many["n_q"])
    other = surveyor.candidate_coverage("bridge1", [12], seed=4)
    assert other["coverage_contact"][0] != many["coverage_contact"][-1]


@pytest.mark.parametrize("sizes, pattern", [([-1], "sizes: -1"), ([20_001], "sizes: 20001")])
def test_bad_candidate_sizes_raise_value_error(sizes, pattern):
    with pytest.raises(ValueError, match=pattern):
        surveyor.candidate_coverage("bridge1", sizes)
    with pytest.raises(ValueError, match="no_such_scene"):
        surveyor.candidate_coverage("no_such_scene", [1])


def test_the_exponential_fit_recovers_a_known_curve():
    x = np.arange(50, 3501, 50)
    y = 80.0 - 45.0 * np.exp(-x / 600.0)
    c_inf, c_0, tau = studies.fit_exponential(x, y)
    assert abs(c_inf - 80.0) < 0.05 and abs(c_0 - 35.0) < 0.1 and abs(tau - 600.0) / 600.0 < 0.01


def test_the_sld_study_is_a_resumable_campaign(small_run, local_ray, tmp_path):
    mus, n_mins = [0.012, 0.04], [4, 30]
    lines = []
    path = studies.sld(small_run.dir, tmp_path, mus_m=mus, n_mins=n_mins, repeats=1,
                       log=lines.append)
    assert lines[0] == "8 points to compute, 0 already done"
    rows = read_csv(path)
    assert [(r["input"], r["vary"]) for r in rows] == (
        [("mesh", "mu")] * 2 + [("mesh", "n_min")] * 2 + [("cloud", "mu")] * 2 + [("cloud", "n_min")] * 2)
    vertices, triangles = small_run.mesh()
    cloud = small_run.cloud()
    for r in rows:
        points, tri = (vertices, triangles) if r["input"] == "mesh" else (cloud, None)
        discs, info = surveyor.scale_like_discs(
            points, triangles=tri, config={"radius_m": float(r["mu_m"]), "min_points": int(r["n_min"])})
        assert int(r["discs"]) == len(discs) and int(r["points"]) == len(points)
        assert float(r["registered_pct"]) == 100 * info["registered_fraction"]
    assert {float(r["mu_m"]) for r in rows if r["vary"] == "n_min"} == {studies.SLD_FIXED_MU_M}
    assert {int(r["n_min"]) for r in rows if r["vary"] == "mu"} == {studies.SLD_FIXED_N_MIN}
    assert (tmp_path / studies.SLD_PNG).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    again = []
    studies.sld(small_run.dir, tmp_path, mus_m=mus, n_mins=n_mins, repeats=1, log=again.append)
    assert again == ["0 points to compute, 8 already done"]
    assert read_csv(path) == rows
    # Another seed is another study: nothing of the first is reused.
    other = []
    studies.sld(small_run.dir, tmp_path, mus_m=[0.04], n_mins=[30], inputs=["mesh"], repeats=1,
                seed=1, log=other.append)
    assert other[0] == "2 points to compute, 0 already done"


def test_the_candidate_study_is_a_resumable_campaign(local_ray, tmp_path):
    lines = []
    path = studies.candidates("bridge1", tmp_path, sizes=[3, 6], seeds=[0, 1], log=lines.append)
    assert lines[0] == "2 points to compute, 0 already done"
    rows = read_csv(path)
    assert [(r["seed"], r["n_q"]) for r in rows] == [
        (s, n) for s in ("0", "1") for n in ("0", "3", "6")]
    for seed in (0, 1):
        table = surveyor.candidate_coverage("bridge1", [0, 3, 6], seed=seed)
        mine = [r for r in rows if r["seed"] == str(seed)]
        assert [float(r["coverage_run"]) for r in mine] == list(table["coverage_run"])
        assert [int(r["clear_contact"]) for r in mine] == list(table["clear_contact"])
    assert (tmp_path / studies.CANDIDATES_PNG).is_file()
    again = []
    studies.candidates("bridge1", tmp_path, sizes=[3, 6], seeds=[0, 1], log=again.append)
    assert again == ["0 points to compute, 2 already done"]


def test_the_strategy_study_is_a_resumable_campaign(local_ray, tmp_path):
    # Ours and one of Delmerico et al.'s gains.
    chosen = ["information", "rear_side_voxel"]
    lines = []
    path = studies.strategies("bridge1", [0], tmp_path, strategies=chosen, max_viewpoints=3,
                              log=lines.append)
    assert path == tmp_path / studies.STRATEGIES_CSV
    assert lines[0].startswith("2 runs to do, 0 already done")  # the campaign's
    assert lines[-1] == "strategies: 2 runs done now, 0 already done"
    rows = read_csv(path)
    assert tuple(rows[0]) == studies.STRATEGY_COLUMNS
    assert [(r["scene"], r["seed"], r["strategy"]) for r in rows] == [
        ("bridge1", "0", "information"), ("bridge1", "0", "rear_side_voxel")]
    for r in rows:
        # Read by hand from the run folder: its config, run.json, viewpoints.csv.
        folder = tmp_path / r["folder"]
        assert folder.parent.parent.parent == tmp_path / "strategies_runs"
        config = json.loads(json.loads((folder / "campaign.json").read_text())["config"])
        assert config == {"stages": "one", "max_viewpoints": 3, "timings": True,
                          "report": False, "explore": studies.STRATEGIES[r["strategy"]]}
        summary = json.loads((folder / "run.json").read_text())
        views = read_csv(folder / "viewpoints.csv")
        assert [v["stage"] for v in views] == ["1"] * 3
        assert int(r["viewpoints"]) == len(views) == 3
        assert r["termination"] == summary["termination"] == "viewpoint_budget"
        assert r["viewpoints_to_rule"] == ""
        a1 = float(views[-1]["coverage_a1"])  # fewer than 12 viewpoints: the last
        oracle = summary["coverage"]["oracle"]
        assert float(r["a1_at_12"]) == a1
        assert float(r["oracle_a1_at_12"]) == oracle["oracle"]["A1_after_sweeps"][11]
        assert float(r["ratio_at_12"]) == a1 / oracle["A1_after_12"]
        assert float(r["ratio_at_12"]) == pytest.approx(oracle["ratio_after_12"], rel=1e-12)
        assert float(r["a1_final"]) == summary["coverage"]["A1"] == pytest.approx(a1, rel=1e-12)
        assert float(r["joint_travel_rad"]) == pytest.approx(
            sum(float(v["joint_travel"]) for v in views), rel=1e-12)
        # viewpoints.csv's robot time is per viewpoint, to the microsecond.
        assert float(r["robot_time_s"]) == summary["robot_time_s"]["stage_one"]
        assert float(r["robot_time_s"]) == pytest.approx(
            sum(float(v["robot_time_s"]) for v in views), abs=1e-5)
        decisions = sorted(float(v["decision_ms"]) for v in views[1:])
        assert float(r["decision_median_ms"]) == summary["decision_ms"]["median"] > 0
        assert float(r["decision_median_ms"]) == pytest.approx(decisions[len(decisions) // 2],
                                                               abs=5e-4)
        assert int(r["collisions"]) == summary["collisions"]
        assert int(r["unsafe_configurations"]) == summary["unsafe_configurations"]
    table = (tmp_path / studies.STRATEGIES_MD).read_text()
    assert "| strategy | bridge1 | all |" in table
    for r in rows:
        a1 = f"{100 * float(r['a1_at_12']):.1f}"
        assert f"| {r['strategy']} | {a1} | {a1} |" in table  # A1 after 12, one seed
        # The 1 % rule ended no run: "– (0/1)", no mean, 0 runs of 1.
        assert f"| {r['strategy']} | – (0/1) | – (0/1) |" in table
    for name in (studies.STRATEGIES_COVERAGE_PNG, studies.STRATEGIES_TIME_PNG,
                 studies.STRATEGIES_DECISION_PNG):
        assert (tmp_path / name).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n", name
    again = []
    studies.strategies("bridge1", [0], tmp_path, strategies=chosen, max_viewpoints=3,
                       log=again.append)
    assert again == ["strategies: 0 runs done now, 2 already done"]
    assert read_csv(path) == rows


def test_bad_study_arguments_raise_before_anything_runs(small_run, tmp_path):
    with pytest.raises(ValueError, match="inputs"):
        studies.sld(small_run.dir, tmp_path, inputs=["voxels"])
    with pytest.raises(ValueError, match="radii"):
        studies.sld(small_run.dir, tmp_path, mus_m=[0.0])
    with pytest.raises(ValueError, match="n_min values"):
        studies.sld(small_run.dir, tmp_path, n_mins=[2])
    with pytest.raises(ValueError, match="sizes"):
        studies.candidates("bridge1", tmp_path, sizes=[30_000])
    with pytest.raises(ValueError, match="sizes"):
        studies.candidates("bridge1", tmp_path, sizes=[])
    with pytest.raises(ValueError, match="no_such_scene"):
        studies.candidates("no_such_scene", tmp_path, sizes=[2])
    with pytest.raises(OSError):
        studies.sld(tmp_path / "no_run", tmp_path)
    for kwargs, pattern in [
        ({"strategies": ["rank_sum", "no_such_strategy"]}, "unknown strategy 'no_such_strategy'"),
        ({"strategies": ["rank_sum", "rank_sum"]}, "listed twice"),
        ({"strategies": []}, "at least one"),
        ({"strategies": {"a": {}, "b": {}}}, "the same overrides"),
        ({"strategies": {"x": {"no_such_key": 1}}}, "no_such_key"),
        ({"strategies": ["rank_sum"], "max_viewpoints": 0}, "max_viewpoints"),
        ({"strategies": ["rank_sum"], "max_viewpoints": 1001}, "max_viewpoints"),
        ({"strategies": ["rank_sum"], "seeds": []}, "seeds"),
        ({"strategies": ["rank_sum"], "scenarios": []}, "scenarios"),
        ({"strategies": ["rank_sum"], "scenarios": ["no_such_scene"]}, "no_such_scene"),
    ]:
        with pytest.raises(ValueError, match=pattern):
            studies.strategies(**{"scenarios": "bridge1", "seeds": [0], **kwargs}, out=tmp_path)
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("args", [
    ["sld", "--run", "r", "--mus", "abc"],
    ["candidates", "--sizes", "5-1:1"],
    ["candidates", "--sizes", "x"],
    ["candidates", "--seeds", "x"],
    ["candidates", "--num-cpus", "0"],
    ["strategies", "--strategies", "rank_sum,no_such_strategy"],
    ["strategies", "--strategies", ","],
    ["strategies", "--max-viewpoints", "0"],
    ["strategies", "--max-viewpoints", "x"],
    ["strategies", "--seeds", "x"],
    ["strategies", "--scenarios", ","],
    ["strategies", "--num-cpus", "0"],
])
def test_bad_study_command_lines_exit_with_code_2(tmp_path, args, capsys):
    with pytest.raises(SystemExit) as e:
        studies.main(args + ["--out", str(tmp_path / "o")])
    assert e.value.code == 2 and "error:" in capsys.readouterr().err
    assert not (tmp_path / "o").exists()
