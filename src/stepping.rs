//! The shared clock's rules: the step-size limits every solver takes from the scene's `[time]`,
//! and landing a run on its end time without a tiny last step (a step far shorter than its
//! neighbours upsets solvers that correct an error within one step: DFSPH's density solve turns
//! the same compression into a velocity kick proportional to 1/dt).

use crate::Real;

/// How a solver bounds its step: a CFL factor between `dt_min` and `dt_max`, or a fixed step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StepLimits {
    /// CFL factor: dt = cfl * spacing / max speed.
    pub cfl: Real,
    /// Smallest allowed step, s; a state that needs a smaller one is unstable.
    pub dt_min: Real,
    /// Largest allowed step, s.
    pub dt_max: Real,
    /// A fixed step, s, instead of the CFL rule.
    pub fixed_dt: Option<Real>,
}

impl Default for StepLimits {
    /// The scene file's defaults (`[time]`).
    fn default() -> Self {
        Self {
            cfl: 0.4,
            dt_min: 1e-6,
            dt_max: 5e-3,
            fixed_dt: None,
        }
    }
}

/// The step to take when `remaining` time is left and the solver would take `dt`: `dt` while
/// at least two steps remain; over the last two, halves of what remains; at the end, the rest.
/// No step falls below half of `dt`, except when the whole run is shorter than that.
pub fn towards_end(dt: Real, remaining: Real) -> Real {
    if remaining >= 2.0 * dt {
        dt
    } else if remaining > dt {
        0.5 * remaining
    } else {
        remaining
    }
}

#[cfg(test)]
mod tests {
    use super::towards_end;

    /// Stepping at a fixed dt towards an end that is not a multiple of it lands exactly on the
    /// end, and no step is shorter than half of dt.
    #[test]
    fn lands_without_a_tiny_step() {
        for end in [1.0, 1.03, 1.0999, 0.04, 2.5] {
            let (dt, mut t, mut shortest) = (0.1, 0.0, f64::INFINITY);
            while t < end {
                let step = towards_end(dt, end - t);
                shortest = shortest.min(step);
                t += step;
            }
            assert!((t - end).abs() < 1e-12, "ended at {t} for {end}");
            assert!(
                shortest >= 0.5 * dt || end < 0.5 * dt,
                "{shortest} for {end}"
            );
        }
    }
}
