//! Frame writers: VTK files with a ParaView `.pvd` series and one HDF5 file per kind of frame
//! (particles, grid), written at the scene's output interval into the run's folder.

use std::path::{Path, PathBuf};

use super::turbulence::Turbulence;
use crate::grid::{forces::vorticity, GridSolver};
use crate::io::{
    write_grid_vtk, write_particles_vtk, AttrValue, Field, GridField, GridFrame, Hdf5Frames,
    Hdf5GridFrames, IoError, ParticleFrame, PvdSeries, VtkOptions,
};
use crate::sph::SphSolver;
use crate::vortex::VortexParticles;
use crate::Real;

/// Where each kind of output goes: a scene with one solver keeps the plain names
/// (`metrics.csv`, `frames.h5`); a scene with both prefixes them by kind.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    Particles,
    Grid,
}

impl Kind {
    /// The file name of an output of this kind, `base` with the kind's prefix when `both`.
    pub fn file(self, base: &str, both: bool) -> String {
        match (both, self) {
            (false, _) => base.to_owned(),
            (true, Kind::Particles) => format!("particles_{base}"),
            (true, Kind::Grid) => format!("grid_{base}"),
        }
    }
}

/// The writers a scene asked for, for one kind of frame.
struct Writers<H> {
    out: PathBuf,
    /// The VTK series and how its files store their arrays, when the scene asked for VTK.
    pvd: Option<(PvdSeries, VtkOptions)>,
    hdf5: Option<H>,
    count: usize,
}

impl<H> Writers<H> {
    /// The series `series.pvd` in `out` (with `vtk`) and the HDF5 file `hdf5`, when opened.
    fn new(out: &Path, vtk: Option<VtkOptions>, series: &str, hdf5: Option<H>) -> Self {
        Self {
            out: out.to_path_buf(),
            pvd: vtk.map(|o| (PvdSeries::new(&out.join(format!("{series}.pvd"))), o)),
            hdf5,
            count: 0,
        }
    }

    fn any(&self) -> bool {
        self.pvd.is_some() || self.hdf5.is_some()
    }

    /// Writes `frame` of time `time` as the next VTK file `NAME_NNNNNN.EXT` (with `vtk`) into
    /// the `.pvd` series, and appends it to the HDF5 file (with `append`).
    fn push<F>(
        &mut self,
        frame: &F,
        time: Real,
        (name, ext): (&str, &str),
        vtk: impl FnOnce(&Path, &F, VtkOptions) -> Result<(), IoError>,
        append: impl FnOnce(&mut H, &F) -> Result<(), IoError>,
    ) -> Result<(), IoError> {
        if let Some((pvd, options)) = self.pvd.as_mut() {
            let file = format!("{name}_{:06}.{ext}", self.count);
            vtk(&self.out.join(&file), frame, *options)?;
            pvd.push(time, &file)?;
        }
        if let Some(h5) = self.hdf5.as_mut() {
            append(h5, frame)?;
        }
        self.count += 1;
        Ok(())
    }
}

/// The particle frame writers: `particles.pvd` with `particles_NNNNNN.vtp`, and `frames.h5`.
pub struct ParticleFrames(Writers<Hdf5Frames>);

impl ParticleFrames {
    /// Writers into `out`; `hdf5` names the HDF5 file and its deflate level when the scene
    /// asked for one.
    pub fn new(
        out: &Path,
        vtk: Option<VtkOptions>,
        hdf5: Option<(&str, u8)>,
        attrs: &[(&str, AttrValue)],
        solver: &SphSolver,
    ) -> Result<Self, IoError> {
        let hdf5 = hdf5
            .map(|(name, level)| {
                let mut all = attrs.to_vec();
                all.extend([
                    ("particle_spacing", AttrValue::Real(solver.spacing)),
                    ("particle_mass", AttrValue::Real(solver.fluid.mass)),
                    ("rest_density", AttrValue::Real(solver.fluid.rest_density)),
                ]);
                Ok(Hdf5Frames::create(&out.join(name), &all)?.compressed(level))
            })
            .transpose()?;
        Ok(Self(Writers::new(out, vtk, "particles", hdf5)))
    }

