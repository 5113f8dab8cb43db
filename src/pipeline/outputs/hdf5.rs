//! HDF5 frames with an XDMF description beside them: `frames.h5` (each frame its own file
//! `frames_NNNNNN.h5`, the index listing only complete ones) per medium, each medium's vortex
//! particles as the group `vortices` of its frames, `smoke_fine.h5` with the smoke on its finer
//! grid, and in a scene with both media one `frames.h5` and `frames.xmf` that open the two
//! series together.

use std::path::Path;

use super::frame::{vortex_sets, Frame};
use super::vtk::{fine_smoke_line, FINE_SMOKE};
use super::{Kind, Output, OutputSpec, RunFile};
use crate::io::{
    write_includes, write_links, AttrValue, Hdf5Frames, Hdf5GridFrames, IoError, ParticleFrame,
};
use crate::pipeline::Simulation;
use crate::state::{Restorer, Saver};
use crate::Real;

/// The files of [`Hdf5Output`] (the XDMF and grid points files are named by `crate::io` after
/// their index).
pub(super) const FILES: &[RunFile] = &[
    RunFile::PerMedium("frames.h5"),
    RunFile::PerMedium("frames.xmf"),
    RunFile::PerMedium("frames_points.h5"),
    RunFile::Numbered {
        stem: "frames_",
        ext: ".h5",
        per_medium: true,
    },
    RunFile::Fixed("smoke_fine.h5"),
    RunFile::Fixed("smoke_fine.xmf"),
    RunFile::Fixed("smoke_fine_points.h5"),
    RunFile::Numbered {
        stem: "smoke_fine_",
        ext: ".h5",
        per_medium: false,
    },
];

/// The HDF5 group of a frame that holds its medium's vortex particles.
const VORTEX_GROUP: &str = "vortices";

/// The HDF5 frame series of every medium of a run.
pub struct Hdf5Output {
    level: u8,
    interval: Real,
    attrs: Vec<(&'static str, AttrValue)>,
    /// Whether the scene has both media (prefixed series and a joining `frames.h5`).
    both: bool,
    particles: Option<Hdf5Frames>,
    grid: Option<Hdf5GridFrames>,
    fine_smoke: Option<Hdf5GridFrames>,
}

/// Built when `output.hdf5` is on.
pub(super) fn build(spec: &OutputSpec, sim: &Simulation) -> Option<Box<dyn Output>> {
    let level = spec.hdf5.then_some(spec.compression)?;
    Some(Box::new(Hdf5Output {
        level,
        interval: spec.interval,
        attrs: spec.attrs.clone(),
        both: sim.both_media(),
        particles: None,
        grid: None,
        fine_smoke: None,
    }))
}

impl Hdf5Output {
    fn file(&self, kind: Kind) -> String {
        kind.file("frames.h5", self.both)
    }
}

impl Output for Hdf5Output {
    fn name(&self) -> &'static str {
        "hdf5"
    }

    fn describe(&self, sim: &Simulation) -> Vec<(&'static str, String)> {
        let every = self.interval;
        let with_vortices = vortex_sets(sim);
        let media = [
            (sim.sph.is_some(), Kind::Particles, "particles"),
            (sim.grid.is_some(), Kind::Grid, "grid"),
        ];
        let mut lines: Vec<_> = media
            .iter()
            .filter(|m| m.0)
            .map(|&(_, kind, name)| {
                let vortices = if with_vortices.iter().any(|(k, _)| *k == kind) {
                    ", vortex particles in each frame's group `vortices`"
                } else {
                    ""
                };
                (
                    "hdf5",
                    format!("{} ({name}{vortices}) every {every} s", self.file(kind)),
                )
            })
            .collect();
        if self.both {
            lines.push((
                "hdf5",
                "frames.h5: /particles and /grid, links to both series, open together".into(),
            ));
        }
        if has_fine_smoke(sim) {
            lines.push(("smoke", fine_smoke_line(sim, "smoke_fine.h5", every)));
        }
        lines
    }

    fn open(&mut self, sim: &Simulation, out: &Path) -> Result<(), IoError> {
        self.open_series(sim, out, None)
    }

    fn write(&mut self, frame: &Frame) -> Result<(), IoError> {
        if let (Some(h5), Some(f)) = (self.particles.as_mut(), frame.particles()) {
            let vortices = frame.vortices(Kind::Particles);
            h5.append_with(&f, &sets(vortices.as_ref()))?;
        }
        if let (Some(h5), Some(f)) = (self.grid.as_mut(), frame.grid()) {
            let vortices = frame.vortices(Kind::Grid);
            h5.append_with(&f, &sets(vortices.as_ref()))?;
        }
        if let (Some(h5), Some(f)) = (self.fine_smoke.as_mut(), frame.fine_smoke()) {
            h5.append(&f)?;
        }
        Ok(())
    }

