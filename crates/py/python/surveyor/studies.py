"""The theses' parameter studies, and Stage One's strategies, as campaigns on Ray.

* ``sld(run, out)``: Paul Figs 5.7-5.8 (§5.2.1). Scale-Like Discs of a run's
  fused mesh (and of its fused point cloud) with the disc radius mu varied
  at n_min = 8, then n_min varied at mu = 25 mm: generation time, number of
  discs n_ss and the percentage of points registered. Writes
  ``out/sld_study.csv`` and ``out/sld_study.png``.
* ``candidates(scenario, out)``: Paul Fig. 3.2 (§3.2.3). The A1 coverage of
  the combined sweeps of n_Q contending viewpoints drawn uniformly in
  C-space, against n_Q, over several draws, with an exponential fitted as in
  the thesis. Writes ``out/candidates_study.csv`` and
  ``out/candidates_study.png``.
* ``strategies(scenarios, seeds, out)``: Stage One's strategies side by side
  (``STRATEGIES``: the information gains of ``[explore] gain``, Paul's rank
  sum, a random and a frontier choice). A Stage One run per scenario, seed
  and strategy (``surveyor.campaign.run`` into ``out/strategies_runs/``,
  resumable as any campaign); writes ``out/strategies_study.csv`` (a row per
  run), ``out/strategies_table.md`` (a table per measure, strategies against
  scenes) and ``out/strategies_coverage.png``, ``out/strategies_time.png``,
  ``out/strategies_decision.png``.

Each point of the first two is a Ray task (a local Ray unless ``address``
names a cluster) whose result is kept as ``out/<study>/<point>.json``
(written under a temporary name, then renamed): a study called again with
the same ``out`` computes only the points missing; the third's points are
its campaign's runs. From the shell::

    python -m surveyor.studies sld --run bridge1_run --out studies
    python -m surveyor.studies candidates --scenario bridge1 --seeds 0-4 --out studies
    python -m surveyor.studies strategies --seeds 0-2 --out studies   # from the repository's root

Needs ``ray`` and ``matplotlib`` (not dependencies of the package itself).
"""

from __future__ import annotations

import argparse
import csv
import hashlib
import json
import os
import re
import statistics
import sys
from pathlib import Path
from types import MappingProxyType
from typing import Any, Callable, Dict, Iterable, List, Mapping, Optional, Sequence, Tuple, Union

from ._runs import PathLike

__all__ = ["sld", "candidates", "strategies", "fit_exponential", "SLD_MUS_M", "SLD_N_MINS",
           "SLD_FIXED_MU_M", "SLD_FIXED_N_MIN", "CANDIDATE_SIZES", "STRATEGIES",
           "STRATEGY_SCENARIOS", "STRATEGY_COLUMNS", "main"]

#: Disc radii mu of the first experiment (metres): Fig. 5.7 went up to 50 mm.
SLD_MUS_M = (0.002, 0.003, 0.004, 0.005, 0.006, 0.007, 0.008, 0.009, 0.010, 0.0125, 0.015,
             0.0175, 0.020, 0.025, 0.030, 0.035, 0.040, 0.045, 0.050)
#: n_min of the first experiment (Fig. 5.7: 8).
SLD_FIXED_N_MIN = 8
#: n_min of the second experiment (Fig. 5.8).
SLD_N_MINS = (3, 4, 5, 6, 8, 10, 12, 15, 20, 25, 30, 35, 40, 50, 60, 80, 100)
#: mu of the second experiment (Fig. 5.8: 25 mm, "the middle of the range").
SLD_FIXED_MU_M = 0.025
#: n_Q of Fig. 3.2: 50 to 3500 (the thesis' range).
CANDIDATE_SIZES = tuple(range(50, 3501, 50))

SLD_CSV, SLD_PNG = "sld_study.csv", "sld_study.png"
SLD_COLUMNS = ("input", "vary", "mu_m", "n_min", "points", "discs", "registered_pct", "seconds")
CANDIDATES_CSV, CANDIDATES_PNG = "candidates_study.csv", "candidates_study.png"
CANDIDATE_COLUMNS = ("scene", "seed", "n_q", "clear_run", "coverage_run", "clear_contact",
                     "coverage_contact")

#: Stage One's strategies of the ``strategies`` study, in order: each a
#: name and its ``[explore]`` overrides. "information" is the default gain
#: (the same runs as no override would be, in other folders).
STRATEGIES: Mapping[str, Mapping[str, str]] = MappingProxyType({
    "information": {"gain": "information"},
    "paul_f1": {"gain": "paul_f1"},
    "average_entropy": {"gain": "average_entropy"},
    "occlusion_aware": {"gain": "occlusion_aware"},
    "unobserved_voxel": {"gain": "unobserved_voxel"},
    "rear_side_voxel": {"gain": "rear_side_voxel"},
    "rear_side_entropy": {"gain": "rear_side_entropy"},
    "proximity_count": {"gain": "proximity_count"},
    "rank_sum": {"selection": "rank_sum"},  # Paul's Pareto front, lowest rank sum
    "random": {"selection": "random"},
    "frontier": {"selection": "frontier"},
    # The baselines to the budget: the 1 % rule ends them as soon as one
    # choice reveals little (after 2 and 4 viewpoints on the bridges).
    "random_to_budget": {"selection": "random", "stop_fraction": 0.0},
    "frontier_to_budget": {"selection": "frontier", "stop_fraction": 0.0},
})
#: The scenes of the ``strategies`` study: the bridge built-ins and the
#: repository's channel4 (a scenario file: the default works from the
#: repository's root; elsewhere pass its path).
STRATEGY_SCENARIOS = ("bridge1", "bridge2", "bridge3", "data/scenarios/channel4.toml")
STRATEGY_RUNS = "strategies_runs"
STRATEGIES_CSV, STRATEGIES_MD = "strategies_study.csv", "strategies_table.md"
STRATEGIES_COVERAGE_PNG = "strategies_coverage.png"
STRATEGIES_TIME_PNG = "strategies_time.png"
STRATEGIES_DECISION_PNG = "strategies_decision.png"
STRATEGY_COLUMNS = ("scene", "seed", "strategy", "viewpoints", "termination",
                    "viewpoints_to_rule", "a1_at_12", "oracle_a1_at_12", "ratio_at_12", "a1_final",
                    "joint_travel_rad", "robot_time_s", "decision_median_ms", "collisions",
                    "unsafe_configurations", "folder")


