//! The SPH fluid as the vortex layer's velocity source (kernel interpolation over the
//! particles near a point) and sink (the fluid particles' velocities, vorticity by the shared
//! difference curl). Both read the neighbour grid of the last neighbourhood update.

use super::boundary::BoundaryParticles;
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
    boundary: &'a BoundaryParticles,
}

impl SphSolver {
    /// The fluid velocity as a vortex-layer source.
    pub fn velocity_source(&self) -> SphVelocity<'_> {
        SphVelocity {
            kernel: &self.kernel,
            fluid: &self.fluid,
            grid: self.grid(),
            boundary: &self.boundary,
        }
    }
}

impl SphVelocity<'_> {
    /// Calls `f(j, V_j W(x - x_j))` for every fluid particle j within the kernel support of
    /// `x`: the weights of kernel interpolation at a point.
    pub fn for_each_weight(&self, x: &Vec3, mut f: impl FnMut(usize, Real)) {
        let fluid = self.fluid;
        self.grid
            .for_each_near(x, &fluid.x, self.kernel.support(), |j| {
                f(
                    j,
                    fluid.mass / fluid.density[j] * self.kernel.w((x - fluid.x[j]).norm()),
                )
            });
    }

    /// The occupancy of `x` by the liquid, sum_j V_j W(x - x_j) / (1 - sum_b V_b W(x - x_b)):
    /// 1 inside the liquid, about 1/2 on its free surface, 0 away from it; the walls' share of
    /// the kernel (which a full neighbourhood of liquid would have filled) is divided out, so a
    /// point in the liquid beside a wall is 1 too. With it the Shepard-normalised velocity (0
    /// where the occupancy is).
    pub fn occupancy(&self, x: &Vec3) -> (Real, Vec3) {
        let (mut sum, mut v) = (0.0, Vec3::zeros());
        let fluid = self.fluid;
        self.for_each_weight(x, |j, w| {
            sum += w;
            v += w * fluid.v[j];
        });
        if sum <= 0.0 {
            return (0.0, v);
        }
        let b = self.boundary;
        let mut wall = 0.0;
        b.grid.for_each_near(x, &b.x, self.kernel.support(), |i| {
            wall += b.volume[i] * self.kernel.w((x - b.x[i]).norm())
        });
        let open = 1.0 - wall;
        let occupancy = if open > 1e-3 { sum / open } else { 0.0 };
        (occupancy, v / sum)
    }

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
