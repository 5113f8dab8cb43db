//! `eddy` from Python: thin PyO3 bindings over the library, which stays the one implementation.
//!
//! - `Scene.load(path, overrides)` and `Scene.from_dict(d)` go through the CLI's loader, its
//!   `--set` overrides and its validation; a bad scene raises `eddy.SceneError` (a
//!   `ValueError`) with the loader's message, which names the key.
//! - `Simulation(scene, out)` is the CLI's run ([`eddy::pipeline::Run`]) stepped from Python:
//!   the same frames, rows and steps as `eddy run`. Long calls release the GIL and check for
//!   Ctrl-C between steps.
//! - Arrays are copies: particle counts change between steps (inflow, outflow), so a view into
//!   the solver's memory could dangle. Writing velocities between steps is safe (the next step
//!   starts from them, as from a scene's initial velocities); nothing else is writable.
//! - `Database.open(path).lookup(velocity, angular)` looks up many directions at once, in
//!   parallel without the GIL.

use std::path::PathBuf;

use eddy::abl::AblDatabase;
use eddy::pipeline::{Kind, Run, RunError, RunOptions};
use eddy::{Real, Vec3};
use eddy_precompute::run::{Engine, Finished, Job, Threads};
use eddy_precompute::solve::Surface;
use numpy::ndarray::{Array1, Array2, Array3, ArrayView2, Axis};
use numpy::{IntoPyArray, PyArray1, PyArray2, PyArray3, PyArray4, PyReadonlyArray2};
use pyo3::create_exception;
use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use rayon::prelude::*;

create_exception!(
    eddy,
    SceneError,
    PyValueError,
    "A scene that cannot be loaded or run as given; the message names the key."
);

/// A run error as a Python exception: what is wrong with the scene as `SceneError`, a failure
/// while running (an instability, a file that cannot be written) as `RuntimeError`.
fn run_error(e: RunError) -> PyErr {
    match e {
        RunError::Scene(_)
        | RunError::Geometry(_)
        | RunError::Abl(_)
        | RunError::Unsupported(_)
        | RunError::TooLarge { .. }
        | RunError::InvalidOption { .. } => SceneError::new_err(e.to_string()),
        _ => PyRuntimeError::new_err(e.to_string()),
    }
}

/// A Python value as the text of a TOML value, as `--set KEY=VALUE` takes it.
fn toml_text(value: &Bound<'_, PyAny>, key: &str) -> PyResult<String> {
    let v: toml::Value =
        pythonize::depythonize(value).map_err(|e| SceneError::new_err(format!("{key}: {e}")))?;
    Ok(v.to_string())
}

/// A resolved scene: loaded, overridden and validated.
#[pyclass(module = "eddy", frozen)]
#[derive(Clone)]
struct Scene {
    inner: eddy::scene::Scene,
}

#[pymethods]
impl Scene {
    /// Loads a scene file with `overrides` ({"time.end": 0.5, "pressure.solver": "iisph"}),
    /// as `eddy run PATH --set KEY=VALUE` does.
    #[staticmethod]
    #[pyo3(signature = (path, overrides = None))]
    fn load(path: PathBuf, overrides: Option<&Bound<'_, PyDict>>) -> PyResult<Self> {
        let sets = assignments(overrides)?;
        let inner =
            eddy::scene::load(&path, &sets).map_err(|e| SceneError::new_err(e.to_string()))?;
        Ok(Scene { inner })
    }

    /// A scene from a dict laid out as the TOML file; relative paths (meshes, databases)
    /// resolve against `base` (default: the current folder).
    #[staticmethod]
    #[pyo3(signature = (scene, base = None, overrides = None))]
    fn from_dict(
        scene: &Bound<'_, PyDict>,
        base: Option<PathBuf>,
        overrides: Option<&Bound<'_, PyDict>>,
    ) -> PyResult<Self> {
        let table: toml::Table = pythonize::depythonize(scene.as_any())
            .map_err(|e| SceneError::new_err(format!("the scene dict: {e}")))?;
        let text = toml::to_string(&table)
            .map_err(|e| SceneError::new_err(format!("the scene dict: {e}")))?;
        let origin = base.unwrap_or_default().join("<dict>.toml");
        let sets = assignments(overrides)?;
        let inner = eddy::scene::parse_str(&text, &origin, &sets)
            .map_err(|e| SceneError::new_err(e.to_string()))?;
        Ok(Scene { inner })
    }

