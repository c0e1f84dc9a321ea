"""Campaigns: many ``surveyor.explore`` runs on Ray, one run folder each.

``run(scenarios, seeds, configs, out)`` runs every (scenario, seed, config)
combination as a Ray task, each into its own run folder under ``out``::

    out/bridge1/seed0/cfg-1a2b3c4d/      # surveyor.explore's run folder (+ campaign.json)
    out/summary.csv                      # one row per finished run
    out/coverage.png                     # A1 coverage against viewpoints, a panel per scene

and is resumable: a combination whose folder holds ``run.json`` is done
(surveyor writes ``run.json`` last, whole or not at all) and is not run
again; a folder without it (a run that was killed) is removed and run anew.

From the shell (exit code 2 for bad arguments, 1 when a run failed)::

    python -m surveyor.campaign --scenarios bridge1,bridge2 --seeds 0-9 \\
        --config '{"stages": "one", "max_viewpoints": 12}' --out DIR [--address auto]

Needs ``ray`` and ``matplotlib`` (not dependencies of the package itself).
"""

from __future__ import annotations

import argparse
import csv
import hashlib
import json
import os
import re
import shutil
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Dict, Iterable, List, Optional, Sequence, Union

from ._runs import PathLike, _seed, check_explore

__all__ = ["run", "Combination", "CampaignResult", "CampaignError", "COLUMNS", "combinations",
           "canonical_json", "scene_folder_name", "parse_seeds", "run_one", "main"]

#: The columns of summary.csv, in order. ``wall_s`` (the run's wall-clock
#: time, measured around the ``surveyor.explore`` call) is the one that
#: differs between two campaigns of the same runs; it is kept last.
COLUMNS = (
    "scene",
    "seed",
    "config",
    "viewpoints_stage_one",
    "viewpoints_stage_two",
    "coverage_a1",
    "material_accuracy",
    "collisions",
    "folder",
    "wall_s",
)

#: The file the campaign adds to each run folder once the run is done:
#: scene, seed, config and wall_s of the run (so a resumed campaign still
#: knows how long an earlier run took, and a folder says what it holds).
CAMPAIGN_JSON = "campaign.json"
SUMMARY_CSV = "summary.csv"
COVERAGE_PNG = "coverage.png"

#: Keywords a config cannot set: they are the campaign's.
_RESERVED = ("scenario", "seed", "out")


def canonical_json(config: Dict[str, Any]) -> str:
    """A config as canonical JSON: keys sorted, no spaces, no NaN."""
    return json.dumps(config, sort_keys=True, separators=(",", ":"), allow_nan=False)


def _hash8(text: str) -> str:
    return hashlib.sha256(text.encode("utf-8")).hexdigest()[:8]


def scene_folder_name(scenario: str) -> str:
    """The folder name of a scenario: a built-in name as it is
    (``bridge1``); anything else (a file path) its sanitised stem and a
    short hash of the whole string, so two files of one name differ."""
    if re.fullmatch(r"[A-Za-z0-9_-]+", scenario):
        return scenario
    stem = re.sub(r"[^A-Za-z0-9_-]+", "_", Path(scenario).stem).strip("_") or "scenario"
    return f"{stem[:40]}-{_hash8(scenario)}"


@dataclass(frozen=True, order=True)
class Combination:
    """One run of a campaign: ``scenario``, ``seed`` and ``config_json``
    (the config's canonical JSON). Ordered as summary.csv's rows."""

    scenario: str
    seed: int
    config_json: str

    @property
    def config(self) -> Dict[str, Any]:
        """The config as a dict of ``surveyor.explore`` keywords."""
        return json.loads(self.config_json)

    @property
    def folder(self) -> Path:
        """The run folder, relative to the campaign's ``out``:
        ``<scene>/seed<seed>/cfg-<first 8 hex digits of the config JSON's SHA-256>``."""
        return Path(scene_folder_name(self.scenario), f"seed{self.seed}",
                    f"cfg-{_hash8(self.config_json)}")

    def __str__(self) -> str:
        return f"{self.scenario} seed {self.seed} config {self.config_json}"


