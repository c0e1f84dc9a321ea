"""Type stub of the surveyor package (the native module surveyor._surveyor)."""

import os
from pathlib import Path
from typing import Any, Dict, List, Mapping, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

__version__: str
__all__ = ["Robot", "Scene", "__version__"]
__all__ += ["SurfaceModel", "Mapper", "scale_like_discs", "candidate_coverage"]
__all__ += ["explore", "follow", "Run"]

_Path = Union[str, "os.PathLike[str]"]
_Joints = Union[Sequence[float], npt.ArrayLike]
_Rows = npt.ArrayLike

class Robot:
    """A robot arm as a serial kinematic chain: a built-in or a URDF file.

    Joint vectors ``q`` hold one value per actuated joint, in ``joint_names``
    order: radians for revolute joints, metres for prismatic ones. Poses are
    4 x 4 homogeneous transforms into the robot's base frame, float64.
    """

    @staticmethod
    def from_urdf(path: _Path, tip: str | None = None) -> "Robot":
        """Load a robot from a URDF file; ``tip`` names the tool link
        (default: the chain's leaf). Raises OSError when a file cannot be
        read, ValueError when it is not a usable robot."""

    @staticmethod
    def builtin(name: str) -> "Robot":
        """A built-in robot: "denso-vm6083", "point3" or "arm4". Raises
        ValueError for another name."""

    def fk(self, q: _Joints) -> npt.NDArray[np.float64]:
        """The tip's pose base_from_tip, shape (4, 4). Raises ValueError for
        a q of the wrong length or with a non-finite value."""

    def frames(self, q: _Joints) -> npt.NDArray[np.float64]:
        """Every link frame base_from_link, shape (len(link_names), 4, 4),
        base first."""

    def jacobian(self, q: _Joints) -> npt.NDArray[np.float64]:
        """Geometric Jacobian of the tip, shape (6, dof): rows 0-2 the tip
        origin's linear velocity, rows 3-5 the angular velocity (base
        frame)."""

    @property
    def joint_limits(self) -> npt.NDArray[np.float64]:
        """[min, max] per joint, shape (dof, 2); [-inf, inf] when unlimited."""

    @property
    def dof(self) -> int:
        """Number of actuated joints (the length of q)."""

    @property
    def joint_names(self) -> list[str]:
        """Names of the actuated joints, in q order."""

    @property
    def link_names(self) -> list[str]:
        """Names of the links, base first (the rows of frames(q))."""

    @property
    def name(self) -> str:
        """The robot's name."""

    @property
    def warnings(self) -> list[str]:
        """What loading noted without failing."""

class Scene:
    """A scene of triangles to cast rays against: a mesh file or a built-in.

    Face ids index ``triangles``.
    """

    @staticmethod
    def from_file(path: _Path, scale: float = 1.0) -> "Scene":
        """Load an .obj, .stl or .ply mesh, coordinates times ``scale``.
        Raises OSError when the file cannot be read, ValueError when it is
        not a usable mesh."""

    @staticmethod
    def builtin(name: str) -> "Scene":
        """A built-in scene: "bridge1", "bridge2", "bridge3", "cube",
        "block1", "block2" or "cylinder". Raises ValueError for another
        name."""

    def raycast(
        self,
        origins: _Rows,
        directions: _Rows,
        max_range: float = ...,
    ) -> Tuple[npt.NDArray[np.float64], npt.NDArray[np.int64]]:
        """First hit of each ray: (distances, face_ids), each of shape (n,).

        origins and directions are float64 arrays of shape (n, 3), each
        direction a unit vector. A miss has distance inf and face id -1.
        max_range defaults to inf. Raises ValueError for bad input.
        """

    @property
    def vertices(self) -> npt.NDArray[np.float64]:
        """Vertex positions, shape (number of vertices, 3), metres."""

    @property
    def triangles(self) -> npt.NDArray[np.int64]:
        """Vertex indices per face, shape (face_count, 3); row i is face id i."""

    @property
    def face_count(self) -> int:
        """Number of triangles."""

    @property
    def name(self) -> str:
        """The built-in's name, or the file the scene was loaded from."""