    /// The scene's name.
    #[getter]
    fn name(&self) -> String {
        self.inner.name.clone()
    }

    /// The resolved scene as TOML, every default filled in: what a run writes as `scene.toml`.
    fn to_toml(&self) -> String {
        self.inner.to_toml()
    }

    fn __repr__(&self) -> String {
        format!("<eddy.Scene {:?}>", self.inner.name)
    }
}

/// `{"a.b": value}` as `--set a.b=VALUE` assignments.
fn assignments(overrides: Option<&Bound<'_, PyDict>>) -> PyResult<Vec<String>> {
    let Some(d) = overrides else {
        return Ok(Vec::new());
    };
    d.iter()
        .map(|(k, v)| {
            let key: String = k
                .extract()
                .map_err(|_| SceneError::new_err(format!("override key {k} is not a string")))?;
            Ok(format!("{key}={}", toml_text(&v, &key)?))
        })
        .collect()
}

/// A scene being run: `eddy run` a step at a time. Used from the thread that made it.
#[pyclass(module = "eddy", unsendable)]
struct Simulation {
    run: Run,
    /// The last step's dt, s (0 before the first).
    dt: Real,
}

/// An (n, 3) array of vectors.
fn vectors<'py>(py: Python<'py>, v: &[Vec3]) -> Bound<'py, PyArray2<Real>> {
    let flat: Vec<Real> = v.iter().flat_map(|p| [p.x, p.y, p.z]).collect();
    Array2::from_shape_vec((v.len(), 3), flat)
        .expect("three components a vector")
        .into_pyarray(py)
}

/// Checks that `array` is (n, 3) and returns its rows as vectors; `what` names it.
fn rows(array: ArrayView2<'_, Real>, n: usize, what: &str) -> PyResult<Vec<Vec3>> {
    if array.shape() != [n, 3] {
        return Err(PyValueError::new_err(format!(
            "{what}: expected shape ({n}, 3), got {:?}",
            array.shape()
        )));
    }
    let v: Vec<Vec3> = array
        .axis_iter(Axis(0))
        .map(|r| Vec3::new(r[0], r[1], r[2]))
        .collect();
    if v.iter().any(|x| !x.iter().all(|c| c.is_finite())) {
        return Err(PyValueError::new_err(format!(
            "{what}: values must be finite"
        )));
    }
    Ok(v)
}

impl Simulation {
    fn sph(&self) -> PyResult<&eddy::sph::SphSolver> {
        self.run
            .pipeline
            .sim
            .sph
            .as_ref()
            .ok_or_else(|| PyValueError::new_err("the scene has no SPH fluid ([fluid])"))
    }

    fn grid(&self) -> PyResult<&eddy::grid::GridSolver> {
        self.run
            .pipeline
            .sim
            .grid
            .as_ref()
            .ok_or_else(|| PyValueError::new_err("the scene has no grid ([grid])"))
    }

    /// A run of `scene` into `out`, started or (with `resume`) gone on from its checkpoint,
    /// built with the GIL released.
    fn begin(py: Python<'_>, scene: &Scene, out: Option<PathBuf>, resume: bool) -> PyResult<Self> {
        let options = RunOptions {
            out,
            resume,
            ..RunOptions::default()
        };
        let inner = &scene.inner;
        let run = py
            .detach(|| Run::begin(inner, &options))
            .map_err(run_error)?;
        Ok(Simulation { run, dt: 0.0 })
    }

    /// One step with the GIL released, then a check for Ctrl-C; false once the run has ended.
    fn advance(&mut self, py: Python<'_>) -> PyResult<bool> {
        let run = &mut self.run;
        let rec = py.detach(|| run.advance(None)).map_err(run_error)?;
        py.check_signals()?;
        match rec {
            Some(rec) => {
                self.dt = rec.dt;
                Ok(true)
            }
            None => {
                self.run.finish().map_err(run_error)?;
                Ok(false)
            }
        }
    }
}

