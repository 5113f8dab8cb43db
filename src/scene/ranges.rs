//! What the validation allows for each scene key, declared once: the checks read a key's range
//! from [`RANGES`], and `eddy scene-keys` prints the same entries (`super::reference`), so the
//! reference cannot drift from what a run accepts.
//!
//! A key is written as a pattern: indices as `[]` (`fluid.blocks[].min`; an element of a list
//! of numbers is the list's key), and a leading `*.` for keys that several tables share
//! (`*.shape.radius` is the radius of the container's, every obstacle's and every smoke
//! source's shape).

use crate::Real;

pub use crate::interval::Interval;

/// Largest `pressure.max_iterations`: beyond it a solve that does not converge never ends in
/// practice.
const MAX_ITERATIONS: Real = 100_000.0;

/// Largest |buoyancy| of the smoke, m/s^2 per unit of smoke (a hundred g).
const MAX_BUOYANCY: Real = 981.0;

/// Largest density a smoke source sets, units of smoke (the shipped scenes use 1).
const MAX_SOURCE_DENSITY: Real = 1e3;

/// Most children per split: beyond it a cascade step makes particles faster than any scene
/// can use.
const MAX_CHILDREN: Real = 8.0;

/// What one key allows.
pub struct KeyRange {
    /// The key's pattern (see the module's doc).
    pub key: &'static str,
    /// A range fixed in advance, which `Checker::ranged` checks; `None` when only `rule` holds.
    pub range: Option<Interval<'static>>,
    /// A rule that depends on other values, checked in code, in words for the reference.
    pub rule: Option<&'static str>,
}

const fn range(key: &'static str, range: Interval<'static>) -> KeyRange {
    KeyRange {
        key,
        range: Some(range),
        rule: None,
    }
}

const fn rule(key: &'static str, rule: &'static str) -> KeyRange {
    KeyRange {
        key,
        range: None,
        rule: Some(rule),
    }
}

const fn both(key: &'static str, range: Interval<'static>, rule: &'static str) -> KeyRange {
    KeyRange {
        key,
        range: Some(range),
        rule: Some(rule),
    }
}

const ANY: Interval<'static> = Interval::any();
const POSITIVE: Interval<'static> = Interval::gt(0.0);
const NON_NEGATIVE: Interval<'static> = Interval::ge(0.0);
const INSIDE: &str = "inside the domain";
const BUOYANCY: Interval<'static> =
    Interval::closed(-MAX_BUOYANCY, MAX_BUOYANCY).noted("m/s^2 per unit");
const THICK: &str = "at least half of `fluid.spacing` on the container and obstacles of a scene \
                     with `[fluid]`";

