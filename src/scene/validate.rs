//! Range and consistency checks of a deserialized scene. The schema only knows types; these rules
//! catch the values that would make a run blow up or silently mean nothing, before it starts.

use std::collections::HashSet;
use std::fmt;
use std::path::Path;

use super::load::base_dir;
pub(super) use super::ranges::Interval;
use super::ranges::{entry, pattern, KeyRange};
use super::{Body, Domain, Metric, Motion, Number, Probe, Scene, SceneError, Shape};
use crate::Real;

impl Scene {
    /// Checks every value against its allowed range; `file` is named in the error. The first
    /// problem found is returned.
    pub fn validate(&self, file: &Path) -> Result<(), SceneError> {
        let c = Checker { file };
        c.vec3("gravity", self.gravity)?;
        c.domain(&self.domain)?;
        self.validate_time(&c)?;
        if let Some(fluid) = &self.fluid {
            let extent = (0..3)
                .map(|i| self.domain.max[i] - self.domain.min[i])
                .fold(Real::INFINITY, Real::min);
            c.ranged("fluid.spacing", fluid.spacing)?;
            c.num(
                "fluid.spacing",
                fluid.spacing,
                Interval::le(extent / 4.0).noted("a quarter of the smallest domain extent"),
            )?;
            c.ranged("fluid.density", fluid.density)?;
            if fluid.blocks.is_empty() && fluid.inflow.is_empty() {
                return Err(c.invalid(
                    "fluid.blocks",
                    "[]",
                    "at least one block, or an inflow to fill the domain",
                ));
            }
            for (i, block) in fluid.blocks.iter().enumerate() {
                let key = format!("fluid.blocks[{i}]");
                c.inside_box(&key, block.min, block.max, &self.domain)?;
                if let Some(axis) = (0..3).find(|&a| block.max[a] - block.min[a] < fluid.spacing) {
                    return Err(c.invalid(
                        format!("{key}.max[{axis}]"),
                        Number(block.max[axis]),
                        format!(
                            "at least {} (min + fluid.spacing): a thinner block holds no particle",
                            Number(block.min[axis] + fluid.spacing)
                        ),
                    ));
                }
                c.vec3(&format!("{key}.velocity"), block.velocity)?;
            }
            c.ranged("fluid.ramp", fluid.ramp)?;
            c.ranged("fluid.lost_fraction", fluid.lost_fraction)?;
            let blocks = &fluid.blocks;
            let differs = blocks.iter().position(|b| b.velocity != blocks[0].velocity);
            if let Some(i) = differs.filter(|_| fluid.ramp > 0.0) {
                return Err(c.invalid(
                    "fluid.ramp",
                    Number(fluid.ramp),
                    format!(
                        "0 while the blocks' velocities differ (fluid.blocks[0] and \
                         fluid.blocks[{i}]): the ramp accelerates the whole fluid by one body \
                         acceleration"
                    ),
                ));
            }
            fluid.validate_open(&c, &self.domain)?;
        }
        let bodies = self
            .container
            .iter()
            .map(|b| ("container".to_owned(), b))
            .chain(
                self.obstacles
                    .iter()
                    .enumerate()
                    .map(|(i, b)| (format!("obstacles[{i}]"), b)),
            );
        let mut body_names: Vec<(&str, String)> = Vec::new();
        for (key, body) in bodies {
            c.body(&key, body)?;
            if let Some(fluid) = &self.fluid {
                c.thick_enough(&format!("{key}.shape"), &body.shape, fluid.spacing)?;
            }
            if let Some(nu) = body.wall_viscosity {
                c.ranged(&format!("{key}.wall_viscosity"), nu)?;
                if self.fluid.is_none() {
                    return Err(c.invalid(
                        format!("{key}.wall_viscosity"),
                        Number(nu),
                        "no value in a scene without `[fluid]`: it sets the SPH walls' no-slip \
                         strength (a grid's walls are set by `grid.boundary`)",
                    ));
                }
            }
            // A body placed outside the domain is a typo (a lost minus sign, the wrong unit).
            if body.motion.keyframes.is_empty() {
                self.point_inside(&c, &format!("{key}.position"), &body.position)?;
            }
            for (i, frame) in body.motion.keyframes.iter().enumerate() {
                let k = format!("{key}.motion.keyframes[{i}].position");
                self.point_inside(&c, &k, &frame.position)?;
            }
            if let Some(name) = &body.name {
                if let Some((_, first)) = body_names.iter().find(|(n, _)| *n == name.as_str()) {
                    return Err(c.invalid(
                        format!("{key}.name"),
                        format!("{name:?}"),
                        format!("a name no other body has (`{first}.name` has it)"),
                    ));
                }
                body_names.push((name, key));
            }
        }
        self.validate_solvers(&c)?;
        self.validate_grid(&c)?;
        self.validate_turbulence(&c)?;
        self.validate_coupling(&c)?;
        self.refinement
            .validate()
            .map_err(|e| c.invalid(e.key, Number(e.value), e.allowed))?;
        self.validate_probes(&c)?;
        self.validate_statistics(&c)?;
        c.ranged("output.interval", self.output.interval)?;
        c.ranged("output.compression", Real::from(self.output.compression))?;
        if let Some(t) = self.output.checkpoint_interval {
            c.ranged("output.checkpoint_interval", t)?;
        }
        if let Some(m) = self.output.checkpoint_every {
            c.ranged("output.checkpoint_every", m)?;
        }
        self.validate_metrics(&c)
    }

