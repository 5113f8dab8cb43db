//! The DFG benchmark "laminar flow around a cylinder" (Schäfer & Turek 1996, cases 2D-1 and
//! 2D-2): what a run of `scenes/dfg_2d1.toml` or `scenes/dfg_2d2.toml` gives, against the
//! bands of the benchmark's reference results (their Table 4 for 2D-1 and Table 5 for 2D-2; the
//! same bands the benchmark's site and the codes validated against it quote).
//!
//! Read from the run's folder: `scene.toml` (the inflow, the cylinder, the depth), `probes.csv`
//! (the force probe `cylinder`, the point probes `front` at (0.15, 0.2) and `back` at
//! (0.25, 0.2)) and, for 2D-1, `profile_centreline.csv` (u along y = 0.2 behind the cylinder).
//! Coefficients use the mean inflow speed U = 2/3 U_max, the diameter D and the force per unit
//! depth: c_D = 2 F_x / (rho U^2 D), c_L = 2 F_y / (rho U^2 D). Pressures are the grid's
//! (rho = 1 in the benchmark).

use std::path::Path;

use crate::grid::params::GridSide;
use crate::io::plot::RunSeries;
use crate::scene::{self, Scene, Shape};
use crate::Real;

/// One benchmark quantity: the published band and the run's value.
#[derive(Debug, Clone, PartialEq)]
pub struct Row {
    pub name: &'static str,
    pub band: [Real; 2],
    pub value: Real,
}

impl Row {
    /// The value's distance from the band relative to the band's middle; 0 inside it.
    pub fn off_by(&self) -> Real {
        let [lo, hi] = self.band;
        let mid = 0.5 * (lo + hi);
        if self.value < lo {
            (self.value - lo) / mid
        } else if self.value > hi {
            (self.value - hi) / mid
        } else {
            0.0
        }
    }
}

/// The published bands: (name, lower, upper).
const STEADY: [(&str, Real, Real); 4] = [
    ("c_D", 5.57, 5.59),
    ("c_L", 0.0104, 0.0110),
    ("L_a", 0.0842, 0.0852),
    ("dp", 0.1172, 0.1176),
];
const PERIODIC: [(&str, Real, Real); 4] = [
    ("c_D max", 3.22, 3.24),
    ("c_L max", 0.99, 1.01),
    ("St", 0.295, 0.305),
    ("dp", 2.46, 2.50),
];

/// What the benchmark's set-up fixes, read from a run's resolved scene.
struct SetUp {
    /// Mean inflow speed, m/s (2/3 of the parabola's peak).
    mean: Real,
    diameter: Real,
    depth: Real,
    density: Real,
    /// The rear of the cylinder, where the recirculation starts, m.
    rear: Real,
}

fn set_up(scene: &Scene) -> Result<SetUp, String> {
    let grid = scene.grid.as_ref().ok_or("the scene has no [grid]")?;
    let GridSide::ProfiledInflow(inflow) = &grid.boundary.x_min else {
        return Err("grid.boundary.x_min is not a profiled inflow".into());
    };
    let cylinder = scene
        .obstacles
        .iter()
        .find(|o| o.name.as_deref() == Some("cylinder"))
        .ok_or("no obstacle named \"cylinder\"")?;
    let Shape::Cylinder { radius, .. } = cylinder.shape else {
        return Err("the obstacle \"cylinder\" is not a cylinder".into());
    };
    Ok(SetUp {
        mean: 2.0 / 3.0 * inflow.velocity[0],
        diameter: 2.0 * radius,
        depth: scene.domain.max[2] - scene.domain.min[2],
        density: grid.density,
        rear: cylinder.position[0] + radius,
    })
}

/// A column of `probes.csv`, or an error naming it.
fn column(series: &RunSeries, name: &str) -> Result<Vec<Real>, String> {
    series
        .column(name)
        .ok_or_else(|| format!("probes.csv has no column `{name}` (the scene's probes?)"))
}

