//! The MAC grid as the vortex layer's velocity source (trilinear interpolation) and sink (face
//! velocities, vorticity by the grid's own finite differences).

use super::forces::vorticity;
use super::mac::MacGrid;
use crate::vortex::{
    Lattice, Mat3, SinkField, SinkLayout, VelocitySink, VelocitySource, VortexError,
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

    fn vorticity(&self) -> Vec<Vec3> {
        let [wx, wy, wz] = vorticity(self);
        wx.iter()
            .zip(wy.iter())
            .zip(wz.iter())
            .map(|((&x, &y), &z)| Vec3::new(x, y, z))
            .collect()
    }

    fn add_velocity(&mut self, field: &SinkField) -> Result<(), VortexError> {
        let SinkField::Faces(faces) = field else {
            return Err(VortexError::Layout(
                "a MAC grid takes face velocities".into(),
            ));
        };
        for (u, du) in self.u.iter_mut().zip(faces.iter()) {
            if u.shape() != du.shape() {
                return Err(VortexError::Layout(format!(
                    "face array of shape {:?} for faces of shape {:?}",
                    du.shape(),
                    u.shape()
                )));
            }
            ndarray::Zip::from(u).and(du).par_for_each(|u, d| *u += d);
        }
        self.sync_periodic();
        Ok(())
    }
}