    /// `output.metrics`: each name at most once, and offered by a solver of the scene.
    fn validate_metrics(&self, c: &Checker) -> Result<(), SceneError> {
        let offered: Vec<(&str, &[Metric])> = [
            (self.fluid.is_some(), "an SPH fluid", &Metric::SPH[..]),
            (self.grid.is_some(), "a grid", &Metric::GRID[..]),
        ]
        .into_iter()
        .filter(|o| o.0)
        .map(|o| (o.1, o.2))
        .collect();
        let mut metrics = HashSet::new();
        for (i, metric) in self.output.metrics.iter().flatten().enumerate() {
            let key = format!("output.metrics[{i}]");
            let value = format!("{:?}", metric.column());
            if !metrics.insert(metric) {
                return Err(c.invalid(key, value, "each metric at most once"));
            }
            if !offered.is_empty() && !offered.iter().any(|(_, o)| o.contains(metric)) {
                let lists: Vec<String> = offered
                    .iter()
                    .map(|(who, o)| {
                        let names: Vec<_> = o.iter().map(|m| m.column()).collect();
                        format!("{who} offers {}", names.join(", "))
                    })
                    .collect();
                return Err(c.invalid(key, value, lists.join("; ")));
            }
        }
        Ok(())
    }

    /// `[statistics]`: its numbers in range, and a particle lattice of at most 10^8 bins.
    fn validate_statistics(&self, c: &Checker) -> Result<(), SceneError> {
        let Some(stats) = &self.statistics else {
            return Ok(());
        };
        c.ranged("statistics.from", stats.from)?;
        c.ranged("statistics.every", stats.every as Real)?;
        c.ranged("statistics.batches", stats.batches as Real)?;
        let mut names: Vec<&str> = Vec::new();
        for (i, station) in stats.stations.iter().enumerate() {
            let key = format!("statistics.stations[{i}]");
            unique_name(c, &key, &station.name, &mut names, "a file", |first| {
                format!("a name no other station has (`statistics.stations[{first}]` has it)")
            })?;
            self.point_inside(c, &format!("{key}.min"), &station.min)?;
            self.point_inside(c, &format!("{key}.max"), &station.max)?;
            for a in 0..3 {
                c.num(
                    &format!("{key}.max[{a}]"),
                    station.max[a],
                    Interval::gt(station.min[a]).noted("> `min`"),
                )?;
            }
            c.ranged(&format!("{key}.bins"), station.bins as Real)?;
        }
        if let Some(bin) = stats.bin {
            c.ranged("statistics.bin", bin)?;
            let bins: Real = (0..3)
                .map(|a| {
                    ((self.domain.max[a] - self.domain.min[a]) / bin)
                        .ceil()
                        .max(1.0)
                })
                .product();
            if bins > 1e8 {
                return Err(c.invalid(
                    "statistics.bin",
                    Number(bin),
                    format!(
                        "a bin that cuts the domain into at most 10^8 bins (this one: {bins:.3e})"
                    ),
                ));
            }
        }
        Ok(())
    }

