//! The MAC grid as the vortex layer's velocity source (trilinear interpolation) and sink (face
//! velocities, vorticity by the grid's own finite differences).

use super::forces::CellVorticity;
use super::mac::MacGrid;
use crate::vortex::{
    AddVelocity, Lattice, Mat3, SinkLayout, SinkSamples, SinkVorticity, VelocitySink,
    VelocitySource, VortexError,
};
use crate::Vec3;

impl VelocitySource for MacGrid {
    fn velocity(&self, x: &Vec3) -> Vec3 {
        self.velocity_at(x)
    }

    /// Central differences of the interpolated velocity half a cell either side: the
    /// interpolated discrete gradient that Pfaff et al. 2009 (section 4.2) use for stretching.
    fn velocity_gradient(&self, x: &Vec3) -> Mat3 {
        let h = 0.5 * self.dx;
        let mut g = Mat3::zeros();
        for b in 0..3 {
            let mut e = Vec3::zeros();
            e[b] = h;
            g.set_column(
                b,
                &((self.velocity_at(&(x + e)) - self.velocity_at(&(x - e))) / (2.0 * h)),
            );
        }
        g
    }
}

impl VelocitySink for MacGrid {
    fn layout(&self) -> SinkLayout<'_> {
        SinkLayout::Faces(Lattice {
            dims: self.dims,
            dx: self.dx,
            origin: self.origin,
            periodic: self.periodic,
        })
    }

    fn vorticity(&self, _only: Option<&[bool]>) -> SinkVorticity<'_> {
        let cells = CellVorticity::new(self);
        SinkVorticity::Cells(Box::new(move |idx, out| cells.row(idx, out)))
    }

    fn add_velocity(&mut self, add: &mut AddVelocity<'_>) -> Result<(), VortexError> {
        let [u, v, w] = &mut self.u;
        add(SinkSamples::Faces([
            u.view_mut(),
            v.view_mut(),
            w.view_mut(),
        ]))?;
        self.sync_periodic();
        Ok(())
    }
}
