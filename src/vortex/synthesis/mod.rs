//! Vorticity synthesis (Pfaff et al. 2009, section 4.3): the three-step process.
//!
//! 1. The sink's own vorticity (finite differences on a grid, the point set's curl for SPH).
//! 2. The desired vorticity `omega_D`, the sum of all particle kernels (see [`kernel`]).
//! 3. Each particle adds `w_k` times its kernel velocity, with Eq. 14:
//!    `w_k = sum (omega_D - omega) . a_k / sum omega_D . a_k` over the samples inside the
//!    particle's cut-off, `a_k` its unit axis. A particle whose denominator is negligible
//!    (under `1e-6` of the sum of `|omega_D . a_k|`) or that covers no sample is skipped with
//!    weight zero (docs/src/paper-notes.md, "Eq. 14").
//! 4. The weight is clamped to `[0, 1]`: a particle adds at most its own kernel in a step and
//!    never removes the flow's vorticity. Unclamped, Eq. 14 regulates the grid's vorticity under
//!    a kernel *to* `omega_D` in one step whatever it was: a weak particle drifting over the
//!    resolved shear of a wake (grid vorticity opposite to it and ten times stronger) asks for
//!    weights of several hundred, a Gaussian vortex of hundreds of 1/s that the projection
//!    cannot return as the same vorticity sum, and the next step asks for more. Measured in
//!    `scenes/abl_sphere_wake.toml`: weights up to 364, and the run blew up at t = 2.7 s. With the
//!    clamp a particle over a flow without its vorticity still gets exactly its kernel (w = 1),
//!    and one over a flow that lacks part of it approaches the target over a few steps.
//!
//! On a grid ([`lattice`]), the samples of Eq. 14 are the cells of a synthesis lattice
//! `upsample` times finer than the sink's (the sink's vorticity interpolated trilinearly onto
//! it), and each face of the sink receives the mean kernel velocity over `upsample^2` points
//! spread over the face: the face-averaging restriction of a finer synthesis grid, which keeps
//! the fluxes through the coarse faces and so the divergence of the kernel. Point sums
//! ([`points`]) are unweighted: SPH particles share one mass at near-rest density, so each
//! stands for the same volume.
//!
//! [`synthesize_refined`] also adds the same weighted kernels at the faces of the refined
//! lattice itself: the fine velocity of section 5.2, by which the smoke on a grid twice as fine
//! is carried. Its face means over the `upsample^2` fine faces that tile a sink face are what
//! the sink receives.
//!
//! Kernel evaluations only touch samples within the cut-off: particles are found through a
//! hashed grid (points) or visit the samples around their centre (lattices); periodic axes
//! are handled with particle images.

mod lattice;
mod points;

use super::{
    kernel, Lattice, SinkLayout, SinkSamples, SinkVorticity, VelocitySink, VortexError,
    VortexParticles,
};
use crate::{Real, Vec3};
use ndarray::ArrayViewMut3;

/// What one synthesis did.
#[derive(Debug, Clone, Default)]
pub struct SynthesisReport {
    /// Eq. 14 weight per particle (zero where skipped).
    pub weights: Vec<Real>,
    /// Particles skipped by the guard.
    pub skipped: usize,
    /// Particles whose Eq. 14 weight fell outside `[0, 1]` and was clamped.
    pub clamped: usize,
}

/// Synthesizes the particles onto `sink`, on a synthesis lattice `upsample` times finer than a
/// grid sink's (ignored for point sinks).
pub fn synthesize<S: VelocitySink + ?Sized>(
    particles: &VortexParticles,
    sink: &mut S,
    upsample: usize,
) -> Result<SynthesisReport, VortexError> {
    synthesize_into(particles, sink, upsample, None)
}

