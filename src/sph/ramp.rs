//! A smooth start. A river set moving all at once against its obstacles (every particle at the
//! inflow's speed at t = 0) starts with a pressure impulse that throws water up: at 1.25 cm the
//! river of Pfaff et al. Figure 10 splashed to y = 0.47 m within 0.35 s, at 0.625 cm a particle
//! reached 4.78 m/s in 0.05 s and left the domain. CFD codes ramp such starts; here the inflows'
//! velocity and the fluid's velocity rise together as
//!
//!   r(t) = (1 - cos(pi t / T)) / 2 for t < T, 1 after,
//!
//! a half cosine, whose rate r'(t) is zero at both ends (no jump in acceleration at the start or
//! at the end of the ramp).
//!
//! **The blocks start at rest and the whole fluid is accelerated by the uniform body
//! acceleration v0 r'(t)**, v0 the blocks' common velocity (the scene refuses a ramp under
//! blocks of different velocities). This is an accelerated start: a uniform body force is what a
//! pressure gradient along a channel or an accelerating frame exerts, it moves every particle
//! alike, so the fluid reaches v0 with no internal pressure impulse, while the inflow buffer
//! keeps up at r(t) times its own velocity. Each step adds the exact integral of the
//! acceleration over the step, v0 (r(t + dt) - r(t)), so the fluid carries v0 r(t) to round-off
//! whatever the steps, and v0 exactly once the ramp is over.

use crate::{Real, Vec3};

/// The ramp of a fluid: its duration and the velocity it accelerates the fluid to.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ramp {
    /// T, s; 0 for an impulsive start.
    duration: Real,
    /// v0, m/s: the blocks' velocity, which the fluid reaches at t = T.
    velocity: Vec3,
}

impl Ramp {
    /// A ramp over `duration` s (0: none) to the fluid velocity `velocity`.
    pub fn new(duration: Real, velocity: Vec3) -> Self {
        Self { duration, velocity }
    }

    /// r(t): 0 at t = 0, 1 from t = T on (always 1 without a ramp).
    pub fn factor(&self, t: Real) -> Real {
        if t >= self.duration {
            1.0
        } else {
            0.5 * (1.0 - (std::f64::consts::PI * t / self.duration).cos())
        }
    }

    /// The velocity the body acceleration v0 r' adds over the step from `t` to `t + dt`;
    /// `None` once it adds nothing (after the ramp, or with v0 = 0).
    pub fn increment(&self, t: Real, dt: Real) -> Option<Vec3> {
        (t < self.duration && self.velocity != Vec3::zeros())
            .then(|| (self.factor(t + dt) - self.factor(t)) * self.velocity)
    }

    /// One line for the plan; `None` without a ramp.
    pub fn describe(&self) -> Option<String> {
        (self.duration > 0.0).then(|| {
            let v = self.velocity;
            format!(
                "smooth start over {} s: inflows at r(t) times their velocity, r = (1 - \
                 cos(pi t / {} s)) / 2; the fluid starts at rest and is accelerated by \
                 [{}, {}, {}] m/s times r'(t)",
                self.duration, self.duration, v.x, v.y, v.z
            )
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// r rises from 0 to 1 monotonically with zero slope at both ends, and the increments of any
    /// steps add up to v0 r(t).
    #[test]
    fn the_half_cosine_rises_smoothly_and_its_increments_add_up() {
        let v0 = Vec3::new(1.0, 0.0, -0.5);
        let ramp = Ramp::new(0.25, v0);
        assert_eq!(ramp.factor(0.0), 0.0);
        assert_eq!(ramp.factor(0.25), 1.0);
        assert!((ramp.factor(0.125) - 0.5).abs() < 1e-15);
        let slope = |t: Real| (ramp.factor(t + 1e-7) - ramp.factor(t)) / 1e-7;
        assert!(slope(0.0) < 1e-5 && slope(0.25 - 1e-7) < 1e-5);
        let mut t = 0.0;
        let mut v = Vec3::zeros();
        for dt in [0.003, 0.01, 0.0071, 0.05, 0.02].iter().cycle().take(30) {
            if let Some(dv) = ramp.increment(t, *dt) {
                v += dv;
            }
            t += dt;
            assert!((v - ramp.factor(t) * v0).norm() < 1e-15, "t = {t}");
        }
        assert_eq!(ramp.increment(t, 0.01), None);
        assert_eq!(Ramp::new(0.0, v0).factor(0.0), 1.0);
        assert_eq!(Ramp::new(0.0, v0).increment(0.0, 0.01), None);
    }
}