def _write_atomic(path: Path, text: str) -> None:
    tmp = path.with_name(f".{path.name}.tmp-{os.getpid()}")
    tmp.write_text(text)
    os.replace(tmp, path)


def _hash8(value: Any) -> str:
    """The first 8 hex digits of the SHA-256 of ``value`` as JSON."""
    return hashlib.sha256(json.dumps(value).encode()).hexdigest()[:8]


def _load(path: Path) -> Optional[dict]:
    try:
        return json.loads(path.read_text())
    except (OSError, ValueError):
        return None


def _run_tasks(tasks: Dict[Path, Tuple[Callable, tuple]], address, num_cpus, ray_options,
               say: Callable[[str], None]) -> None:
    """Run each ``(function, args)`` not yet done as a Ray task and keep its
    result (a dict) as the JSON file it is keyed by."""
    todo = {path: t for path, t in tasks.items() if _load(path) is None}
    say(f"{len(todo)} points to compute, {len(tasks) - len(todo)} already done")
    if not todo:
        return
    from .campaign import _start_ray, completed

    ray, started = _start_ray(address, num_cpus, ray_options)
    try:
        shared: Dict[int, Any] = {}
        pending = {}
        for path, (fn, args) in todo.items():
            # Large arrays go to the object store once, not once per task.
            refs = tuple(shared.setdefault(id(a), ray.put(a)) if _is_array(a) else a for a in args)
            pending[ray.remote(fn).options(num_cpus=1).remote(*refs)] = path
        failed = []
        for path, result, error in completed(ray, pending):
            if error is not None:
                failed.append(f"{path.stem}: {error}")
                continue
            path.parent.mkdir(parents=True, exist_ok=True)
            _write_atomic(path, json.dumps(result) + "\n")
            say(f"{path.parent.name}/{path.stem}")
        if failed:
            raise RuntimeError("study points failed:\n" + "\n".join(failed))
    finally:
        if started:
            ray.shutdown()


def _is_array(a: Any) -> bool:
    return hasattr(a, "__array_interface__")


# ---------------------------------------------------------------------------
# Paul Figs 5.7-5.8: Scale-Like Discs against mu and n_min


def _sld_point(points, triangles, mu_m: float, n_min: int, seed: int, repeats: int) -> dict:
    """One point of the SLD study (a Ray task): the discs of ``points`` with
    ``radius_m = mu_m`` and ``min_points = n_min``, timed ``repeats`` times
    (the median kept)."""
    import surveyor

    times = []
    for _ in range(repeats):
        discs, info = surveyor.scale_like_discs(
            points, triangles=triangles, config={"radius_m": mu_m, "min_points": n_min}, seed=seed)
        times.append(info["seconds"])
    return {"points": info["points"], "discs": int(len(discs)),
            "registered_pct": 100.0 * info["registered_fraction"],
            "seconds": statistics.median(times)}


def _key(value: float) -> str:
    return f"{value:.6g}".replace(".", "p")


def sld(run: PathLike, out: PathLike = "studies", *, mus_m: Sequence[float] = SLD_MUS_M,
        n_mins: Sequence[int] = SLD_N_MINS, fixed_n_min: int = SLD_FIXED_N_MIN,
        fixed_mu_m: float = SLD_FIXED_MU_M, inputs: Sequence[str] = ("mesh", "cloud"),
        repeats: int = 3, seed: int = 0, address: Optional[str] = None,
        num_cpus: Optional[int] = None, ray_options: Optional[Dict[str, Any]] = None,
        log: Optional[Callable[[str], None]] = None) -> Path:
    """Paul Figs 5.7-5.8 on the run folder ``run`` (an explore run): the
    Scale-Like Discs of its fused mesh (``"mesh"``: mesh.ply's vertices,
    oriented by its faces, as the run made its discs) and of its fused point
    cloud (``"cloud"``: cloud.ply, every sweep's points), first for each
    radius of ``mus_m`` with ``min_points = fixed_n_min``, then for each
    n_min of ``n_mins`` with ``radius_m = fixed_mu_m``. Each point is a Ray
    task timing the generation ``repeats`` times (median; one thread).

    Writes ``out/sld_study.csv`` (``SLD_COLUMNS``: input, vary (``mu`` or
    ``n_min``), mu_m, n_min, points, discs, registered_pct, seconds) and
    ``out/sld_study.png`` (time, discs and % registered against mu and
    against n_min); returns the CSV's path. Points already in
    ``out/sld_study/`` are not computed again. Raises ``ValueError`` for a
    bad argument before anything runs, ``OSError`` for an unreadable run."""
    import surveyor

    inputs = list(inputs)
    if not inputs or any(i not in ("mesh", "cloud") for i in inputs):
        raise ValueError(f"inputs={inputs!r}: expected \"mesh\" and/or \"cloud\"")
    if not (isinstance(repeats, int) and 1 <= repeats <= 100):
        raise ValueError(f"repeats={repeats!r}: expected 1 to 100")
    if any(not (0 < m <= 1.0) for m in list(mus_m) + [fixed_mu_m]):
        raise ValueError("mu values are disc radii in metres, in (0, 1]")
    if any(not (isinstance(n, int) and 3 <= n <= 100_000) for n in list(n_mins) + [fixed_n_min]):
        raise ValueError("n_min values are whole numbers of points, 3 (a plane) to 100000")
    loaded = surveyor.Run.load(run)
    out = Path(out).absolute()
    out.mkdir(parents=True, exist_ok=True)
    say = log or (lambda line: None)
    arrays = {}
    if "mesh" in inputs:
        arrays["mesh"] = loaded.mesh()
    if "cloud" in inputs:
        arrays["cloud"] = (loaded.cloud(), None)
    points_of = [("mu", m, fixed_n_min) for m in mus_m] + [("n_min", fixed_mu_m, n) for n in n_mins]
    # A point is kept for this run folder and seed: another run or seed in
    # the same ``out`` is computed anew.
    tag = _hash8([os.fspath(Path(run).resolve()), seed])
    tasks = {}
    where = {}
    for name, (points, triangles) in arrays.items():
        for vary, mu, n_min in points_of:
            path = out / "sld_study" / f"{name}-{vary}-mu{_key(mu)}-n{n_min}-{tag}.json"
            tasks[path] = (_sld_point, (points, triangles, mu, n_min, seed, repeats))
            where[path] = (name, vary, mu, n_min)
    _run_tasks(tasks, address, num_cpus, ray_options, say)
    rows = []
    for path, (name, vary, mu, n_min) in where.items():
        r = _load(path)
        rows.append({"input": name, "vary": vary, "mu_m": mu, "n_min": n_min, **r})
    csv_path = out / SLD_CSV
    _write_csv(csv_path, SLD_COLUMNS, rows)
    _plot_sld(out / SLD_PNG, rows, fixed_n_min, fixed_mu_m)
    return csv_path


