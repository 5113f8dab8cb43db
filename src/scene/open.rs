//! The SPH fluid's open boundaries in a scene: `[[fluid.inflow]]` and `[[fluid.outflow]]`.

use super::validate::{Checker, Interval};
use super::{Domain, Fluid, SceneError};
use crate::sph::{DomainSide, InflowShape};

impl Fluid {
    /// Each inflow's rectangle on its side holds at least one lattice site, its velocity points
    /// into the domain, the outflow sides are distinct and none is also an inflow side, and a
    /// scene with an inflow has an outflow for the fluid to leave by.
    pub(super) fn validate_open(&self, c: &Checker, domain: &Domain) -> Result<(), SceneError> {
        let name = |side: DomainSide| side.name();
        for (i, inflow) in self.inflow.iter().enumerate() {
            let key = format!("fluid.inflow[{i}]");
            let side = inflow.side;
            for (k, axis) in side.tangents().into_iter().enumerate() {
                let (lo, hi) = (domain.min[axis], domain.max[axis]);
                let range = || Interval::closed(lo, hi).noted("the domain's extent along the side");
                c.num(&format!("{key}.min[{k}]"), inflow.min[k], range())?;
                c.num(&format!("{key}.max[{k}]"), inflow.max[k], range())?;
                if inflow.max[k] - inflow.min[k] < self.spacing {
                    return Err(c.invalid(
                        format!("{key}.max[{k}]"),
                        inflow.max[k],
                        format!(
                            "at least min + fluid.spacing = {}: a narrower emitter spawns no \
                             particle",
                            inflow.min[k] + self.spacing
                        ),
                    ));
                }
            }
            c.vec3(&format!("{key}.velocity"), inflow.velocity)?;
            let axis = side.axis();
            let tangents = side.tangents();
            match (inflow.shape, inflow.across) {
                (InflowShape::Plane, Some(a)) if tangents.contains(&a) => {}
                (InflowShape::Plane, across) => {
                    return Err(c.invalid(
                        format!("{key}.across"),
                        across.map_or("nothing".into(), |a| a.to_string()),
                        format!(
                            "{} or {}: a plane profile runs across one of the side's axes",
                            tangents[0], tangents[1]
                        ),
                    ));
                }
                (_, Some(a)) => {
                    return Err(c.invalid(
                        format!("{key}.across"),
                        a,
                        "no value: only `shape = \"plane\"` takes an axis",
                    ));
                }
                (_, None) => {}
            }
            let inward = inflow.velocity[axis] * side.inward()[axis];
            if inward <= 0.0 {
                let sign = if side.is_max() { "< 0" } else { "> 0" };
                return Err(c.invalid(
                    format!("{key}.velocity[{axis}]"),
                    inflow.velocity[axis],
                    format!(
                        "{sign}: the fluid must enter the domain through {}",
                        name(side)
                    ),
                ));
            }
        }
        for (i, outflow) in self.outflow.iter().enumerate() {
            let key = format!("fluid.outflow[{i}].side");
            if self.outflow[..i].iter().any(|o| o.side == outflow.side) {
                return Err(c.invalid(key, name(outflow.side), "a side named once"));
            }
            if self.inflow.iter().any(|f| f.side == outflow.side) {
                return Err(c.invalid(
                    key,
                    name(outflow.side),
                    "a side without an inflow (fluid cannot enter and leave by one side)",
                ));
            }
        }
        if !self.inflow.is_empty() && self.outflow.is_empty() {
            return Err(c.invalid(
                "fluid.outflow",
                "nothing",
                "an outflow side (`[[fluid.outflow]] side = \"x_max\"`): with an inflow and no \
                 outflow the fluid piles up until it leaves the domain",
            ));
        }
        Ok(())
    }
}
