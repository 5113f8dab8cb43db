//! The plan of a run, printed by `eddy run --plan`: read from the built stages and writers
//! themselves, so it lists exactly what runs.

use std::fmt;

use super::build::Pipeline;
use super::footprint::available_memory;
use super::order::SceneKind;
use super::outputs::CHECKPOINT_FILE;

/// One stage of a step, with the parts it runs inside.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct PlannedStage {
    pub name: &'static str,
    pub detail: String,
    pub parts: Vec<(&'static str, String)>,
}

/// The stages of a step in order, what is written at frame times, and how the solvers share
/// the clock.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Plan {
    pub stages: Vec<PlannedStage>,
    pub outputs: Vec<(&'static str, String)>,
    pub clock: String,
    /// The memory estimate, one line.
    pub memory: String,
}

impl Plan {
    /// The plan of a built pipeline.
    pub fn of(p: &Pipeline) -> Self {
        let stages = p
            .stages
            .iter()
            .map(|s| {
                let (detail, parts) = s.describe(&p.sim);
                PlannedStage {
                    name: s.name(),
                    detail,
                    parts,
                }
            })
            .collect();
        let mut outputs = p.outputs.describe(&p.sim);
        outputs.push(("checkpoint", checkpoint_line(p)));
        let clock = match p.kind {
            SceneKind::Coupled => "one dt for both solvers, the smaller of their stable \
                                        steps; the water and the air exchange momentum across \
                                        the surface each step (stages coupling and surface \
                                        pressure)"
                .to_owned(),
            SceneKind::SideBySide => {
                "one dt for both solvers, the smaller of their stable steps; no \
                             exchange between the grid and the SPH fluid (each moves in its own \
                             part of the scene; add [coupling] for the exchange)"
                    .to_owned()
            }
            SceneKind::Grid | SceneKind::Sph => {
                "dt from the solver's stable step (CFL or fixed), the last steps shortened to \
                  land on the end time"
                    .to_owned()
            }
        };
        let memory = match available_memory() {
            Some(a) => format!(
                "{} ({:.0} MiB available)",
                p.footprint,
                a / (1024.0 * 1024.0)
            ),
            None => p.footprint.to_string(),
        };
        Plan {
            stages,
            outputs,
            clock,
            memory,
        }
    }

    /// What one step records in the stage trace: each stage's name, then `name/part` for each
    /// of its parts, in order.
    pub fn step_trace(&self) -> Vec<String> {
        self.stages
            .iter()
            .flat_map(|s| {
                std::iter::once(s.name.to_owned())
                    .chain(s.parts.iter().map(|(part, _)| format!("{}/{part}", s.name)))
            })
            .collect()
    }
}

impl fmt::Display for Plan {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(f, "memory: {}", self.memory)?;
        writeln!(f, "clock: {}", self.clock)?;
        writeln!(f, "each step, in order:")?;
        for (i, s) in self.stages.iter().enumerate() {
            writeln!(f, "{:>3}. {:<11} {}", i + 1, s.name, s.detail)?;
            let width = s
                .parts
                .iter()
                .map(|(p, _)| p.len())
                .max()
                .unwrap_or(0)
                .max(11);
            for (part, detail) in &s.parts {
                writeln!(f, "       - {part:<width$} {detail}")?;
            }
        }
        if !self.outputs.is_empty() {
            writeln!(f, "outputs:")?;
            for (name, detail) in &self.outputs {
                writeln!(f, "     - {name:<11} {detail}")?;
            }
        }
        Ok(())
    }
}

/// The plan's line on checkpoints: when they are written, where, and the state's size now (it
/// grows with the particles and vortex particles a run adds).
fn checkpoint_line(p: &Pipeline) -> String {
    let mut when = Vec::new();
    if let Some(dt) = p.outputs.checkpoint_interval {
        when.push(format!("every {dt} s"));
    }
    if let Some(m) = p.outputs.checkpoint_every {
        when.push(format!("every {m} min of wall time"));
    }
    when.push("on SIGINT or SIGTERM".into());
    let mib = p.state_bytes() as f64 / (1024.0 * 1024.0);
    format!(
        "{CHECKPOINT_FILE} {}, {mib:.1} MiB of state at the start; `eddy resume DIR` goes on \
         from it",
        when.join(", ")
    )
}
