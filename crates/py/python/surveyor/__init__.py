"""surveyor: robot kinematics and bulk ray casting on NumPy arrays.

The Python face of the surveyor workspace (Rust):

* ``Robot``: a built-in robot (``Robot.builtin("denso-vm6083")``) or a URDF
  file (``Robot.from_urdf(path, tip=None)``); ``fk(q)`` the tip's 4 x 4 pose,
  ``frames(q)`` every link frame, ``jacobian(q)`` the 6 x dof geometric
  Jacobian of the tip, ``joint_limits``, ``dof``, ``joint_names``.
* ``Scene``: a triangle mesh file (``Scene.from_file(path, scale=1.0)``) or
  a built-in scene (``Scene.builtin("bridge1")``); ``raycast(origins,
  directions, max_range)`` casts (n, 3) float64 rays on all cores and returns
  ``(distances, face_ids)`` (``inf`` and -1 on a miss).
* ``SurfaceModel``: Pudney's incremental surface model (``surveyor model``);
  ``add_set(points, axes)`` feeds a sensor set, ``polygons()``,
  ``shared_edges()``, ``to_obj(path)``, ``to_json(path)``, ``check()``,
  ``stats``.
* ``Mapper``: the AXBAM occupancy grid and TSDF (``surveyor map``);
  ``insert_sweep(points, origins, intensities, cells)``, ``entropy()``,
  ``report()``, ``mesh()``, ``discs()``, ``segments()``.

* ``scale_like_discs(points, triangles=None, origins=None, config=None,
  seed=0)``: the discs of any points (``surveyor sld``), timed;
  ``candidate_coverage(scenario, sizes, seed=0)``: the coverage of the
  combined sweeps of n_Q candidate viewpoints (Paul Fig. 3.2);
  ``surveyor.studies`` runs both as parameter studies on Ray.

* ``explore(scenario, seed=0, out=None, **config)`` and ``follow(scenario,
  seed=0, out=None, **options)``: whole runs, as ``surveyor explore`` and
  ``surveyor follow`` make them, returned as a ``Run``;
* ``Run.load(dir)``: a run folder read: ``summary`` (run.json),
  ``viewpoints`` / ``steps`` (NumPy structured arrays), ``cloud()``,
  ``mesh()``.

Results equal the ``surveyor`` command line's (``surveyor fk --json``,
``surveyor raycast``). Bad input raises ``ValueError`` and an unreadable
file ``OSError``, each with the library's message.
"""

from ._surveyor import Robot, Scene, __version__
from ._surveyor import Mapper, SurfaceModel, candidate_coverage, scale_like_discs

__all__ = ["Robot", "Scene", "__version__"]
__all__ += ["SurfaceModel", "Mapper", "scale_like_discs", "candidate_coverage"]

from ._runs import Run, explore, follow

__all__ += ["explore", "follow", "Run"]
