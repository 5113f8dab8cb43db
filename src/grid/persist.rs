//! The grid's state between steps for a checkpoint: the face velocities, the pressure (what a
//! step adds its increment to) and the projection's warm start, the smoke's fields, the running
//! average and impulses pending from a coupled liquid. The boundaries, the pressure and
//! viscosity systems and the scratch fields are rebuilt from the bodies at the restored time,
//! as the step that ended there built them.

use ndarray::Array3;

use super::average::RunningAverage;
use super::solver::GridSolver;
use crate::geometry::RigidBody;
use crate::state::{Persist, Restorer, Saver, StateError};
use crate::Real;

const AXES: [&str; 3] = ["x", "y", "z"];

fn save_faces(into: &mut Saver, name: &str, faces: &[Array3<Real>; 3]) {
    let mut s = into.section(name);
    for (a, f) in faces.iter().enumerate() {
        s.reals(AXES[a], f.as_slice().expect("fields are contiguous"));
    }
}

fn restore_faces(
    from: &Restorer,
    name: &str,
    faces: &mut [Array3<Real>; 3],
) -> Result<(), StateError> {
    let r = from.section(name);
    for (a, f) in faces.iter_mut().enumerate() {
        r.reals_into(AXES[a], f.as_slice_mut().expect("fields are contiguous"))?;
    }
    Ok(())
}

fn save_field(into: &mut Saver, name: &str, field: &Array3<Real>) {
    into.reals(name, field.as_slice().expect("fields are contiguous"));
}

fn restore_field(from: &Restorer, name: &str, field: &mut Array3<Real>) -> Result<(), StateError> {
    from.reals_into(name, field.as_slice_mut().expect("fields are contiguous"))
}

impl Persist for GridSolver {
    fn save(&self, into: &mut Saver) {
        into.real("time", self.time);
        into.u64("step", self.step);
        save_faces(into, "velocity", &self.mac.u);
        save_field(into, "pressure", &self.pressure);
        save_field(into, "scaled_pressure", &self.scaled_pressure);
        if let Some(smoke) = &self.smoke {
            let mut s = into.section("smoke");
            save_field(&mut s, "density", &smoke.density);
            if let Some(t) = &smoke.temperature {
                save_field(&mut s, "temperature", t);
            }
        }
        if let Some((_, avg)) = &self.average {
            let mut s = into.section("average");
            s.real("time", avg.time());
            save_faces(&mut s, "sum", avg.sum());
        }
        if let Some(du) = &self.impulses {
            save_faces(into, "impulses", du);
        }
    }

    fn restore(&mut self, from: &Restorer) -> Result<(), StateError> {
        self.time = from.real("time")?;
        self.step = from.u64("step")?;
        restore_faces(from, "velocity", &mut self.mac.u)?;
        restore_field(from, "pressure", &mut self.pressure)?;
        restore_field(from, "scaled_pressure", &mut self.scaled_pressure)?;
        if let Some(smoke) = self.smoke.as_mut() {
            let s = from.section("smoke");
            restore_field(&s, "density", &mut smoke.density)?;
            if let Some(t) = smoke.temperature.as_mut() {
                restore_field(&s, "temperature", t)?;
            }
        }
        if let Some((_, avg)) = self.average.as_mut() {
            let s = from.section("average");
            let time = s.real("time")?;
            let mut sum = avg.sum().clone();
            restore_faces(&s, "sum", &mut sum)?;
            *avg = RunningAverage::from_parts(sum, time);
        }
        self.impulses = if from.has("impulses") {
            let mut du = self.mac.u.clone();
            restore_faces(from, "impulses", &mut du)?;
            Some(du)
        } else {
            None
        };
        if self.bodies.iter().any(RigidBody::is_moving) {
            // The step that ended at `time` placed the obstacles there.
            self.rebuild_boundaries(self.time);
        }
        Ok(())
    }
}