#[pymethods]
impl Simulation {
    /// Builds the scene and opens its outputs in `out` (default: the scene's `output.dir`,
    /// else `out/NAME`), as `eddy run` does; the frame at t = 0 is written by the first step.
    #[new]
    #[pyo3(signature = (scene, out = None))]
    fn new(py: Python<'_>, scene: &Scene, out: Option<PathBuf>) -> PyResult<Self> {
        Self::begin(py, scene, out, false)
    }

    /// Goes on with the run in `out` (default: the scene's output folder) from its
    /// checkpoint, as `eddy resume` does: the scene must be the checkpoint's but for
    /// `time.end`, `time.steps` and the `[output]` keys; frames and rows go on from it.
    #[staticmethod]
    #[pyo3(signature = (scene, out = None))]
    fn resume(py: Python<'_>, scene: &Scene, out: Option<PathBuf>) -> PyResult<Self> {
        Self::begin(py, scene, out, true)
    }

    /// Writes the whole state between steps to `checkpoint.h5` in the output folder (what
    /// `Simulation.resume` and `eddy resume` go on from) and returns its path.
    fn save(&mut self, py: Python<'_>) -> PyResult<PathBuf> {
        // A unique borrow: the run is Send, not Sync.
        let run = &mut self.run;
        py.detach(move || run.checkpoint()).map_err(run_error)
    }

    /// The stages each step runs and what is written, as `eddy run --plan` prints them.
    fn plan(&self) -> String {
        self.run.plan().to_string()
    }

    /// One step (writing the frame that is due first, as `eddy run`); False, and nothing
    /// done but the end's frame, once the run has reached the scene's end.
    fn step(&mut self, py: Python<'_>) -> PyResult<bool> {
        self.advance(py)
    }

    /// Steps until the time reaches `until` (s), or `steps` more steps are taken, or the
    /// scene ends, whichever comes first; with neither, to the scene's end. Steps are never
    /// shortened to land on `until`, so a run in pieces takes the very steps of a run in one.
    /// Returns the steps taken.
    #[pyo3(signature = (until = None, steps = None, progress = false))]
    fn run(
        &mut self,
        py: Python<'_>,
        until: Option<Real>,
        steps: Option<u64>,
        progress: bool,
    ) -> PyResult<u64> {
        if let Some(t) = until.filter(|t| !t.is_finite()) {
            return Err(PyValueError::new_err(format!(
                "until = {t}: a finite time, s"
            )));
        }
        let bar = if progress {
            indicatif::ProgressBar::new(steps.unwrap_or(0))
        } else {
            indicatif::ProgressBar::hidden()
        };
        let mut taken = 0;
        while until.is_none_or(|t| self.time() < t) && steps.is_none_or(|n| taken < n) {
            if !self.advance(py)? {
                break;
            }
            taken += 1;
            bar.inc(1);
            bar.set_message(format!("t = {:.4} s", self.time()));
        }
        bar.finish_and_clear();
        Ok(taken)
    }

    /// Simulated time, s.
    #[getter]
    fn time(&self) -> Real {
        self.run.pipeline.sim.time()
    }

    /// The last step's dt, s (0 before the first step).
    #[getter]
    fn dt(&self) -> Real {
        self.dt
    }

    /// Steps taken.
    #[getter]
    fn steps(&self) -> u64 {
        self.run.pipeline.sim.steps()
    }

    /// Whether the run has reached the scene's end.
    #[getter]
    fn ended(&self) -> bool {
        self.run.ended()
    }

    /// The output folder.
    #[getter]
    fn out(&self) -> PathBuf {
        self.run.out().to_path_buf()
    }