    fn validate_time(&self, c: &Checker) -> Result<(), SceneError> {
        let time = &self.time;
        // With both, the run ends at whichever comes first (a resolved scene run with
        // `--steps` records both).
        if time.end.is_none() && time.steps.is_none() {
            return Err(c.invalid(
                "time.end, time.steps",
                "neither given",
                "at least one of `time.end` (> 0, s) and `time.steps` (>= 1)",
            ));
        }
        if let Some(end) = time.end {
            c.ranged("time.end", end)?;
        }
        if let Some(steps) = time.steps {
            c.count("time.steps", steps)?;
        }
        c.ranged("time.cfl", time.cfl)?;
        c.ranged("time.dt_min", time.dt_min)?;
        c.num(
            "time.dt_max",
            time.dt_max,
            Interval::ge(time.dt_min).noted("`time.dt_min`"),
        )?;
        if let Some(dt) = time.dt {
            c.num(
                "time.dt",
                dt,
                Interval::closed(time.dt_min, time.dt_max)
                    .noted("from `time.dt_min` to `time.dt_max`"),
            )?;
        }
        Ok(())
    }

    fn validate_solvers(&self, c: &Checker) -> Result<(), SceneError> {
        let p = &self.pressure;
        c.ranged("pressure.density_tolerance", p.density_tolerance)?;
        c.ranged("pressure.divergence_tolerance", p.divergence_tolerance)?;
        c.ranged("pressure.max_iterations", Real::from(p.max_iterations))?;
        c.num(
            "pressure.min_iterations",
            Real::from(p.min_iterations),
            Interval::closed(1.0, Real::from(p.max_iterations))
                .noted("1 to `pressure.max_iterations`"),
        )?;
        if let Some(least) = p.divergence_min_iterations {
            c.num(
                "pressure.divergence_min_iterations",
                Real::from(least),
                Interval::closed(1.0, Real::from(p.max_iterations))
                    .noted("1 to `pressure.max_iterations`"),
            )?;
        }
        if p.signed && p.solver != crate::sph::PressureSolverKind::Dfsph {
            return Err(c.invalid(
                "pressure.signed",
                true,
                "false with `pressure.solver = \"iisph\"`: signed pressure is a DFSPH solve",
            ));
        }
        c.ranged("pressure.ambient", p.ambient)?;
        let v = &self.viscosity;
        c.ranged("viscosity.kinematic", v.kinematic)?;
        c.ranged("viscosity.boundary", v.boundary)?;
        c.ranged("viscosity.xsph", v.xsph)?;
        let spacing = self.fluid.as_ref().map(|f| f.spacing).filter(|s| *s > 0.0);
        let walls = super::build::wall_viscosities(self);
        let limit =
            spacing.and_then(|s| crate::sph::forces::viscous_step_limit(s, v.kinematic, &walls));
        if let Some(limit) = limit.filter(|l| *l < self.time.dt_min) {
            return Err(c.invalid(
                "viscosity.kinematic",
                v.kinematic,
                format!(
                    "a stable step of at least `time.dt_min` = {} s: explicit viscosity at \
                     fluid.spacing {} needs dt <= {} spacing^2 / (kinematic + the strongest wall's) = \
                     {limit:.3e} s",
                    self.time.dt_min,
                    spacing.unwrap_or_default(),
                    crate::sph::forces::VISCOUS_STEP
                ),
            ));
        }
        Ok(())
    }

