//! Fluid particles that leave the domain. A splash can throw a particle out through a side no
//! wall closes (over the top of an open channel, over a bank): it is removed and counted, as
//! DualSPHysics excludes the particles that leave its domain, so that one stray particle no
//! longer ends a run. The solver removes it with the outflow's removal, so every per-particle
//! array follows.
//!
//! A particle counts as outside once it lies beyond the domain by more than the wall layer's
//! depth (a container flush with the domain lets particles touch its walls). One that lies
//! inside a solid there (outside the container, or inside an obstacle that reaches beyond the
//! domain) went through a wall's samples, which a stable step does not do: the run stops as
//! before. Where it lies in the open it is lost, whichever way it came: a particle that went
//! over a bank and falls down its outer face beyond the domain is, and so would be one that
//! tunnelled through a wall into open space (the lost share stops a run whose walls leak).

use super::params::DomainSide;
use crate::state::{Persist, Restorer, Saver, StateError};
use crate::{Real, Vec3};

/// The lost particles so far: the count through each side and where the last one was.
#[derive(Debug, Clone, Default)]
pub struct LostParticles {
    /// By [`DomainSide::index`].
    by_side: [u64; 6],
    last: Option<Vec3>,
}

impl LostParticles {
    /// Counts a particle lost through `side` at `x`.
    pub fn add(&mut self, side: DomainSide, x: Vec3) {
        self.by_side[side.index()] += 1;
        self.last = Some(x);
    }

    /// Every lost particle.
    pub fn total(&self) -> u64 {
        self.by_side.iter().sum()
    }

    /// Where the last one was when it was removed.
    pub fn last(&self) -> Option<Vec3> {
        self.last
    }

    /// The counts of the sides that lost any: "12 through y_max, 3 through z_min".
    pub fn by_side(&self) -> String {
        DomainSide::ALL
            .iter()
            .filter(|s| self.by_side[s.index()] > 0)
            .map(|s| format!("{} through {}", self.by_side[s.index()], s.name()))
            .collect::<Vec<_>>()
            .join(", ")
    }
}

/// The counts (the lost-share stop reads them) and the last position (its message).
impl Persist for LostParticles {
    fn save(&self, into: &mut Saver) {
        into.u64s("by_side", &self.by_side);
        into.reals("last", self.last.as_ref().map_or(&[][..], |x| x.as_slice()));
    }

    fn restore(&mut self, from: &Restorer) -> Result<(), StateError> {
        let counts = from.u64s("by_side")?;
        let by_side = counts.as_slice().try_into().map_err(|_| {
            let found = format!("{} u64 values", counts.len());
            from.invalid("by_side", found, "6 u64 values, one a side".into())
        })?;
        let last = match from.reals("last")?.as_slice() {
            [] => None,
            _ => Some(from.vec3s_n("last", 1)?[0]),
        };
        *self = Self { by_side, last };
        Ok(())
    }
}

/// The side of the box `(lo, hi)` that `x` lies beyond by more than `margin` (of several, the
/// one it lies farthest beyond).
pub fn beyond(x: &Vec3, (lo, hi): (Vec3, Vec3), margin: Real) -> Option<DomainSide> {
    (0..3)
        .flat_map(|a| {
            [
                (DomainSide::of(a, false), lo[a] - x[a]),
                (DomainSide::of(a, true), x[a] - hi[a]),
            ]
        })
        .filter(|(_, depth)| *depth > margin)
        .max_by(|a, b| a.1.total_cmp(&b.1))
        .map(|(side, _)| side)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_side_is_the_one_farthest_beyond() {
        let b = (Vec3::zeros(), Vec3::repeat(1.0));
        assert_eq!(beyond(&Vec3::new(0.5, 0.5, 0.5), b, 0.01), None);
        assert_eq!(beyond(&Vec3::new(0.5, 1.005, 0.5), b, 0.01), None);
        let side = |x: Vec3| beyond(&x, b, 0.01);
        assert_eq!(side(Vec3::new(-0.02, 1.05, 0.5)), Some(DomainSide::YMax));
        assert_eq!(side(Vec3::new(-0.05, 1.02, 0.5)), Some(DomainSide::XMin));
        assert_eq!(side(Vec3::new(0.5, 0.5, -0.02)), Some(DomainSide::ZMin));
    }

    #[test]
    fn the_count_names_each_side_that_lost_any() {
        let mut lost = LostParticles::default();
        assert_eq!(lost.total(), 0);
        lost.add(DomainSide::ZMin, Vec3::zeros());
        lost.add(DomainSide::YMax, Vec3::zeros());
        lost.add(DomainSide::YMax, Vec3::new(1.0, 2.0, 3.0));
        assert_eq!(lost.total(), 3);
        assert_eq!(lost.by_side(), "2 through y_max, 1 through z_min");
        assert_eq!(lost.last(), Some(Vec3::new(1.0, 2.0, 3.0)));
    }
}
