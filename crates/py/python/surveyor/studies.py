"""Two of the theses' parameter studies, as campaigns on Ray.

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

Each point of a study is a Ray task (a local Ray unless ``address`` names a
cluster) whose result is kept as ``out/<study>/<point>.json`` (written under
a temporary name, then renamed): a study called again with the same ``out``
computes only the points missing. From the shell::

    python -m surveyor.studies sld --run bridge1_run --out studies
    python -m surveyor.studies candidates --scenario bridge1 --seeds 0-4 --out studies

Needs ``ray`` and ``matplotlib`` (not dependencies of the package itself).
"""

from __future__ import annotations

import argparse
import csv
import hashlib
import json
import os
import statistics
import sys
from pathlib import Path
from typing import Any, Callable, Dict, Iterable, List, Optional, Sequence, Tuple

from ._runs import PathLike

__all__ = ["sld", "candidates", "fit_exponential", "SLD_MUS_M", "SLD_N_MINS", "SLD_FIXED_MU_M",
           "SLD_FIXED_N_MIN", "CANDIDATE_SIZES", "main"]

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
    for a in (p, q):
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
        else:
            kw["sizes"] = _sizes(args.sizes)
            kw["seeds"] = parse_seeds(args.seeds)
    except ValueError as e:
        parser.error(str(e))
    if args.num_cpus is not None and args.num_cpus < 1:
        parser.error("--num-cpus: expected at least 1")
    try:
        if args.study == "sld":
            path = sld(args.run, args.out, inputs=[i.strip() for i in args.inputs.split(",")],
                       repeats=args.repeats, **kw, **common)
        else:
            path = candidates(args.scenario, args.out, **kw, **common)
    except (ValueError, OSError, ImportError, RuntimeError) as e:
        print(f"error: {e}", file=sys.stderr)
        return 1
    print(f"{path} and {path.with_suffix('.png')}")
    return 0


if __name__ == "__main__":
    from surveyor.studies import main as _main

    sys.exit(_main())
