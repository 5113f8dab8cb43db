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
//! - A field the scene does not have (particles on a grid scene, smoke without a source) reads
//!   `None`, so `hasattr` and `is None` tell what a scene holds; writing one, or a method asked
//!   for what the scene lacks, raises `ValueError` saying what it has instead.
//! - `Database.open(path).lookup(velocity, angular)` looks up many directions at once, in
//!   parallel without the GIL.

use std::path::PathBuf;

use eddy::abl::AblDatabase;
use eddy::grid::forces::vorticity;
use eddy::io::plot::RunSeries;
use eddy::io::CsvSeries;
use eddy::pipeline::{Kind, Run, RunError, RunOptions, StepRecord, ABL_FIELD};
use eddy::{Real, Vec3};
use eddy_precompute::run::{Engine, Finished, Job, Threads};
use eddy_precompute::solve::Surface;
use numpy::ndarray::{Array1, Array2, Array3, ArrayView2, Axis};
use numpy::{IntoPyArray, PyArray1, PyArray2, PyArray3, PyArray4, PyReadonlyArray2};
use pyo3::create_exception;
use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList, PyTuple};
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
    let v: toml::Value = pythonize::depythonize(&plain(value)?)
        .map_err(|e| SceneError::new_err(format!("{key}: {e}")))?;
    Ok(v.to_string())
}

/// `value` with its NumPy arrays and scalars, at any depth of lists, tuples and dicts, as
/// their `tolist()`: the Python lists and numbers a scene's TOML is made of.
fn plain<'py>(value: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyAny>> {
    let py = value.py();
    let generic = py.import("numpy")?.getattr("generic")?;
    if value.is_instance_of::<numpy::PyUntypedArray>() || value.is_instance(&generic)? {
        return value.call_method0("tolist");
    }
    if value.is_instance_of::<PyList>() || value.is_instance_of::<PyTuple>() {
        let items = value.try_iter()?.map(|v| plain(&v?));
        return Ok(PyList::new(py, items.collect::<PyResult<Vec<_>>>()?)?.into_any());
    }
    if let Ok(d) = value.cast::<PyDict>() {
        let out = PyDict::new(py);
        for (k, v) in d.iter() {
            out.set_item(k, plain(&v)?)?;
        }
        return Ok(out.into_any());
    }
    Ok(value.clone())
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
        let table: toml::Table = pythonize::depythonize(&plain(scene.as_any())?)
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

/// Components on the grid's cells as one (nx, ny, nz, c) array, indexed [i, j, k, c] as the
/// frames' vector fields.
fn stacked<'py>(py: Python<'py>, components: &[Array3<Real>]) -> Bound<'py, PyArray4<Real>> {
    let views: Vec<_> = components.iter().map(|a| a.view()).collect();
    numpy::ndarray::stack(Axis(3), &views)
        .expect("equal shapes")
        .into_pyarray(py)
}

impl Simulation {
    fn sph(&self) -> Option<&eddy::sph::SphSolver> {
        self.run.pipeline.sim.sph.as_ref()
    }

    fn grid(&self) -> Option<&eddy::grid::GridSolver> {
        self.run.pipeline.sim.grid.as_ref()
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
        if run.removed_outputs() > 0 {
            let message = format!(
                "removed {} output files of an earlier run from {}",
                run.removed_outputs(),
                run.out().display()
            );
            let category = py.get_type::<pyo3::exceptions::PyUserWarning>();
            PyErr::warn(py, &category, &std::ffi::CString::new(message)?, 1)?;
        }
        Ok(Simulation { run, dt: 0.0 })
    }

    /// One step with the GIL released, then a check for Ctrl-C; `None` once the run has
    /// ended.
    fn advance(&mut self, py: Python<'_>) -> PyResult<Option<StepRecord>> {
        let run = &mut self.run;
        let rec = py.detach(|| run.advance(None)).map_err(run_error)?;
        py.check_signals()?;
        match &rec {
            Some(rec) => self.dt = rec.dt,
            None => {
                self.run.finish().map_err(run_error)?;
            }
        }
        Ok(rec)
    }