    /// The last step's row of `metrics.csv` as {column: value} (a coupled scene's two files
    /// as keys `particles.COLUMN` and `grid.COLUMN`); empty before the first step.
    fn metrics<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        self.rows(py, "metrics.csv")
    }

    /// The last step's row of `probes.csv`, laid out as [`Self::metrics`].
    fn probes<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        self.rows(py, "probes.csv")
    }

    // ------------------------------------------------------------------ particles

    /// Fluid particle positions, (n, 3) float64, m.
    #[getter]
    fn position<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<Real>>> {
        Ok(vectors(py, &self.sph()?.fluid.x))
    }

    /// Fluid particle velocities, (n, 3) float64, m/s.
    #[getter]
    fn velocity<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<Real>>> {
        Ok(vectors(py, &self.sph()?.fluid.v))
    }

    /// Writes the fluid particles' velocities, (n, 3) m/s; the next step starts from them.
    #[setter]
    fn set_velocity(&mut self, velocity: PyReadonlyArray2<'_, Real>) -> PyResult<()> {
        let n = self.sph()?.fluid.len();
        let v = rows(velocity.as_array(), n, "velocity")?;
        let sim = &mut self.run.pipeline.sim;
        sim.sph.as_mut().expect("checked above").fluid.v = v;
        self.run.state_edited();
        Ok(())
    }

    /// Fluid particle densities, (n,) float64, kg/m^3 (as of the last step).
    #[getter]
    fn density<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray1<Real>>> {
        Ok(PyArray1::from_slice(py, &self.sph()?.fluid.density))
    }

    /// Fluid particle pressures, (n,) float64, Pa (as of the last step).
    #[getter]
    fn pressure<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray1<Real>>> {
        Ok(PyArray1::from_slice(py, &self.sph()?.fluid.pressure))
    }

    /// The SPH curl of the fluid's velocity, (n, 3) float64, 1/s.
    #[getter]
    fn vorticity<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<Real>>> {
        Ok(vectors(py, &self.sph()?.vorticity()))
    }

    // ------------------------------------------------------------------ grid

    /// Cell-centred grid velocity, (nx, ny, nz, 3) float64, m/s, indexed [i, j, k].
    #[getter]
    fn grid_velocity<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray4<Real>>> {
        let [u, v, w] = self.grid()?.mac.cell_velocity();
        let views = [u.view(), v.view(), w.view()];
        let stacked = numpy::ndarray::stack(Axis(3), &views).expect("equal shapes");
        Ok(stacked.into_pyarray(py))
    }

    /// Face velocities of the MAC grid: three arrays, the x faces (nx + 1, ny, nz), the y
    /// faces (nx, ny + 1, nz) and the z faces (nx, ny, nz + 1), float64, m/s.
    #[getter]
    fn grid_faces<'py>(&self, py: Python<'py>) -> PyResult<[Bound<'py, PyArray3<Real>>; 3]> {
        let u = &self.grid()?.mac.u;
        Ok([0, 1, 2].map(|a| u[a].clone().into_pyarray(py)))
    }

    /// Writes the face velocities (shapes as `grid_faces`), m/s, then the walls' and
    /// obstacles' conditions, as a scene's `initial_velocity` is set; the next step projects
    /// them.
    fn set_grid_faces(
        &mut self,
        x: numpy::PyReadonlyArray3<'_, Real>,
        y: numpy::PyReadonlyArray3<'_, Real>,
        z: numpy::PyReadonlyArray3<'_, Real>,
    ) -> PyResult<()> {
        self.grid()?;
        let sim = &mut self.run.pipeline.sim;
        let grid = sim.grid.as_mut().expect("checked above");
        grid.set_faces([x.as_array(), y.as_array(), z.as_array()])
            .map_err(|e| PyValueError::new_err(format!("grid faces: {e}")))?;
        self.run.state_edited();
        Ok(())
    }

    /// Cell pressure, (nx, ny, nz) float64, Pa (kinematic with `grid.density` 1).
    #[getter]
    fn grid_pressure<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray3<Real>>> {
        Ok(self.grid()?.pressure.clone().into_pyarray(py))
    }

    /// Smoke density per flow cell, (nx, ny, nz) float64; None without smoke.
    #[getter]
    fn smoke<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyArray3<Real>>>> {
        let smoke = self.grid()?.smoke.as_ref();
        Ok(smoke.map(|s| s.on_flow_cells(&s.density).into_owned().into_pyarray(py)))
    }

    /// The grid's origin (m), cell size (m) and cells along x, y, z.
    #[getter]
    fn grid_geometry(&self) -> PyResult<([Real; 3], Real, [usize; 3])> {
        let mac = &self.grid()?.mac;
        Ok(([mac.origin.x, mac.origin.y, mac.origin.z], mac.dx, mac.dims))
    }

    // ------------------------------------------------------------------ vortex particles

    /// The vortex particles of `medium` ("grid" or "particles"; default: the scene's one set)
    /// as {"position", "vorticity" (n, 3), "radius", "energy", "age" (n,)}.
    #[pyo3(signature = (medium = None))]
    fn vortices<'py>(&self, py: Python<'py>, medium: Option<&str>) -> PyResult<Bound<'py, PyDict>> {
        let sim = &self.run.pipeline.sim;
        let sets = [
            ("grid", &sim.grid_turbulence),
            ("particles", &sim.sph_turbulence),
        ];
        let have: Vec<_> = sets.iter().filter(|(_, t)| t.is_some()).collect();
        let chosen = match medium {
            Some(m) => sets.iter().find(|(name, _)| *name == m).ok_or_else(|| {
                PyValueError::new_err(format!("medium {m:?}: \"grid\" or \"particles\""))
            })?,
            None if have.len() == 1 => have[0],
            None if have.is_empty() => &sets[0],
            None => {
                return Err(PyValueError::new_err(
                    "the scene has vortex particles in both media: pass medium=\"grid\" or \
                     \"particles\"",
                ))
            }
        };
        let t = chosen.1.as_ref().ok_or_else(|| {
            PyValueError::new_err(format!(
                "the scene has no vortex particles in {:?} (no obstacle with a database)",
                chosen.0
            ))
        })?;
        let p = &t.vortices;
        let d = PyDict::new(py);
        d.set_item("position", vectors(py, &p.x))?;
        d.set_item("vorticity", vectors(py, &p.omega))?;
        let per = |f: &dyn Fn(usize) -> Real| Array1::from_iter((0..p.len()).map(f));
        d.set_item("radius", per(&|i| p.radius(i)).into_pyarray(py))?;
        d.set_item("energy", per(&|i| p.energy(i)).into_pyarray(py))?;
        d.set_item("age", PyArray1::from_slice(py, &p.age))?;
        Ok(d)
    }

    // ------------------------------------------------------------------ statistics

    /// The running statistics of `medium` ("grid" or "particles"; default: the scene's one
    /// medium), as written to `statistics.h5`: {"mean_velocity" (nx, ny, nz, 3),
    /// "reynolds_stress" (nx, ny, nz, 6: xx, yy, zz, xy, yz, xz), "k", "mean_vorticity" (3),
    /// "mean_enstrophy", "samples" (nx, ny, nz), "origin", "spacing", "dims" (the lattice:
    /// cell (i, j, k) spans origin + spacing * [i, i + 1] x ...), "time_from", "time_to",
    /// "sample_count"}; NaN where no sample found fluid. `None` before the first sample.
    #[pyo3(signature = (medium = None))]
    fn statistics<'py>(
        &self,
        py: Python<'py>,
        medium: Option<&str>,
    ) -> PyResult<Option<Bound<'py, PyDict>>> {
        let all = &self.run.pipeline.sim.statistics;
        let name = |k: Kind| match k {
            Kind::Grid => "grid",
            Kind::Particles => "particles",
        };
        let chosen =
            match (medium, all.len()) {
                (_, 0) => return Err(PyValueError::new_err(
                    "the scene has no [statistics] (add it, or pass {\"statistics.from\": 0.0} \
                     as an override)",
                )),
                (Some(m), _) => all.iter().find(|s| name(s.kind) == m).ok_or_else(|| {
                    let have: Vec<_> = all.iter().map(|s| name(s.kind)).collect();
                    PyValueError::new_err(format!("medium {m:?}: one of {have:?}"))
                })?,
                (None, 1) => &all[0],
                (None, _) => {
                    return Err(PyValueError::new_err(
                        "the scene has statistics in both media: pass medium=\"grid\" or \
                     \"particles\"",
                    ))
                }
            };
        let stats = &chosen.stats;
        let Some((from, to)) = stats.span else {
            return Ok(None);
        };
        let f = stats.fields();
        let stack = |c: &[Array3<Real>]| {
            let views: Vec<_> = c.iter().map(|a| a.view()).collect();
            numpy::ndarray::stack(Axis(3), &views)
                .expect("equal shapes")
                .into_pyarray(py)
        };
        let l = &stats.lattice;
        let d = PyDict::new(py);
        d.set_item("mean_velocity", stack(&f.mean_velocity))?;
        d.set_item("reynolds_stress", stack(&f.reynolds_stress))?;
        d.set_item("k", f.k.into_pyarray(py))?;
        d.set_item("mean_vorticity", stack(&f.mean_vorticity))?;
        d.set_item("mean_enstrophy", f.mean_enstrophy.into_pyarray(py))?;
        d.set_item("samples", f.samples.into_pyarray(py))?;
        d.set_item("origin", [l.origin.x, l.origin.y, l.origin.z])?;
        d.set_item("spacing", l.spacing)?;
        d.set_item("dims", l.dims)?;
        d.set_item("time_from", from)?;
        d.set_item("time_to", to)?;
        d.set_item("sample_count", stats.steps)?;
        Ok(Some(d))
    }

    fn __repr__(&self) -> String {
        format!(
            "<eddy.Simulation t = {} s, {} steps, out {:?}>",
            self.time(),
            self.steps(),
            self.run.out()
        )
    }
}