/// Every key the validation checks: the numbers through `Checker` (a check of a number without
/// an entry panics), other keys' rules in words for the reference.
pub static RANGES: &[KeyRange] = &[
    range("gravity", ANY),
    range("domain.min", ANY),
    both("domain.max", ANY, "> `domain.min` along each axis"),
    both(
        "time.end",
        POSITIVE,
        "at least one of `time.end` and `time.steps`",
    ),
    range("time.steps", Interval::ge(1.0).whole()),
    range("time.cfl", Interval::open_closed(0.0, 1.0)),
    range("time.dt_min", POSITIVE),
    rule("time.dt_max", ">= `time.dt_min`"),
    rule("time.dt", "from `time.dt_min` to `time.dt_max`"),
    both(
        "fluid.spacing",
        POSITIVE,
        "<= a quarter of the smallest domain extent",
    ),
    range("fluid.density", POSITIVE),
    rule("fluid.blocks", "at least one block, or an inflow to fill the domain"),
    rule("fluid.blocks[].min", INSIDE),
    rule(
        "fluid.blocks[].max",
        "inside the domain, at least `min` + `fluid.spacing` along each axis",
    ),
    range("fluid.blocks[].velocity", ANY),
    rule(
        "fluid.inflow[].min",
        "inside the domain's extent along the side",
    ),
    rule(
        "fluid.inflow[].max",
        "inside the domain's extent along the side, at least `min` + `fluid.spacing`",
    ),
    rule("fluid.outflow", "at least one in a scene with an inflow"),
    both(
        "fluid.ramp",
        NON_NEGATIVE.noted("s"),
        "0 unless every block has the same velocity",
    ),
    range("fluid.lost_fraction", Interval::closed(0.0, 1.0)),
    rule("fluid.outflow[].side", "each side once, and not an inflow's"),
    both(
        "fluid.inflow[].velocity",
        ANY,
        "its component into the domain > 0",
    ),
    rule(
        "fluid.inflow[].across",
        "an axis along the side (0, 1 or 2 for x, y, z) with `shape = \"plane\"`, none otherwise",
    ),
    both("*.shape.half_extents", POSITIVE, THICK),
    both("*.shape.radius", POSITIVE, THICK),
    both("*.shape.half_height", POSITIVE, THICK),
    range("*.shape.scale", POSITIVE),
    rule("*.shape.type", "not \"mesh\" for a smoke source"),
    rule("obstacles[].name", "non-empty, and no other body's"),
    rule("container.abl", "none: boundary layers belong to obstacles"),
    both("*.position", ANY, INSIDE),
    range("*.rotation", ANY),
    range("*.motion.linear", ANY),
    range("*.motion.angular", ANY),
    both(
        "*.motion.keyframes[].t",
        ANY,
        "strictly increasing; none or at least 2 keyframes",
    ),
    both(
        "*.wall_viscosity",
        NON_NEGATIVE,
        "only in a scene with `[fluid]`",
    ),
    range(
        "pressure.density_tolerance",
        Interval::open_closed(0.0, 0.1),
    ),
    range(
        "pressure.divergence_tolerance",
        Interval::open_closed(0.0, 1.0),
    ),
    range(
        "pressure.max_iterations",
        Interval::closed(1.0, MAX_ITERATIONS),
    ),
    rule("pressure.min_iterations", "1 to `pressure.max_iterations`"),
    rule(
        "pressure.divergence_min_iterations",
        "1 to `pressure.max_iterations`",
    ),
    range("pressure.ambient", NON_NEGATIVE),
    rule("pressure.signed", "false with `pressure.solver = \"iisph\"`"),
    both(
        "viscosity.kinematic",
        NON_NEGATIVE,
        "a stable explicit step at `fluid.spacing` of at least `time.dt_min`",
    ),
    range("viscosity.boundary", NON_NEGATIVE),
    range("viscosity.xsph", Interval::closed(0.0, 1.0)),
    rule(
        "grid.resolution",
        "at least 1 cell per axis, at most 512^3 in all, cubic cells over the domain",
    ),
    rule(
        "grid.boundary",
        "inflows that balance, or an \"open\" side for the flow to leave by",
    ),
    both(
        "grid.boundary.x_min",
        ANY,
        "moving walls in their own plane",
    ),
    both(
        "grid.boundary.x_max",
        ANY,
        "moving walls in their own plane",
    ),
    both(
        "grid.boundary.y_min",
        ANY,
        "moving walls in their own plane",
    ),
    both(
        "grid.boundary.y_max",
        ANY,
        "moving walls in their own plane",
    ),
    both(
        "grid.boundary.z_min",
        ANY,
        "moving walls in their own plane",
    ),
    both(
        "grid.boundary.z_max",
        ANY,
        "moving walls in their own plane",
    ),
    both("*.profiled_inflow.velocity", ANY, "normal to its side"),
    both("*.profiled_inflow.table", ANY, "coordinates increasing"),
    rule(
        "*.profiled_inflow.across",
        "an axis along the side (0, 1 or 2 for x, y, z), not its normal; needed by `plane` and \
         `table`",
    ),
    rule(
        "grid.inflow_turbulence",
        "an inflow side, an \"open\" side, and no `grid.static_flow`",
    ),
    range(
        "grid.inflow_turbulence.intensity",
        Interval::open_closed(0.0, 0.5),
    ),
    range("grid.inflow_turbulence.length", POSITIVE),
    range(
        "grid.inflow_turbulence.modes",
        Interval::closed(1.0, 4096.0),
    ),
    both(
        "grid.density",
        POSITIVE,
        "left out or `coupling.air_density` in a coupled scene",
    ),
    range("grid.initial_velocity", ANY),
    range("grid.pressure_tolerance", Interval::open_closed(0.0, 0.1)),
    range(
        "grid.pressure_max_iterations",
        Interval::closed(1.0, MAX_ITERATIONS),
    ),
    range("grid.vorticity_confinement", NON_NEGATIVE),
    range("grid.average_from", NON_NEGATIVE),
    range("grid.steady_tolerance", POSITIVE),
    range("grid.smoke.buoyancy", BUOYANCY),
    range("grid.smoke.heat_buoyancy", BUOYANCY),
    range(
        "grid.smoke.sources[].density",
        Interval::closed(0.0, MAX_SOURCE_DENSITY).noted("units of smoke"),
    ),
    range("grid.smoke.sources[].temperature", ANY),
    range("grid.smoke.sources[].velocity", ANY),
    rule("turbulence", "an obstacle with `abl` for it to act on"),
    range("turbulence.c_p", NON_NEGATIVE.noted("1/s")),
    range("turbulence.u0", POSITIVE.noted("m/s")),
    range("turbulence.gain", NON_NEGATIVE),
    range("turbulence.dissipation_radius", NON_NEGATIVE.noted("cells")),
    rule(
        "turbulence.r_max",
        ">= the dissipation radius and 0.5 cells (smaller particles would vanish)",
    ),
    range("turbulence.split_radius", NON_NEGATIVE.noted("cells")),
    range("turbulence.cascade_time", NON_NEGATIVE.noted("s/m^(2/3)")),
    both(
        "turbulence.upsample",
        Interval::closed(1.0, 2.0)
            .whole()
            .noted("Pfaff et al. 2009, Table 1"),
        "1 in a scene without `[grid]`",
    ),
    range(
        "turbulence.children",
        Interval::closed(2.0, MAX_CHILDREN).whole(),
    ),
    range("coupling.drag_coefficient", Interval::closed(0.0, 0.1)),
    rule(
        "coupling",
        "a scene with both `[grid]` and `[fluid]`; not with `grid.reflection` or `grid.static_flow`",
    ),
    range("coupling.air_density", Interval::open_closed(0.0, 100.0)),
    range("coupling.occupancy_threshold", Interval::open(0.0, 1.0)),
    rule(
        "probes[].type",
        "\"front\" needs `[fluid]`, \"line\" and \"force\" `[grid]`; none with both",
    ),
    rule("probes[].name", "A-Z, a-z, 0-9 and _, and no other probe's"),
    rule("probes[].body", "the `name` of an obstacle"),
    range("probes[].origin", ANY),
    rule("probes[].from", INSIDE),
    rule("probes[].to", INSIDE),
    range("probes[].points", Interval::closed(2.0, 100_000.0).whole()),
    range("statistics.from", NON_NEGATIVE),
    range(
        "statistics.every",
        Interval::closed(1.0, 1_000_000.0).whole(),
    ),
    both(
        "statistics.bin",
        POSITIVE,
        "cuts the domain into at most 10^8 bins",
    ),
    range("statistics.batches", Interval::closed(2.0, 1000.0).whole()),
    rule("statistics.stations[].name", "A-Z, a-z, 0-9 and _, and no other station's"),
    rule("statistics.stations[].min", INSIDE),
    rule("statistics.stations[].max", "inside the domain, > `min` along each axis"),
    range("statistics.stations[].bins", Interval::closed(1.0, 100_000.0).whole()),
    range("output.interval", POSITIVE),
    range("output.checkpoint_interval", POSITIVE),
    range(
        "output.checkpoint_every",
        Interval::gt(0.0).noted("minutes of wall-clock time"),
    ),
    rule(
        "output.metrics",
        "each at most once, and offered by a solver of the scene",
    ),
    range(
        "output.compression",
        Interval::closed(0.0, 9.0).noted("a deflate level, 0 for none"),
    ),
];