def _write_csv(path: Path, columns: Sequence[str], rows: List[dict]) -> None:
    tmp = path.with_name(f".{path.name}.tmp-{os.getpid()}")
    with open(tmp, "w", newline="") as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow(columns)
        for r in rows:
            w.writerow([repr(r[c]) if isinstance(r[c], float) else r[c] for c in columns])
    os.replace(tmp, path)


def _figure(rows: int, cols: int, size: Tuple[float, float]):
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=size, layout="constrained")
    FigureCanvasAgg(fig)
    return fig, fig.subplots(rows, cols, squeeze=False)


def _save(fig, path: Path) -> None:
    tmp = path.with_name(f".{path.name}.tmp-{os.getpid()}")
    fig.savefig(tmp, format="png", dpi=90)
    os.replace(tmp, path)


def _plot_sld(path: Path, rows: List[dict], fixed_n_min: int, fixed_mu_m: float) -> None:
    fig, axes = _figure(2, 3, (13, 7))
    labels = {"mesh": "fused mesh (run's discs)", "cloud": "fused point cloud"}
    for r, (vary, xlabel, x_of) in enumerate([
            ("mu", f"disc radius μ (mm), n_min = {fixed_n_min}", lambda row: 1000 * row["mu_m"]),
            ("n_min", f"n_min (points), μ = {1000 * fixed_mu_m:g} mm", lambda row: row["n_min"])]):
        for name in ("mesh", "cloud"):
            mine = sorted((row for row in rows if row["vary"] == vary and row["input"] == name),
                          key=x_of)
            if not mine:
                continue
            label = f"{labels[name]}, {mine[0]['points']:,} points"
            xs = [x_of(row) for row in mine]
            for c, key in enumerate(("seconds", "discs", "registered_pct")):
                axes[r][c].plot(xs, [row[key] for row in mine], marker=".", label=label)
        for c, (title, log) in enumerate([("a) time to generate (s, one thread)", True),
                                          ("b) discs created, n_ss", True),
                                          ("c) points registered (%)", False)]):
            ax = axes[r][c]
            ax.set_xlabel(xlabel)
            ax.set_title(title, fontsize="medium")
            if log:
                ax.set_yscale("log")
            ax.grid(True, alpha=0.3)
        axes[r][0].legend(fontsize="small")
    fig.suptitle("Scale-Like Discs against μ (Paul Fig. 5.7) and n_min (Fig. 5.8)")
    _save(fig, path)


# ---------------------------------------------------------------------------
# Paul Fig. 3.2: coverage of the combined sweeps of n_Q candidates


def _candidates_point(scenario: str, sizes: List[int], seed: int) -> dict:
    """One draw of the candidate study (a Ray task)."""
    import surveyor

    table = surveyor.candidate_coverage(scenario, sizes, seed=seed)
    return {k: [v.item() for v in table[k]] for k in table}


def fit_exponential(x: Sequence[float], y: Sequence[float]) -> Tuple[float, float, float]:
    """The least-squares fit ``y = c_inf - (c_inf - c_0) exp(-x / tau)``
    (tau searched on a logarithmic grid, c_inf and c_0 solved for each):
    returns ``(c_inf, c_0, tau)``."""
    import numpy as np

    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)
    if len(x) < 3:
        raise ValueError("fit_exponential needs at least 3 points")
    best = None
    for tau in np.geomspace(1.0, 1e5, 2000):
        e = np.exp(-x / tau)
        a = np.column_stack([np.ones_like(x), e])
        coef, *_ = np.linalg.lstsq(a, y, rcond=None)
        err = float(np.sum((a @ coef - y) ** 2))
        if best is None or err < best[0]:
            best = (err, coef, tau)
    _, (c_inf, b), tau = best
    return float(c_inf), float(c_inf + b), float(tau)


def candidates(scenario: str = "bridge1", out: PathLike = "studies", *,
               sizes: Iterable[int] = CANDIDATE_SIZES, seeds: Iterable[int] = range(5),
               address: Optional[str] = None, num_cpus: Optional[int] = None,
               ray_options: Optional[Dict[str, Any]] = None,
               log: Optional[Callable[[str], None]] = None) -> Path:
    """Paul Fig. 3.2 on ``scenario``: for each seed (one Ray task, one draw
    of ``max(sizes)`` candidates uniformly within the joint limits), the A1
    coverage of the start's sweep and of the sweeps of every clear candidate
    among the first n_Q, for each n_Q of ``sizes`` and n_Q = 0
    (``surveyor.candidate_coverage``).

    Writes ``out/candidates_study.csv`` (``CANDIDATE_COLUMNS``) and
    ``out/candidates_study.png`` (coverage against n_Q: every draw, their
    mean, and the exponential of ``fit_exponential`` through all points);
    returns the CSV's path. Draws already in ``out/candidates_study/`` are
    not computed again."""
    import surveyor

    sizes = sorted({int(s) for s in sizes})
    if not sizes:
        raise ValueError("sizes: expected at least one n_Q")
    if sizes[-1] > 20_000 or sizes[0] < 0:
        raise ValueError("sizes: expected 0 to 20000 candidates")
    sizes = sorted({0, *sizes})
    seeds = sorted({int(s) for s in seeds})
    if not seeds or seeds[0] < 0 or seeds[-1] >= 2**64:
        raise ValueError("seeds: expected at least one, each 0 to 2**64 - 1")
    # The scenario is loaded here (its regions), so that a bad one is an
    # error before anything runs.
    surveyor.Mapper(scenario=scenario)
    out = Path(out).absolute()
    out.mkdir(parents=True, exist_ok=True)
    say = log or (lambda line: None)
    from .campaign import _for_worker, scene_folder_name

    scene = scene_folder_name(scenario)
    tag = _hash8(sizes)
    tasks = {out / "candidates_study" / f"{scene}-seed{s}-{tag}.json":
             (_candidates_point, (_for_worker(scenario), sizes, s)) for s in seeds}
    _run_tasks(tasks, address, num_cpus, ray_options, say)
    rows = []
    for (path, (_, (_, _, s))) in tasks.items():
        r = _load(path)
        for k in range(len(r["n_q"])):
            rows.append({"scene": scene, "seed": s, **{c: r[c][k] for c in CANDIDATE_COLUMNS[2:]}})
    csv_path = out / CANDIDATES_CSV
    _write_csv(csv_path, CANDIDATE_COLUMNS, rows)
    _plot_candidates(out / CANDIDATES_PNG, rows, scene)
    return csv_path


