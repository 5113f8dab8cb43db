//! The vortex-particle kernel: a Gaussian in the vector potential (Pfaff et al. 2009, Eqs. 11–13),
//! derived again because the printed equations carry typos (docs/src/paper-notes.md, "The vortex kernel").
//!
//! **Derivation.** Let `a = omega_p` (axis and strength), `d = x - x_p`, `r = |d|` and
//! `g(r) = exp(-r^2 / (2 sigma^2))`, a Gaussian of standard deviation sigma in the squared
//! *distance* (Eq. 11 prints `rho^2 - z^2`, which grows along the axis). Take the potential
//!
//! ```text
//! Psi = (sigma^2 / 2) g(r) a.
//! ```
//!
//! Since `grad g = -g d / sigma^2`, the velocity is
//!
//! ```text
//! u = curl Psi = grad((sigma^2/2) g) x a = (1/2) g(r) a x d,
//! ```
//!
//! i.e. `u = (|a| / 2) rho g e_phi` in cylindrical coordinates about the axis (Eq. 12 up to the
//! amplitude). It is divergence-free, being a curl. With `curl(g A) = grad g x A + g curl A`
//! and `A = (1/2) a x d`, `curl A = a`:
//!
//! ```text
//! omega = curl u = g a - (g / (2 sigma^2)) d x (a x d)
//!       = g [ a (1 - r^2 / (2 sigma^2)) + d (d . a) / (2 sigma^2) ],
//! ```
//!
//! whose axial part is `|a| g (1 - rho^2 / (2 sigma^2))` and radial part
//! `|a| g rho z / (2 sigma^2) e_rho` (Eq. 13 prints it along e_phi). At the centre
//! `omega = a` exactly, sign included: the printed amplitude `-|omega_p| sigma^2` would give
//! `-2 omega_p`, so the amplitude here is `+sigma^2 / 2`.
//!
//! **Energy.** `|u|^2 = (|a|^2 / 4) rho^2 g^2` and `int rho^2 exp(-r^2/sigma^2) dV = pi^(3/2)
//! sigma^5`, so `E = 1/2 int |u|^2 dV = (pi^(3/2) / 8) |a|^2 sigma^5`.
//!
//! **Cut-offs.** The vorticity kernel is cut off at `r_c = sqrt(6) sigma` (section 4.3): the
//! sums of Eq. 14 run over the samples inside it, and it is the particle's *radius* for
//! dissipation and merging. The velocity is evaluated further out, to `3 sigma`: a velocity
//! truncated at `r_c` (where it is still 5 % of its Gaussian) leaves a vortex sheet on the
//! cut-off sphere whose discrete curl falls into the cells of Eq. 14 and spoils the regulation
//! (by 38 % at sigma = 3 cells); stopping at 3 sigma keeps the sheet (1.1 % of the Gaussian)
//! outside every cell that Eq. 14 sums for sigma >= 1.5 cells. Energy bookkeeping uses the
//! untruncated formula above: the synthesized field (to 3 sigma) holds all but 0.3 % of it.

use crate::{Real, Vec3};

/// `r_c / sigma`: the vorticity cut-off, the particle radius.
pub const CUTOFF: Real = 2.449_489_742_783_178;
/// How far the velocity is evaluated, in sigma.
pub const VELOCITY_REACH: Real = 3.0;
/// `pi^(3/2) / 8`: the energy constant, `E = ENERGY * |omega_p|^2 sigma^5`.
pub const ENERGY: Real = 0.696_040_999_603_963_5;

/// Velocity of the kernel of `omega` (axis and strength) and scale `sigma` at offset `d` from
/// its centre (untruncated).
#[inline]
pub fn velocity(omega: &Vec3, sigma: Real, d: &Vec3) -> Vec3 {
    let g = (-d.norm_squared() / (2.0 * sigma * sigma)).exp();
    (0.5 * g) * omega.cross(d)
}

/// Vorticity of the kernel at offset `d` (untruncated); equals `omega` at `d = 0`.
#[inline]
pub fn vorticity(omega: &Vec3, sigma: Real, d: &Vec3) -> Vec3 {
    let s2 = sigma * sigma;
    let r2 = d.norm_squared();
    let g = (-r2 / (2.0 * s2)).exp();
    g * (omega * (1.0 - r2 / (2.0 * s2)) + d * (d.dot(omega) / (2.0 * s2)))
}

/// Kinetic energy per unit density of the untruncated kernel, m^5/s^2.
#[inline]
pub fn energy(strength: Real, sigma: Real) -> Real {
    ENERGY * strength * strength * sigma.powi(5)
}

/// The particle radius `sqrt(6) sigma`.
#[inline]
pub fn radius(sigma: Real) -> Real {
    CUTOFF * sigma
}

/// The kernel scale of a particle of radius `r`.
#[inline]
pub fn sigma_for_radius(r: Real) -> Real {
    r / CUTOFF
}

/// How far the velocity is evaluated, `3 sigma`.
#[inline]
pub fn velocity_radius(sigma: Real) -> Real {
    VELOCITY_REACH * sigma
}