    fn validate_probes(&self, c: &Checker) -> Result<(), SceneError> {
        let mut names: Vec<&str> = Vec::new();
        for (i, probe) in self.probes.iter().enumerate() {
            let key = format!("probes[{i}]");
            let name = probe.name();
            unique_name(c, &key, name, &mut names, "CSV columns", |first| {
                format!("a name no other probe has (`probes[{first}].name` has it)")
            })?;
            let grid_only = matches!(probe, Probe::Line { .. } | Probe::Force { .. });
            if grid_only && self.grid.is_none() {
                return Err(c.invalid(
                    format!("{key}.type"),
                    format!("{name:?}"),
                    "front or point probes in a scene without [grid]",
                ));
            }
            if matches!(probe, Probe::Front { .. }) && self.fluid.is_none() {
                return Err(c.invalid(
                    format!("{key}.type"),
                    "\"front\"",
                    "point, line or force probes in a scene without [fluid]",
                ));
            }
            match probe {
                Probe::Front { origin, .. } => {
                    c.ranged(&format!("{key}.origin"), *origin)?;
                }
                Probe::Line {
                    from, to, points, ..
                } => {
                    for (end, point) in [("from", from), ("to", to)] {
                        self.point_inside(c, &format!("{key}.{end}"), point)?;
                    }
                    c.count(&format!("{key}.points"), *points as u64)?;
                }
                Probe::Force { body, .. } => {
                    if !self
                        .obstacles
                        .iter()
                        .any(|b| b.name.as_deref() == Some(body))
                    {
                        return Err(c.invalid(
                            format!("{key}.body"),
                            format!("{body:?}"),
                            "the `name` of one of the obstacles",
                        ));
                    }
                }
                Probe::Point { position, .. } => {
                    self.point_inside(c, &format!("{key}.position"), position)?;
                }
            }
        }
        Ok(())
    }
}

impl Scene {
    /// Checks that a point lies in the domain.
    pub(super) fn point_inside(
        &self,
        c: &Checker,
        key: &str,
        p: &[Real; 3],
    ) -> Result<(), SceneError> {
        for (axis, &x) in p.iter().enumerate() {
            c.num(
                &format!("{key}[{axis}]"),
                x,
                Interval::closed(self.domain.min[axis], self.domain.max[axis])
                    .noted("inside the domain"),
            )?;
        }
        Ok(())
    }
}

/// The half sizes of an analytic shape under their keys (`half_extents[0]`, `radius`,
/// `half_height`, ...); none for a mesh.
fn half_sizes(shape: &Shape) -> Vec<(String, Real)> {
    match shape {
        Shape::Box { half_extents } => half_extents
            .iter()
            .enumerate()
            .map(|(axis, &h)| (format!("half_extents[{axis}]"), h))
            .collect(),
        Shape::Sphere { radius } => vec![("radius".into(), *radius)],
        Shape::Cylinder {
            radius,
            half_height,
        }
        | Shape::Capsule {
            radius,
            half_height,
        } => vec![
            ("radius".into(), *radius),
            ("half_height".into(), *half_height),
        ],
        Shape::Mesh { .. } => Vec::new(),
    }
}

/// Builds the errors of one file, so each rule is one line.
pub(super) struct Checker<'a> {
    pub(super) file: &'a Path,
}

