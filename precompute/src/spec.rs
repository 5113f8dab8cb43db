//! The obstacle file: the shape, the precomputation grid, the layer and the direction sampling,
//! read with `--set dotted.key=value` overrides and checked with errors that name the key.

use std::path::{Path, PathBuf};

use anyhow::{bail, Context};
use eddy::abl::{geometry_fingerprint, hash_hex, Sampling};
use eddy::geometry::RigidBody;
use eddy::scene::{Advection, Body, ObstacleSurface, Shape};
use eddy::Real;
use serde::{Deserialize, Serialize};

/// How the precomputation runs, beyond the settings: part of the fingerprint, so that shards and
/// parts computed by a different scheme are never merged or resumed into one database.
const SCHEME: &[u8] = b"free stream prescribed on every side";

/// One obstacle and how to precompute its artificial boundary layer.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ObstacleSpec {
    /// Name stored in the database.
    pub name: String,
    /// The shape in the object's frame (meshes relative to the obstacle file).
    pub shape: Shape,
    #[serde(default)]
    pub grid: GridSettings,
    #[serde(default)]
    pub layer: LayerSettings,
    #[serde(default)]
    pub sampling: SamplingSettings,
}

/// One value for every axis, or one per axis (`[x, y, z]`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(untagged)]
pub enum PerAxis<T> {
    Same(T),
    Each([T; 3]),
}

impl<'de, T: Deserialize<'de>> Deserialize<'de> for PerAxis<T> {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        #[derive(Deserialize)]
        #[serde(untagged)]
        enum Raw<T> {
            Same(T),
            Each([T; 3]),
        }
        match Raw::deserialize(d) {
            Ok(Raw::Same(v)) => Ok(PerAxis::Same(v)),
            Ok(Raw::Each(v)) => Ok(PerAxis::Each(v)),
            Err(_) => Err(serde::de::Error::custom(
                "expected one number for every axis or three, [x, y, z]",
            )),
        }
    }
}

impl<T: Copy> PerAxis<T> {
    /// The value of each axis.
    pub fn each(&self) -> [T; 3] {
        match *self {
            PerAxis::Same(v) => [v; 3],
            PerAxis::Each(v) => v,
        }
    }
}

/// The precomputation grid: a box of cubic cells centred on the object's origin.
///
/// A single `domain` makes a cube whose side is that multiple of the object's largest extent
/// (the default). `domain = [dx, dy, dz]` makes a box whose side along each axis is that
/// multiple of the object's extent along the axis (twice its largest local coordinate there),
/// so a long thin object is not computed in a cube. A single `resolution` is the cell count
/// along the box's longest side; `[nx, ny, nz]` gives each axis its count, and the cell size is
/// then the largest side over its count, so each side covers at least its multiple.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GridSettings {
    /// Cells along the longest side, or along each axis.
    #[serde(default = "d_resolution")]
    pub resolution: PerAxis<usize>,
    /// Side of the box as a multiple of the object's extent (one value: a cube over the
    /// largest extent; three: per axis), so the box does not disturb the flow near the object
    /// (section 5.1).
    #[serde(default = "d_domain")]
    pub domain: PerAxis<Real>,
    /// The raised kinematic viscosity, m^2/s (section 5.1); 0 is inviscid with free slip.
    #[serde(default = "d_viscosity")]
    pub viscosity: Real,
    /// Steps before averaging starts (50 in the paper).
    #[serde(default = "d_steps")]
    pub stabilise_steps: u32,
    /// Steps averaged (50 in the paper).
    #[serde(default = "d_steps")]
    pub average_steps: u32,
    /// Time step as a CFL number at the largest wall or inflow speed: dt = cfl dx / speed.
    #[serde(default = "d_cfl")]
    pub cfl: Real,
    /// Advection scheme of the velocity.
    #[serde(default = "d_advection")]
    pub advection: Advection,
    /// How the obstacle meets the cells: `cut` or `staircase` (the scenes' `grid.obstacle_surface`).
    #[serde(default)]
    pub obstacle_surface: ObstacleSurface,
    /// Project the pressure's increment only (the scenes' `grid.incremental_pressure`).
    #[serde(default = "d_true")]
    pub incremental_pressure: bool,
    /// Relative residual of the pressure and viscosity solves while averaging. 1e-3 moves
    /// omega_pre by 8e-4 of itself against 1e-5 for a spinning sphere at 64^3 (2e-6 for a
    /// translating one) for a fifth less time per rotation.
    #[serde(default = "d_tolerance")]
    pub tolerance: Real,
    /// Relative residual of the solves while stabilising: only the flow they lead to matters,
    /// and 1e-3 there moves omega_pre by about 1e-4 of itself (sphere, 32^3) for a fifth less
    /// time; 1e-2 moves it by 10 %.
    #[serde(default = "d_stabilise_tolerance")]
    pub stabilise_tolerance: Real,
    /// Stabilising stops early once the flow just outside the layer is estimated to be within
    /// this relative distance of its steady state (see `solve::Settle`), and a settled flow
    /// is averaged over 5 steps; 0 always runs the fixed step counts. A shedding wake or a
    /// spinning object never settles and keeps them.
    #[serde(default = "d_settle_tolerance")]
    pub settle_tolerance: Real,
}

