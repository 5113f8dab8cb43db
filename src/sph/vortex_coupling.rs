//! The SPH fluid as the vortex layer's velocity source (kernel interpolation over the
//! particles near a point) and sink (the fluid particles' velocities, vorticity by the shared
//! difference curl). Both read the neighbour grid of the last neighbourhood update.

use super::fluid::FluidParticles;
use super::kernel::CubicSpline;
use super::neighbors::CellGrid;
use super::solver::SphSolver;
use crate::vortex::{
    AddVelocity, Mat3, SinkLayout, SinkSamples, SinkVorticity, VelocitySink, VelocitySource,
    VortexError,
};
use crate::{Real, Vec3};

/// A read-only view of the fluid's velocity: the velocity source (the solver itself holds its
/// refinement, which need not be shared between threads).
#[derive(Clone, Copy)]
pub struct SphVelocity<'a> {
    kernel: &'a CubicSpline,
    fluid: &'a FluidParticles,
    grid: &'a CellGrid,
}

impl SphSolver {
    /// The fluid velocity as a vortex-layer source.
    pub fn velocity_source(&self) -> SphVelocity<'_> {
        SphVelocity {
            kernel: &self.kernel,
            fluid: &self.fluid,
            grid: self.grid(),
        }
    }
}

impl SphVelocity<'_> {
    /// Calls `f(V_j, v_j, x - x_j)` for every fluid particle j within the kernel support of `x`.
    fn near_point(&self, x: &Vec3, mut f: impl FnMut(Real, Vec3, Vec3)) {
        let fluid = self.fluid;
        self.grid
            .for_each_near(x, &fluid.x, self.kernel.support(), |j| {
                f(fluid.mass / fluid.density[j], fluid.v[j], x - fluid.x[j])
            });
    }
}

impl VelocitySource for SphVelocity<'_> {
    /// Shepard-normalised kernel interpolation, sum V_j v_j W / sum V_j W (zero far from the
    /// fluid).
    fn velocity(&self, x: &Vec3) -> Vec3 {
        let (mut num, mut den) = (Vec3::zeros(), 0.0);
        self.near_point(x, |vol, v, d| {
            let w = vol * self.kernel.w(d.norm());
            num += w * v;
            den += w;
        });
        if den > 0.0 {
            num / den
        } else {
            Vec3::zeros()
        }
    }

    /// The difference-form gradient at a point, sum V_j (v_j - v(x)) (x) grad W(x - x_j).
    fn velocity_gradient(&self, x: &Vec3) -> Mat3 {
        let vx = self.velocity(x);
        let mut g = Mat3::zeros();
        self.near_point(x, |vol, v, d| {
            g += (vol * (v - vx)) * self.kernel.grad(&d).transpose()
        });
        g
    }
}

impl VelocitySink for SphSolver {
    fn layout(&self) -> SinkLayout<'_> {
        SinkLayout::Points(&self.fluid.x)
    }

    fn vorticity(&self, only: Option<&[bool]>) -> SinkVorticity<'_> {
        SinkVorticity::Points(self.vorticity_on(only))
    }

    fn add_velocity(&mut self, add: &mut AddVelocity<'_>) -> Result<(), VortexError> {
        add(SinkSamples::Points(&mut self.fluid.v))
    }
}
