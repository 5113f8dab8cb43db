//! Open boundaries of the SPH fluid: inflow emitters and outflow sides of the domain.
//!
//! **Inflow: a buffer zone.** The fluid particles within [`BUFFER_LAYERS`] spacings of the side,
//! inside the emitter's rectangle, move with the prescribed velocity: it is set before the step's
//! solves and again after the pressure solve, so the solves see the buffer as moving boundary
//! data and no pressure pushes it back. The fluid beyond the buffer has a full kernel support of
//! buffer particles behind it (the support is two spacings): they are its boundary samples, so
//! the inflow neither leaks back nor sees a free surface. The buffer is fed with lattice layers
//! on the side: a new layer each time the last one has moved a spacing in, so particles enter
//! at the rate `u_n A / h^3` the velocity implies. This is the buffer-layer inlet SPlisHSPlasH's
//! emitters also use (particles in the emitter box move kinematically); the alternative,
//! mirrored ghost particles, needs a pressure boundary condition DFSPH does not have.
//!
//! **Outflow: removal at the plane.** A particle that crosses the side's plane is removed. Ahead
//! of the plane the fluid thins as at a free surface: pressure is clamped at zero there, so it
//! neither sucks the fluid nor sends a wave back when a particle goes (the p = 0 outflow of a
//! grid's open side). The signed solve (`super::cg`) holds the pressure at its ambient value
//! within a kernel support of the plane, and treats the inflow buffer as a moving wall.

use rayon::prelude::*;

use super::fluid::FluidParticles;
use super::params::{Inflow, InflowShape, Outflow};
use crate::state::{Persist, Restorer, Saver, StateError};
use crate::{Real, Vec3};

/// Depth of an inflow's buffer, in spacings: one more than the kernel support.
pub const BUFFER_LAYERS: Real = 3.0;

/// One emitter and, per lattice site, the offset of the particle it spawned last: under a
/// profile each site spawns at the rate its own speed implies.
#[derive(Debug, Clone)]
struct Emitter {
    inflow: Inflow,
    /// The side's coordinate along its axis, m.
    plane: Real,
    /// The sites on the plane (the normal coordinate is set when spawning).
    sites: Vec<Vec3>,
    /// Per site, the distance from the plane of its last particle, m.
    last: Vec<Real>,
}

impl Emitter {
    /// The prescribed velocity at `x` (the profile's factor times the peak), times `ramp`
    /// (`super::ramp`'s r(t), 1 after a smooth start).
    fn velocity(&self, x: &Vec3, ramp: Real) -> Vec3 {
        ramp * (self.inflow.factor(x) * Vec3::from(self.inflow.velocity))
    }

    /// Distance of `x` from the plane into the domain, if it lies over the rectangle.
    fn depth(&self, x: &Vec3) -> Option<Real> {
        let side = self.inflow.side;
        let [a, b] = side.tangents();
        let (min, max) = (self.inflow.min, self.inflow.max);
        let over = x[a] >= min[0] && x[a] <= max[0] && x[b] >= min[1] && x[b] <= max[1];
        over.then(|| (x[side.axis()] - self.plane) * side.inward()[side.axis()])
    }

    /// The particle of site `s` at `depth` from the plane, with its velocity at `ramp`.
    fn particle(&self, s: usize, depth: Real, ramp: Real) -> (Vec3, Vec3) {
        let axis = self.inflow.side.axis();
        let mut p = self.sites[s];
        p[axis] = self.plane + depth * self.inflow.side.inward()[axis];
        (p, self.velocity(&p, ramp))
    }
}

/// The open boundaries of one fluid.
#[derive(Debug, Clone, Default)]
pub struct OpenBoundaries {
    emitters: Vec<Emitter>,
    outflows: Vec<(Outflow, Real)>,
    spacing: Real,
}

/// What one exchange does: which particles are kept, and the particles (position, velocity)
/// appended after them.
pub struct Exchange {
    pub keep: Vec<bool>,
    pub added: Vec<(Vec3, Vec3)>,
}

impl OpenBoundaries {
    /// The boundaries of a fluid at `spacing` in the domain `(lo, hi)`; an emitter's lattice
    /// sites are those for which `keep` holds half a spacing in (the solver's rule for fluid
    /// sites: clear of walls and obstacles). The scene checked that each rectangle lies on its
    /// side and each velocity points in.
    pub fn new(
        inflows: &[Inflow],
        outflows: &[Outflow],
        domain: (Vec3, Vec3),
        spacing: Real,
        keep: impl Fn(&Vec3) -> bool,
    ) -> Self {
        let plane = |axis: usize, max: bool| if max { domain.1[axis] } else { domain.0[axis] };
        let emitters = inflows
            .iter()
            .map(|inflow| {
                let side = inflow.side;
                let [a, b] = side.tangents();
                let count = |k: usize| {
                    ((inflow.max[k] - inflow.min[k]) / spacing + 1e-9)
                        .floor()
                        .max(0.0) as usize
                };
                let mut e = Emitter {
                    inflow: inflow.clone(),
                    plane: plane(side.axis(), side.is_max()),
                    sites: Vec::new(),
                    last: Vec::new(),
                };
                for j in 0..count(1) {
                    for i in 0..count(0) {
                        let mut s = Vec3::zeros();
                        s[a] = inflow.min[0] + (i as Real + 0.5) * spacing;
                        s[b] = inflow.min[1] + (j as Real + 0.5) * spacing;
                        e.sites.push(s);
                    }
                }
                let first: Vec<Vec3> = (0..e.sites.len())
                    .map(|s| e.particle(s, 0.5 * spacing, 1.0).0)
                    .collect();
                let mut at = first.iter();
                e.sites
                    .retain(|_| keep(at.next().expect("one position per site")));
                e.last = vec![Real::INFINITY; e.sites.len()];
                if e.sites.is_empty() {
                    tracing::warn!(
                        "the inflow on {} has no lattice site clear of the walls: no fluid \
                         enters through it",
                        side.name()
                    );
                }
                e
            })
            .collect();
        let outflows = outflows
            .iter()
            .map(|o| (o.clone(), plane(o.side.axis(), o.side.is_max())))
            .collect();
        Self {
            emitters,
            outflows,
            spacing,
        }
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.emitters.is_empty() && self.outflows.is_empty()
    }