/// [`synthesize`] onto a grid sink, and the same weighted kernel velocities added to `fine`,
/// the faces of the sink's lattice refined by `upsample` (`fine[a]` of the refined face
/// shape, MAC layout). Pfaff et al. 2009, section 5.2: the kernels evaluated on the higher
/// resolution grid, whose velocity carries the smoke there.
pub fn synthesize_refined<S: VelocitySink + ?Sized>(
    particles: &VortexParticles,
    sink: &mut S,
    upsample: usize,
    fine: [ArrayViewMut3<'_, Real>; 3],
) -> Result<SynthesisReport, VortexError> {
    synthesize_into(particles, sink, upsample, Some(fine))
}

fn synthesize_into<S: VelocitySink + ?Sized>(
    particles: &VortexParticles,
    sink: &mut S,
    upsample: usize,
    fine: Option<[ArrayViewMut3<'_, Real>; 3]>,
) -> Result<SynthesisReport, VortexError> {
    if upsample == 0 {
        return Err(VortexError::InvalidSettings(
            "synthesis upsample factor must be at least 1".into(),
        ));
    }
    if particles.is_empty() {
        return Ok(SynthesisReport::default());
    }
    // The increment is planned while the sink is read and added once it is lent.
    let planned = match sink.layout() {
        SinkLayout::Faces(lattice) => {
            let SinkVorticity::Cells(vorticity) = sink.vorticity(None) else {
                return Err(mismatch());
            };
            let images = Image::all(particles, &lattice);
            let sums = lattice::sums(particles, &images, &lattice, upsample, &vorticity);
            Planned::Faces(lattice, images, weights(&sums))
        }
        SinkLayout::Points(x) => {
            let under = points::covered(particles, x);
            let SinkVorticity::Points(vorticity) = sink.vorticity(Some(&under)) else {
                return Err(mismatch());
            };
            if vorticity.len() != x.len() {
                return Err(VortexError::Layout(format!(
                    "{} vorticity samples for {} points",
                    vorticity.len(),
                    x.len()
                )));
            }
            let (report, dv) = points::synthesize(particles, x, &vorticity, &under);
            Planned::Points(dv, report)
        }
    };
    match planned {
        Planned::Faces(lattice, images, report) => {
            sink.add_velocity(&mut |samples| match samples {
                SinkSamples::Faces(faces) => lattice::add_velocity(
                    particles,
                    &images,
                    &report.weights,
                    &lattice,
                    upsample,
                    faces,
                ),
                SinkSamples::Points(_) => Err(mismatch()),
            })?;
            if let Some(fine) = fine {
                let refined = lattice.refined(upsample);
                lattice::add_velocity(particles, &images, &report.weights, &refined, 1, fine)?;
            }
            Ok(report)
        }
        Planned::Points(_, _) if fine.is_some() => Err(mismatch()),
        Planned::Points(dv, report) => {
            sink.add_velocity(&mut |samples| match samples {
                SinkSamples::Points(v) if v.len() == dv.len() => {
                    v.iter_mut().zip(&dv).for_each(|(v, d)| *v += d);
                    Ok(())
                }
                SinkSamples::Points(v) => Err(VortexError::Layout(format!(
                    "{} velocities for {} points",
                    v.len(),
                    dv.len()
                ))),
                SinkSamples::Faces(_) => Err(mismatch()),
            })?;
            Ok(report)
        }
    }
}

/// A synthesis computed from the sink's state, before it is added.
enum Planned {
    /// The lattice, the particle images and the Eq. 14 weights.
    Faces(Lattice, Vec<Image>, SynthesisReport),
    /// The velocity increment at every point and the weights.
    Points(Vec<Vec3>, SynthesisReport),
}

fn mismatch() -> VortexError {
    VortexError::Layout(
        "the sink's layout, vorticity and samples disagree (faces or points)".into(),
    )
}

/// The Eq. 14 sums of one particle: sum omega_D . a, sum omega . a, sum |omega_D . a|.
type Sums = [Real; 3];

/// Eq. 14 with the guard and the clamp.
fn weights(sums: &[Sums]) -> SynthesisReport {
    let raw: Vec<Option<Real>> = sums
        .iter()
        .map(|&[desired, have, scale]| {
            (scale > 0.0 && desired.abs() > 1e-6 * scale).then(|| (desired - have) / desired)
        })
        .collect();
    SynthesisReport {
        weights: raw
            .iter()
            .map(|w| w.map_or(0.0, |w| w.clamp(0.0, 1.0)))
            .collect(),
        skipped: raw
            .iter()
            .zip(sums)
            .filter(|(w, s)| w.is_none() && s[0] != s[1])
            .count(),
        clamped: raw
            .iter()
            .flatten()
            .filter(|&&w| !(0.0..=1.0).contains(&w))
            .count(),
    }
}

/// Unit axis of a vorticity vector (zero for a zero vector).
#[inline]
fn axis(omega: &Vec3) -> Vec3 {
    let n = omega.norm();
    if n > 0.0 {
        omega / n
    } else {
        Vec3::zeros()
    }
}

/// A particle or one of its periodic copies.
#[derive(Debug, Clone, Copy)]
struct Image {
    particle: usize,
    x: Vec3,
}

impl Image {
    /// Every particle, plus its copies shifted by a period along the periodic axes where its
    /// velocity reach crosses the lattice's end.
    fn all(particles: &VortexParticles, lattice: &Lattice) -> Vec<Self> {
        let mut out = Vec::with_capacity(particles.len());
        for (particle, (x, &s)) in particles.x.iter().zip(&particles.sigma).enumerate() {
            let reach = kernel::velocity_radius(s);
            let shifts: [Vec<Real>; 3] = std::array::from_fn(|a| {
                let mut v = vec![0.0];
                if lattice.periodic[a] {
                    let len = lattice.dims[a] as Real * lattice.dx;
                    let lo = lattice.origin[a];
                    if x[a] - reach < lo {
                        v.push(len);
                    }
                    if x[a] + reach > lo + len {
                        v.push(-len);
                    }
                }
                v
            });
            for &sx in &shifts[0] {
                for &sy in &shifts[1] {
                    for &sz in &shifts[2] {
                        out.push(Self {
                            particle,
                            x: x + Vec3::new(sx, sy, sz),
                        });
                    }
                }
            }
        }
        out
    }
}