def _plot_candidates(path: Path, rows: List[dict], scene: str) -> None:
    import numpy as np

    fig, axes = _figure(1, 2, (13, 4.8))
    ax, clear_ax = axes[0]
    seeds = sorted({r["seed"] for r in rows})
    for s in seeds:
        mine = [r for r in rows if r["seed"] == s]
        ax.plot([r["n_q"] for r in mine], [100 * r["coverage_run"] for r in mine], ".",
                ms=3, alpha=0.5, label=f"draw {s}" if len(seeds) <= 6 else None)
        clear_ax.plot([r["n_q"] for r in mine], [r["clear_run"] for r in mine], ".", ms=3, alpha=0.5)
    sizes = sorted({r["n_q"] for r in rows})
    for key, style, label in (("coverage_run", "-", "mean, run's rule"),
                              ("coverage_contact", "--", "mean, no-contact rule")):
        mean = [100 * statistics.mean(r[key] for r in rows if r["n_q"] == n) for n in sizes]
        ax.plot(sizes, mean, style, color="black", lw=1, label=label)
    fit_rows = [r for r in rows if r["n_q"] > 0]
    if len(fit_rows) >= 3:
        c_inf, c_0, tau = fit_exponential([r["n_q"] for r in fit_rows],
                                          [100 * r["coverage_run"] for r in fit_rows])
        xs = np.linspace(0, sizes[-1], 200)
        ax.plot(xs, c_inf - (c_inf - c_0) * np.exp(-xs / tau), color="tab:red", lw=1.5,
                label=f"fit {c_inf:.1f} − {c_inf - c_0:.1f}·exp(−n_Q/{tau:.0f}) %")
    ax.axvline(1571, color="grey", ls=":", lw=1)
    ax.text(1571, 0.4, " Stage One's roadmap, n_Q = 1571", color="grey", fontsize="small",
            transform=ax.get_xaxis_transform())
    ax.set_xlabel("contending viewpoints n_Q (drawn uniformly in C-space)")
    ax.set_ylabel("A1 coverage of all their sweeps and the start's (%)")
    ax.set_title(f"{scene}: coverage of the combined sweeps (Paul Fig. 3.2)", fontsize="medium")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize="small", loc="lower right")
    clear_ax.plot(sizes, sizes, color="grey", lw=0.8, label="all candidates")
    clear_ax.set_xlabel("contending viewpoints n_Q")
    clear_ax.set_ylabel("candidates clear by the run's rule")
    clear_ax.set_title("feasible candidates (whole sweep clear)", fontsize="medium")
    clear_ax.grid(True, alpha=0.3)
    clear_ax.legend(fontsize="small")
    _save(fig, path)


# ---------------------------------------------------------------------------
# Stage One's strategies: the information gains and selections side by side


def _strategy_table(strategies) -> Dict[str, Dict[str, Any]]:
    """``strategies`` (names of ``STRATEGIES``, or a mapping of name to
    ``[explore]`` overrides) as an ordered dict of name to overrides,
    checked: a ``ValueError`` for an unknown, repeated or badly formed name
    and for two strategies that would be the same runs."""
    if isinstance(strategies, str):
        strategies = [strategies]
    if isinstance(strategies, Mapping):
        table = {}
        for name, overrides in strategies.items():
            if not isinstance(overrides, Mapping) or not all(isinstance(k, str) for k in overrides):
                raise ValueError(f"strategies[{name!r}]={overrides!r}: expected a dict of "
                                 "[explore] overrides ({} for none)")
            table[name] = dict(overrides)
    else:
        try:
            names = list(strategies)
        except TypeError:
            raise ValueError(f"strategies={strategies!r}: expected names or a mapping "
                             "of name to [explore] overrides") from None
        table = {}
        for name in names:
            if name not in STRATEGIES:
                raise ValueError(f"strategies: unknown strategy {name!r} "
                                 f"(known: {', '.join(STRATEGIES)})")
            if name in table:
                raise ValueError(f"strategies: {name!r} is listed twice")
            table[name] = dict(STRATEGIES[name])
    if not table:
        raise ValueError("strategies: expected at least one")
    seen: Dict[str, str] = {}
    for name, overrides in table.items():
        if not (isinstance(name, str) and re.fullmatch(r"[A-Za-z0-9_.+-]+", name)):
            raise ValueError(f"strategies: name {name!r}: expected letters, digits and _ . + -")
        try:
            key = json.dumps(overrides, sort_keys=True, allow_nan=False)
        except (TypeError, ValueError) as e:
            raise ValueError(f"strategies[{name!r}]={overrides!r}: not JSON ({e})") from None
        if key in seen:
            raise ValueError(f"strategies {seen[key]!r} and {name!r} have the same overrides "
                             f"{key}: they would be the same runs")
        seen[key] = name
    return table