    /// The run's series whose files end in `base` (`metrics.csv`, `probes.csv`), each with the
    /// prefix of its keys: none for a scene's one series, `MEDIUM.` for a coupled scene's two.
    fn series_named(&self, base: &str) -> Vec<(String, &CsvSeries)> {
        let file = |s: &CsvSeries| {
            let name = s.path().file_name().unwrap_or_default();
            name.to_string_lossy().into_owned()
        };
        let named: Vec<_> = self
            .run
            .series()
            .filter(|s| file(s).ends_with(base))
            .collect();
        let both = named.len() > 1;
        named
            .into_iter()
            .map(|s| {
                let name = file(s);
                let medium = name.strip_suffix(base).unwrap_or("").trim_end_matches('_');
                let prefix = if both {
                    format!("{medium}.")
                } else {
                    String::new()
                };
                (prefix, s)
            })
            .collect()
    }

    /// Every row written so far of the series `base`, as {column: (rows,) array}: read back
    /// from the files, so a resumed run's history holds the rows before its checkpoint too.
    fn history<'py>(&self, py: Python<'py>, base: &str) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        for (prefix, series) in self.series_named(base) {
            let table = RunSeries::read_csv(series.path())
                .map_err(|e| PyRuntimeError::new_err(e.to_string()))?;
            for name in table.columns() {
                let column = table.column(name).unwrap_or_default();
                d.set_item(format!("{prefix}{name}"), PyArray1::from_vec(py, column))?;
            }
        }
        Ok(d)
    }

    /// The last row of the series `base`, as {column: value}; empty before the first step.
    fn last_row<'py>(&self, py: Python<'py>, base: &str) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        for (prefix, series) in self.series_named(base) {
            for (column, value) in series.last_row() {
                d.set_item(format!("{prefix}{column}"), value)?;
            }
        }
        Ok(d)
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
        Ok(self.advance(py)?.is_some())
    }

    /// Steps until the time reaches `until` (s), or `steps` more steps are taken, or the
    /// scene ends, whichever comes first; with neither, to the scene's end. Steps are never
    /// shortened to land on `until`, so a run in pieces takes the very steps of a run in one.
    /// Returns the steps taken. `progress` draws `eddy run`'s bar on a terminal: the share done
    /// of the simulated time to go (or of the steps, when they stop the run first), elapsed
    /// time and ETA.
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
        let bar = self.run.progress(progress, until, steps);
        let mut taken = 0;
        while until.is_none_or(|t| self.time() < t) && steps.is_none_or(|n| taken < n) {
            let Some(rec) = self.advance(py)? else {
                break;
            };
            taken += 1;
            bar.update(&self.run, &rec);
        }
        bar.finish();
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

    /// The rows of `metrics.csv` written so far, one per step, as {column: (rows,) float64
    /// array} (a coupled scene's two files as keys `particles.COLUMN` and `grid.COLUMN`);
    /// empty arrays before the first step, an empty dict when the scene writes no metrics.
    fn metrics<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        self.history(py, "metrics.csv")
    }

    /// The last row of `metrics.csv` as {column: value}, keyed as `metrics()`; empty before
    /// the first step.
    fn last_metrics<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        self.last_row(py, "metrics.csv")
    }

    /// The rows of `probes.csv` written so far, laid out as `metrics()`.
    fn probes<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        self.history(py, "probes.csv")
    }

    /// The last row of `probes.csv`, laid out as `last_metrics()`.
    fn last_probes<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        self.last_row(py, "probes.csv")
    }

    // ------------------------------------------------------------------ particles

    /// Fluid particle positions, (n, 3) float64, m; None without an SPH fluid.
    #[getter]
    fn position<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyArray2<Real>>> {
        Some(vectors(py, &self.sph()?.fluid.x))
    }

    /// Fluid particle velocities, (n, 3) float64, m/s; None without an SPH fluid.
    #[getter]
    fn velocity<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyArray2<Real>>> {
        Some(vectors(py, &self.sph()?.fluid.v))
    }

    /// Writes the fluid particles' velocities, (n, 3) m/s; the next step starts from them.
    #[setter]
    fn set_velocity(&mut self, velocity: PyReadonlyArray2<'_, Real>) -> PyResult<()> {
        let sph = self.sph().ok_or_else(|| {
            PyValueError::new_err(
                "velocity: the scene has no SPH fluid ([fluid]); a grid's velocities are \
                 written with set_grid_faces",
            )
        })?;
        let v = rows(velocity.as_array(), sph.fluid.len(), "velocity")?;
        let sim = &mut self.run.pipeline.sim;
        sim.sph.as_mut().expect("checked above").fluid.v = v;
        self.run.state_edited();
        Ok(())
    }

    /// Fluid particle densities, (n,) float64, kg/m^3 (as of the last step); None without an
    /// SPH fluid.
    #[getter]
    fn density<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyArray1<Real>>> {
        Some(PyArray1::from_slice(py, &self.sph()?.fluid.density))
    }

    /// Fluid particle pressures, (n,) float64, Pa (as of the last step); None without an SPH
    /// fluid.
    #[getter]
    fn pressure<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyArray1<Real>>> {
        Some(PyArray1::from_slice(py, &self.sph()?.fluid.pressure))
    }

    /// The SPH curl of the fluid's velocity, (n, 3) float64, 1/s; None without an SPH fluid
    /// (a grid's is `grid_vorticity`).
    #[getter]
    fn vorticity<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyArray2<Real>>> {
        Some(vectors(py, &self.sph()?.vorticity()))
    }

    /// The boundary-layer vorticity omega_ABL each fluid particle carries, (n, 3) float64,
    /// 1/s, as the particle frames' `abl_vorticity`; None without boundary layers on the
    /// particles (a grid's is `grid_abl_vorticity`).
    #[getter]
    fn abl_vorticity<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyArray2<Real>>> {
        let carried = &self.sph()?.fluid.carried;
        let (_, omega) = carried.iter().find(|(name, _)| *name == ABL_FIELD)?;
        Some(vectors(py, omega))
    }

    // ------------------------------------------------------------------ grid

    /// Cell-centred grid velocity, (nx, ny, nz, 3) float64, m/s, indexed [i, j, k, component];
    /// None without a grid.
    #[getter]
    fn grid_velocity<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyArray4<Real>>> {
        Some(stacked(py, &self.grid()?.mac.cell_velocity()))
    }

    /// Cell-centred grid vorticity, (nx, ny, nz, 3) float64, 1/s, as the grid frames'
    /// `vorticity`: central differences of `grid_velocity` (one-sided at the ends of an axis
    /// that does not wrap); None without a grid.
    #[getter]
    fn grid_vorticity<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyArray4<Real>>> {
        Some(stacked(py, &vorticity(&self.grid()?.mac)))
    }

    /// The boundary-layer vorticity omega_ABL on the grid's cells, (nx, ny, nz, 3) float64,
    /// 1/s, as the grid frames' `abl_vorticity`; None without boundary layers on the grid.
    #[getter]
    fn grid_abl_vorticity<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyArray4<Real>>> {
        let turbulence = self.run.pipeline.sim.grid_turbulence.as_ref()?;
        Some(stacked(py, turbulence.abl.as_ref()?))
    }

    /// The cells the grid's fluid does not hold, (nx, ny, nz) bool: those inside obstacles
    /// (and under a coupled liquid), as the grid frames' `solid`; None without a grid.
    #[getter]
    fn grid_solid<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyArray3<bool>>> {
        let fluid = self.grid()?.bounds.fluid_mask();
        Some(fluid.mapv(|f| !f).into_pyarray(py))
    }

    /// Face velocities of the MAC grid: three arrays, the x faces (nx + 1, ny, nz), the y
    /// faces (nx, ny + 1, nz) and the z faces (nx, ny, nz + 1), float64, m/s; None without a
    /// grid.
    #[getter]
    fn grid_faces<'py>(&self, py: Python<'py>) -> Option<[Bound<'py, PyArray3<Real>>; 3]> {
        let u = &self.grid()?.mac.u;
        Some([0, 1, 2].map(|a| u[a].clone().into_pyarray(py)))
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
        let sim = &mut self.run.pipeline.sim;
        let grid = sim.grid.as_mut().ok_or_else(|| {
            PyValueError::new_err(
                "grid faces: the scene has no grid ([grid]); SPH particles' velocities are \
                 written to `velocity`",
            )
        })?;
        grid.set_faces([x.as_array(), y.as_array(), z.as_array()])
            .map_err(|e| PyValueError::new_err(format!("grid faces: {e}")))?;
        self.run.state_edited();
        Ok(())
    }

    /// Cell pressure, (nx, ny, nz) float64, Pa (kinematic with `grid.density` 1); None without
    /// a grid.
    #[getter]
    fn grid_pressure<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyArray3<Real>>> {
        Some(self.grid()?.pressure.clone().into_pyarray(py))
    }

    /// Smoke density per flow cell, (nx, ny, nz) float64, indexed [i, j, k] (cell means of a
    /// finer smoke grid); None without smoke.
    #[getter]
    fn smoke<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyArray3<Real>>> {
        let s = self.grid()?.smoke.as_ref()?;
        Some(s.on_flow_cells(&s.density).into_owned().into_pyarray(py))
    }

    /// The grid's lattice as `eddy.GridGeometry(origin, spacing, dims)`: cell (i, j, k) spans
    /// origin + spacing * [i, i + 1] x [j, j + 1] x [k, k + 1] (m), as the grid frames' root
    /// attributes; None without a grid.
    #[getter]
    fn grid_geometry<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyAny>>> {
        let Some(grid) = self.grid() else {
            return Ok(None);
        };
        let (o, [nx, ny, nz]) = (grid.mac.origin, grid.mac.dims);
        let class = py.import("eddy")?.getattr("GridGeometry")?;
        let geometry = class.call1(((o.x, o.y, o.z), grid.mac.dx, (nx, ny, nz)))?;
        Ok(Some(geometry))
    }

    // ------------------------------------------------------------------ vortex particles

    /// The vortex particles of `medium` ("grid" or "particles"; default: the scene's one set)
    /// as {"position", "vorticity" (n, 3), "radius", "energy", "age" (n,)}. A scene without
    /// them in that medium raises `ValueError` naming the medium that has them, if any.
    #[pyo3(signature = (medium = None))]
    fn vortices<'py>(&self, py: Python<'py>, medium: Option<&str>) -> PyResult<Bound<'py, PyDict>> {
        let sim = &self.run.pipeline.sim;
        let sets = [
            ("grid", &sim.grid_turbulence),
            ("particles", &sim.sph_turbulence),
        ];
        let have: Vec<_> = sets
            .iter()
            .filter_map(|(m, t)| Some((*m, t.as_ref()?)))
            .collect();
        let t = match (medium, have.as_slice()) {
            (Some(m), _) if sets.iter().all(|(name, _)| *name != m) => {
                return Err(PyValueError::new_err(format!(
                    "medium {m:?}: \"grid\" or \"particles\""
                )))
            }
            (_, []) => {
                return Err(PyValueError::new_err(
                    "the scene has no vortex particles: no obstacle has a boundary-layer \
                     database (`abl.database` of an obstacle)",
                ))
            }
            (Some(m), _) => match have.iter().find(|(name, _)| *name == m) {
                Some((_, t)) => *t,
                None => {
                    let other = have[0].0;
                    return Err(PyValueError::new_err(format!(
                        "the scene has no vortex particles in medium {m:?}: its boundary \
                         layers are on the {other}; ask for vortices(\"{other}\")"
                    )));
                }
            },
            (None, [(_, t)]) => *t,
            (None, _) => {
                return Err(PyValueError::new_err(
                    "the scene has vortex particles in both media: pass medium=\"grid\" or \
                     \"particles\"",
                ))
            }
        };
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
        let l = &stats.lattice;
        let d = PyDict::new(py);
        d.set_item("mean_velocity", stacked(py, &f.mean_velocity))?;
        d.set_item("reynolds_stress", stacked(py, &f.reynolds_stress))?;
        d.set_item("k", f.k.into_pyarray(py))?;
        d.set_item("mean_vorticity", stacked(py, &f.mean_vorticity))?;
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
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