    fn frames(&self) -> usize {
        let p = self.particles.as_ref().map_or(0, |h| h.len());
        let g = self.grid.as_ref().map_or(0, |h| h.len());
        p.max(g) as usize
    }

    /// Each series' frames so far, as the XDMF descriptions its index lists.
    fn save(&self, into: &mut Saver) {
        let series = [
            ("particles", self.particles.as_ref().map(|h| h.listing())),
            ("grid", self.grid.as_ref().map(|h| h.listing())),
            ("fine_smoke", self.fine_smoke.as_ref().map(|h| h.listing())),
        ];
        for (name, listing) in series {
            if let Some(listing) = listing {
                into.bytes(name, listing.join(SEPARATOR).as_bytes());
            }
        }
    }

    /// Each series goes on after the checkpoint's frames (frame files written after it are
    /// overwritten as the run catches up).
    fn resume(&mut self, sim: &Simulation, out: &Path, from: &Restorer) -> Result<(), IoError> {
        self.open_series(sim, out, Some(from))
    }
}

/// Between two frames' XDMF descriptions in a checkpoint.
const SEPARATOR: &str = "\0";

impl Hdf5Output {
    /// Creates every series in `out`, or with `resumed` goes on with them from a checkpoint.
    fn open_series(
        &mut self,
        sim: &Simulation,
        out: &Path,
        resumed: Option<&Restorer>,
    ) -> Result<(), IoError> {
        let level = self.level;
        let listing = |name: &str| -> Result<Option<Vec<String>>, IoError> {
            let Some(from) = resumed else {
                return Ok(None);
            };
            let bytes = from
                .bytes(name)
                .map_err(|e| IoError::invalid(out, e.to_string()))?;
            let text = String::from_utf8_lossy(&bytes).into_owned();
            Ok(Some(if text.is_empty() {
                Vec::new()
            } else {
                text.split(SEPARATOR).map(str::to_owned).collect()
            }))
        };
        if let Some(sph) = sim.sph.as_ref() {
            let mut attrs = self.attrs.clone();
            attrs.extend([
                ("particle_spacing", AttrValue::Real(sph.spacing)),
                ("particle_mass", AttrValue::Real(sph.fluid.mass)),
                ("rest_density", AttrValue::Real(sph.fluid.rest_density)),
            ]);
            let path = out.join(self.file(Kind::Particles));
            self.particles = Some(match listing("particles")? {
                Some(l) => Hdf5Frames::resumed(&path, &attrs, level, l)?,
                None => Hdf5Frames::create(&path, &attrs)?.compressed(level),
            });
        }
        let grid_series = |file: &str, name: &str| {
            let path = out.join(file);
            Ok::<_, IoError>(match listing(name)? {
                Some(l) => Hdf5GridFrames::resumed(&path, &self.attrs, level, l)?,
                None => Hdf5GridFrames::create(&path, &self.attrs)?.compressed(level),
            })
        };
        if sim.grid.is_some() {
            self.grid = Some(grid_series(&self.file(Kind::Grid), "grid")?);
            if has_fine_smoke(sim) {
                self.fine_smoke = Some(grid_series(&format!("{FINE_SMOKE}.h5"), "fine_smoke")?);
            }
        }
        if self.both {
            // One file that opens both series: /particles and /grid link to their indexes.
            let links = [Kind::Particles, Kind::Grid].map(|k| self.file(k));
            write_links(
                &out.join("frames.h5"),
                &self.attrs,
                &[("particles", &links[0]), ("grid", &links[1])],
            )?;
            let series = [Kind::Particles, Kind::Grid].map(|k| k.file("frames.xmf", true));
            write_includes(&out.join("frames.xmf"), &[&series[0], &series[1]])?;
        }
        Ok(())
    }
}

fn has_fine_smoke(sim: &Simulation) -> bool {
    sim.grid
        .as_ref()
        .is_some_and(|g| g.smoke.as_ref().is_some_and(|s| s.fine.is_some()))
}

/// The particle sets written into an HDF5 frame beside its own data.
fn sets<'a>(vortices: Option<&'a ParticleFrame<'a>>) -> Vec<(&'static str, &'a ParticleFrame<'a>)> {
    vortices.map(|v| (VORTEX_GROUP, v)).into_iter().collect()
}