def _strategy_config(overrides: Dict[str, Any], max_viewpoints: int) -> Dict[str, Any]:
    """The campaign config of a strategy: Stage One alone, timed (the
    decision times are the study's), without the report page (the study's
    132 runs would hold 1.3 GB of them), the overrides as the scenario's
    ``[explore]`` table (no table when there are none)."""
    config: Dict[str, Any] = {"stages": "one", "max_viewpoints": max_viewpoints, "timings": True,
                              "report": False}
    if overrides:
        config["explore"] = overrides
    return config


def _number(value: Any) -> Optional[float]:
    """``value`` as a Python float; None for no value (None, NaN, not a number)."""
    if value is None or isinstance(value, bool):
        return None
    try:
        x = float(value)
    except (TypeError, ValueError):
        return None
    return None if x != x else x


def _whole(value: Any) -> Optional[int]:
    x = _number(value)
    return None if x is None else int(x)


def _strategy_run(folder: Path) -> Tuple[dict, dict]:
    """One finished run of the study: its ``STRATEGY_COLUMNS`` values
    (without scene, seed, strategy and folder) and the series the plots
    draw (Stage One's ``a1`` after each viewpoint, cumulative ``time_s``,
    ``decision_ms`` of each chosen viewpoint, the ``oracle``'s A1 after
    1, 2, ... sweeps)."""
    import numpy as np
    import surveyor

    run = surveyor.Run.load(folder)
    s = run.summary
    vp = run.viewpoints
    names = vp.dtype.names or ()

    def column(name):
        return np.asarray(vp[name], dtype=float) if name in names else np.full(len(vp), np.nan)

    one = np.asarray(vp["stage"]) == 1 if "stage" in names else np.ones(len(vp), dtype=bool)
    order = np.argsort(np.asarray(vp["k"])[one], kind="stable") if "k" in names else slice(None)
    a1 = column("coverage_a1")[one][order]
    per_viewpoint_s = column("robot_time_s")[one][order]
    decision = column("decision_ms")[one][order][1:]  # the start's sweep is no decision
    coverage = s.get("coverage") or {}
    oracle = coverage.get("oracle") or {}
    counts = s.get("viewpoints") or {}
    viewpoints = _whole(counts.get("stage_one"))
    if viewpoints is None:
        viewpoints = len(a1)
    termination = s.get("termination")
    # After 12 viewpoints (the start's the first): viewpoint k = 11, or the
    # last of a Stage One that ended sooner (as run.json's ratio_after_12).
    a1_at_12 = _number(a1[min(11, len(a1) - 1)]) if len(a1) else None
    oracle_at_12 = _number(oracle.get("A1_after_12"))
    robot_time = _number((s.get("robot_time_s") or {}).get("stage_one"))
    if robot_time is None and len(per_viewpoint_s):
        robot_time = _number(np.nansum(per_viewpoint_s))
    values = {
        "viewpoints": viewpoints,
        "termination": termination,
        "viewpoints_to_rule": viewpoints if termination == "information_converged" else None,
        "a1_at_12": a1_at_12,
        "oracle_a1_at_12": oracle_at_12,
        "ratio_at_12": (a1_at_12 / oracle_at_12
                        if a1_at_12 is not None and oracle_at_12 else None),
        "a1_final": _number(coverage.get("A1")),
        "joint_travel_rad": _number(np.nansum(column("joint_travel")[one])),
        "robot_time_s": robot_time,
        "decision_median_ms": _number((s.get("decision_ms") or {}).get("median")),
        "collisions": _whole(s.get("collisions")),
        "unsafe_configurations": _whole(s.get("unsafe_configurations")),
    }
    sweeps = (oracle.get("oracle") or {}).get("A1_after_sweeps") or []
    series = {
        "a1": [_number(v) for v in a1],
        "time_s": [_number(v) for v in np.cumsum(np.nan_to_num(per_viewpoint_s))],
        "decision_ms": [v for v in (_number(d) for d in decision) if v is not None and v > 0],
        "oracle": [_number(v) for v in sweeps],
    }
    return values, series


