//! The running statistics of each medium (`[statistics]`), rewritten at every frame time once
//! a sample is in: `statistics.h5` (h5py) with `statistics.xmf` beside it (ParaView), and with
//! `output.vtk` `statistics.vti`; `grid_statistics.*` and `particles_statistics.*` in a scene
//! with both media. Each file is replaced atomically, so a kill keeps the previous one whole.
//!
//! Datasets, each per lattice cell `[i, j, k]` (NaN where no sample found fluid):
//! `mean_velocity` (3), `reynolds_stress` (6: xx, yy, zz, xy, yz, xz, VTK's order for
//! symmetric tensors), `k`, `mean_vorticity` (3), `mean_enstrophy`, `samples` (the samples
//! that found fluid there); root attributes `format` ("eddy-statistics"), `format_version`,
//! the lattice's `origin`, `spacing`, `dims`, `time_from` and `time_to` (the time the samples
//! span), `sample_count`, `medium`, the scene's name and seed. Each station's profile is
//! `station_NAME.csv` (`crate::metrics::stations`).

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use ndarray::{Array3, ArrayView3};

use super::frame::Frame;
use super::{Kind, Output, OutputSpec, RunFile};
use crate::io::{
    write_atomic, write_grid_file, write_grid_vtk, AttrValue, GridField, GridFrame, IoError,
    VtkOptions,
};
use crate::metrics::stations::Station;
use crate::metrics::statistics::{CellMoments, FlowStatistics};
use crate::pipeline::Simulation;
use crate::Real;

/// The files of [`StatisticsOutput`].
pub(super) const FILES: &[RunFile] = &[
    RunFile::PerMedium("statistics.h5"),
    RunFile::PerMedium("statistics.xmf"),
    RunFile::PerMedium("statistics_points.h5"),
    RunFile::PerMedium("statistics.vti"),
    RunFile::Named("station_", ".csv"),
    RunFile::Named("grid_station_", ".csv"),
    RunFile::Named("particles_station_", ".csv"),
];

/// Value of the root attribute `format`.
pub const STATISTICS_FORMAT: &str = "eddy-statistics";
/// Value of the root attribute `format_version`; raised when the layout changes.
pub const STATISTICS_FORMAT_VERSION: i64 = 1;

/// The statistics files of every medium.
pub struct StatisticsOutput {
    vtk: Option<VtkOptions>,
    level: u8,
    attrs: Vec<(&'static str, AttrValue)>,
    both: bool,
    out: PathBuf,
}

/// Built when the scene has `[statistics]` (its stage put the accumulators in the simulation).
pub(super) fn build(spec: &OutputSpec, sim: &Simulation) -> Option<Box<dyn Output>> {
    (!sim.statistics.is_empty()).then(|| {
        Box::new(StatisticsOutput {
            vtk: spec.vtk.then_some(spec.vtk_options),
            level: spec.compression,
            attrs: spec.attrs.clone(),
            both: sim.statistics.len() > 1,
            out: PathBuf::new(),
        }) as Box<dyn Output>
    })
}

impl StatisticsOutput {
    fn file(&self, kind: Kind, base: &str) -> PathBuf {
        self.out.join(kind.file(base, self.both))
    }

