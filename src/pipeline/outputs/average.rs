//! The time-averaged grid velocity as `average.vti`, written at the end of a run whose grid
//! keeps one.

use std::path::{Path, PathBuf};

use super::frame::Frame;
use super::{Output, OutputSpec, RunFile};
use crate::io::{write_grid_vtk, GridField, GridFrame, IoError, VtkOptions};
use crate::pipeline::Simulation;

/// The file of [`Average`].
pub(super) const FILES: &[RunFile] = &[RunFile::Fixed("average.vti")];

/// `average.vti`, stored as the VTK frames are (`output.precision`, `output.compression`).
pub struct Average {
    options: VtkOptions,
    path: PathBuf,
}

/// Built when the grid keeps a time average, whatever the frame formats.
pub(super) fn build(spec: &OutputSpec, sim: &Simulation) -> Option<Box<dyn Output>> {
    sim.grid.as_ref()?.average.as_ref()?;
    Some(Box::new(Average {
        options: spec.vtk_options,
        path: PathBuf::new(),
    }))
}

impl Output for Average {
    fn name(&self) -> &'static str {
        "average"
    }

    fn describe(&self, _sim: &Simulation) -> Vec<(&'static str, String)> {
        vec![(
            "average",
            "average.vti: the time-averaged grid velocity, at the end".into(),
        )]
    }

    fn open(&mut self, _sim: &Simulation, out: &Path) -> Result<(), IoError> {
        self.path = out.join("average.vti");
        Ok(())
    }

    fn write(&mut self, _frame: &Frame) -> Result<(), IoError> {
        Ok(())
    }

    fn finish(&mut self, sim: &Simulation) -> Result<(), IoError> {
        let Some(solver) = sim.grid.as_ref() else {
            return Ok(());
        };
        let Some(mean) = solver
            .average
            .as_ref()
            .and_then(|(_, a)| a.mean(&solver.mac))
        else {
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
        write_grid_vtk(&self.path, &frame, self.options)
    }
}