impl Simulation {
    /// The last rows of the series whose files end in `base`, keyed by column (prefixed by the
    /// medium when there are two).
    fn rows<'py>(&self, py: Python<'py>, base: &str) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        let series: Vec<_> = self
            .run
            .last_rows()
            .into_iter()
            .filter(|(file, _)| file.ends_with(base))
            .collect();
        let both = series.len() > 1;
        for (file, row) in series {
            let prefix = file.strip_suffix(base).unwrap_or("").trim_end_matches('_');
            for (column, value) in row {
                let key = if both {
                    format!("{prefix}.{column}")
                } else {
                    column
                };
                d.set_item(key, value)?;
            }
        }
        Ok(d)
    }
}

/// An artificial-boundary-layer database (`eddy-precompute`'s HDF5 file).
#[pyclass(module = "eddy", frozen)]
struct Database {
    inner: AblDatabase,
}

#[pymethods]
impl Database {
    /// Opens and checks a database.
    #[staticmethod]
    fn open(path: PathBuf) -> PyResult<Self> {
        let inner =
            AblDatabase::open(&path, None).map_err(|e| SceneError::new_err(e.to_string()))?;
        Ok(Database { inner })
    }

    /// Boundary points (object frame), (p, 3) float64, m.
    #[getter]
    fn points<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<Real>> {
        vectors(
            py,
            &self
                .inner
                .points()
                .iter()
                .map(|p| p.coords)
                .collect::<Vec<_>>(),
        )
    }