    /// Position, velocity, vorticity (the solver's curl of the velocity, 1/s: a wake shows in
    /// ParaView without post-processing), density, pressure, the hooks' fields and the carried
    /// fields (`abl_vorticity` with a boundary layer), and in the HDF5 frame the fluid's vortex
    /// particles as the group `vortices`.
    pub fn write(
        &mut self,
        solver: &SphSolver,
        vortices: Option<&ParticleFrame>,
    ) -> Result<(), IoError> {
        let w = &mut self.0;
        if !w.any() {
            return Ok(());
        }
        let f = &solver.fluid;
        let omega = solver.vorticity();
        let mut frame = ParticleFrame {
            step: solver.steps(),
            time: solver.time(),
            positions: &f.x,
            fields: vec![
                Field::vector("velocity", &f.v),
                Field::vector("vorticity", &omega),
                Field::scalar("density", &f.density),
                Field::scalar("pressure", &f.pressure),
            ],
        };
        let extra = solver.refinement_fields();
        let carried = f
            .carried
            .iter()
            .map(|(name, data)| (*name, data.as_slice()));
        frame.fields.extend(
            extra
                .into_iter()
                .chain(carried)
                .map(|(name, data)| Field::vector(name, data)),
        );
        w.push(
            &frame,
            frame.time,
            ("particles", "vtp"),
            write_particles_vtk,
            |h5, f| h5.append_with(f, &sets(vortices)),
        )
    }

    /// Frames written so far.
    pub fn count(&self) -> usize {
        self.0.count
    }
}

/// The grid frame writers: `grid.pvd` with `grid_NNNNNN.vti`, and `frames.h5`; with smoke on a
/// finer grid (section 5.2), also `smoke_fine.pvd` with `smoke_fine_NNNNNN.vti` and
/// `smoke_fine.h5` (with HDF5) on that grid, while the flow's frames carry the smoke's cell
/// means.
pub struct GridFrames {
    flow: Writers<Hdf5GridFrames>,
    fine_smoke: Option<Writers<Hdf5GridFrames>>,
}

impl Writers<Hdf5GridFrames> {
    /// The `series.pvd` (with `vtk`) and the HDF5 file `hdf5` (name, deflate level) of one
    /// grid in `out`.
    fn grid(
        out: &Path,
        vtk: Option<VtkOptions>,
        series: &str,
        hdf5: Option<(&str, u8)>,
        attrs: &[(&str, AttrValue)],
    ) -> Result<Self, IoError> {
        let hdf5 = hdf5
            .map(|(name, level)| {
                Ok::<_, IoError>(Hdf5GridFrames::create(&out.join(name), attrs)?.compressed(level))
            })
            .transpose()?;
        Ok(Self::new(out, vtk, series, hdf5))
    }
}

/// The series (and HDF5 file stem) of the smoke on its fine grid.
const FINE_SMOKE: &str = "smoke_fine";

impl GridFrames {
    /// Writers into `out` for `solver`'s frames; `hdf5` names the HDF5 file and its deflate
    /// level when the scene asked for one.
    pub fn new(
        out: &Path,
        vtk: Option<VtkOptions>,
        hdf5: Option<(&str, u8)>,
        attrs: &[(&str, AttrValue)],
        solver: &GridSolver,
    ) -> Result<Self, IoError> {
        let fine = solver.smoke.as_ref().is_some_and(|s| s.fine.is_some());
        let fine_h5 = format!("{FINE_SMOKE}.h5");
        Ok(Self {
            flow: Writers::grid(out, vtk, "grid", hdf5, attrs)?,
            fine_smoke: fine
                .then(|| {
                    let fine = hdf5.map(|(_, level)| (fine_h5.as_str(), level));
                    Writers::grid(out, vtk, FINE_SMOKE, fine, attrs)
                })
                .transpose()?,
        })
    }

