//! The shell-averaged kinetic-energy spectrum E(k) of a cell-centred velocity field (Pope,
//! *Turbulent Flows*, 2000, §6.5): the energy of the Fourier modes whose wavenumber magnitude
//! lies in a spherical shell, per unit wavenumber, so that E integrates to the kinetic energy
//! per unit mass, ½⟨|u|²⟩. In an inertial range it falls as k^(-5/3).
//!
//! The transform is the field's 3-D DFT. A periodic axis is transformed as it is; a
//! non-periodic one (walls, inflow, outflow) would add the jump between its ends to every mode,
//! so the field is tapered by a Hann window along it first and the energy divided by the
//! window's mean square.

use ndarray::{Array3, ArrayView3, Axis, Zip};
use rustfft::num_complex::Complex;
use rustfft::FftPlanner;

use super::SpectrumError;
use crate::Real;

/// What to do with the mean velocity before the transform.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mean {
    /// Subtract the mean over the fluid cells from each component: the spectrum of the
    /// fluctuations (the usual turbulence spectrum), nothing at k = 0 in a periodic box (a
    /// window gives the windowed fluctuations a mean of their own, which lands there).
    Remove,
    /// Transform the velocity as it is: the mean flow's energy lands in the shell k = 0
    /// (with a window, partly in the first shells too).
    Keep,
}

/// How [`energy_spectrum`] treats the box.
#[derive(Debug, Clone)]
pub struct ShellOptions<'a> {
    /// Per axis x, y, z: whether the field wraps around (periodic sides); the others are
    /// windowed. An axis one cell thick (a 2-D flow) has only k = 0 along it either way.
    pub periodic: [bool; 3],
    pub mean: Mean,
    /// Solid cells (true), of the field's shape: set to zero before the transform, after the
    /// mean (over the fluid cells) is removed. None: every cell is fluid.
    pub solid: Option<ArrayView3<'a, bool>>,
}

/// E(k) on shells of width `dk` centred on k_n = n dk, n = 0, 1, ...
#[derive(Debug, Clone, PartialEq)]
pub struct EnergySpectrum {
    /// The shells' centres, rad/m.
    pub k: Vec<Real>,
    /// E(k_n), (m/s)² m: the energy of the modes with n dk - dk/2 <= |k| < n dk + dk/2,
    /// divided by dk.
    pub energy: Vec<Real>,
    /// The shells' width: 2 pi / L with L the box's longest side, the finest wavenumber step
    /// of its axes.
    pub dk: Real,
    /// The mean velocity over the fluid cells, m/s (removed or kept as [`Mean`] said).
    pub mean: [Real; 3],
    /// Per axis, whether it was windowed.
    pub windowed: [bool; 3],
}

impl EnergySpectrum {
    /// sum_n E(k_n) dk: the kinetic energy per unit mass the spectrum holds (see
    /// [`energy_spectrum`]).
    pub fn integral(&self) -> Real {
        self.energy.iter().sum::<Real>() * self.dk
    }
}