    /// Outward normals at the boundary points, (p, 3) float64.
    #[getter]
    fn normals<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<Real>> {
        vectors(py, self.inner.normals())
    }

    /// omega_pre at every boundary point for each motion: `velocity` (m/s, the object relative
    /// to the fluid) and `angular` (rad/s), each (k, 3) or (3,), object frame (the CLI's
    /// `eddy lookup --velocity --angular`). Returns (k, p, 3), or (p, 3) for single vectors.
    #[pyo3(signature = (velocity, angular = None))]
    fn lookup<'py>(
        &self,
        py: Python<'py>,
        velocity: &Bound<'py, PyAny>,
        angular: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let (linear, single) = motions(velocity, "velocity")?;
        let rotation = match angular {
            Some(a) => motions(a, "angular")?,
            None => (vec![Vec3::zeros(); linear.len()], single),
        };
        let (angular, single_angular) = rotation;
        let k = match (linear.len(), angular.len()) {
            (a, b) if a == b => a,
            (1, b) => b,
            (a, 1) => a,
            (a, b) => {
                return Err(PyValueError::new_err(format!(
                    "velocity has {a} rows and angular {b}: give as many, or one of them"
                )))
            }
        };
        let p = self.inner.len();
        let db = &self.inner;
        let out = py.detach(|| {
            let mut out = vec![Vec3::zeros(); k * p];
            out.par_chunks_mut(p).enumerate().for_each(|(i, o)| {
                let v = linear[if linear.len() == 1 { 0 } else { i }];
                let w = angular[if angular.len() == 1 { 0 } else { i }];
                db.lookup_into(&v, &w, o);
            });
            out
        });
        let flat: Vec<Real> = out.iter().flat_map(|w| [w.x, w.y, w.z]).collect();
        let array = Array3::from_shape_vec((k, p, 3), flat).expect("k p 3");
        if single && single_angular {
            Ok(array
                .index_axis_move(Axis(0), 0)
                .into_pyarray(py)
                .into_any())
        } else {
            Ok(array.into_pyarray(py).into_any())
        }
    }

    fn __len__(&self) -> usize {
        self.inner.len()
    }
}