@dataclass
class CampaignResult:
    """What ``run`` did.

    * ``rows``: summary.csv's rows (every finished run of the campaign,
      sorted by scene, seed and config), each a dict keyed by ``COLUMNS``:
      ``seed``, ``viewpoints_stage_*`` and ``collisions`` ints,
      ``coverage_a1``, ``material_accuracy`` and ``wall_s`` floats or
      ``None`` (an empty cell), the others strings;
    * ``ran``: the combinations run by this call (``len(result.ran)`` runs
      done), in the order they finished;
    * ``skipped``: those already done in ``out`` (not run again);
    * ``failed``: ``(combination, message)`` of the runs that failed (``run``
      raises ``CampaignError`` then, carrying this result);
    * ``summary``, ``plot``: the paths of summary.csv and coverage.png.
    """

    out: Path
    rows: List[Dict[str, Any]] = field(default_factory=list)
    ran: List[Combination] = field(default_factory=list)
    skipped: List[Combination] = field(default_factory=list)
    failed: List[tuple] = field(default_factory=list)

    @property
    def summary(self) -> Path:
        return self.out / SUMMARY_CSV

    @property
    def plot(self) -> Path:
        return self.out / COVERAGE_PNG


class CampaignError(RuntimeError):
    """Runs of a campaign failed. Raised once every other run has finished
    and summary.csv and coverage.png hold the finished ones; ``failures``
    lists ``(combination, message)``, ``result`` the ``CampaignResult``."""

    def __init__(self, result: CampaignResult):
        self.result = result
        self.failures = list(result.failed)
        lines = [f"{c}: {message}" for c, message in self.failures]
        super().__init__(
            f"{len(self.failures)} of {len(result.ran) + len(self.failures) + len(result.skipped)} "
            f"campaign runs failed (the others are in {result.out}):\n  " + "\n  ".join(lines))


# ---------------------------------------------------------------------------
# Arguments


def _scenarios(scenarios: Union[str, Iterable[str]]) -> List[str]:
    bad = ValueError(f"scenarios={scenarios!r}: expected one or more scenario names or files")
    if isinstance(scenarios, (str, os.PathLike)):
        scenarios = [scenarios]
    try:
        items = list(scenarios)
    except TypeError:
        raise bad from None
    if not items or any(not isinstance(s, (str, os.PathLike)) for s in items):
        raise bad
    names = [os.fspath(s) for s in items]
    if any(not isinstance(s, str) or not s for s in names):
        raise bad
    return names


def _seeds(seeds: Union[int, Iterable[int]]) -> List[int]:
    if isinstance(seeds, int):
        seeds = [seeds]
    try:
        values = [_seed(s) for s in seeds]
    except TypeError:
        raise ValueError(f"seeds={seeds!r}: expected whole numbers") from None
    if not values:
        raise ValueError("seeds: expected at least one seed")
    return values


def _configs(configs) -> List[str]:
    """The configs' canonical JSON, checked: dicts with string keys, no
    reserved key, values JSON can hold."""
    if configs is None:
        configs = [{}]
    elif isinstance(configs, dict):
        configs = [configs]
    configs = list(configs)
    if not configs:
        raise ValueError("configs: expected a dict, a list of dicts or None")
    out = []
    for i, config in enumerate(configs):
        if not isinstance(config, dict) or not all(isinstance(k, str) for k in config):
            raise ValueError(f"configs[{i}]={config!r}: expected a dict of surveyor.explore keywords")
        reserved = [k for k in _RESERVED if k in config]
        if reserved:
            raise ValueError(f"configs[{i}]: {reserved[0]!r} is set by the campaign, not by a config")
        try:
            out.append(canonical_json(config))
        except (TypeError, ValueError) as e:
            raise ValueError(f"configs[{i}]={config!r}: not JSON ({e})") from None
    return out


def combinations(scenarios, seeds, configs=None) -> List[Combination]:
    """Every (scenario, seed, config) combination, sorted, each once."""
    return sorted({Combination(s, n, c) for s in _scenarios(scenarios) for n in _seeds(seeds)
                   for c in _configs(configs)})


# ---------------------------------------------------------------------------
# One run (a Ray task)