    /// Writes one medium's files.
    fn write_medium(
        &self,
        kind: Kind,
        stats: &FlowStatistics,
        sim: &Simulation,
    ) -> Result<(), IoError> {
        let h5 = self.file(kind, "statistics.h5");
        let vti = self.file(kind, "statistics.vti");
        let vtk = self.vtk.map(|o| (vti.as_path(), o));
        let at = (sim.steps(), sim.time());
        write_statistics(&h5, vtk, stats, kind, at, &self.attrs, self.level)?;
        for station in &stats.stations {
            let path = self.file(kind, &format!("station_{}.csv", station.spec.name));
            write_profile(&path, station, &stats.cells)?;
        }
        Ok(())
    }
}

/// Writes `stats` (of `medium`, at step and time `at`) as the HDF5 file `h5` with its XDMF
/// (and with `vtk` as that `.vti`), with `attrs` among the root attributes; nothing before
/// the first sample.
pub fn write_statistics(
    h5: &Path,
    vtk: Option<(&Path, VtkOptions)>,
    stats: &FlowStatistics,
    medium: Kind,
    (step, time): (u64, Real),
    attrs: &[(&'static str, AttrValue)],
    level: u8,
) -> Result<(), IoError> {
    let Some((from, to)) = stats.span else {
        return Ok(());
    };
    let f = stats.fields();
    let frame = GridFrame {
        step,
        time,
        origin: stats.lattice.origin,
        spacing: stats.lattice.spacing,
        dims: stats.lattice.dims,
        fields: vec![
            GridField::vector("mean_velocity", views(&f.mean_velocity)),
            GridField::tensor("reynolds_stress", views(&f.reynolds_stress)),
            GridField::scalar("k", f.k.view()),
            GridField::vector("mean_vorticity", views(&f.mean_vorticity)),
            GridField::scalar("mean_enstrophy", f.mean_enstrophy.view()),
            GridField::scalar("samples", f.samples.view()),
        ],
    };
    let medium = match medium {
        Kind::Grid => "grid",
        Kind::Particles => "particles",
    };
    let mut all = vec![
        ("format", AttrValue::from(STATISTICS_FORMAT)),
        ("format_version", AttrValue::Int(STATISTICS_FORMAT_VERSION)),
        ("medium", AttrValue::from(medium)),
        ("time_from", AttrValue::Real(from)),
        ("time_to", AttrValue::Real(to)),
        ("sample_count", AttrValue::Int(stats.steps as i64)),
    ];
    all.extend(attrs.iter().cloned());
    write_grid_file(h5, &frame, &all, level)?;
    if let Some((path, options)) = vtk {
        write_grid_vtk(path, &frame, options)?;
    }
    Ok(())
}

/// A station's profile as CSV, rewritten whole: per bin its centre along the axis, U, k, their
/// 95 % half-widths (NaN before two batches are complete) and the complete batches.
fn write_profile(path: &Path, station: &Station, cells: &[CellMoments]) -> Result<(), IoError> {
    let mut text = String::from("position,u,v,w,k,u_ci,v_ci,w_ci,k_ci,batches\n");
    for b in station.profile(cells) {
        let [u, v, w] = b.mean;
        let [cu, cv, cw] = b.mean_ci;
        let _ = writeln!(
            text,
            "{},{u},{v},{w},{},{cu},{cv},{cw},{},{}",
            b.position,
            b.k,
            b.k_ci,
            station.batches()
        );
    }
    write_atomic(path, |w| w.write_all(text.as_bytes()))
}

impl Output for StatisticsOutput {
    fn name(&self) -> &'static str {
        "statistics"
    }

    fn describe(&self, sim: &Simulation) -> Vec<(&'static str, String)> {
        sim.statistics
            .iter()
            .map(|m| {
                let h5 = m.kind.file("statistics.h5", self.both);
                let vti = m.kind.file("statistics.vti", self.both);
                let mut files = match self.vtk {
                    Some(_) => format!("{h5} (+ .xmf), {vti}"),
                    None => format!("{h5} (+ .xmf)"),
                };
                for s in &m.stats.stations {
                    let csv = m
                        .kind
                        .file(&format!("station_{}.csv", s.spec.name), self.both);
                    files += &format!(", {csv}");
                }
                (
                    "statistics",
                    format!("{files}: the running statistics, rewritten at every frame time"),
                )
            })
            .collect()
    }

    fn open(&mut self, _sim: &Simulation, out: &Path) -> Result<(), IoError> {
        self.out = out.to_path_buf();
        Ok(())
    }

    fn write(&mut self, frame: &Frame) -> Result<(), IoError> {
        let sim = frame.sim;
        sim.statistics
            .iter()
            .try_for_each(|m| self.write_medium(m.kind, &m.stats, sim))
    }
}

/// Views of each component.
fn views<const N: usize>(a: &[Array3<Real>; N]) -> [ArrayView3<'_, Real>; N] {
    a.each_ref().map(|x| x.view())
}