def strategies(scenarios: Union[str, Sequence[str]] = STRATEGY_SCENARIOS,
               seeds: Union[int, Iterable[int]] = (0, 1, 2), out: PathLike = "studies", *,
               strategies: Union[Sequence[str], Mapping[str, Dict[str, Any]]] = tuple(STRATEGIES),
               max_viewpoints: int = 20, address: Optional[str] = None,
               num_cpus: Optional[int] = None, ray_options: Optional[Dict[str, Any]] = None,
               log: Optional[Callable[[str], None]] = None) -> Path:
    """Stage One's strategies side by side: for each scenario, seed and
    strategy a Stage One run (``surveyor.campaign.run``, a Ray task each,
    into ``out/strategies_runs/``) of at most ``max_viewpoints`` viewpoints
    with the strategy's ``[explore]`` overrides, timed (``timings=True``:
    the decision times are part of the study, and the robot time counts
    them as measured). ``strategies``: names of ``STRATEGIES`` (default: all
    of them), or a mapping of name to ``[explore]`` overrides (``{}`` for
    the scenario's own). Runs already in ``out/strategies_runs/`` are not run
    again (the campaign's resumption).

    Writes, from every finished run:

    * ``out/strategies_study.csv`` (``STRATEGY_COLUMNS``; a row per run,
      empty cells for no value): the Stage One ``viewpoints`` and
      ``termination``; ``viewpoints_to_rule``, the viewpoints when the 1 %
      rule ended Stage One (``information_converged``), else empty;
      ``a1_at_12``, viewpoints.csv's ``coverage_a1`` after 12 viewpoints (the
      start's the first: k = 11), or after the last when Stage One ended
      sooner; ``oracle_a1_at_12``, the coverage oracle's after 12 sweeps
      (run.json's ``coverage.oracle.A1_after_12``) and ``ratio_at_12``, the
      first over it; ``a1_final`` (run.json's ``coverage.A1``);
      ``joint_travel_rad``, the sum of viewpoints.csv's ``joint_travel`` over
      Stage One; ``robot_time_s``, Stage One's robot time (run.json's
      ``robot_time_s.stage_one``: the sum of viewpoints.csv's per-viewpoint
      ``robot_time_s``); ``decision_median_ms`` (run.json's
      ``decision_ms.median``); ``collisions``, ``unsafe_configurations``; the
      run ``folder`` relative to ``out``;
    * ``out/strategies_table.md``: a table per measure, a row per strategy,
      a column per scene (the mean over its seeds) and one over all;
    * ``out/strategies_coverage.png`` (A1 coverage against viewpoints, the
      mean over the seeds of each strategy beside the oracle's),
      ``out/strategies_time.png`` (A1 coverage against Stage One's robot
      time, a line per run) and ``out/strategies_decision.png`` (each
      strategy's decision times, every chosen viewpoint of every run).

    Returns the CSV's path. Raises ``ValueError`` for a bad argument (an
    unknown strategy, no scenario or seed, ``max_viewpoints`` not 1 to 1000,
    a scenario the overrides do not fit) before anything runs, and the
    campaign's ``CampaignError`` when runs failed, after writing the files
    from the others."""
    from .campaign import CampaignError, _scenarios, _seeds, canonical_json, run, scene_folder_name

    table = _strategy_table(strategies)
    if isinstance(max_viewpoints, bool) or not isinstance(max_viewpoints, int) \
            or not 1 <= max_viewpoints <= 1000:
        raise ValueError(f"max_viewpoints={max_viewpoints!r}: expected a whole number, 1 to 1000")
    scenario_list = list(dict.fromkeys(_scenarios(scenarios)))
    seed_list = sorted(set(_seeds(seeds)))
    configs = {name: _strategy_config(overrides, max_viewpoints)
               for name, overrides in table.items()}
    by_config = {canonical_json(config): name for name, config in configs.items()}
    out = Path(out).absolute()
    runs_out = out / STRATEGY_RUNS
    say = log or (lambda line: None)
    failure = None
    try:
        # campaign.run checks every scenario with every config before Ray
        # starts or a folder is made.
        result = run(scenario_list, seed_list, list(configs.values()), out=runs_out,
                     address=address, num_cpus=num_cpus, ray_options=ray_options, log=say)
    except CampaignError as e:
        failure, result = e, e.result
    say(f"strategies: {len(result.ran)} runs done now, {len(result.skipped)} already done"
        + (f", {len(result.failed)} failed" if result.failed else ""))
    rows, series = [], {}
    for r in result.rows:
        name = by_config[r["config"]]
        folder = runs_out / r["folder"]
        values, drawn = _strategy_run(folder)
        row = {"scene": scene_folder_name(r["scene"]), "seed": r["seed"], "strategy": name,
               **values, "folder": folder.relative_to(out).as_posix()}
        rows.append(row)
        series[(row["scene"], row["seed"], name)] = drawn
    scene_order = {scene_folder_name(s): i for i, s in enumerate(scenario_list)}
    strategy_order = {name: i for i, name in enumerate(table)}
    rows.sort(key=lambda row: (scene_order[row["scene"]], row["seed"],
                               strategy_order[row["strategy"]]))
    scenes = list(scene_order)
    names = list(table)
    colours = _strategy_colours(names)
    csv_path = out / STRATEGIES_CSV
    _write_csv(csv_path, STRATEGY_COLUMNS, rows)
    _write_atomic(out / STRATEGIES_MD,
                  _strategies_markdown(rows, scenes, names, table, seed_list, max_viewpoints))
    _plot_strategy_coverage(out / STRATEGIES_COVERAGE_PNG, rows, series, scenes, names, colours)
    _plot_strategy_time(out / STRATEGIES_TIME_PNG, rows, series, scenes, names, colours)
    _plot_strategy_decision(out / STRATEGIES_DECISION_PNG, rows, series, names, colours)
    if failure is not None:
        raise failure
    return csv_path


def _strategy_colours(names: Sequence[str]) -> Dict[str, Any]:
    """A fixed colour per strategy: ``STRATEGIES``' own by their place in
    it (tab20's dark shades first, then its light ones), the others after."""
    from matplotlib import colormaps

    cmap = colormaps["tab20"]
    shades = [cmap(i) for i in range(0, 20, 2)] + [cmap(i) for i in range(1, 20, 2)]
    known = list(STRATEGIES)
    others = [n for n in names if n not in STRATEGIES]
    return {n: shades[(known.index(n) if n in STRATEGIES else len(known) + others.index(n))
                      % len(shades)] for n in names}


def _mean(values: Iterable[Optional[float]]) -> Optional[float]:
    xs = [v for v in values if v is not None]
    return statistics.mean(xs) if xs else None


def _strategies_markdown(rows: List[dict], scenes: List[str], names: List[str],
                         table: Dict[str, Dict[str, Any]], seeds: List[int],
                         max_viewpoints: int) -> str:
    def fmt(digits):
        return lambda v: "–" if v is None else f"{v:.{digits}f}"

    def ms(v):
        return "–" if v is None else (f"{v:.0f}" if v >= 100 else f"{v:.3g}")

    def pct(v):
        return "–" if v is None else f"{100 * v:.1f}"

    def rule(mine):
        reached = [r["viewpoints_to_rule"] for r in mine if r["viewpoints_to_rule"] is not None]
        if not mine:
            return "–"
        mean = f"{statistics.mean(reached):.1f}" if reached else "–"
        return f"{mean} ({len(reached)}/{len(mine)})"

    measures = [
        ("A1 coverage after 12 viewpoints (%)",
         lambda mine: pct(_mean(r["a1_at_12"] for r in mine))),
        ("A1 after 12 viewpoints over the oracle's after 12 sweeps",
         lambda mine: fmt(3)(_mean(r["ratio_at_12"] for r in mine))),
        ("A1 coverage at the end of Stage One (%)",
         lambda mine: pct(_mean(r["a1_final"] for r in mine))),
        ("Viewpoints to the 1 % rule (mean over the runs it ended; how many of them)", rule),
        ("Joint travel of Stage One (rad)",
         lambda mine: fmt(1)(_mean(r["joint_travel_rad"] for r in mine))),
        ("Robot time of Stage One (s)",
         lambda mine: fmt(0)(_mean(r["robot_time_s"] for r in mine))),
        ("Median decision time (ms)",
         lambda mine: ms(_mean(r["decision_median_ms"] for r in mine))),
    ]
    expected = len(scenes) * len(seeds) * len(names)
    lines = [
        "# Stage One's strategies",
        "",
        f"Stage One alone, at most {max_viewpoints} viewpoints (the start's the first), "
        f"seeds {', '.join(map(str, seeds))}; {len(rows)} of {expected} runs finished. "
        "A cell is the mean over the scene's seeds, \"all\" over every scene and seed; "
        "– for no value. The robot time counts the decisions as measured on the machine "
        "that ran them.",
        "",
        "Strategies (their `[explore]` overrides):",
        "",
    ]
    lines += [f"- `{name}`: `{json.dumps(table[name], sort_keys=True)}`" for name in names]
    header = "| strategy | " + " | ".join(scenes) + " | all |"
    rule_line = "|---|" + "---:|" * (len(scenes) + 1)
    for title, cell in measures:
        lines += ["", f"## {title}", "", header, rule_line]
        for name in names:
            mine = [r for r in rows if r["strategy"] == name]
            cells = [cell([r for r in mine if r["scene"] == scene]) for scene in scenes]
            lines.append(f"| {name} | " + " | ".join(cells + [cell(mine)]) + " |")
    return "\n".join(lines) + "\n"