/// The benchmark's quantities for the run in `run`: 2D-1's for a steady inflow (peak below
/// 1 m/s), 2D-2's otherwise.
pub fn evaluate(run: &Path) -> Result<Vec<Row>, String> {
    let scene = scene::load(&run.join("scene.toml"), &[]).map_err(|e| e.to_string())?;
    let s = set_up(&scene)?;
    let probes = RunSeries::read_file(run, "probes.csv").map_err(|e| e.to_string())?;
    let time = column(&probes, "time")?;
    let force = |axis: &str| -> Result<Vec<Real>, String> {
        let p = column(&probes, &format!("cylinder_f{axis}_pressure"))?;
        let v = column(&probes, &format!("cylinder_f{axis}_viscous"))?;
        let scale = 2.0 / (s.density * s.mean * s.mean * s.diameter * s.depth);
        Ok(p.iter().zip(&v).map(|(p, v)| (p + v) * scale).collect())
    };
    let (drag, lift) = (force("x")?, force("y")?);
    let front = column(&probes, "front_p")?;
    let back = column(&probes, "back_p")?;
    let dp: Vec<Real> = front.iter().zip(&back).map(|(f, b)| f - b).collect();
    let last = time.len().checked_sub(1).ok_or("probes.csv has no rows")?;
    let rows = if s.mean < 0.5 {
        let profile =
            RunSeries::read_file(run, "profile_centreline.csv").map_err(|e| e.to_string())?;
        let x = profile
            .column("x")
            .ok_or("profile_centreline.csv has no x")?;
        let u = profile
            .column("u")
            .ok_or("profile_centreline.csv has no u")?;
        // The last step is shortened to land on the end time, and a projection's pressure
        // depends on its step (docs/src/mac-grid.md): the state is read at the step
        // before, a whole CFL step like the run's others.
        let at = last.saturating_sub(1);
        let values = [
            drag[at],
            lift[at],
            recirculation_end(&x, &u) - s.rear,
            dp[at],
        ];
        rows(&STEADY, values)
    } else {
        // The shedding once established: the second half of the run.
        let from = time.partition_point(|&t| t < 0.5 * time[last]);
        let (t, l, d) = (&time[from..], &lift[from..], &drag[from..]);
        let period = period(t, l).ok_or("the lift does not oscillate: no shedding to measure")?;
        let max = |v: &[Real]| v.iter().copied().fold(Real::NEG_INFINITY, Real::max);
        // dp half a period after the last lift maximum that has one after it (the
        // benchmark's t0 + 1 / (2 f)); a maximum is a crest of the oscillation, above half
        // its height, not a wiggle.
        let crest = 0.5 * max(l);
        let at = l
            .iter()
            .enumerate()
            .rev()
            .skip(1)
            .filter(|&(i, v)| i > 0 && *v > crest && *v >= l[i - 1] && *v >= l[i + 1])
            .map(|(i, _)| t[i] + 0.5 * period)
            .find(|&at| at <= time[last])
            .ok_or("no lift maximum half a period before the run's end")?;
        let dp_at = interpolate(&time, &dp, at).ok_or("the run ends before t0 + T/2")?;
        let values = [max(d), max(l), s.diameter / (period * s.mean), dp_at];
        rows(&PERIODIC, values)
    };
    Ok(rows)
}

fn rows(bands: &[(&'static str, Real, Real); 4], values: [Real; 4]) -> Vec<Row> {
    bands
        .iter()
        .zip(values)
        .map(|(&(name, lo, hi), value)| Row {
            name,
            band: [lo, hi],
            value,
        })
        .collect()
}

/// Where u along the centreline first turns from backward to forward (linear between
/// samples), m; the first sample's x when it never flows backward (no recirculation).
pub fn recirculation_end(x: &[Real], u: &[Real]) -> Real {
    let backward = u.iter().position(|&v| v < 0.0);
    let Some(start) = backward else {
        return x.first().copied().unwrap_or(0.0);
    };
    for i in start..u.len().saturating_sub(1) {
        if u[i] < 0.0 && u[i + 1] >= 0.0 {
            return x[i] + (x[i + 1] - x[i]) * (-u[i]) / (u[i + 1] - u[i]);
        }
    }
    x.last().copied().unwrap_or(0.0)
}

/// The mean time between upward crossings of a signal's mean, over whole periods; None with
/// fewer than two crossings.
pub fn period(t: &[Real], v: &[Real]) -> Option<Real> {
    let mean = v.iter().sum::<Real>() / v.len() as Real;
    let crossings: Vec<Real> = (1..v.len())
        .filter(|&i| v[i - 1] < mean && v[i] >= mean)
        .map(|i| t[i - 1] + (t[i] - t[i - 1]) * (mean - v[i - 1]) / (v[i] - v[i - 1]))
        .collect();
    let n = crossings.len();
    (n >= 2).then(|| (crossings[n - 1] - crossings[0]) / (n - 1) as Real)
}

/// `v` at time `at`, linear between samples; None outside `t`.
fn interpolate(t: &[Real], v: &[Real], at: Real) -> Option<Real> {
    let i = t.partition_point(|&s| s <= at);
    if i == 0 || i >= t.len() {
        return None;
    }
    let f = (at - t[i - 1]) / (t[i] - t[i - 1]);
    Some(v[i - 1] + f * (v[i] - v[i - 1]))
}

/// The rows as a table: quantity, band, value, distance from the band.
pub fn table(rows: &[Row]) -> String {
    let mut s = String::from("quantity   band                 eddy        off by\n");
    for r in rows {
        s += &format!(
            "{:<10} {:>8.4} – {:<8.4}   {:<10.5}  {:+.1} %\n",
            r.name,
            r.band[0],
            r.band[1],
            r.value,
            100.0 * r.off_by()
        );
    }
    s
}