class SurfaceModel:
    """Pudney's incremental surface model (P ch. 2), the model of
    ``surveyor model``: planar polygon segments with shared edges and corner
    vertices, built set by set from range sensor readings.

    ``config`` is a dict of SurfaceConfig fields (lambda, mu_deg, psi, phi,
    collinear_fraction, max_set_points, merge_order); missing fields keep
    Pudney's defaults. An unknown key or a value out of range raises
    ValueError naming it.
    """

    def __init__(self, config: Mapping[str, Any] | None = None) -> None: ...
    def add_set(self, points: _Rows, axes: _Rows) -> None:
        """Feed one sensor set: points and unit sensing axes, float64 of
        shape (n, 3), world frame (a line of a ``--sets`` file). Raises
        ValueError naming points[i] or axes[i] for bad input; the model is
        then unchanged."""

    def add_initial_segment(self, vertices: _Rows) -> int:
        """Add an a-priori segment (``--initial``): (k, 3) coplanar vertices,
        anticlockwise about the outward normal. Returns its segment id."""

    def polygons(self) -> List[Dict[str, Any]]:
        """Planar polygon segments in id order: dicts of id, vertices (k, 3),
        normal (3,), centroid (3,), points and initial."""

    def shared_edges(self) -> npt.NDArray[np.int64]:
        """Shared edges, each pair once: int64 rows [segment, edge,
        neighbour, neighbour_edge], shape (shared_edge_pairs, 4)."""

    def to_obj(self, path: _Path) -> None:
        """Write surface_model.obj (through a temporary name, then renamed).
        Raises OSError when it cannot be written."""

    def to_json(self, path: _Path) -> None:
        """Write surface_model.json, as to_obj writes. Raises OSError when it
        cannot be written."""

    def check(self) -> None:
        """Run the invariant checker (``--check``); raises ValueError naming
        the broken rule."""

    @property
    def stats(self) -> Dict[str, int]:
        """updates, segments, polygons, points, shared_edge_pairs,
        corner_vertices (run.json's model record)."""

    @property
    def config(self) -> Dict[str, Any]:
        """The configuration in effect, every field."""

class Mapper:
    """The AXBAM maps of ``surveyor map``: the tri-state occupancy grid over
    the regions A1, A2, A3 with its entropies and the TSDF whose zero level
    set is the fused mesh; the mesh's Scale-Like Discs and their segments.

    ``config`` is a dict of MapConfig fields (tables "occupancy" and "tsdf",
    as ``surveyor map --print-config``); ``voxel`` sets both voxel edges
    (``--voxel``); ``scenario`` takes the regions of a built-in scenario or
    scenario file (``--scenario``). Bad keys or values raise ValueError.
    """

    def __init__(
        self,
        config: Mapping[str, Any] | None = None,
        scenario: str | None = None,
        voxel: float | None = None,
    ) -> None: ...
    def insert_sweep(
        self,
        points: _Rows,
        origins: _Rows,
        intensities: npt.ArrayLike | None = None,
        cells: npt.ArrayLike | None = None,
    ) -> Dict[str, Dict[str, int]]:
        """Integrate a sweep: returns (n, 3) float64 and their rays' origins
        (n, 3) float64, intensities (n,) float64, cells (n, 2) integer
        (scan, ray) grid cells, strictly increasing scan-major (occlusions
        between grid neighbours). Returns what it did to each map. Raises
        ValueError naming the argument for bad input."""

    def entropy(self) -> Dict[str, float]:
        """h1_unweighted, h1_weighted and h2, nats (occupancy.json's)."""

    def report(self) -> Dict[str, Any]:
        """The whole occupancy.json report as a dict."""

    def mesh(self) -> Tuple[npt.NDArray[np.float64], npt.NDArray[np.int64]]:
        """The fused mesh: vertices (m, 3) float64, triangles (k, 3) int64."""

    def discs(self, seed: int = 0) -> npt.NDArray[np.void]:
        """Scale-Like Discs of the mesh: a structured array with float64
        cx cy cz nx ny nz radius and int64 points segment."""

    def segments(self, seed: int = 0) -> List[npt.NDArray[np.int64]]:
        """The discs' segments: arrays of disc indices (rows of discs())."""

    @property
    def config(self) -> Dict[str, Any]:
        """The configuration in effect, every field."""