    /// Velocity, vorticity, pressure, smoke, temperature, the obstacle cells and, with
    /// `turbulence`, the boundary-layer field `abl_vorticity`, and in the HDF5 frame the
    /// grid's vortex particles as the group `vortices`; the fine smoke into its own series.
    pub fn write(
        &mut self,
        solver: &GridSolver,
        turbulence: Option<&Turbulence>,
        vortices: Option<&ParticleFrame>,
    ) -> Result<(), IoError> {
        if !self.flow.any() {
            return Ok(());
        }
        let vel = solver.mac.cell_velocity();
        let omega = vorticity(&solver.mac);
        let solid = solver
            .bounds
            .fluid_mask()
            .mapv(|f| if f { 0.0 } else { 1.0 });
        let mut fields = vec![
            GridField::vector("velocity", [vel[0].view(), vel[1].view(), vel[2].view()]),
            GridField::vector(
                "vorticity",
                [omega[0].view(), omega[1].view(), omega[2].view()],
            ),
            GridField::scalar("pressure", solver.pressure.view()),
            GridField::scalar("solid", solid.view()),
        ];
        if let Some([x, y, z]) = turbulence.and_then(|t| t.abl.as_ref()) {
            fields.push(GridField::vector(
                "abl_vorticity",
                [x.view(), y.view(), z.view()],
            ));
        }
        let smoke = solver.smoke.as_ref();
        let density = smoke.map(|s| s.on_flow_cells(&s.density));
        let temperature = smoke.and_then(|s| Some(s.on_flow_cells(s.temperature.as_ref()?)));
        fields.extend(
            density
                .as_ref()
                .map(|d| GridField::scalar("smoke", d.view())),
        );
        fields.extend(
            temperature
                .as_ref()
                .map(|t| GridField::scalar("temperature", t.view())),
        );
        let frame = GridFrame {
            step: solver.steps(),
            time: solver.time(),
            origin: solver.mac.origin,
            spacing: solver.mac.dx,
            dims: solver.mac.dims,
            fields,
        };
        self.flow.push(
            &frame,
            frame.time,
            ("grid", "vti"),
            write_grid_vtk,
            |h5, f| h5.append_with(f, &sets(vortices)),
        )?;
        if let (Some(w), Some(s)) = (self.fine_smoke.as_mut(), smoke) {
            let grid = &s.fine.as_ref().expect("a fine series for fine smoke").mac;
            let mut fields = vec![GridField::scalar("smoke", s.density.view())];
            fields.extend(
                s.temperature
                    .as_ref()
                    .map(|t| GridField::scalar("temperature", t.view())),
            );
            let frame = GridFrame {
                fields,
                origin: grid.origin,
                spacing: grid.dx,
                dims: grid.dims,
                ..frame
            };
            w.push(
                &frame,
                frame.time,
                (FINE_SMOKE, "vti"),
                write_grid_vtk,
                |h5, f| h5.append(f),
            )?;
        }
        Ok(())
    }

    /// Frames written so far.
    pub fn count(&self) -> usize {
        self.flow.count
    }

    /// The time-averaged velocity as `average.vti`, stored as `options` say, when the grid
    /// keeps one.
    pub fn write_average(&self, solver: &GridSolver, options: VtkOptions) -> Result<(), IoError> {
        let Some((_, avg)) = &solver.average else {
            return Ok(());
        };
        let Some(mean) = avg.mean(&solver.mac) else {
            return Ok(());
        };
        let vel = mean.cell_velocity();
        let frame = GridFrame {
            step: solver.steps(),
            time: solver.time(),
            origin: mean.origin,
            spacing: mean.dx,
            dims: mean.dims,
            fields: vec![GridField::vector(
                "velocity_mean",
                [vel[0].view(), vel[1].view(), vel[2].view()],
            )],
        };
        write_grid_vtk(&self.flow.out.join("average.vti"), &frame, options)
    }
}

/// The HDF5 group of a frame that holds its medium's vortex particles.
const VORTEX_GROUP: &str = "vortices";

/// The particle sets written into an HDF5 frame beside its own data.
fn sets<'a>(vortices: Option<&'a ParticleFrame<'a>>) -> Vec<(&'static str, &'a ParticleFrame<'a>)> {
    vortices.map(|v| (VORTEX_GROUP, v)).into_iter().collect()
}

/// The per-particle values of a vortex set that it does not store, computed once per frame.
pub struct VortexValues<'a> {
    particles: &'a VortexParticles,
    radius: Vec<Real>,
    energy: Vec<Real>,
}

impl<'a> VortexValues<'a> {
    pub fn of(particles: &'a VortexParticles) -> Self {
        let n = particles.len();
        Self {
            particles,
            radius: (0..n).map(|i| particles.radius(i)).collect(),
            energy: (0..n).map(|i| particles.energy(i)).collect(),
        }
    }