/// The pattern of a concrete key: `obstacles[2].shape.half_extents[1]` is
/// `obstacles[].shape.half_extents`.
pub fn pattern(key: &str) -> String {
    let mut out = String::with_capacity(key.len());
    let mut chars = key.chars();
    while let Some(ch) = chars.next() {
        out.push(ch);
        if ch == '[' {
            chars.by_ref().take_while(|c| *c != ']').for_each(drop);
            out.push(']');
        }
    }
    while let Some(list) = out.strip_suffix("[]") {
        out.truncate(list.len());
    }
    out
}

/// The entry of a key pattern: its own, else the longest `*.` entry it ends with.
pub fn entry(pattern: &str) -> Option<&'static KeyRange> {
    RANGES.iter().find(|r| r.key == pattern).or_else(|| {
        RANGES
            .iter()
            .filter(|r| {
                r.key
                    .strip_prefix('*')
                    .is_some_and(|tail| pattern.ends_with(tail))
            })
            .max_by_key(|r| r.key.len())
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_pattern_writes_indices_as_brackets_and_drops_a_lists_own() {
        assert_eq!(
            pattern("obstacles[2].shape.half_extents[1]"),
            "obstacles[].shape.half_extents"
        );
        assert_eq!(
            pattern("grid.boundary.x_min.profiled_inflow.table[3][0]"),
            "grid.boundary.x_min.profiled_inflow.table"
        );
        assert_eq!(pattern("time.cfl"), "time.cfl");
    }

    #[test]
    fn a_shared_entry_matches_every_table_that_holds_the_key() {
        let key = |k: &str| entry(k).map(|r| r.key);
        assert_eq!(
            key("grid.smoke.sources[].shape.radius"),
            Some("*.shape.radius")
        );
        assert_eq!(
            key("container.motion.keyframes[].position"),
            Some("*.position")
        );
        assert_eq!(key("time.cfl"), Some("time.cfl"));
        assert_eq!(key("time.nothing"), None);
    }
}
