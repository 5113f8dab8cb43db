//! VTK frames for ParaView: `particles.pvd` with `particles_NNNNNN.vtp`, `grid.pvd` with
//! `grid_NNNNNN.vti`, `smoke_fine.pvd` with the smoke on its finer grid, and each medium's
//! vortex particles as `vortices.pvd` (`grid_vortices` and `particles_vortices` in a coupled
//! scene), every `.pvd` rewritten after each frame so a run cut short keeps a valid series.

use std::path::{Path, PathBuf};

use super::frame::{vortex_sets, Frame};
use super::{Kind, Output, OutputSpec, RunFile};
use crate::io::{write_grid_vtk, write_particles_vtk, IoError, PvdSeries, VtkOptions};
use crate::pipeline::Simulation;
use crate::state::{Restorer, Saver};
use crate::Real;

/// The stem of the fine smoke's series.
pub(super) const FINE_SMOKE: &str = "smoke_fine";

/// The files of [`VtkFrames`].
pub(super) const FILES: &[RunFile] = &[
    RunFile::Fixed("particles.pvd"),
    RunFile::Numbered {
        stem: "particles_",
        ext: ".vtp",
        per_medium: false,
    },
    RunFile::Fixed("grid.pvd"),
    RunFile::Numbered {
        stem: "grid_",
        ext: ".vti",
        per_medium: false,
    },
    RunFile::Fixed("smoke_fine.pvd"),
    RunFile::Numbered {
        stem: "smoke_fine_",
        ext: ".vti",
        per_medium: false,
    },
    RunFile::PerMedium("vortices.pvd"),
    RunFile::Numbered {
        stem: "vortices_",
        ext: ".vtp",
        per_medium: true,
    },
];

/// What a series holds, which says how its files are written.
#[derive(Clone, Copy)]
enum Content {
    Particles,
    Grid,
    FineSmoke,
    Vortices(Kind),
}

/// One `NAME.pvd` series with its numbered files `NAME_NNNNNN.EXT`.
struct Series {
    content: Content,
    stem: String,
    ext: &'static str,
    pvd: Option<PvdSeries>,
    count: usize,
}

/// The VTK series of every medium of a run.
pub struct VtkFrames {
    options: VtkOptions,
    interval: Real,
    series: Vec<Series>,
    out: PathBuf,
}

/// Built when `output.vtk` is on.
pub(super) fn build(spec: &OutputSpec, sim: &Simulation) -> Option<Box<dyn Output>> {
    let options = spec.vtk.then_some(spec.vtk_options)?;
    let series = |content, stem: &str, ext| Series {
        content,
        stem: stem.to_owned(),
        ext,
        pvd: None,
        count: 0,
    };
    let mut all: Vec<Series> = vortex_sets(sim)
        .into_iter()
        .map(|(kind, name)| series(Content::Vortices(kind), &name, "vtp"))
        .collect();
    if sim.sph.is_some() {
        all.push(series(Content::Particles, "particles", "vtp"));
    }
    if let Some(grid) = sim.grid.as_ref() {
        all.push(series(Content::Grid, "grid", "vti"));
        if grid.smoke.as_ref().is_some_and(|s| s.fine.is_some()) {
            all.push(series(Content::FineSmoke, FINE_SMOKE, "vti"));
        }
    }
    Some(Box::new(VtkFrames {
        options,
        interval: spec.interval,
        series: all,
        out: PathBuf::new(),
    }))
}

impl Output for VtkFrames {
    fn name(&self) -> &'static str {
        "vtk"
    }

    fn describe(&self, sim: &Simulation) -> Vec<(&'static str, String)> {
        let every = self.interval;
        self.series
            .iter()
            .map(|s| match s.content {
                Content::Vortices(_) => (
                    "vtk",
                    format!("vortex particles + {}.pvd every {every} s", s.stem),
                ),
                Content::Particles | Content::Grid => (
                    "vtk",
                    format!("VTK frames + {}.pvd every {every} s", s.stem),
                ),
                Content::FineSmoke => (
                    "smoke",
                    fine_smoke_line(sim, "VTK frames + smoke_fine.pvd", every),
                ),
            })
            .collect()
    }

    fn open(&mut self, _sim: &Simulation, out: &Path) -> Result<(), IoError> {
        self.out = out.to_path_buf();
        for s in &mut self.series {
            s.pvd = Some(PvdSeries::new(&out.join(format!("{}.pvd", s.stem))));
        }
        Ok(())
    }

    fn write(&mut self, frame: &Frame) -> Result<(), IoError> {
        for s in &mut self.series {
            let Some(pvd) = s.pvd.as_mut() else {
                continue;
            };
            let file = format!("{}_{:06}.{}", s.stem, s.count, s.ext);
            let path = self.out.join(&file);
            let time = match s.content {
                Content::Particles => frame
                    .particles()
                    .map(|f| write_particles_vtk(&path, &f, self.options).map(|()| f.time)),
                Content::Grid => frame
                    .grid()
                    .map(|f| write_grid_vtk(&path, &f, self.options).map(|()| f.time)),
                Content::FineSmoke => frame
                    .fine_smoke()
                    .map(|f| write_grid_vtk(&path, &f, self.options).map(|()| f.time)),
                Content::Vortices(kind) => frame
                    .vortices(kind)
                    .map(|f| write_particles_vtk(&path, &f, self.options).map(|()| f.time)),
            };
            if let Some(time) = time.transpose()? {
                pvd.push(time, &file)?;
                s.count += 1;
            }
        }
        Ok(())
    }

    fn frames(&self) -> usize {
        let media = self
            .series
            .iter()
            .filter(|s| matches!(s.content, Content::Particles | Content::Grid));
        media.map(|s| s.count).max().unwrap_or(0)
    }

    /// Each series' frame times: its files are numbered in order.
    fn save(&self, into: &mut Saver) {
        for s in &self.series {
            let times: Vec<Real> = s
                .pvd
                .iter()
                .flat_map(|p| p.entries())
                .map(|e| e.0)
                .collect();
            into.reals(&s.stem, &times);
        }
    }

    /// Each series goes on numbering from its checkpoint's count, its `.pvd` listing the frames
    /// written before it (any written after the checkpoint are overwritten as the run catches
    /// up).
    fn resume(&mut self, _sim: &Simulation, out: &Path, from: &Restorer) -> Result<(), IoError> {
        self.out = out.to_path_buf();
        for s in &mut self.series {
            let times = from
                .reals(&s.stem)
                .map_err(|e| IoError::invalid(out, e.to_string()))?;
            let entries: Vec<(Real, String)> = times
                .iter()
                .enumerate()
                .map(|(k, &t)| (t, format!("{}_{k:06}.{}", s.stem, s.ext)))
                .collect();
            s.count = entries.len();
            s.pvd = Some(PvdSeries::resumed(
                &out.join(format!("{}.pvd", s.stem)),
                entries,
            ));
        }
        Ok(())
    }
}

/// The plan's line on the smoke's own grid, naming the files `files` that hold it.
pub(super) fn fine_smoke_line(sim: &Simulation, files: &str, every: Real) -> String {
    let dims = sim
        .grid
        .as_ref()
        .and_then(|g| Some(g.smoke.as_ref()?.fine.as_ref()?.mac.dims))
        .unwrap_or_default();
    format!(
        "{files}: smoke on its {dims:?} grid every {every} s (the grid frames hold its cell \
         means)"
    )
}