/// The precomputation grid as built: cells per axis and their size, centred on the origin.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GridBox {
    pub cells: [usize; 3],
    pub dx: Real,
    /// Half the side along each axis, m.
    pub half: [Real; 3],
}

impl GridBox {
    /// The lowest corner, m.
    pub fn origin(&self) -> eddy::Vec3 {
        -eddy::Vec3::from(self.half)
    }

    /// "nx x ny x nz".
    pub fn describe(&self) -> String {
        let [x, y, z] = self.cells;
        format!("{x} x {y} x {z}")
    }
}

/// The artificial boundary layer of Figure 5.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LayerSettings {
    /// Vortex gain beta of Eq. 1.
    #[serde(default = "d_beta")]
    pub beta: Real,
    /// Layer thickness l in cells of the precomputation grid (1-2 in the paper).
    #[serde(default = "d_thickness")]
    pub thickness: Real,
    /// Spacing of the boundary points in cells.
    #[serde(default = "d_point_spacing")]
    pub point_spacing: Real,
}

/// Direction samples [polar (poles included), azimuth] for each motion (10 x 20 in the paper).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SamplingSettings {
    #[serde(default = "d_sampling")]
    pub translation: [usize; 2],
    #[serde(default = "d_sampling")]
    pub rotation: [usize; 2],
}

fn d_true() -> bool {
    true
}
fn d_resolution() -> PerAxis<usize> {
    PerAxis::Same(32)
}
fn d_domain() -> PerAxis<Real> {
    PerAxis::Same(4.0)
}
fn d_viscosity() -> Real {
    0.02
}
fn d_steps() -> u32 {
    50
}
fn d_cfl() -> Real {
    1.0
}
fn d_advection() -> Advection {
    Advection::SEMI_LAGRANGIAN
}
fn d_tolerance() -> Real {
    1e-3
}
fn d_stabilise_tolerance() -> Real {
    1e-3
}
fn d_settle_tolerance() -> Real {
    4e-3
}
fn d_beta() -> Real {
    1.0
}
fn d_thickness() -> Real {
    1.5
}
fn d_point_spacing() -> Real {
    1.0
}
fn d_sampling() -> [usize; 2] {
    [10, 20]
}

impl Default for GridSettings {
    fn default() -> Self {
        toml::from_str("").expect("every grid key has a default")
    }
}
impl Default for LayerSettings {
    fn default() -> Self {
        toml::from_str("").expect("every layer key has a default")
    }
}
impl Default for SamplingSettings {
    fn default() -> Self {
        toml::from_str("").expect("every sampling key has a default")
    }
}

