//! `surveyor.Robot`: a robot's kinematics as NumPy arrays.

use crate::arrays::{joint_values, matrices4, matrix4};
use crate::errors::{robot_error, scenario_error};
use geom::Point3;
use geom::math::isometry_to_rows;
use numpy::PyArray2;
use numpy::ndarray::Array2;
use pyo3::prelude::*;
use robot::Robot;
use scenario::RobotChoice;
use std::path::PathBuf;

/// A robot arm as a serial kinematic chain: a built-in (``Robot.builtin``)
/// or a URDF file (``Robot.from_urdf``).
///
/// Joint vectors ``q`` hold one value per actuated joint, in ``joint_names``
/// order: radians for revolute joints, metres for prismatic ones. Poses are
/// 4 × 4 homogeneous transforms from the frame to the robot's base frame
/// (``base_from_tip``), float64, the values ``surveyor fk --json`` prints.
#[pyclass(name = "Robot", module = "surveyor", frozen)]
pub struct PyRobot {
    robot: Robot,
}

impl PyRobot {
    /// The robot a choice names, built as `surveyor fk` builds it.
    fn build(choice: &RobotChoice) -> PyResult<Self> {
        let robot = choice.build().map_err(|e| scenario_error(&e))?;
        Ok(Self { robot })
    }

    /// The robot itself.
    pub fn robot(&self) -> &Robot {
        &self.robot
    }

    /// `q` as a checked joint vector.
    fn q(&self, q: &Bound<'_, PyAny>) -> PyResult<Vec<f64>> {
        let values = joint_values(q, self.robot.dof())?;
        self.robot
            .check_joints(&values)
            .map_err(|e| robot_error(&e))?;
        Ok(values)
    }
}

#[pymethods]
impl PyRobot {
    /// Load a robot from a URDF file.
    ///
    /// ``tip`` names the link to treat as the tip (the tool); by default the
    /// chain's leaf (a branching tree needs a tip). The same robot as
    /// ``surveyor fk --robot PATH [--tip TIP]``. Raises ``OSError`` when the
    /// file (or a collision mesh it names) cannot be read, ``ValueError``
    /// when its contents are not a usable robot.
    #[staticmethod]
    #[pyo3(signature = (path, tip = None))]
    fn from_urdf(path: PathBuf, tip: Option<String>) -> PyResult<Self> {
        Self::build(&RobotChoice::Urdf { path, tip })
    }

    /// A built-in robot by name: ``"denso-vm6083"`` (the DENSO VM-6083 arm),
    /// ``"point3"`` or ``"arm4"`` (Pudney's point robot and four-link arm).
    /// Raises ``ValueError`` for another name, listing the valid ones.
    #[staticmethod]
    fn builtin(name: &str) -> PyResult<Self> {
        Self::build(&RobotChoice::Builtin(name.to_owned()))
    }

    /// Forward kinematics of the tip: its pose ``base_from_tip`` as a 4 × 4
    /// float64 array, for the joint vector ``q`` (``dof`` values).
    ///
    /// The ``tip`` of ``surveyor fk --json``. Raises ``ValueError`` when
    /// ``q`` has the wrong length or a value that is not finite.
    fn fk<'py>(
        &self,
        py: Python<'py>,
        q: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let q = self.q(q)?;
        let pose = self.robot.tool_pose(&q).map_err(|e| robot_error(&e))?;
        Ok(matrix4(py, &isometry_to_rows(&pose)))
    }

    /// Every link frame ``base_from_link`` for ``q``: an array of shape
    /// (len(link_names), 4, 4), the base link first (the ``frames`` of
    /// ``surveyor fk --json``, in ``link_names`` order).
    fn frames<'py>(
        &self,
        py: Python<'py>,
        q: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, numpy::PyArray3<f64>>> {
        let q = self.q(q)?;
        let frames = self
            .robot
            .forward_kinematics(&q)
            .map_err(|e| robot_error(&e))?;
        let rows: Vec<[[f64; 4]; 4]> = frames.iter().map(isometry_to_rows).collect();
        Ok(matrices4(py, &rows))
    }

    /// The geometric Jacobian of the tip at ``q``: a 6 × dof float64 array.
    ///
    /// Rows 0–2 give the velocity of the tip's origin and rows 3–5 the
    /// angular velocity of the tip, both in the base frame, per unit joint
    /// speed (rad/s, or m/s for prismatic joints): ``v = J @ q_dot``.
    fn jacobian<'py>(
        &self,
        py: Python<'py>,
        q: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let q = self.q(q)?;
        let (link, link_from_tip) = self.robot.tool;
        let tip_in_link = Point3::from(link_from_tip.translation.vector);
        let j = self
            .robot
            .jacobian(&q, link, &tip_in_link)
            .map_err(|e| robot_error(&e))?;
        let a = Array2::from_shape_fn((j.nrows(), j.ncols()), |(r, c)| j[(r, c)]);
        Ok(PyArray2::from_owned_array(py, a))
    }

    /// The joints' limits: a dof × 2 float64 array of ``[min, max]`` rows
    /// (radians, or metres for prismatic joints); ``[-inf, inf]`` for a
    /// joint without limits (a URDF ``continuous`` joint).
    #[getter]
    fn joint_limits<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        let limits = self.robot.limits();
        let a = Array2::from_shape_fn((limits.len(), 2), |(k, side)| {
            limits[k].map_or(
                if side == 0 {
                    f64::NEG_INFINITY
                } else {
                    f64::INFINITY
                },
                |l| if side == 0 { l.min } else { l.max },
            )
        });
        PyArray2::from_owned_array(py, a)
    }

    /// Number of actuated joints: the length of ``q``.
    #[getter]
    fn dof(&self) -> usize {
        self.robot.dof()
    }

    /// Names of the actuated joints, in ``q`` order.
    #[getter]
    fn joint_names(&self) -> Vec<String> {
        self.robot
            .joint_names()
            .into_iter()
            .map(str::to_owned)
            .collect()
    }

    /// Names of the links, base first: the rows of ``frames(q)``.
    #[getter]
    fn link_names(&self) -> Vec<String> {
        self.robot.links.iter().map(|l| l.name.clone()).collect()
    }

    /// The robot's name (the built-in's, or the URDF's ``<robot name>``).
    #[getter]
    fn name(&self) -> &str {
        &self.robot.name
    }

    /// What loading noted without failing (e.g. a collision mesh in a format
    /// that is not read); ``surveyor fk`` prints these as warnings.
    #[getter]
    fn warnings(&self) -> Vec<String> {
        self.robot.warnings.clone()
    }

    fn __repr__(&self) -> String {
        format!(
            "Robot(name='{}', dof={}, tip='{}')",
            self.robot.name,
            self.robot.dof(),
            self.robot
                .links
                .get(self.robot.tool.0.0)
                .map_or("", |l| l.name.as_str())
        )
    }
}
