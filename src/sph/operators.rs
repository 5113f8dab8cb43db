//! Difference-form SPH differential operators shared by the turbulence refinements and the
//! vorticity metrics (Ye et al. Eqs. 6–8, Liu et al. 2021 Eqs. 3, 4, 6).
//!
//! Every sum runs over the fluid neighbours j of particle i with the weight V_j = m / rho_j and
//! `grad W_ij = grad_i W(x_i - x_j)`:
//!
//! - gradient (Ye Eq. 7/22): `(grad A)_i = sum_j V_j (A_j - A_i) (x) grad W_ij`, entry [a][b] is
//!   dA_a / dx_b;
//! - curl (Liu Eq. 6, Wang Eq. 6): `(curl A)_i = sum_j V_j (A_i - A_j) x grad W_ij`. Ye Eq. 21
//!   prints `(A_j - A_i) x grad W_ij`, which is minus the curl with this `grad W_ij`
//!   (docs/src/paper-notes.md, "The curl's sign"); the solid-body test in `tests/refine_operators.rs` fixes the sign;
//! - Laplacian (Ye Eq. 8): `2 (d + 2) sum_j V_j (A_ij . x_ij) / (|x_ij|^2 + 0.01 h^2) grad W_ij`.
//!
//! The curl is the antisymmetric part of the same gradient tensor, so one pass gives both.
//!
//! These f64 forms serve the metrics, the micropolar and confinement baselines and the tests;
//! the Rankine, VRSPH and MCVSPH passes use their single-precision packed twins in
//! `crate::refine::packed` (which also holds the Laplacian), checked against these.
//!
//! **Walls.** With `walls` on, the Akinci boundary samples take part in every sum as neighbours
//! with their own volume, their kinematic velocity in velocity operators, and zero in the
//! others (walls carry no vorticity, stream function or loss: Wang et al. Sec. 4.3, Ye et al.
//! after Eq. 28). With it off, sums run over the fluid alone.

use super::neighborhood::Neighborhood;
use crate::{Real, Vec3};
use rayon::prelude::*;

use crate::Mat3;

/// What the boundary samples hold in an operator's sums when walls take part.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum WallField {
    /// Their kinematic velocity (operators on the fluid velocity).
    Velocity,
    /// Zero (vorticity, stream function, losses).
    Zero,
}

/// The operators over one step's neighbourhood.
#[derive(Clone, Copy)]
pub struct Operators<'a> {
    pub nb: Neighborhood<'a>,
    /// V_j = m / rho_j per fluid particle.
    pub volume: &'a [Real],
    /// Boundary samples take part in the sums.
    pub walls: bool,
}

impl<'a> Operators<'a> {
    /// Calls `f(V_j, A_j, x_i - x_j, grad W_ij)` for every neighbour of i that takes part:
    /// fluid neighbours, then boundary samples when walls are on. The kernel gradients come
    /// from the step's pair cache (`super::pair_cache`), so no pass evaluates the kernel.
    #[inline]
    fn pairs(
        &self,
        i: usize,
        a: &[Vec3],
        wall: WallField,
        mut f: impl FnMut(Real, Vec3, Vec3, Vec3),
    ) {
        self.nb
            .fluid_pairs_grad(i, |j, xij, g| f(self.volume[j], a[j], xij, g));
        if self.walls {
            let b = self.nb.boundary;
            self.nb.boundary_pairs_grad(i, |k, xik, g| {
                let ak = match wall {
                    WallField::Velocity => b.v[k],
                    WallField::Zero => Vec3::zeros(),
                };
                f(b.volume[k], ak, xik, g)
            });
        }
    }

    /// Gradient tensors (Ye Eq. 7) of the field `a`.
    pub fn gradient(&self, a: &[Vec3], wall: WallField) -> Vec<Mat3> {
        self.gradient_on(a, wall, None)
    }

    /// [`Self::gradient`] only where `only` holds (zero elsewhere), or everywhere for None.
    pub fn gradient_on(&self, a: &[Vec3], wall: WallField, only: Option<&[bool]>) -> Vec<Mat3> {
        per_particle(a.len(), only, |i| self.gradient_at(i, a, wall))
    }

    /// [`Self::gradient`] at particle i.
    #[inline]
    pub fn gradient_at(&self, i: usize, a: &[Vec3], wall: WallField) -> Mat3 {
        let ai = a[i];
        let mut g = Mat3::zeros();
        self.pairs(i, a, wall, |vj, aj, _, grad| {
            g += (vj * (aj - ai)) * grad.transpose()
        });
        g
    }

    /// Curl (Liu Eq. 6) of the field `a`.
    pub fn curl(&self, a: &[Vec3], wall: WallField) -> Vec<Vec3> {
        self.curl_on(a, wall, None)
    }

    /// [`Self::curl`] only where `only` holds (zero elsewhere), or everywhere for None.
    pub fn curl_on(&self, a: &[Vec3], wall: WallField, only: Option<&[bool]>) -> Vec<Vec3> {
        per_particle(a.len(), only, |i| self.curl_at(i, a, wall))
    }

    /// [`Self::curl`] at particle i.
    #[inline]
    pub fn curl_at(&self, i: usize, a: &[Vec3], wall: WallField) -> Vec3 {
        let ai = a[i];
        let mut c = Vec3::zeros();
        self.pairs(i, a, wall, |vj, aj, _, grad| {
            c += vj * (ai - aj).cross(&grad)
        });
        c
    }

    /// Gradient (Ye Eq. 7) of a scalar field `s` (walls hold zero).
    pub fn scalar_gradient(&self, s: &[Real]) -> Vec<Vec3> {
        (0..s.len())
            .into_par_iter()
            .map(|i| {
                let si = s[i];
                let mut g = Vec3::zeros();
                self.nb
                    .fluid_pairs_grad(i, |j, _, grad| g += (self.volume[j] * (s[j] - si)) * grad);
                if self.walls {
                    let b = self.nb.boundary;
                    self.nb
                        .boundary_pairs_grad(i, |m, _, grad| g -= (b.volume[m] * si) * grad);
                }
                g
            })
            .collect()
    }
}

/// The curl of a velocity field from its gradient tensor: the antisymmetric part,
/// (dv_z/dy - dv_y/dz, dv_x/dz - dv_z/dx, dv_y/dx - dv_x/dy).
#[inline]
pub fn curl_of(g: &Mat3) -> Vec3 {
    Vec3::new(
        g[(2, 1)] - g[(1, 2)],
        g[(0, 2)] - g[(2, 0)],
        g[(1, 0)] - g[(0, 1)],
    )
}

/// `f(i)` for every particle i below `n` in parallel, or only where `only[i]` holds (the
/// default, zero, elsewhere).
pub fn per_particle<T: Default + Send>(
    n: usize,
    only: Option<&[bool]>,
    f: impl Fn(usize) -> T + Sync,
) -> Vec<T> {
    (0..n)
        .into_par_iter()
        .map(|i| match only {
            Some(only) if !only[i] => T::default(),
            _ => f(i),
        })
        .collect()
}

/// V_j = m / rho_j for every fluid particle.
pub fn volumes(mass: Real, density: &[Real]) -> Vec<Real> {
    let mut out = Vec::new();
    volumes_into(mass, density, &mut out);
    out
}

/// [`volumes`] into `out`, keeping its allocation (the solver refills it every step).
pub fn volumes_into(mass: Real, density: &[Real], out: &mut Vec<Real>) {
    out.clear();
    out.par_extend(density.par_iter().map(|rho| mass / rho));
}
