//! Landing a run on its end time without a tiny last step: a step far shorter than its
//! neighbours upsets solvers that correct an error within one step (DFSPH's density solve turns
//! the same compression into a velocity kick proportional to 1/dt).

use crate::Real;

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
