//! The energy stop: a blow-up that has not reached NaN yet shows as kinetic energy the scene
//! has no source for. The fluid's mean kinetic energy per unit mass, e = sum |v|^2 / (2 n)
//! (every particle has one mass), may not exceed
//!
//!   e_max = 1/2 (10 (U + sqrt(2 g H)))^2,
//!
//! U the fastest source of motion the scene has (a block's velocity, an inflow's peak velocity,
//! the fastest point of a moving body, the fastest particle of the state the first step starts
//! from, which takes in velocities written before the run), sqrt(2 g H) the speed of a fall
//! across the domain's whole extent H along gravity. A physical flow's mean speed stays under
//! U + sqrt(2 g H): gravity turns at most g H per unit mass into motion, and nothing drives the
//! fluid faster than its sources. The factor [`SPEED_FACTOR`] on that speed is room for what is
//! not a blow-up: splashes and jets focus energy, an inflow or a moving body keeps doing work,
//! and an impulsive start against no-slip walls multiplies the kinetic energy of the plates
//! channel (`tests/sph_open_boundaries.rs`, 0.2 m/s, no gravity) by 4.6 within its first ten
//! steps, a transient the explicit wall viscosity makes, which then decays. A blow-up grows
//! exponentially, through any such factor within a few steps. A scene with no source at all (no
//! gravity, nothing moving) has no bound.

use crate::state::{Persist, Restorer, Saver, StateError};
use crate::{Real, Vec3};

/// How many times faster than its fastest source and a fall across the domain the fluid may
/// move on average (a hundred times the energy).
pub const SPEED_FACTOR: Real = 10.0;

/// The bound, fixed at the first step.
#[derive(Debug, Clone, Copy)]
pub struct EnergyBound {
    /// U without the fluid's own state, m/s.
    source: Real,
    /// sqrt(2 g H), m/s.
    fall: Real,
    /// e_max, J/kg, from the first step on; `None` before it.
    bound: Option<Real>,
}

impl EnergyBound {
    /// The bound of a fluid driven by sources no faster than `source` m/s, under `gravity` in
    /// the domain `(lo, hi)`.
    pub fn new(source: Real, gravity: Vec3, (lo, hi): (Vec3, Vec3)) -> Self {
        let g = gravity.norm();
        let height = if g > 0.0 {
            (hi - lo).dot(&(gravity / g).abs())
        } else {
            0.0
        };
        Self {
            source,
            fall: (2.0 * g * height).sqrt(),
            bound: None,
        }
    }

    /// e_max, J/kg, with the fastest particle of the first step's state at `fastest` m/s (taken
    /// at the first call, kept after).
    pub fn bound(&mut self, fastest: impl FnOnce() -> Real) -> Real {
        *self.bound.get_or_insert_with(|| {
            let speed = SPEED_FACTOR * (self.source.max(fastest()) + self.fall);
            0.5 * speed * speed
        })
    }

    /// Whether the mean kinetic energy `energy` (J/kg) is beyond the bound (a bound of zero is
    /// none).
    pub fn exceeded(bound: Real, energy: Real) -> bool {
        bound > 0.0 && energy > bound
    }
}

/// The bound once fixed (it took in the first step's fastest particle); the sources are the
/// scene's.
impl Persist for EnergyBound {
    fn save(&self, into: &mut Saver) {
        into.reals("bound", self.bound.as_slice());
    }

    fn restore(&mut self, from: &Restorer) -> Result<(), StateError> {
        self.bound = match from.reals("bound")?.as_slice() {
            [] => None,
            _ => Some(from.real("bound")?),
        };
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_bound_adds_a_fall_across_the_domain_to_the_fastest_source() {
        let domain = (Vec3::zeros(), Vec3::new(2.0, 0.5, 1.0));
        let mut b = EnergyBound::new(1.0, Vec3::new(0.0, -9.81, 0.0), domain);
        let fall = (2.0 * 9.81 * 0.5 as Real).sqrt();
        let e = b.bound(|| 0.5);
        assert!((e - 50.0 * (1.0 + fall).powi(2)).abs() < 1e-9);
        // Fixed at the first call.
        assert_eq!(b.bound(|| 100.0), e);
        // The fluid's own speed counts when faster than the sources.
        let mut still = EnergyBound::new(0.0, Vec3::zeros(), domain);
        assert!((still.bound(|| 0.3) - 4.5).abs() < 1e-12);
        assert!(!EnergyBound::exceeded(0.0, 1e9));
        assert!(EnergyBound::exceeded(4.5, 4.6));
    }
}
