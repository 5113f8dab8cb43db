//! The grid velocity along each line probe as `profile_NAME.csv`, written at the end.

use std::path::{Path, PathBuf};

use super::frame::Frame;
use super::{Output, OutputSpec, RunFile};
use crate::io::IoError;
use crate::metrics::grid_probes::write_profile;
use crate::pipeline::Simulation;

/// The files of [`Profiles`].
pub(super) const FILES: &[RunFile] = &[RunFile::Named("profile_", ".csv")];

/// A line probe: its name, ends and number of points.
#[derive(Debug, Clone, PartialEq)]
pub struct LineProbe {
    pub name: String,
    pub from: [crate::Real; 3],
    pub to: [crate::Real; 3],
    pub points: usize,
}

/// Every line probe of a grid scene.
pub struct Profiles {
    lines: Vec<LineProbe>,
    out: PathBuf,
}

/// Built when a grid scene has line probes.
pub(super) fn build(spec: &OutputSpec, sim: &Simulation) -> Option<Box<dyn Output>> {
    sim.grid.as_ref()?;
    (!spec.profiles.is_empty()).then(|| {
        Box::new(Profiles {
            lines: spec.profiles.clone(),
            out: PathBuf::new(),
        }) as Box<dyn Output>
    })
}

impl Output for Profiles {
    fn name(&self) -> &'static str {
        "profile"
    }

    fn describe(&self, _sim: &Simulation) -> Vec<(&'static str, String)> {
        let line = |p: &LineProbe| {
            (
                "profile",
                format!(
                    "profile_{}.csv: grid velocity along a line, at the end",
                    p.name
                ),
            )
        };
        self.lines.iter().map(line).collect()
    }

    fn open(&mut self, _sim: &Simulation, out: &Path) -> Result<(), IoError> {
        self.out = out.to_path_buf();
        Ok(())
    }

    fn write(&mut self, _frame: &Frame) -> Result<(), IoError> {
        Ok(())
    }

    fn finish(&mut self, sim: &Simulation) -> Result<(), IoError> {
        let Some(grid) = sim.grid.as_ref() else {
            return Ok(());
        };
        for p in &self.lines {
            let path = self.out.join(format!("profile_{}.csv", p.name));
            write_profile(grid, &path, p.from, p.to, p.points)?;
        }
        Ok(())
    }
}
