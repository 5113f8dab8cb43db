//! A time-weighted running average of the face velocities: the precomputation of artificial
//! boundary layers averages the flow over many steps (Pfaff et al. 2009, section 3.2).

use ndarray::{Array3, Zip};

use super::mac::MacGrid;
use crate::Real;

/// Sum of u dt per face and the time it covers.
#[derive(Debug, Clone)]
pub struct RunningAverage {
    sum: [Array3<Real>; 3],
    time: Real,
}

impl RunningAverage {
    /// An empty average over faces shaped like `grid`'s.
    pub fn new(grid: &MacGrid) -> Self {
        Self {
            sum: std::array::from_fn(|a| Array3::zeros(grid.u[a].raw_dim())),
            time: 0.0,
        }
    }

    /// Adds the state `grid` held over a step of length `dt`.
    pub fn add(&mut self, grid: &MacGrid, dt: Real) {
        for (s, u) in self.sum.iter_mut().zip(&grid.u) {
            Zip::from(s).and(u).par_for_each(|s, &u| *s += u * dt);
        }
        self.time += dt;
    }

    /// The sums and the time they span (a checkpoint's).
    pub fn sum(&self) -> &[Array3<Real>; 3] {
        &self.sum
    }

    /// An average from [`Self::sum`] and [`Self::time`] (a checkpoint's).
    pub fn from_parts(sum: [Array3<Real>; 3], time: Real) -> Self {
        Self { sum, time }
    }

    /// Time covered so far, s.
    pub fn time(&self) -> Real {
        self.time
    }

    /// The mean velocity as a MAC grid like `like`, or None before any step was added.
    pub fn mean(&self, like: &MacGrid) -> Option<MacGrid> {
        (self.time > 0.0).then(|| {
            let mut out = like.clone();
            for (u, s) in out.u.iter_mut().zip(&self.sum) {
                Zip::from(u).and(s).par_for_each(|u, &s| *u = s / self.time);
            }
            out
        })
    }
}