/// Motions as vectors from a (3,) or (k, 3) array-like; whether it was a single vector.
fn motions(value: &Bound<'_, PyAny>, what: &str) -> PyResult<(Vec<Vec3>, bool)> {
    let array = numpy::PyArrayLike2::<Real, numpy::AllowTypeChange>::extract(value.as_borrowed());
    if let Ok(a) = array {
        let n = a.as_array().shape()[0];
        return Ok((rows(a.as_array(), n, what)?, false));
    }
    let single = numpy::PyArrayLike1::<Real, numpy::AllowTypeChange>::extract(value.as_borrowed())
        .map_err(|_| PyValueError::new_err(format!("{what}: expected shape (3,) or (k, 3)")))?;
    let a = single.as_array();
    let two = a
        .into_shape_with_order((1, a.len()))
        .map_err(|e| PyValueError::new_err(e.to_string()))?;
    Ok((rows(two, 1, what)?, true))
}

/// Precomputes the boundary-layer database of the obstacle file `obstacle` into `out`, with
/// `jobs` directions at once (default: every core), as `eddy-precompute OBSTACLE --out OUT`;
/// `resume` keeps the directions an earlier run finished (Ctrl-C stops after the directions in
/// flight and keeps those done). Returns the directions computed.
#[pyfunction]
#[pyo3(signature = (obstacle, out, jobs = None, resume = false, overrides = None))]
fn precompute(
    py: Python<'_>,
    obstacle: PathBuf,
    out: PathBuf,
    jobs: Option<usize>,
    resume: bool,
    overrides: Option<&Bound<'_, PyDict>>,
) -> PyResult<usize> {
    let sets = assignments(overrides)?;
    let spec = eddy_precompute::ObstacleSpec::load(&obstacle, &sets)
        .map_err(|e| SceneError::new_err(format!("{e:#}")))?;
    let options = eddy_precompute::RunOptions {
        out,
        shard: None,
        resume,
        workers: jobs
            .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()))
            .max(1),
        progress: false,
    };
    let mut engine = Interruptible {
        threads: Threads {
            workers: options.workers,
        },
        interrupt: None,
    };
    let result = py.detach(|| eddy_precompute::precompute_with(&spec, &options, &mut engine));
    if let Some(interrupt) = engine.interrupt {
        return Err(interrupt);
    }
    let summary = result.map_err(|e| PyRuntimeError::new_err(format!("{e:#}")))?;
    Ok(summary.computed)
}

/// The precomputation's threads, stopping after the directions in flight when Python has a
/// signal pending (Ctrl-C); the finished directions stay in the parts folder, for `resume`.
struct Interruptible {
    threads: Threads,
    interrupt: Option<PyErr>,
}

impl Engine for Interruptible {
    fn compute(
        &mut self,
        spec: &eddy_precompute::ObstacleSpec,
        surface: &Surface,
        todo: &[Job],
        deliver: &mut dyn FnMut(Finished) -> bool,
    ) {
        let interrupt = &mut self.interrupt;
        self.threads.compute(spec, surface, todo, &mut |finished| {
            let keep = deliver(finished);
            match Python::attach(|py| py.check_signals()) {
                Ok(()) => keep,
                Err(e) => {
                    *interrupt = Some(e);
                    false
                }
            }
        });
    }
}

#[pymodule]
fn _eddy(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<Scene>()?;
    m.add_class::<Simulation>()?;
    m.add_class::<Database>()?;
    m.add_function(wrap_pyfunction!(precompute, m)?)?;
    m.add("SceneError", m.py().get_type::<SceneError>())?;
    Ok(())
}