    /// Position, vorticity vector (1/s), radius `sqrt(6) sigma` (m), kernel energy (m^5/s^2)
    /// and age (s) of every particle.
    pub fn frame(&self, step: u64, time: Real) -> ParticleFrame<'_> {
        let p = self.particles;
        ParticleFrame {
            step,
            time,
            positions: &p.x,
            fields: vec![
                Field::vector("vorticity", &p.omega),
                Field::scalar("radius", &self.radius),
                Field::scalar("energy", &self.energy),
                Field::scalar("age", &p.age),
            ],
        }
    }
}

/// The vortex particles of a scene with boundary layers as a VTK series, `NAME.pvd` with
/// `NAME_NNNNNN.vtp`, NAME `vortices` (`grid_vortices` and `particles_vortices` in a coupled
/// scene, which has a set in each medium). In HDF5 they are a group of their medium's frames.
pub struct VortexFrames(Writers<()>, String);

impl VortexFrames {
    /// The series in `out` named `name`, written when `vtk`.
    pub fn new(out: &Path, name: &str, vtk: Option<VtkOptions>) -> Self {
        Self(Writers::new(out, vtk, name, None), name.to_owned())
    }

    /// Writes the next file of the series.
    pub fn write(&mut self, frame: &ParticleFrame) -> Result<(), IoError> {
        let w = &mut self.0;
        if !w.any() {
            return Ok(());
        }
        w.push(
            frame,
            frame.time,
            (&self.1, "vtp"),
            write_particles_vtk,
            |(), _| Ok(()),
        )
    }
}

/// Whether `name` is a file a run writes (see the table in docs/src/outputs.md), so that a run into
/// a folder can clear an earlier run's files and ParaView never mixes two runs.
pub fn is_run_output(name: &str) -> bool {
    const FIXED: [&str; 8] = [
        "scene.toml",
        "average.vti",
        "particles.pvd",
        "grid.pvd",
        "smoke_fine.pvd",
        "smoke_fine.h5",
        "smoke_fine.xmf",
        "smoke_fine_points.h5",
    ];
    // Written once per medium in a scene with both, as `particles_NAME` and `grid_NAME`.
    const PER_MEDIUM: [&str; 6] = [
        "metrics.csv",
        "probes.csv",
        "frames.h5",
        "frames.xmf",
        "frames_points.h5",
        "vortices.pvd",
    ];
    let six_digits =
        |n: Option<&str>| n.is_some_and(|n| n.len() == 6 && n.bytes().all(|b| b.is_ascii_digit()));
    let numbered = |s: &str, prefix: &str, ext: &str| {
        six_digits(
            s.strip_prefix(prefix)
                .and_then(|rest| rest.strip_suffix(ext)),
        )
    };
    let unprefixed = name
        .strip_prefix("particles_")
        .or_else(|| name.strip_prefix("grid_"))
        .unwrap_or(name);
    FIXED.contains(&name)
        || PER_MEDIUM.contains(&unprefixed)
        || numbered(unprefixed, "vortices_", ".vtp")
        || numbered(name, "particles_", ".vtp")
        || numbered(name, "grid_", ".vti")
        || numbered(name, "smoke_fine_", ".vti")
        || numbered(name, "smoke_fine_", ".h5")
        || numbered(unprefixed, "frames_", ".h5")
        || (name.starts_with("profile_") && name.ends_with(".csv"))
}

/// Removes the files of an earlier run from `out` (only names [`is_run_output`] accepts);
/// returns how many.
pub fn remove_earlier_outputs(out: &Path) -> Result<usize, IoError> {
    let io = |action, source| IoError::Io {
        path: out.to_path_buf(),
        action,
        source,
    };
    let mut removed = 0;
    for entry in std::fs::read_dir(out).map_err(|e| io("listing the output folder", e))? {
        let entry = entry.map_err(|e| io("listing the output folder", e))?;
        let is_file = entry.file_type().is_ok_and(|t| t.is_file());
        if is_file && entry.file_name().to_str().is_some_and(is_run_output) {
            std::fs::remove_file(entry.path())
                .map_err(|e| io("removing an earlier run's output", e))?;
            removed += 1;
        }
    }
    Ok(removed)
}
