"""Whole runs: ``explore``, ``follow`` and ``Run`` (a run folder, read)."""

from __future__ import annotations

import csv
import json
import os
import tempfile
from pathlib import Path
from typing import Any, Optional, Union

import numpy as np

from . import _surveyor

#: Keyword arguments of ``explore`` that are its options; any other keyword
#: is a scenario key (a dict merges into a scenario table).
EXPLORE_OPTIONS = ("stages", "max_viewpoints", "stage_one", "oracle", "timings", "report")
#: Keyword arguments of ``follow``.
FOLLOW_OPTIONS = ("robot", "max_sets", "noise_m", "timings", "report")

PathLike = Union[str, "os.PathLike[str]"]


def _out_folder(out: Optional[PathLike]):
    """The run folder to write: ``out``, or one in a temporary directory
    that lives as long as the ``Run`` read from it."""
    if out is not None:
        return Path(out), None
    keep = tempfile.TemporaryDirectory(prefix="surveyor-run-")
    return Path(keep.name) / "run", keep


def explore(scenario: str, seed: int = 0, out: Optional[PathLike] = None, **config: Any) -> "Run":
    """Run AXBAM exploration (Paul's Stage One, then Stage Two, the blast
    plan) of ``scenario`` (a built-in name such as ``"bridge1"`` or a
    scenario file) with noise seed ``seed``, as ``surveyor explore
    --scenario SCENARIO --seed SEED --out OUT --no-timings`` does, and return
    the run read back (``Run``).

    ``out``: the run folder to write (created; ``None``: a temporary one,
    removed with the returned ``Run``).

    Options (keywords): ``stages`` (``"both"`` or ``"one"``),
    ``max_viewpoints`` (Stage One's budget), ``stage_one``
    (``"information"`` or ``"thesis"``), ``oracle`` (compute the coverage
    oracle; default True), ``timings`` (record wall-clock times; default
    False, so reruns are byte-identical), ``report`` (write report.html;
    default True). Any other keyword is a scenario key: a dict merges into
    that table, e.g. ``explore={"local_candidates": 0}``, and the scenario's
    checks apply.

    Runs with the GIL released. Raises ``ValueError`` for a bad option,
    scenario or override, ``OSError`` when the folder cannot be written.
    """
    options, overrides = _explore_arguments(config)
    folder, keep = _out_folder(out)
    _surveyor._explore(str(scenario), _seed(seed), os.fspath(folder), options, overrides)
    return Run.load(folder, _keep=keep)


def _explore_arguments(config: dict):
    """``explore``'s keywords as its options' and scenario overrides' JSON,
    checked."""
    options = {k: v for k, v in config.items() if k in EXPLORE_OPTIONS}
    _count(options, "max_viewpoints")
    _flags(options, "explore", ("oracle", "timings", "report"))
    overrides = {k: v for k, v in config.items() if k not in EXPLORE_OPTIONS}
    return _json(options, "explore options"), _json(overrides, "scenario overrides")


def check_explore(scenario: str, **config: Any) -> None:
    """Check ``explore(scenario, **config)``'s arguments without running
    it: the ``ValueError`` ``explore`` would raise for a bad option,
    scenario or override."""
    _surveyor._check_explore(str(scenario), *_explore_arguments(config))


def follow(scenario: str, seed: int = 0, out: Optional[PathLike] = None, **options: Any) -> "Run":
    """Run Pudney's surface following of ``scenario`` (``"block1"``,
    ``"cube"``, ... or a scenario file) with noise seed ``seed``, as
    ``surveyor follow --scenario SCENARIO --seed SEED --out OUT
    --no-timings`` does, and return the run read back (``Run``).

    Options (keywords): ``robot`` (``"point3"``, ``"arm4"`` or a URDF file),
    ``max_sets`` (most sensor sets; default 20 000), ``noise_m`` (range
    noise σ, metres; default the scenario's), ``timings`` (default False),
    ``report`` (default True). ``out`` as in ``explore``.

    Runs with the GIL released. Raises ``ValueError`` for a bad option or
    scenario, ``OSError`` when the folder cannot be written.
    """
    unknown = sorted(set(options) - set(FOLLOW_OPTIONS))
    if unknown:
        raise ValueError(f"follow: unknown option {unknown[0]!r} (options: {', '.join(FOLLOW_OPTIONS)})")
    _count(options, "max_sets")
    _flags(options, "follow", ("timings", "report"))
    folder, keep = _out_folder(out)
    _surveyor._follow(str(scenario), _seed(seed), os.fspath(folder), _json(options, "follow options"))
    return Run.load(folder, _keep=keep)


def _seed(seed: Any) -> int:
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or not 0 <= int(seed) < 2**64:
        raise ValueError(f"seed={seed!r}: expected a whole number from 0 to 2**64 - 1")
    return int(seed)