    /// Before the first step: each emitter continues the lattice of the fluid already over its
    /// rectangle (the layer nearest the plane within a spacing), or spawns its first layer half
    /// a spacing in, at `ramp` times its velocity.
    pub fn prime(&mut self, fluid: &mut FluidParticles, ramp: Real) {
        let h = self.spacing;
        let mut added = Vec::new();
        for e in &mut self.emitters {
            let nearest = fluid
                .x
                .iter()
                .filter_map(|x| e.depth(x))
                .filter(|d| (0.0..h).contains(d))
                .fold(Real::INFINITY, Real::min);
            let depth = if nearest.is_infinite() {
                added.extend((0..e.sites.len()).map(|s| e.particle(s, 0.5 * h, ramp)));
                0.5 * h
            } else {
                nearest
            };
            e.last.fill(depth);
        }
        if !added.is_empty() {
            fluid.exchange(&vec![true; fluid.len()], &added);
        }
    }

    /// Sets the velocity of every particle in an inflow's buffer to the inflow's there, times
    /// `ramp`.
    pub fn impose(&self, x: &[Vec3], v: &mut [Vec3], ramp: Real) {
        if self.emitters.is_empty() {
            return;
        }
        x.par_iter().zip(v.par_iter_mut()).for_each(|(x, v)| {
            if let Some(e) = self.buffer_of(x) {
                *v = e.velocity(x, ramp);
            }
        });
    }

    /// The last emitter whose buffer holds `x` (the one [`Self::impose`] takes the velocity of).
    fn buffer_of(&self, x: &Vec3) -> Option<&Emitter> {
        let depth = BUFFER_LAYERS * self.spacing;
        self.emitters
            .iter()
            .rev()
            .find(|e| e.depth(x).is_some_and(|d| d < depth))
    }

    /// Whether `x` lies in an inflow's buffer, where the velocity is prescribed.
    pub fn in_buffer(&self, x: &Vec3) -> bool {
        self.buffer_of(x).is_some()
    }

    /// Whether `x` lies within `reach` of an outflow plane, inside the domain.
    pub fn near_outflow(&self, x: &Vec3, reach: Real) -> bool {
        self.outflows.iter().any(|(o, plane)| {
            let axis = o.side.axis();
            (x[axis] - plane) * o.side.inward()[axis] < reach
        })
    }

    /// After the positions `x` moved by `dt`, the buffers at `ramp` times their velocity: the
    /// particles beyond an outflow plane to remove and the inflow layers that are due. None
    /// when nothing changes.
    pub fn exchange(&mut self, x: &[Vec3], dt: Real, ramp: Real) -> Option<Exchange> {
        if self.is_empty() {
            return None;
        }
        let h = self.spacing;
        let mut added = Vec::new();
        for e in &mut self.emitters {
            let inward = e.inflow.side.inward();
            for s in 0..e.sites.len() {
                e.last[s] += e.velocity(&e.sites[s], ramp).dot(&inward) * dt;
                while e.last[s] >= 1.5 * h {
                    e.last[s] -= h;
                    added.push(e.particle(s, e.last[s], ramp));
                }
            }
        }
        let keep: Vec<bool> = x
            .par_iter()
            .map(|x| {
                self.outflows.iter().all(|(o, plane)| {
                    let axis = o.side.axis();
                    (x[axis] - plane) * o.side.inward()[axis] >= 0.0
                })
            })
            .collect();
        let removed = keep.iter().any(|k| !k);
        if !removed && added.is_empty() {
            return None;
        }
        Some(Exchange { keep, added })
    }

    /// One line for the plan.
    pub fn describe(&self) -> String {
        let mut parts: Vec<String> = self
            .emitters
            .iter()
            .map(|e| {
                let shape = match (e.inflow.shape, e.inflow.across) {
                    (InflowShape::Uniform, _) => String::new(),
                    (InflowShape::Plane, Some(a)) => {
                        format!(" peak, plane profile across axis {a}")
                    }
                    (shape, _) => format!(" peak, {shape:?} profile").to_lowercase(),
                };
                format!(
                    "inflow on {} at {:?} m/s{shape} ({} sites a layer, buffer {BUFFER_LAYERS} \
                     spacings)",
                    e.inflow.side.name(),
                    e.inflow.velocity,
                    e.sites.len()
                )
            })
            .collect();
        parts.extend(
            self.outflows
                .iter()
                .map(|(o, _)| format!("outflow on {}", o.side.name())),
        );
        parts.join(", ")
    }
}

/// Each emitter's phase: how far its sites' last particles have moved in. The sites, planes
/// and outflows are the scene's.
impl Persist for OpenBoundaries {
    fn save(&self, into: &mut Saver) {
        for (k, e) in self.emitters.iter().enumerate() {
            into.reals(&format!("emitter_{k}"), &e.last);
        }
    }

    fn restore(&mut self, from: &Restorer) -> Result<(), StateError> {
        let last = (0..self.emitters.len())
            .map(|k| from.reals_n(&format!("emitter_{k}"), self.emitters[k].sites.len()))
            .collect::<Result<Vec<_>, _>>()?;
        for (e, last) in self.emitters.iter_mut().zip(last) {
            e.last = last;
        }
        Ok(())
    }
}
