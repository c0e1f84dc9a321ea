//! Forward kinematics + flange Jacobian of the Denso VM-6083, per call.
//!
//! Run: `cargo bench -p robot --bench kinematics -- --warm-up-time 1 --measurement-time 3`.
//! Reference: pinocchio (C++) takes 378 ns for the same work on the team machine.

// A benchmark fails loudly on a broken setup; that is what `expect` is for here.
#![allow(clippy::expect_used)]

use criterion::{Criterion, criterion_group, criterion_main};
use geom::{Isometry3, Point3};
use nalgebra::Matrix6xX;
use std::hint::black_box;

fn fk_and_jacobian(c: &mut Criterion) {
    let robot = robot::builtin("denso-vm6083").expect("built-in robot");
    let mut frames: Vec<Isometry3> = Vec::with_capacity(robot.links.len());
    let mut jacobian = Matrix6xX::zeros(robot.dof());
    let flange = Point3::origin();
    let mut q = [0.1, -0.5, 1.2, 0.3, -0.8, 0.4];
    c.bench_function("vm6083 fk_into + jacobian_into (6x6, flange)", |b| {
        b.iter(|| {
            q[0] += 1e-9;
            robot.fk_into(black_box(&q), &mut frames).expect("valid q");
            robot.jacobian_into(&frames, robot::LinkId(6), &flange, &mut jacobian);
            black_box(&jacobian);
        });
    });
}

criterion_group!(benches, fk_and_jacobian);
criterion_main!(benches);
