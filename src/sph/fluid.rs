//! The fluid particles: structure-of-arrays state, lattice initialisation, reordering.

use super::kernel::CubicSpline;
use super::neighbors::{permute, resize};
use super::params::FluidBlock;
use crate::state::{Persist, Restorer, Saver, StateError};
use crate::{Real, Vec3};

/// Fluid particle state. All particles share one mass.
#[derive(Debug, Clone, Default)]
pub struct FluidParticles {
    pub x: Vec<Vec3>,
    pub v: Vec<Vec3>,
    /// Density, kg/m^3, from the last neighbourhood update.
    pub density: Vec<Real>,
    /// Pressure, Pa, of the last step: the sum of its pressure solves (DFSPH has two).
    pub pressure: Vec<Real>,
    /// DFSPH warm start: stiffness of the density solve times dt^2 (dt-independent).
    pub kappa: Vec<Real>,
    /// DFSPH warm start: stiffness of the divergence solve times dt^2 (dt-independent).
    pub kappa_v: Vec<Real>,
    /// Mass of every particle, kg.
    pub mass: Real,
    /// Rest density, kg/m^3.
    pub rest_density: Real,
    /// Vector fields that ride on the particles, by name: reordered, spawned (as zero) and
    /// removed with them, so particle motion is their advection (the SPH boundary layer's
    /// omega_ABL, Pfaff et al. 2009 section 3.1). Written into the output frames.
    pub carried: Vec<(&'static str, Vec<Vec3>)>,
}

impl FluidParticles {
    /// Fills the blocks on a cubic lattice of the given spacing (particle centres half a spacing
    /// inside each face), keeping the sites for which `keep` holds (the solver drops those closer
    /// than half a spacing to a wall and inside obstacles). The mass makes the lattice density
    /// exactly `rest_density`, so a fluid at rest starts with no density error.
    pub fn from_blocks(
        blocks: &[FluidBlock],
        spacing: Real,
        rest_density: Real,
        kernel: &CubicSpline,
        keep: impl Fn(&Vec3) -> bool,
    ) -> Self {
        let mut x = Vec::new();
        let mut v = Vec::new();
        for b in blocks {
            let n: Vec<usize> = (0..3)
                .map(|a| ((b.max[a] - b.min[a]) / spacing + 1e-9).floor().max(0.0) as usize)
                .collect();
            for k in 0..n[2] {
                for j in 0..n[1] {
                    for i in 0..n[0] {
                        let idx = [i, j, k];
                        let site =
                            Vec3::from_fn(|a, _| b.min[a] + (idx[a] as Real + 0.5) * spacing);
                        if keep(&site) {
                            x.push(site);
                            v.push(Vec3::from(b.velocity));
                        }
                    }
                }
            }
        }
        let n = x.len();
        Self {
            x,
            v,
            density: vec![rest_density; n],
            pressure: vec![0.0; n],
            kappa: vec![0.0; n],
            kappa_v: vec![0.0; n],
            mass: rest_density / lattice_kernel_sum(kernel, spacing),
            rest_density,
            carried: Vec::new(),
        }
    }

    /// Number of particles.
    pub fn len(&self) -> usize {
        self.x.len()
    }

    /// True without particles.
    pub fn is_empty(&self) -> bool {
        self.x.is_empty()
    }

    /// Rest volume of a particle, m^3.
    pub fn volume(&self) -> Real {
        self.mass / self.rest_density
    }

    /// Reorders every per-particle array by `perm` (see [`super::neighbors::cell_order`]).
    pub fn permute(&mut self, perm: &[u32]) {
        permute(&mut self.x, perm);
        permute(&mut self.v, perm);
        permute(&mut self.density, perm);
        permute(&mut self.pressure, perm);
        permute(&mut self.kappa, perm);
        permute(&mut self.kappa_v, perm);
        for (_, field) in &mut self.carried {
            permute(field, perm);
        }
    }