def scale_like_discs(
    points: _Rows,
    triangles: npt.ArrayLike | None = None,
    origins: _Rows | None = None,
    config: Mapping[str, Any] | None = None,
    seed: int = 0,
) -> Tuple[npt.NDArray[np.void], Dict[str, Any]]:
    """Scale-Like Discs of points (n, 3) float64, as ``surveyor sld``:
    returns (discs, info). Normals follow the mesh ``triangles`` (m, 3)
    when given, else the sensor ``origins`` (n, 3), else a canonical sign.
    ``config``: SldConfig fields (radius_m, min_points, ...). discs: float64
    cx cy cz nx ny nz radius, int64 points. info: points, registered,
    registered_fraction, occupied_voxels, seconds (generation alone).
    Raises ValueError for bad input."""

def candidate_coverage(
    scenario: str, sizes: Sequence[int], seed: int = 0
) -> Dict[str, npt.NDArray[Any]]:
    """Paul Fig. 3.2: the A1 coverage of the combined sweeps of n_Q
    candidates drawn uniformly in C-space (and the start's), for each n_Q
    of sizes (0 to 20000): arrays n_q, clear_run, coverage_run,
    clear_contact, coverage_contact. Raises ValueError for bad input."""

class Run:
    """A run folder of ``surveyor explore`` or ``surveyor follow``, read
    through the workspace's run-folder reader (format version checked)."""

    kind: str
    """``"explore"`` or ``"follow"``."""
    dir: Path
    """The folder."""
    summary: Dict[str, Any]
    """run.json as a dict."""
    viewpoints: npt.NDArray[np.void] | None
    """viewpoints.csv (explore) as a structured array, one field per column
    (int64, float64 with NaN for empty cells, or str)."""
    steps: npt.NDArray[np.void] | None
    """steps.csv (follow), as ``viewpoints``."""

    @classmethod
    def load(cls, dir: str | os.PathLike[str]) -> Run:
        """Read the run folder ``dir``: FileNotFoundError when it is missing,
        ValueError when it is no run folder of this format version, OSError
        when a file cannot be read."""

    def cloud(self) -> npt.NDArray[np.float64]:
        """Every measured point of cloud.ply, (n, 3) float64 (explore)."""

    def mesh(self) -> Tuple[npt.NDArray[np.float64], npt.NDArray[np.int64]]:
        """The TSDF mesh of mesh.ply: vertices (m, 3), triangles (k, 3)."""

def explore(
    scenario: str,
    seed: int = 0,
    out: str | os.PathLike[str] | None = None,
    *,
    stages: str = "both",
    max_viewpoints: int | None = None,
    stage_one: str = "information",
    oracle: bool = True,
    timings: bool = False,
    report: bool = True,
    **scenario_keys: Any,
) -> Run:
    """AXBAM exploration of ``scenario`` (a built-in name or a scenario
    file) into the run folder ``out`` (None: a temporary one, removed with
    the Run), as ``surveyor explore --no-timings`` does; any other keyword
    is a scenario key (a dict merges into that table). ValueError for a bad
    option, scenario or override; OSError when the folder cannot be written."""

def follow(
    scenario: str,
    seed: int = 0,
    out: str | os.PathLike[str] | None = None,
    *,
    robot: str | None = None,
    max_sets: int = 20000,
    noise_m: float | None = None,
    timings: bool = False,
    report: bool = True,
) -> Run:
    """Pudney's surface following of ``scenario`` into the run folder ``out``
    (None: a temporary one), as ``surveyor follow --no-timings`` does."""