/// The shell-averaged spectrum of the velocity (u, v, w), each of shape (nx, ny, nz) indexed
/// [i, j, k] = [x, y, z], on cubic cells of side `dx` (m).
///
/// With u' the velocity less its mean over the fluid cells ([`Mean::Remove`]) or as it is
/// ([`Mean::Keep`]), zero in solid cells, and W the product of the windows of the non-periodic
/// axes (w(i) = sin²(pi (i + ½) / n) at cell i of n; 1 on periodic axes), the modes are
/// û(κ) = (1/N) sum_x W u' e^(-i κ·x) over the N cells, and
///
/// E(k_n) dk = ½ sum over the κ of shell n of |û(κ)|² / ⟨W²⟩,
///
/// so that by Parseval's identity sum_n E(k_n) dk = ½⟨W² |u'|²⟩ / ⟨W²⟩ exactly, ⟨·⟩ the mean
/// over all N cells of the box (solid ones counting as zero). With every axis periodic W = 1
/// and the sum is ½⟨|u'|²⟩; with windows it is the same for a field that is statistically
/// homogeneous along the windowed axes. Every mode is in some shell, the corners of the box
/// of wavenumbers beyond pi / dx included, so the last shells are only partly filled.
pub fn energy_spectrum(
    velocity: [ArrayView3<'_, Real>; 3],
    dx: Real,
    options: &ShellOptions<'_>,
) -> Result<EnergySpectrum, SpectrumError> {
    let dims: [usize; 3] = velocity[0]
        .shape()
        .try_into()
        .map_err(|_| SpectrumError::Invalid("the velocity is not 3-D".into()))?;
    check(&velocity, dims, dx, options)?;
    let cells = dims.iter().product::<usize>();
    let fluid = |idx: (usize, usize, usize)| !options.solid.is_some_and(|s| s[idx]);
    let fluid_cells = match &options.solid {
        Some(s) => s.iter().filter(|s| !**s).count(),
        None => cells,
    };
    if fluid_cells == 0 {
        return Err(SpectrumError::Invalid("every cell is solid".into()));
    }
    let mean: [Real; 3] = std::array::from_fn(|c| {
        let sum: Real = velocity[c]
            .indexed_iter()
            .filter(|(idx, _)| fluid(*idx))
            .map(|(_, v)| v)
            .sum();
        sum / fluid_cells as Real
    });
    let windowed: [bool; 3] = std::array::from_fn(|a| !options.periodic[a] && dims[a] > 1);
    let windows: [Vec<Real>; 3] = std::array::from_fn(|a| {
        (0..dims[a])
            .map(|i| {
                if windowed[a] {
                    (std::f64::consts::PI * (i as Real + 0.5) / dims[a] as Real)
                        .sin()
                        .powi(2)
                } else {
                    1.0
                }
            })
            .collect()
    });
    let mean_square: Real = windows
        .iter()
        .map(|w| w.iter().map(|w| w * w).sum::<Real>() / w.len() as Real)
        .product();
    let longest = dims.iter().copied().max().unwrap_or(1) as Real * dx;
    let dk = 2.0 * std::f64::consts::PI / longest;
    let wavenumber: [Vec<Real>; 3] = std::array::from_fn(|a| {
        let n = dims[a];
        let step = 2.0 * std::f64::consts::PI / (n as Real * dx);
        (0..n)
            .map(|i| if i <= n / 2 { i as Real } else { i as Real - n as Real } * step)
            .collect()
    });
    let shell = Array3::from_shape_fn(dims, |(i, j, k)| {
        let [kx, ky, kz] = [wavenumber[0][i], wavenumber[1][j], wavenumber[2][k]];
        ((kx * kx + ky * ky + kz * kz).sqrt() / dk).round() as usize
    });
    let shells = shell.iter().copied().max().unwrap_or(0) + 1;
    let mut energy = vec![0.0; shells];
    let norm = 0.5 / (cells as Real * cells as Real * mean_square * dk);
    let mut planner = FftPlanner::<Real>::new();
    for (c, u) in velocity.iter().enumerate() {
        let mut modes = Array3::from_shape_fn(dims, |idx @ (i, j, k)| {
            let value = match (fluid(idx), options.mean) {
                (false, _) => 0.0,
                (true, Mean::Remove) => u[idx] - mean[c],
                (true, Mean::Keep) => u[idx],
            };
            Complex::new(value * windows[0][i] * windows[1][j] * windows[2][k], 0.0)
        });
        for (a, &n) in dims.iter().enumerate() {
            if n > 1 {
                let fft = planner.plan_fft_forward(n);
                Zip::from(modes.lanes_mut(Axis(a))).par_for_each(|mut lane| {
                    let mut line: Vec<Complex<Real>> = lane.iter().copied().collect();
                    fft.process(&mut line);
                    lane.iter_mut().zip(line).for_each(|(l, v)| *l = v);
                });
            }
        }
        // In index order, so the sums do not depend on the threads.
        Zip::from(&modes).and(&shell).for_each(|m, &s| {
            energy[s] += norm * m.norm_sqr();
        });
    }
    Ok(EnergySpectrum {
        k: (0..shells).map(|n| n as Real * dk).collect(),
        energy,
        dk,
        mean,
        windowed,
    })
}

/// Refuses components of different shapes, an empty box, a bad cell size, a mask of another
/// shape and values that are not finite.
fn check(
    velocity: &[ArrayView3<'_, Real>; 3],
    dims: [usize; 3],
    dx: Real,
    options: &ShellOptions<'_>,
) -> Result<(), SpectrumError> {
    if let Some(c) = velocity.iter().position(|u| u.shape() != dims) {
        return Err(SpectrumError::Invalid(format!(
            "velocity component {c} has shape {:?}, component 0 {dims:?}",
            velocity[c].shape()
        )));
    }
    if dims.contains(&0) {
        return Err(SpectrumError::Invalid(format!(
            "an empty box of {dims:?} cells"
        )));
    }
    if !(dx.is_finite() && dx > 0.0) {
        return Err(SpectrumError::Invalid(format!(
            "the cell size must be positive, not {dx} m"
        )));
    }
    if let Some(s) = options.solid.as_ref().filter(|s| s.shape() != dims) {
        return Err(SpectrumError::Invalid(format!(
            "the solid mask has shape {:?}, the velocity {dims:?}",
            s.shape()
        )));
    }
    for (c, u) in velocity.iter().enumerate() {
        if let Some((idx, v)) = u.indexed_iter().find(|(_, v)| !v.is_finite()) {
            return Err(SpectrumError::Invalid(format!(
                "velocity component {c} is {v} at cell {idx:?}"
            )));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use ndarray::Array3;
    use std::f64::consts::PI;

    /// A smooth field that does not wrap around: a ramp plus a wave.
    fn field(dims: [usize; 3], dx: Real, phase: Real) -> Array3<Real> {
        Array3::from_shape_fn(dims, |(i, j, k)| {
            let (x, y, z) = (i as Real * dx, j as Real * dx, k as Real * dx);
            0.3 + x - 0.5 * y + (2.0 * x + 3.0 * z + phase).sin() * (y + 0.2).cos()
        })
    }

    /// Parseval as documented, with windows on two axes and a mask: ½⟨W²|u'|²⟩ / ⟨W²⟩.
    #[test]
    fn a_windowed_masked_field_integrates_to_its_weighted_energy() {
        let (dims, dx) = ([12, 10, 8], 0.1);
        let u = [
            field(dims, dx, 0.0),
            field(dims, dx, 1.0),
            field(dims, dx, 2.0),
        ];
        let solid = Array3::from_shape_fn(dims, |(i, j, _)| {
            (i as i32 - 5).pow(2) + (j as i32 - 4).pow(2) < 5
        });
        for mean in [Mean::Remove, Mean::Keep] {
            let options = ShellOptions {
                periodic: [false, true, false],
                mean,
                solid: Some(solid.view()),
            };
            let s = energy_spectrum([u[0].view(), u[1].view(), u[2].view()], dx, &options)
                .expect("a valid field");
            assert_eq!(s.windowed, [true, false, true]);
            let w = |a: usize, i: usize| {
                if a == 1 {
                    1.0
                } else {
                    (PI * (i as Real + 0.5) / dims[a] as Real).sin().powi(2)
                }
            };
            let (mut weighted, mut weights) = (0.0, 0.0);
            for ((i, j, k), &solid) in solid.indexed_iter() {
                let w2 = (w(0, i) * w(1, j) * w(2, k)).powi(2);
                weights += w2;
                if !solid {
                    let keep = mean == Mean::Keep;
                    let q: Real = (0..3)
                        .map(|c| u[c][(i, j, k)] - if keep { 0.0 } else { s.mean[c] })
                        .map(|v| v * v)
                        .sum();
                    weighted += w2 * q;
                }
            }
            let expected = 0.5 * weighted / weights;
            let got = s.integral();
            assert!(
                ((got - expected) / expected).abs() < 1e-10,
                "{mean:?}: {got} against {expected}"
            );
        }
    }

    /// What a solid cell holds does not reach the spectrum.
    #[test]
    fn solid_cells_are_zero_whatever_they_hold() {
        let (dims, dx) = ([8, 8, 8], 0.25);
        let u = field(dims, dx, 0.5);
        let solid = Array3::from_shape_fn(dims, |(i, j, k)| i + j + k < 6);
        let spoilt = Array3::from_shape_fn(dims, |idx| if solid[idx] { 1e3 } else { u[idx] });
        let options = ShellOptions {
            periodic: [true; 3],
            mean: Mean::Remove,
            solid: Some(solid.view()),
        };
        let a = energy_spectrum([u.view(), u.view(), u.view()], dx, &options).expect("valid");
        let b = energy_spectrum([spoilt.view(), u.view(), u.view()], dx, &options).expect("valid");
        assert_eq!(a, b);
    }

    #[test]
    fn bad_fields_are_refused_with_what_is_wrong() {
        let u = Array3::<Real>::zeros([4, 4, 4]);
        let v = Array3::<Real>::zeros([4, 4, 3]);
        let options = ShellOptions {
            periodic: [true; 3],
            mean: Mean::Remove,
            solid: None,
        };
        let error = energy_spectrum([u.view(), v.view(), u.view()], 0.1, &options).unwrap_err();
        assert!(
            error
                .to_string()
                .contains("component 1 has shape [4, 4, 3]"),
            "{error}"
        );
        let error = energy_spectrum([u.view(), u.view(), u.view()], 0.0, &options).unwrap_err();
        assert!(error.to_string().contains("cell size"), "{error}");
        let all = Array3::from_elem([4, 4, 4], true);
        let masked = ShellOptions {
            solid: Some(all.view()),
            ..options
        };
        let error = energy_spectrum([u.view(), u.view(), u.view()], 0.1, &masked).unwrap_err();
        assert!(error.to_string().contains("every cell is solid"), "{error}");
    }
}