def _count(options: dict, key: str) -> None:
    """``options[key]``, when given, must be a whole number of at least 1."""
    value = options.get(key)
    if value is None:
        return
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 1:
        raise ValueError(f"{key}={value!r}: expected a whole number of at least 1")
    options[key] = int(value)


def _flags(options: dict, what: str, keys) -> None:
    """Each of ``keys`` in ``options``, when given, must be True or False:
    a ``ValueError`` naming the keyword (``oracle='yes'`` is no flag)."""
    for key in keys:
        value = options.get(key)
        if value is not None and not isinstance(value, (bool, np.bool_)):
            raise ValueError(f"{what}: {key}={value!r}: expected True or False")
        if value is not None:
            options[key] = bool(value)


def _json(values: dict, what: str) -> str:
    """``values`` as JSON; a value JSON cannot hold (NaN, an object) is a
    ``ValueError`` naming its key."""
    for key, value in values.items():
        try:
            json.dumps(value, allow_nan=False)
        except (TypeError, ValueError) as e:
            raise ValueError(f"{what}: {key}={value!r}: {e}") from None
    return json.dumps(values, allow_nan=False)


def _column(values: list) -> np.ndarray:
    """A CSV column as the narrowest of int64, float64 (empty cells NaN) or str."""
    try:
        return np.array([int(v) for v in values], dtype=np.int64)
    except ValueError:
        pass
    try:
        return np.array([float(v) if v != "" else np.nan for v in values], dtype=np.float64)
    except ValueError:
        return np.array(values, dtype=str)


def _table(path: Path) -> np.ndarray:
    """A run folder's CSV file as a NumPy structured array, one field per
    column. An empty, binary or ragged file is a ``ValueError`` naming the
    file and the line."""
    try:
        with open(path, newline="", encoding="utf-8") as f:
            rows = list(csv.reader(f))
    except UnicodeDecodeError as e:
        raise ValueError(f"{path}: not UTF-8 text (byte {e.start}): a binary or damaged file") from None
    except csv.Error as e:
        raise ValueError(f"{path}: not a CSV table: {e}") from None
    if not rows or not rows[0]:
        raise ValueError(f"{path}, line 1: empty, expected a header row")
    header, body = rows[0], rows[1:]
    for line, row in enumerate(body, start=2):
        if len(row) != len(header):
            raise ValueError(
                f"{path}, line {line}: {len(row)} fields, expected {len(header)} "
                f"({','.join(header)}): is the file cut short?"
            )
    columns = [_column([r[i] for r in body]) for i in range(len(header))]
    return np.rec.fromarrays(columns, names=header).view(np.ndarray) if body else np.zeros(
        0, dtype=[(h, np.float64) for h in header])


class Run:
    """A run folder of ``surveyor explore`` or ``surveyor follow``, read
    through the workspace's run-folder reader (its format version checked).

    * ``summary``: run.json as a dict;
    * ``kind``: ``"explore"`` or ``"follow"``;
    * ``viewpoints`` (explore) / ``steps`` (follow): viewpoints.csv /
      steps.csv as NumPy structured arrays, one field per column (empty
      cells NaN);
    * ``cloud()``: every measured point, float64 (n, 3) (explore);
    * ``mesh()``: the TSDF mesh, ``(vertices, triangles)`` (explore);
    * ``dir``: the folder.
    """

    def __init__(self, folder: "_surveyor._RunFolder", keep=None):
        self._folder = folder
        self._keep = keep  # a temporary directory removed with the Run
        self.kind: str = folder.kind
        self.dir: Path = Path(folder.dir)
        self.summary: dict = json.loads(folder.summary_json())
        self.viewpoints: Optional[np.ndarray] = None
        self.steps: Optional[np.ndarray] = None
        if self.kind == "explore":
            self.viewpoints = _table(Path(folder.path("viewpoints.csv")))
        else:
            self.steps = _table(Path(folder.path("steps.csv")))

    @classmethod
    def load(cls, dir: PathLike, _keep=None) -> "Run":
        """Read the run folder ``dir``. Raises ``FileNotFoundError`` when it
        is missing, ``ValueError`` when it is no run folder of this format
        version, ``OSError`` when a file cannot be read."""
        return cls(_surveyor._RunFolder(os.fspath(dir)), _keep)

    def cloud(self) -> np.ndarray:
        """Every measured point of cloud.ply, float64 (n, 3)."""
        return self._folder.cloud()

    def mesh(self):
        """The TSDF mesh of mesh.ply: ``(vertices, triangles)``, float64
        (m, 3) and int64 (k, 3)."""
        return self._folder.mesh()

    def __repr__(self) -> str:
        rows = self.viewpoints if self.kind == "explore" else self.steps
        return f"Run(kind={self.kind!r}, dir='{self.dir}', rows={len(rows)})"
