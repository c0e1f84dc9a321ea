"""Type stub of the surveyor package (the native module surveyor._surveyor)."""

import os
from typing import Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

__version__: str
__all__ = ["Robot", "Scene", "__version__"]

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