def _for_worker(scenario: str) -> str:
    """A scenario file as an absolute path (a worker may run elsewhere); a
    built-in name as it is."""
    if not re.fullmatch(r"[A-Za-z0-9_-]+", scenario) and os.path.exists(scenario):
        return os.path.abspath(scenario)
    return scenario


def run_one(scenario: str, seed: int, config_json: str, folder: str) -> Dict[str, Any]:
    """Run one combination into ``folder`` (the body of a campaign's Ray
    task): a folder without run.json (a killed run) is removed first; then
    ``surveyor.explore(scenario, seed=seed, out=folder, timings=False,
    **config)`` (the config may set ``timings``), timed, and campaign.json
    written. Returns ``{"wall_s": seconds}``, or ``{"error": message}``
    when the run raised."""
    import surveyor

    path = Path(folder)
    if (path / "run.json").is_file():  # done meanwhile (a retried task)
        return {"wall_s": _campaign_info(path).get("wall_s")}
    if path.exists() or path.is_symlink():
        if path.is_dir() and not path.is_symlink():
            shutil.rmtree(path)
        else:
            path.unlink()
    config = json.loads(config_json)
    start = time.perf_counter()
    try:
        surveyor.explore(scenario, seed=seed, out=path, **{"timings": False, **config})
    except Exception as e:  # noqa: BLE001 - every failure is reported with its combination
        return {"error": f"{type(e).__name__}: {e}"}
    wall_s = time.perf_counter() - start
    info = {"scene": scenario, "seed": seed, "config": config_json, "wall_s": wall_s}
    _write_atomic(path / CAMPAIGN_JSON, json.dumps(info, indent=2) + "\n")
    return {"wall_s": wall_s}


def _campaign_info(folder: Path) -> Dict[str, Any]:
    try:
        return json.loads((folder / CAMPAIGN_JSON).read_text())
    except (OSError, ValueError):
        return {}


def _write_atomic(path: Path, text: str) -> None:
    tmp = path.with_name(f".{path.name}.tmp-{os.getpid()}")
    tmp.write_text(text)
    os.replace(tmp, path)


# ---------------------------------------------------------------------------
# Ray


def _start_ray(address: Optional[str], num_cpus: Optional[int], ray_options: Optional[dict]):
    """Ray, started or joined; returns (ray, whether this call started it)."""
    try:
        import ray
    except ImportError:
        raise ImportError("surveyor.campaign needs Ray: pip install ray") from None
    if ray.is_initialized():
        return ray, False
    options = dict(ray_options or {})
    options.setdefault("include_dashboard", False)
    if address is None and os.environ.get("RAY_ADDRESS"):
        address = os.environ["RAY_ADDRESS"]
    if address is not None:
        ray.init(address=address, **options)
    else:
        # "local": a Ray of our own, not one found running on this machine.
        ray.init(address="local", num_cpus=num_cpus or os.cpu_count(), **options)
    return ray, True


def completed(ray, pending: Dict[Any, Any]):
    """Yield ``(key, result, error)`` for each Ray task of ``pending`` (a
    dict of object ref to key) as it finishes: ``error`` is None, or the
    text of what the task raised (a crashed worker, a lost node)."""
    waiting = list(pending)
    while waiting:
        done, waiting = ray.wait(waiting, num_returns=1)
        for ref in done:
            try:
                yield pending[ref], ray.get(ref), None
            except Exception as e:  # noqa: BLE001 - every failure is reported with its key
                yield pending[ref], None, f"{type(e).__name__}: {e}"


# ---------------------------------------------------------------------------
# The campaign