def _scene_axes(scenes: List[str], size: Tuple[float, float]):
    cols = min(len(scenes), 2) or 1
    nrows = (len(scenes) + cols - 1) // cols or 1
    fig, axes = _figure(nrows, cols, (size[0] * cols + 2.5, size[1] * nrows))
    axes = axes.ravel()
    for ax in axes[len(scenes):]:
        ax.set_axis_off()
    return fig, axes


def _strategy_legend(fig, names: List[str], colours: Dict[str, Any], oracle: bool) -> None:
    from matplotlib.lines import Line2D

    handles = [Line2D([], [], color=colours[n], lw=1.5, label=n) for n in names]
    if oracle:
        handles.append(Line2D([], [], color="black", lw=3, ls="--", label="coverage oracle"))
    fig.legend(handles=handles, loc="outside lower center", ncols=min(len(handles), 6),
               fontsize="small")


def _plot_strategy_coverage(path: Path, rows: List[dict], series: Dict[tuple, dict],
                            scenes: List[str], names: List[str], colours: Dict[str, Any]) -> None:
    from matplotlib.ticker import MaxNLocator

    fig, axes = _scene_axes(scenes, (5.5, 4))
    any_oracle = False
    for ax, scene in zip(axes, scenes):
        mine = [r for r in rows if r["scene"] == scene]
        longest = 0
        for name in names:
            curves = [[v for v in series[(r["scene"], r["seed"], name)]["a1"] if v is not None]
                      for r in mine if r["strategy"] == name]
            curves = [c for c in curves if c]
            if not curves:
                continue
            n = max(len(c) for c in curves)
            longest = max(longest, n)
            # A run that ended sooner keeps its last coverage.
            mean = [100 * statistics.mean(c[min(i, len(c) - 1)] for c in curves) for i in range(n)]
            ax.plot(range(1, n + 1), mean, color=colours[name], lw=1.5, marker=".", ms=3)
        oracles = {r["seed"]: [v for v in series[(r["scene"], r["seed"], r["strategy"])]["oracle"]
                               if v is not None] for r in mine}
        oracles = [o for o in oracles.values() if o]
        if oracles:
            any_oracle = True
            n = min(max(longest, 12), min(len(o) for o in oracles))
            mean = [100 * statistics.mean(o[i] for o in oracles) for i in range(n)]
            ax.plot(range(1, n + 1), mean, color="black", lw=3, ls="--", zorder=1)
        seeds = len({r["seed"] for r in mine})
        ax.set_title(f"{scene} (mean over {seeds} seeds)", fontsize="medium")
        ax.set_xlabel("viewpoints (the start's the first)")
        ax.set_ylabel("A1 coverage (%)")
        ax.xaxis.set_major_locator(MaxNLocator(integer=True))
        ax.grid(True, alpha=0.3)
    _strategy_legend(fig, names, colours, any_oracle)
    fig.suptitle("Stage One's strategies: A1 coverage against viewpoints\n"
                 "(a run that ended sooner keeps its last coverage)", fontsize="medium")
    _save(fig, path)


def _plot_strategy_time(path: Path, rows: List[dict], series: Dict[tuple, dict],
                        scenes: List[str], names: List[str], colours: Dict[str, Any]) -> None:
    fig, axes = _scene_axes(scenes, (5.5, 4))
    for ax, scene in zip(axes, scenes):
        for r in rows:
            if r["scene"] != scene:
                continue
            s = series[(r["scene"], r["seed"], r["strategy"])]
            points = [(t, 100 * a) for t, a in zip(s["time_s"], s["a1"])
                      if t is not None and a is not None]
            if points:
                ax.plot(*zip(*points), color=colours[r["strategy"]], lw=0.8, alpha=0.8,
                        marker=".", ms=2)
        ax.set_title(f"{scene} (a line per seed)", fontsize="medium")
        ax.set_xlabel("robot time of Stage One (s, cumulative)")
        ax.set_ylabel("A1 coverage (%)")
        ax.grid(True, alpha=0.3)
    _strategy_legend(fig, names, colours, False)
    fig.suptitle("Stage One's strategies: A1 coverage against robot time", fontsize="medium")
    _save(fig, path)


def _plot_strategy_decision(path: Path, rows: List[dict], series: Dict[tuple, dict],
                            names: List[str], colours: Dict[str, Any]) -> None:
    from matplotlib.ticker import FuncFormatter

    fig, axes = _figure(1, 1, (max(6.0, 0.8 * len(names) + 2), 4.5))
    ax = axes[0][0]
    data = {n: [] for n in names}
    for r in rows:
        data[r["strategy"]].extend(series[(r["scene"], r["seed"], r["strategy"])]["decision_ms"])
    shown = [n for n in names if data[n]]
    if shown:
        box = ax.boxplot([data[n] for n in shown], positions=range(1, len(shown) + 1),
                         widths=0.6, patch_artist=True, showfliers=True,
                         medianprops={"color": "black"})
        for patch, n in zip(box["boxes"], shown):
            patch.set_facecolor(colours[n])
            patch.set_alpha(0.7)
        ax.set_yscale("log")
        # Plain numbers: the decades, and 2 and 5 between them.
        ax.yaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
        ax.yaxis.set_minor_formatter(FuncFormatter(
            lambda v, _: f"{v:g}" if f"{v:.0e}"[0] in "25" else ""))
        ax.tick_params(axis="y", which="both", labelsize="small")
    else:
        ax.text(0.5, 0.5, "no decision timed", ha="center", va="center", transform=ax.transAxes)
    ax.set_xticks(range(1, len(shown) + 1))
    ax.set_xticklabels([f"{n}\n({len(data[n])})" for n in shown], rotation=30, ha="right",
                       fontsize="small")
    ax.set_ylabel("decision time per viewpoint (ms)")
    ax.set_title("Stage One's decision times:\nevery chosen viewpoint of every run (how many)",
                 fontsize="medium")
    ax.grid(True, axis="y", alpha=0.3, which="both")
    _save(fig, path)