impl ObstacleSpec {
    /// Reads `path`, applies the overrides, resolves a mesh path against the file's folder and
    /// validates.
    pub fn load(path: &Path, overrides: &[String]) -> anyhow::Result<Self> {
        let text = std::fs::read_to_string(path)
            .with_context(|| format!("reading obstacle file {}", path.display()))?;
        Self::parse(&text, path, overrides)
    }

    /// [`Self::load`] of text already in memory; `origin` names it in messages.
    pub fn parse(text: &str, origin: &Path, overrides: &[String]) -> anyhow::Result<Self> {
        let mut table: toml::Table =
            toml::from_str(text).with_context(|| format!("{}: TOML syntax", origin.display()))?;
        for o in overrides {
            eddy::scene::apply_override(&mut table, o)?;
        }
        let mut spec: Self = table
            .try_into()
            .with_context(|| format!("{}: not an obstacle file", origin.display()))?;
        if let Shape::Mesh { path, .. } = &mut spec.shape {
            if path.is_relative() {
                let base = origin.parent().map(PathBuf::from).unwrap_or_default();
                *path = base.join(&*path);
            }
        }
        spec.validate()
            .with_context(|| format!("{}: invalid obstacle file", origin.display()))?;
        Ok(spec)
    }

    /// Checks every value's range.
    pub fn validate(&self) -> anyhow::Result<()> {
        let g = &self.grid;
        let check = |key: &str, v: Real, ok: bool, allowed: &str| -> anyhow::Result<()> {
            if ok && v.is_finite() {
                Ok(())
            } else {
                bail!("`{key}` = {v}; allowed: {allowed}")
            }
        };
        for r in g.resolution.each() {
            let r = r as Real;
            check(
                "grid.resolution",
                r,
                (8.0..=512.0).contains(&r),
                "8 to 512 cells per axis",
            )?;
        }
        for d in g.domain.each() {
            check(
                "grid.domain",
                d,
                d >= 1.5,
                "at least 1.5 times the extent on every axis",
            )?;
        }
        check("grid.viscosity", g.viscosity, g.viscosity >= 0.0, ">= 0")?;
        let avg = Real::from(g.average_steps);
        check("grid.average_steps", avg, avg >= 1.0, "at least 1")?;
        check("grid.cfl", g.cfl, g.cfl > 0.0 && g.cfl <= 5.0, "(0, 5]")?;
        for (key, tol) in [
            ("grid.tolerance", g.tolerance),
            ("grid.stabilise_tolerance", g.stabilise_tolerance),
        ] {
            check(key, tol, tol > 0.0 && tol <= 0.1, "(0, 0.1]")?;
        }
        let settle = g.settle_tolerance;
        check(
            "grid.settle_tolerance",
            settle,
            (0.0..=0.1).contains(&settle),
            "[0, 0.1]; 0 runs the fixed step counts",
        )?;
        let l = &self.layer;
        check("layer.beta", l.beta, true, "any finite number")?;
        check(
            "layer.thickness",
            l.thickness,
            l.thickness > 0.0 && l.thickness <= 10.0,
            "(0, 10] cells",
        )?;
        check(
            "layer.point_spacing",
            l.point_spacing,
            l.point_spacing >= 0.1 && l.point_spacing <= 10.0,
            "[0.1, 10] cells",
        )?;
        for (key, s) in [
            ("sampling.translation", self.sampling.translation),
            ("sampling.rotation", self.sampling.rotation),
        ] {
            Sampling::new(s[0], s[1]).map_err(|e| anyhow::anyhow!("`{key}`: {e}"))?;
        }
        // Builds the body, so a bad shape or unreadable mesh is reported here.
        self.body()?;
        Ok(())
    }