def run(
    scenarios: Union[str, Sequence[str]],
    seeds: Union[int, Iterable[int]],
    configs: Union[None, Dict[str, Any], Sequence[Dict[str, Any]]] = None,
    out: PathLike = "campaign",
    address: Optional[str] = None,
    *,
    num_cpus: Optional[int] = None,
    cpus_per_run: float = 1,
    ray_options: Optional[Dict[str, Any]] = None,
    log: Optional[Callable[[str], None]] = None,
) -> CampaignResult:
    """Run every (scenario, seed, config) combination with
    ``surveyor.explore`` as a Ray task, each into its own run folder under
    ``out``, and write ``out/summary.csv`` and ``out/coverage.png``.

    ``scenarios``: built-in names or scenario files (a str is one).
    ``seeds``: noise seeds (an int is one; ``range(10)``). ``configs``: a
    dict of ``surveyor.explore`` keywords applied to every run (``{"stages":
    "one", "max_viewpoints": 12}``, or a scenario key such as
    ``{"explore": {"local_candidates": 0}}``), or a list of such dicts, each
    a variant; ``None`` is ``[{}]``. ``timings`` is False unless a config
    sets it. The run folder of a combination is
    ``out/<scene>/seed<seed>/cfg-<hash>`` (``Combination.folder``; the hash is
    that of the config's canonical JSON), so a campaign called again with
    the same ``out`` skips the runs already done (their folder holds
    run.json) and runs the rest, removing a folder without run.json first.
    With Ray on a cluster ``out`` must be a folder every node can write.

    Ray: joined when this process already initialised it; else
    ``ray.init(address=address)`` (``"auto"``: the cluster of ``ray
    start``; ``RAY_ADDRESS`` when set and ``address`` is None); else a
    local Ray of ``num_cpus`` CPUs (default ``os.cpu_count()``) without the
    dashboard. ``ray_options``: more ``ray.init`` keywords (``_temp_dir``,
    ...). A Ray this call started is shut down before it returns. Each run
    asks Ray for ``cpus_per_run`` CPUs (a surveyor run uses every core in
    parts, so 1 is a fair share). ``log``: called with a line per finished
    run.

    summary.csv (``COLUMNS``; written under a temporary name, then renamed)
    holds a row per finished run of these combinations, sorted by scene,
    seed and config: ``viewpoints_stage_one``/``_two``, ``coverage_a1``,
    ``material_accuracy`` and ``collisions`` from run.json (empty when
    absent), the run ``folder`` relative to ``out`` and ``wall_s``, the
    seconds around the ``explore`` call (empty when unknown). coverage.png
    plots viewpoints.csv's ``coverage_a1`` against the viewpoint count, a
    panel per scene and a line per run.

    Returns a ``CampaignResult`` (``rows``, ``ran``, ``skipped``). Raises
    ``ValueError`` for bad arguments before running anything, and
    ``CampaignError`` when runs failed: after every other run finished,
    naming each failed combination with its message (the finished runs and
    summary.csv stay).
    """
    todo_all = combinations(scenarios, seeds, configs)
    if not (isinstance(cpus_per_run, (int, float)) and cpus_per_run > 0):
        raise ValueError(f"cpus_per_run={cpus_per_run!r}: expected a positive number")
    if num_cpus is not None and (isinstance(num_cpus, bool) or not isinstance(num_cpus, int)
                                 or num_cpus < 1):
        raise ValueError(f"num_cpus={num_cpus!r}: expected a whole number of at least 1")
    # Every scenario and config checked before Ray starts (a typo found
    # after a cluster came up costs minutes).
    for scenario in sorted({c.scenario for c in todo_all}):
        for config_json in sorted({c.config_json for c in todo_all}):
            try:
                check_explore(scenario, **json.loads(config_json))
            except ValueError as e:
                raise ValueError(f"campaign: scenario {scenario!r} with config {config_json}: {e}") from None
    out = Path(out).absolute()
    if out.exists() and not out.is_dir():
        raise ValueError(f"out={os.fspath(out)!r}: exists and is not a folder")
    out.mkdir(parents=True, exist_ok=True)
    say = log or (lambda line: None)

    result = CampaignResult(out=out)
    todo = []
    for c in todo_all:
        (result.skipped if (out / c.folder / "run.json").is_file() else todo).append(c)
    wall: Dict[Combination, Optional[float]] = {}
    if todo:
        say(f"{len(todo)} runs to do, {len(result.skipped)} already done, in {out}")
        ray, started = _start_ray(address, num_cpus, ray_options)
        try:
            task = ray.remote(run_one).options(num_cpus=cpus_per_run)
            pending = {
                task.remote(_for_worker(c.scenario), c.seed, c.config_json,
                            os.fspath(out / c.folder)): c
                for c in todo
            }
            for c, outcome, error in completed(ray, pending):
                error = error or (outcome or {}).get("error")
                if error is not None:
                    result.failed.append((c, error))
                    say(f"FAILED {c}: {error}")
                else:
                    result.ran.append(c)
                    wall[c] = outcome.get("wall_s")
                    done_n = len(result.ran) + len(result.failed)
                    say(f"[{done_n}/{len(todo)}] {c.folder}: {wall[c]:.1f} s"
                        if wall[c] is not None else f"[{done_n}/{len(todo)}] {c.folder}")
        finally:
            if started:
                ray.shutdown()

    runs = {}
    import surveyor

    for c in todo_all:
        folder = out / c.folder
        if not (folder / "run.json").is_file():
            continue
        loaded = surveyor.Run.load(folder)
        runs[c] = loaded
        result.rows.append(_row(c, loaded.summary, wall.get(c, _campaign_info(folder).get("wall_s"))))
    _write_summary(out / SUMMARY_CSV, result.rows)
    _plot(out / COVERAGE_PNG, runs)
    if result.failed:
        raise CampaignError(result)
    return result