impl Checker<'_> {
    pub(super) fn invalid(
        &self,
        key: impl Into<String>,
        value: impl fmt::Display,
        allowed: impl Into<String>,
    ) -> SceneError {
        SceneError::Invalid {
            file: self.file.to_owned(),
            key: key.into(),
            value: value.to_string(),
            allowed: allowed.into(),
            set_by: None,
        }
    }

    /// Checks that `value` is finite and inside `allowed`, a range computed from other values;
    /// the key's entry in `RANGES` says the rule in words.
    pub(super) fn num(&self, key: &str, value: Real, allowed: Interval) -> Result<(), SceneError> {
        self.entry(key);
        if value.is_finite() && allowed.contains(value) {
            Ok(())
        } else {
            Err(self.invalid(key, Number(value), allowed.describe(!value.is_finite())))
        }
    }

    /// Checks that `value` is finite and inside the key's range in `RANGES`.
    pub(super) fn ranged(&self, key: &str, value: Real) -> Result<(), SceneError> {
        self.num(key, value, self.range(key))
    }

    /// Checks a count against the key's range in `RANGES`; the message shows it as an integer.
    pub(super) fn count(&self, key: &str, n: u64) -> Result<(), SceneError> {
        let allowed = self.range(key);
        if allowed.contains(n as Real) {
            Ok(())
        } else {
            Err(self.invalid(key, n, allowed.describe(false)))
        }
    }

    /// Checks that each component is finite (and in the key's range).
    pub(super) fn vec3(&self, key: &str, v: [Real; 3]) -> Result<(), SceneError> {
        for (axis, &x) in v.iter().enumerate() {
            self.ranged(&format!("{key}[{axis}]"), x)?;
        }
        Ok(())
    }

    /// The key's entry; a check of a key without one is a bug the tests catch (every scene
    /// they validate would panic here).
    fn entry(&self, key: &str) -> &'static KeyRange {
        entry(&pattern(key)).unwrap_or_else(|| panic!("no RANGES entry for `{}`", pattern(key)))
    }

    fn range(&self, key: &str) -> Interval<'static> {
        self.entry(key)
            .range
            .unwrap_or_else(|| panic!("the RANGES entry of `{}` has no range", pattern(key)))
    }

    fn domain(&self, domain: &Domain) -> Result<(), SceneError> {
        self.vec3("domain.min", domain.min)?;
        self.vec3("domain.max", domain.max)?;
        for axis in 0..3 {
            self.num(
                &format!("domain.max[{axis}]"),
                domain.max[axis],
                Interval::gt(domain.min[axis]).noted(&format!("`domain.min[{axis}]`")),
            )?;
        }
        Ok(())
    }

    /// A box given by corners `min` < `max`, inside the domain.
    fn inside_box(
        &self,
        key: &str,
        min: [Real; 3],
        max: [Real; 3],
        domain: &Domain,
    ) -> Result<(), SceneError> {
        for axis in 0..3 {
            let domain_axis =
                || Interval::closed(domain.min[axis], domain.max[axis]).noted("inside the domain");
            self.num(&format!("{key}.min[{axis}]"), min[axis], domain_axis())?;
            self.num(&format!("{key}.max[{axis}]"), max[axis], domain_axis())?;
            self.num(
                &format!("{key}.max[{axis}]"),
                max[axis],
                Interval::gt(min[axis]).noted(&format!("`{key}.min[{axis}]`")),
            )?;
        }
        Ok(())
    }

    fn body(&self, key: &str, body: &Body) -> Result<(), SceneError> {
        if body.name.as_deref() == Some("") {
            return Err(self.invalid(format!("{key}.name"), "\"\"", "a non-empty name"));
        }
        self.shape(&format!("{key}.shape"), &body.shape)?;
        self.vec3(&format!("{key}.position"), body.position)?;
        self.vec3(&format!("{key}.rotation"), body.rotation)?;
        self.motion(&format!("{key}.motion"), &body.motion)
    }

    pub(super) fn shape(&self, key: &str, shape: &Shape) -> Result<(), SceneError> {
        for (name, v) in half_sizes(shape) {
            self.ranged(&format!("{key}.{name}"), v)?;
        }
        if let Shape::Mesh { path, scale } = shape {
            self.ranged(&format!("{key}.scale"), *scale)?;
            // `load` made the path absolute; resolve again for scenes built in code.
            let resolved = base_dir(self.file).join(path);
            if resolved.is_dir() {
                return Err(self.invalid(
                    format!("{key}.path"),
                    resolved.display(),
                    "an OBJ or STL file (this is a folder)",
                ));
            }
            if !resolved.is_file() {
                return Err(SceneError::MissingMesh {
                    file: self.file.to_owned(),
                    key: format!("{key}.path"),
                    path: resolved,
                    set_by: None,
                });
            }
        }
        Ok(())
    }

    /// A body of an SPH scene must be at least one particle `spacing` thick along every axis:
    /// the walls sample its surface at the spacing, so a thinner one has no inside, lets the
    /// fluid through, and a box a few nanometres thick grows a boundary shell of one column per
    /// few nanometres of its offset (minutes and gigabytes in the neighbour search). A capsule's caps make it a diameter long
    /// whatever its half height. Meshes are not held to it: their samples follow their area.
    pub(super) fn thick_enough(
        &self,
        key: &str,
        shape: &Shape,
        spacing: Real,
    ) -> Result<(), SceneError> {
        let capsule = matches!(shape, Shape::Capsule { .. });
        for (name, v) in half_sizes(shape) {
            if capsule && name == "half_height" {
                continue;
            }
            self.num(
                &format!("{key}.{name}"),
                v,
                Interval::ge(0.5 * spacing)
                    .noted("half the fluid spacing: a body thinner than a spacing has no inside"),
            )?;
        }
        Ok(())
    }

    pub(super) fn motion(&self, key: &str, motion: &Motion) -> Result<(), SceneError> {
        self.vec3(&format!("{key}.linear"), motion.linear)?;
        self.vec3(&format!("{key}.angular"), motion.angular)?;
        if motion.keyframes.len() == 1 {
            return Err(self.invalid(
                format!("{key}.keyframes"),
                "1 keyframe",
                "none, or at least 2",
            ));
        }
        let mut previous: Option<Real> = None;
        for (i, frame) in motion.keyframes.iter().enumerate() {
            let k = format!("{key}.keyframes[{i}]");
            let note;
            let allowed = match previous {
                Some(t) => {
                    note = format!("`{key}.keyframes[{}].t` (times strictly increasing)", i - 1);
                    Interval::gt(t).noted(&note)
                }
                None => Interval::any(),
            };
            self.num(&format!("{k}.t"), frame.t, allowed)?;
            self.vec3(&format!("{k}.position"), frame.position)?;
            self.vec3(&format!("{k}.rotation"), frame.rotation)?;
            previous = Some(frame.t);
        }
        Ok(())
    }
}

/// `KEY.name` is a non-empty name of A-Z, a-z, 0-9 and _ (it names `names_what`), and no earlier
/// entry of `names` has it (`taken` words the refusal from the first that does); it is added.
fn unique_name<'a>(
    c: &Checker,
    key: &str,
    name: &'a str,
    names: &mut Vec<&'a str>,
    names_what: &str,
    taken: impl Fn(usize) -> String,
) -> Result<(), SceneError> {
    let well_formed = !name.is_empty()
        && name
            .chars()
            .all(|ch| ch.is_ascii_alphanumeric() || ch == '_');
    if !well_formed {
        return Err(c.invalid(
            format!("{key}.name"),
            format!("{name:?}"),
            format!("a non-empty name of A-Z, a-z, 0-9 and _ (it names {names_what})"),
        ));
    }
    if let Some(first) = names.iter().position(|n| *n == name) {
        return Err(c.invalid(format!("{key}.name"), format!("{name:?}"), taken(first)));
    }
    names.push(name);
    Ok(())
}