# ---------------------------------------------------------------------------
# Command line


def _numbers(text: str, kind):
    try:
        return [kind(v) for v in text.split(",") if v.strip()]
    except ValueError:
        raise ValueError(f"{text!r}: expected a comma list of numbers") from None


def _sizes(text: str) -> List[int]:
    """``"50-3500:50"`` (a range with a step) or ``"0,10,20"``."""
    try:
        if ":" in text:
            span, step = text.split(":", 1)
            lo, hi = span.split("-", 1)
            sizes = list(range(int(lo), int(hi) + 1, int(step)))
        else:
            sizes = _numbers(text, int)
    except ValueError:
        raise ValueError(f"--sizes {text!r}: expected A-B:STEP or a comma list of whole numbers") from None
    if not sizes:
        raise ValueError(f"--sizes {text!r}: no n_Q in it")
    return sizes


def main(argv: Optional[List[str]] = None) -> int:
    from .campaign import parse_seeds

    parser = argparse.ArgumentParser(
        prog="python -m surveyor.studies",
        description="The theses' parameter studies as campaigns on Ray (resumable).")
    sub = parser.add_subparsers(dest="study", required=True)
    p = sub.add_parser("sld", help="Paul Figs 5.7-5.8: discs against mu and n_min on a run's maps")
    p.add_argument("--run", required=True, help="an explore run folder")
    p.add_argument("--inputs", default="mesh,cloud", help="mesh, cloud or both (default)")
    p.add_argument("--mus", help="disc radii in metres, comma-separated (default: 2 to 50 mm)")
    p.add_argument("--n-mins", help="n_min values, comma-separated (default: 3 to 100)")
    p.add_argument("--repeats", type=int, default=3, help="timings per point (median kept)")
    q = sub.add_parser("candidates", help="Paul Fig. 3.2: coverage of n_Q candidates' sweeps")
    q.add_argument("--scenario", default="bridge1")
    q.add_argument("--seeds", default="0-4", help="draws: N, A-B or a comma list (default 0-4)")
    q.add_argument("--sizes", default="50-3500:50", help="n_Q values: A-B:STEP or a comma list")
    t = sub.add_parser("strategies", help="Stage One's strategies side by side (a campaign)")
    t.add_argument("--scenarios", default=",".join(STRATEGY_SCENARIOS),
                   help="comma-separated scenarios (default: %(default)s)")
    t.add_argument("--seeds", default="0-2", help="seeds: N, A-B or a comma list (default 0-2)")
    t.add_argument("--strategies", default=",".join(STRATEGIES),
                   help="comma-separated strategies of studies.STRATEGIES (default: all)")
    t.add_argument("--max-viewpoints", type=int, default=20,
                   help="Stage One's budget, the start's viewpoint included (default 20)")
    for a in (p, q, t):
        a.add_argument("--out", required=True, help="the study folder")
        a.add_argument("--address", help='a Ray cluster to join ("auto"); default: a local Ray')
        a.add_argument("--num-cpus", type=int, help="CPUs of a local Ray (default: all)")
    args = parser.parse_args(argv)

    def log(line: str) -> None:
        print(line, file=sys.stderr, flush=True)

    common = dict(address=args.address, num_cpus=args.num_cpus, log=log)
    kw: Dict[str, Any] = {}
    try:
        if args.study == "sld":
            if args.mus:
                kw["mus_m"] = _numbers(args.mus, float)
            if args.n_mins:
                kw["n_mins"] = _numbers(args.n_mins, int)
        elif args.study == "candidates":
            kw["sizes"] = _sizes(args.sizes)
            kw["seeds"] = parse_seeds(args.seeds)
        else:
            kw["scenarios"] = [s.strip() for s in args.scenarios.split(",") if s.strip()]
            if not kw["scenarios"]:
                raise ValueError("--scenarios: expected one or more names, e.g. bridge1,bridge2")
            kw["seeds"] = parse_seeds(args.seeds)
            kw["strategies"] = [s.strip() for s in args.strategies.split(",") if s.strip()]
            _strategy_table(kw["strategies"])
            if not 1 <= args.max_viewpoints <= 1000:
                raise ValueError(f"--max-viewpoints {args.max_viewpoints}: expected 1 to 1000")
    except ValueError as e:
        parser.error(str(e))
    if args.num_cpus is not None and args.num_cpus < 1:
        parser.error("--num-cpus: expected at least 1")
    try:
        if args.study == "sld":
            path = sld(args.run, args.out, inputs=[i.strip() for i in args.inputs.split(",")],
                       repeats=args.repeats, **kw, **common)
        elif args.study == "candidates":
            path = candidates(args.scenario, args.out, **kw, **common)
        else:
            path = strategies(out=args.out, max_viewpoints=args.max_viewpoints, **kw, **common)
    except (ValueError, OSError, ImportError, RuntimeError) as e:
        print(f"error: {e}", file=sys.stderr)
        return 1
    if args.study == "strategies":
        print(", ".join(os.fspath(path.with_name(name)) for name in (
            STRATEGIES_CSV, STRATEGIES_MD, STRATEGIES_COVERAGE_PNG, STRATEGIES_TIME_PNG,
            STRATEGIES_DECISION_PNG)))
    else:
        print(f"{path} and {path.with_suffix('.png')}")
    return 0


if __name__ == "__main__":
    from surveyor.studies import main as _main

    sys.exit(_main())
