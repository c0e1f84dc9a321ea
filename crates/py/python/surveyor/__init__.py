"""surveyor: robot kinematics and bulk ray casting on NumPy arrays.

The Python face of the surveyor workspace (Rust). Two classes:

* ``Robot``: a built-in robot (``Robot.builtin("denso-vm6083")``) or a URDF
  file (``Robot.from_urdf(path, tip=None)``); ``fk(q)`` the tip's 4 x 4 pose,
  ``frames(q)`` every link frame, ``jacobian(q)`` the 6 x dof geometric
  Jacobian of the tip, ``joint_limits``, ``dof``, ``joint_names``.
* ``Scene``: a triangle mesh file (``Scene.from_file(path, scale=1.0)``) or
  a built-in scene (``Scene.builtin("bridge1")``); ``raycast(origins,
  directions, max_range)`` casts (n, 3) float64 rays on all cores and returns
  ``(distances, face_ids)`` (``inf`` and -1 on a miss).

Results equal the ``surveyor`` command line's (``surveyor fk --json``,
``surveyor raycast``). Bad input raises ``ValueError`` and an unreadable
file ``OSError``, each with the library's message.
"""

from ._surveyor import Robot, Scene, __version__

__all__ = ["Robot", "Scene", "__version__"]