def _row(c: Combination, summary: dict, wall_s: Optional[float]) -> Dict[str, Any]:
    viewpoints = summary.get("viewpoints") or {}
    coverage = summary.get("coverage") or {}
    return {
        "scene": c.scenario,
        "seed": c.seed,
        "config": c.config_json,
        "viewpoints_stage_one": viewpoints.get("stage_one"),
        "viewpoints_stage_two": viewpoints.get("stage_two"),
        "coverage_a1": coverage.get("A1"),
        "material_accuracy": summary.get("material_accuracy"),
        "collisions": summary.get("collisions"),
        "folder": c.folder.as_posix(),
        "wall_s": wall_s,
    }


def _cell(value: Any) -> str:
    return "" if value is None else str(value)


def _write_summary(path: Path, rows: List[Dict[str, Any]]) -> None:
    tmp = path.with_name(f".{path.name}.tmp-{os.getpid()}")
    with open(tmp, "w", newline="") as f:
        writer = csv.writer(f, lineterminator="\n")
        writer.writerow(COLUMNS)
        for row in rows:
            writer.writerow([_cell(row[k]) for k in COLUMNS])
    os.replace(tmp, path)


def _plot(path: Path, runs: Dict[Combination, Any]) -> None:
    """coverage.png: A1 coverage against viewpoints, a panel per scene, a
    line per run (matplotlib's Agg canvas; pyplot's state is not touched)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure
    from matplotlib.ticker import MaxNLocator

    scenes = sorted({c.scenario for c in runs})
    configs = sorted({c.config_json for c in runs})
    cols = min(len(scenes), 3) or 1
    rows = (len(scenes) + cols - 1) // cols or 1
    fig = Figure(figsize=(5 * cols, 3.6 * rows), layout="constrained")
    FigureCanvasAgg(fig)
    axes = fig.subplots(rows, cols, squeeze=False).ravel()
    for ax in axes[len(scenes):]:
        ax.set_axis_off()
    if not scenes:
        axes[0].text(0.5, 0.5, "no finished runs", ha="center", va="center")
    for ax, scene in zip(axes, scenes):
        for c in sorted(r for r in runs if r.scenario == scene):
            table = runs[c].viewpoints
            if table is None or len(table) == 0 or "coverage_a1" not in table.dtype.names:
                continue
            label = f"seed {c.seed}"
            if len(configs) > 1:
                label += f" cfg-{_hash8(c.config_json)}"
            ax.plot(range(1, len(table) + 1), table["coverage_a1"], marker=".", label=label)
        ax.set_title(scene)
        ax.set_xlabel("viewpoints")
        ax.xaxis.set_major_locator(MaxNLocator(integer=True))
        ax.set_ylabel("A1 coverage")
        ax.grid(True, alpha=0.3)
        if ax.lines and len(ax.lines) <= 12:
            ax.legend(fontsize="small")
    tmp = path.with_name(f".{path.name}.tmp-{os.getpid()}")
    fig.savefig(tmp, format="png", dpi=100)
    os.replace(tmp, path)


# ---------------------------------------------------------------------------
# Command line


def parse_seeds(text: str) -> List[int]:
    """``"0-9"``, ``"3"`` or ``"0,2,5-7"`` as a list of seeds (a
    ``ValueError`` naming the bad part)."""
    seeds: List[int] = []
    for part in text.split(","):
        part = part.strip()
        m = re.fullmatch(r"(\d+)(?:-(\d+))?", part)
        if not m:
            raise ValueError(f"{part!r} is not a seed or a range of seeds (N or A-B, e.g. 0-9)")
        lo = int(m.group(1))
        hi = int(m.group(2)) if m.group(2) is not None else lo
        if hi < lo:
            raise ValueError(f"{part!r}: the range ends before it starts")
        if hi >= 2**64:
            raise ValueError(f"{part!r}: seeds go up to 2**64 - 1")
        seeds.extend(range(lo, hi + 1))
    return seeds


def _parse_configs(texts: Optional[List[str]]) -> Optional[List[Dict[str, Any]]]:
    if not texts:
        return None
    configs: List[Dict[str, Any]] = []
    for text in texts:
        value = json.loads(text)
        if isinstance(value, dict):
            configs.append(value)
        elif isinstance(value, list) and value and all(isinstance(v, dict) for v in value):
            configs.extend(value)
        else:
            raise ValueError(f"{text!r}: expected a JSON object or a list of them")
    return configs


def main(argv: Optional[List[str]] = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m surveyor.campaign",
        description="Run surveyor explore for every scenario x seed x config on Ray "
        "(resumable: runs already in --out are skipped), then write "
        "OUT/summary.csv and OUT/coverage.png.")
    parser.add_argument("--scenarios", required=True,
                        help="comma-separated built-in scenarios or scenario files, e.g. bridge1,bridge2")
    parser.add_argument("--seeds", required=True, help="seeds: N, A-B or a comma list of them, e.g. 0-9")
    parser.add_argument("--config", action="append", metavar="JSON",
                        help='surveyor.explore keywords as a JSON object, e.g. '
                        '\'{"stages": "one", "max_viewpoints": 12}\', or a list of them; '
                        "repeat for more variants (default: {})")
    parser.add_argument("--out", required=True, help="the campaign folder")
    parser.add_argument("--address", help='a Ray cluster to join ("auto": the one `ray start` made); '
                        "default: a local Ray")
    parser.add_argument("--num-cpus", type=int, help="CPUs of a local Ray (default: all)")
    parser.add_argument("--ray-temp-dir", help="Ray's temporary folder (absolute; default RAY_TMPDIR or /tmp/ray)")
    args = parser.parse_args(argv)

    scenarios = [s.strip() for s in args.scenarios.split(",") if s.strip()]
    if not scenarios:
        parser.error("--scenarios: expected one or more names, e.g. bridge1,bridge2")
    try:
        seeds = parse_seeds(args.seeds)
    except ValueError as e:
        parser.error(f"--seeds: {e}")
    try:
        configs = _parse_configs(args.config)
    except ValueError as e:
        parser.error(f"--config: {e}")
    if args.num_cpus is not None and args.num_cpus < 1:
        parser.error("--num-cpus: expected at least 1")
    ray_options = {}
    if args.ray_temp_dir:
        ray_options["_temp_dir"] = os.path.abspath(args.ray_temp_dir)
    try:
        combinations(scenarios, seeds, configs)
    except ValueError as e:
        parser.error(str(e))

    def log(line: str) -> None:
        print(line, file=sys.stderr, flush=True)

    try:
        result = run(scenarios, seeds, configs, out=args.out, address=args.address,
                     num_cpus=args.num_cpus, ray_options=ray_options, log=log)
    except CampaignError as e:
        print(f"error: {e}", file=sys.stderr)
        return 1
    except (ValueError, OSError, ImportError) as e:
        print(f"error: {e}", file=sys.stderr)
        return 1
    print(f"{len(result.ran)} runs done, {len(result.skipped)} already there; "
          f"{result.summary} ({len(result.rows)} rows), {result.plot}")
    return 0


if __name__ == "__main__":
    # Through the imported module, so Ray's tasks refer to
    # surveyor.campaign.run_one rather than to this __main__'s copy.
    from surveyor.campaign import main as _main

    sys.exit(_main())
