//! Vortex particles as structure-of-arrays, so that every per-particle loop is a parallel
//! iterator over plain slices.

use super::{kernel, VortexError};
use crate::{Real, Vec3};

/// The particles: centre, vorticity vector (axis and strength, 1/s), kernel scale and the time
/// since the particle was created (the clock of the energy cascade, section 4.2).
#[derive(Debug, Clone, Default)]
pub struct VortexParticles {
    pub x: Vec<Vec3>,
    pub omega: Vec<Vec3>,
    pub sigma: Vec<Real>,
    pub age: Vec<Real>,
}

impl VortexParticles {
    /// No particles.
    pub fn new() -> Self {
        Self::default()
    }

    /// Number of particles.
    pub fn len(&self) -> usize {
        self.x.len()
    }

    /// True without particles.
    pub fn is_empty(&self) -> bool {
        self.x.is_empty()
    }

    /// Adds a particle; the scale must be positive and everything finite.
    pub fn push(&mut self, x: Vec3, omega: Vec3, sigma: Real) -> Result<(), VortexError> {
        if !(sigma.is_finite() && sigma > 0.0) {
            return Err(VortexError::InvalidParticle(format!(
                "sigma = {sigma} must be positive and finite"
            )));
        }
        if !(x.iter().chain(omega.iter()).all(|c| c.is_finite())) {
            return Err(VortexError::InvalidParticle(format!(
                "position {x:?} and vorticity {omega:?} must be finite"
            )));
        }
        self.x.push(x);
        self.omega.push(omega);
        self.sigma.push(sigma);
        self.age.push(0.0);
        Ok(())
    }

    /// Radius `sqrt(6) sigma` of particle i (the kernel's cut-off).
    pub fn radius(&self, i: usize) -> Real {
        kernel::radius(self.sigma[i])
    }

    /// Kernel energy of particle i (untruncated, see [`kernel`]).
    pub fn energy(&self, i: usize) -> Real {
        kernel::energy(self.omega[i].norm(), self.sigma[i])
    }

    /// Sum of the kernel energies.
    pub fn total_energy(&self) -> Real {
        (0..self.len()).map(|i| self.energy(i)).sum()
    }

    /// Keeps the particles for which `keep[i]` holds, in order.
    pub fn retain(&mut self, keep: &[bool]) {
        retain_by(&mut self.x, keep);
        retain_by(&mut self.omega, keep);
        retain_by(&mut self.sigma, keep);
        retain_by(&mut self.age, keep);
    }
}

/// Keeps `v[i]` where `keep[i]` holds (entries past the end of `keep` stay).
fn retain_by<T>(v: &mut Vec<T>, keep: &[bool]) {
    let mut flags = keep.iter();
    v.retain(|_| *flags.next().unwrap_or(&true));
}

impl crate::state::Persist for VortexParticles {
    fn save(&self, into: &mut crate::state::Saver) {
        into.vec3s("x", &self.x);
        into.vec3s("omega", &self.omega);
        into.reals("sigma", &self.sigma);
        into.reals("age", &self.age);
    }

    fn restore(&mut self, from: &crate::state::Restorer) -> Result<(), crate::state::StateError> {
        let x = from.vec3s("x")?;
        let n = x.len();
        self.omega = from.vec3s_n("omega", n)?;
        self.sigma = from.reals_n("sigma", n)?;
        self.age = from.reals_n("age", n)?;
        self.x = x;
        Ok(())
    }
}