    /// The obstacle at rest at the origin.
    pub fn body(&self) -> anyhow::Result<RigidBody> {
        Ok(RigidBody::from_scene(&self.body_entry([0.0; 3]), 0)?)
    }

    /// The scene entry of the obstacle spinning at `angular` rad/s about its origin.
    pub fn body_entry(&self, angular: [Real; 3]) -> Body {
        Body {
            name: Some(self.name.clone()),
            shape: self.shape.clone(),
            position: [0.0; 3],
            rotation: [0.0; 3],
            motion: eddy::scene::Motion {
                angular,
                ..Default::default()
            },
            abl: None,
            wall_viscosity: None,
        }
    }

    /// The precomputation box (see [`GridSettings`]).
    pub fn grid_box(&self) -> anyhow::Result<GridBox> {
        let (lo, hi) = self.body()?.local_aabb();
        let reach = lo.coords.abs().sup(&hi.coords.abs());
        let half: [Real; 3] = match self.grid.domain {
            PerAxis::Same(d) => [d * reach.max(); 3],
            PerAxis::Each(d) => std::array::from_fn(|a| d[a] * reach[a]),
        };
        if let Some(a) = (0..3).find(|&a| half[a] <= 0.0) {
            bail!(
                "obstacle '{}' has no extent along {}: give grid.domain one value (a cube)",
                self.name,
                ["x", "y", "z"][a]
            );
        }
        let longest = |n: [usize; 3]| {
            (0..3)
                .map(|a| 2.0 * half[a] / n[a] as Real)
                .fold(0.0, Real::max)
        };
        let cells = match self.grid.resolution {
            PerAxis::Same(n) => {
                let dx = longest([n; 3]);
                half.map(|h| ((2.0 * h / dx).round() as usize).max(1))
            }
            PerAxis::Each(n) => n,
        };
        let dx = match self.grid.resolution {
            PerAxis::Same(n) => longest([n; 3]),
            PerAxis::Each(n) => longest(n),
        };
        // A side that is a whole number of cells keeps its exact half-width.
        let half = std::array::from_fn(|a| {
            let side = cells[a] as Real * dx;
            if (side - 2.0 * half[a]).abs() <= 1e-9 * side {
                half[a]
            } else {
                0.5 * side
            }
        });
        Ok(GridBox { cells, dx, half })
    }

    /// Cell size, m.
    pub fn spacing(&self) -> anyhow::Result<Real> {
        Ok(self.grid_box()?.dx)
    }

    /// The samplings of translation and rotation.
    pub fn samplings(&self) -> [Sampling; 2] {
        [self.sampling.translation, self.sampling.rotation]
            .map(|[p, a]| Sampling::new(p, a).expect("validated"))
    }

    /// Everything but the name as TOML: what the fingerprint covers and the database records.
    pub fn settings_toml(&self) -> String {
        #[derive(Serialize)]
        struct Settings<'a> {
            shape: &'a Shape,
            grid: &'a GridSettings,
            layer: &'a LayerSettings,
            sampling: &'a SamplingSettings,
        }
        toml::to_string(&Settings {
            shape: &self.shape,
            grid: &self.grid,
            layer: &self.layer,
            sampling: &self.sampling,
        })
        .unwrap_or_else(|e| format!("# settings could not be written: {e}\n"))
    }

    /// (fingerprint of geometry and settings, fingerprint of the geometry alone).
    pub fn fingerprints(&self) -> anyhow::Result<(String, String)> {
        let geometry = geometry_fingerprint(&self.shape)?;
        // The mesh path is not part of the identity; its bytes are, through `geometry`.
        let mut settings = self.clone();
        if let Shape::Mesh { path, .. } = &mut settings.shape {
            *path = PathBuf::new();
        }
        let all = hash_hex(&[
            SCHEME,
            geometry.as_bytes(),
            settings.settings_toml().as_bytes(),
        ]);
        Ok((all, geometry))
    }
}