    /// Removes the particles where `keep` is false, then appends the `added` particles
    /// (position, velocity), at rest density with no pressure, warm start or carried values:
    /// the one place open boundaries change the count, so no per-particle array is forgotten.
    pub fn exchange(&mut self, keep: &[bool], added: &[(Vec3, Vec3)]) {
        let n = added.len();
        resize(&mut self.x, keep, 0, Vec3::zeros());
        resize(&mut self.v, keep, 0, Vec3::zeros());
        self.x.extend(added.iter().map(|a| a.0));
        self.v.extend(added.iter().map(|a| a.1));
        resize(&mut self.density, keep, n, self.rest_density);
        resize(&mut self.pressure, keep, n, 0.0);
        resize(&mut self.kappa, keep, n, 0.0);
        resize(&mut self.kappa_v, keep, n, 0.0);
        for (_, field) in &mut self.carried {
            resize(field, keep, n, Vec3::zeros());
        }
    }

    /// The index of the carried field `name` in [`Self::carried`], added as zeros if absent.
    pub fn carry(&mut self, name: &'static str) -> usize {
        if let Some(i) = self.carried.iter().position(|(n, _)| *n == name) {
            return i;
        }
        self.carried.push((name, vec![Vec3::zeros(); self.len()]));
        self.carried.len() - 1
    }

    /// Bytes held by the per-particle arrays.
    pub fn memory_bytes(&self) -> usize {
        (self.x.capacity() + self.v.capacity()) * std::mem::size_of::<Vec3>()
            + (self.density.capacity()
                + self.pressure.capacity()
                + self.kappa.capacity()
                + self.kappa_v.capacity())
                * std::mem::size_of::<Real>()
            + self
                .carried
                .iter()
                .map(|(_, f)| f.capacity() * std::mem::size_of::<Vec3>())
                .sum::<usize>()
    }
}

/// The particles in their current order (the neighbour sums add in it), their count set by
/// `x`. Not stored: the density, recomputed by the neighbourhood update from the positions;
/// the mass and rest density, the scene's. The carried fields are restored by name into those
/// the fresh fluid was given by its stages.
impl Persist for FluidParticles {
    fn save(&self, into: &mut Saver) {
        into.vec3s("x", &self.x);
        into.vec3s("v", &self.v);
        into.reals("pressure", &self.pressure);
        into.reals("kappa", &self.kappa);
        into.reals("kappa_v", &self.kappa_v);
        let mut carried = into.section("carried");
        for (name, field) in &self.carried {
            carried.vec3s(name, field);
        }
    }

    fn restore(&mut self, from: &Restorer) -> Result<(), StateError> {
        let x = from.vec3s("x")?;
        let n = x.len();
        let v = from.vec3s_n("v", n)?;
        let pressure = from.reals_n("pressure", n)?;
        let kappa = from.reals_n("kappa", n)?;
        let kappa_v = from.reals_n("kappa_v", n)?;
        let from_carried = from.section("carried");
        let carried = self
            .carried
            .iter()
            .map(|(name, _)| Ok((*name, from_carried.vec3s_n(name, n)?)))
            .collect::<Result<_, StateError>>()?;
        *self = Self {
            x,
            v,
            density: vec![self.rest_density; n],
            pressure,
            kappa,
            kappa_v,
            carried,
            ..*self
        };
        Ok(())
    }
}

/// Sum of W over an infinite cubic lattice of the given spacing, self included.
pub fn lattice_kernel_sum(kernel: &CubicSpline, spacing: Real) -> Real {
    let reach = (kernel.support() / spacing).ceil() as i64;
    (-reach..=reach)
        .map(|k| plane_kernel_sum_at(kernel, spacing, k as Real * spacing))
        .sum()
}

/// Sum of W from a point over an infinite square lattice of the given spacing in a plane at
/// `distance` from it, the point above a lattice site (self included at distance zero).
pub fn plane_kernel_sum_at(kernel: &CubicSpline, spacing: Real, distance: Real) -> Real {
    let reach = (kernel.support() / spacing).ceil() as i64;
    let mut sum = 0.0;
    for i in -reach..=reach {
        for j in -reach..=reach {
            let r2 = spacing * spacing * (i * i + j * j) as Real + distance * distance;
            sum += kernel.w(r2.sqrt());
        }
    }
    sum
}
