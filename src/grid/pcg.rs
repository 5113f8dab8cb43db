//! The outer preconditioned conjugate gradient in f64, with the multigrid V-cycle as
//! preconditioner. Vector operations are fused so that each iteration makes few passes over
//! memory: `q = A p` with `p.q`; `x += a p`, `r -= a q` with `r.r` and the f32 copy of `r` the
//! V-cycle reads; `r.z`; `p = z + b p`.

use super::multigrid::Multigrid;
use super::stencil::FineStencil;
use crate::parallel::ordered_sum;
use rayon::prelude::*;

/// Elements per parallel chunk of the vector operations.
const CHUNK: usize = 1 << 14;

/// The CG vectors, kept between solves so that no solve allocates.
#[derive(Clone, Debug, Default)]
pub(crate) struct Workspace {
    pub x: Vec<f64>,
    pub b: Vec<f64>,
    r: Vec<f64>,
    p: Vec<f64>,
    q: Vec<f64>,
}

impl Workspace {
    pub fn new(n: usize) -> Self {
        let v = || vec![0.0; n];
        Self {
            x: v(),
            b: v(),
            r: v(),
            p: v(),
            q: v(),
        }
    }
}

/// How a CG run ended.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Outcome {
    pub iterations: usize,
    pub relative_residual: f64,
    pub converged: bool,
    /// A non-finite residual or curvature stopped the iteration.
    pub non_finite: bool,
}

/// `r.z` with `z` the V-cycle's f32 output.
fn dot_mixed(r: &[f64], z: &[f32]) -> f64 {
    ordered_sum(r.par_chunks(CHUNK).zip(z.par_chunks(CHUNK)).map(|(r, z)| {
        r.iter()
            .zip(z)
            .map(|(&r, &z)| r * f64::from(z))
            .sum::<f64>()
    }))
}

/// Solves `A x = b` from the initial guess in `ws.x` to `|r| <= tolerance |b|` (`b_norm = |b|`,
/// positive), at most `max_iterations` iterations.
pub(crate) fn solve(
    a: &FineStencil,
    mg: &mut Multigrid,
    ws: &mut Workspace,
    b_norm: f64,
    tolerance: f64,
    max_iterations: usize,
) -> Outcome {
    let Workspace { x, b, r, p, q } = ws;
    a.apply_dot(x, q);
    let target = tolerance * b_norm;
    let mut rr = {
        let rhs = mg.rhs_mut();
        ordered_sum(
            r.par_chunks_mut(CHUNK)
                .zip(rhs.par_chunks_mut(CHUNK))
                .zip(b.par_chunks(CHUNK).zip(q.par_chunks(CHUNK)))
                .map(|((r, r32), (b, q))| {
                    let mut s = 0.0;
                    for (((r, r32), b), q) in r.iter_mut().zip(r32).zip(b).zip(q) {
                        *r = b - q;
                        *r32 = *r as f32;
                        s += *r * *r;
                    }
                    s
                }),
        )
    };
    let outcome = |iterations: usize, rr: f64, non_finite: bool| Outcome {
        iterations,
        relative_residual: rr.sqrt() / b_norm,
        converged: rr.sqrt() <= target,
        non_finite,
    };
    if !rr.is_finite() {
        return outcome(0, rr, true);
    }
    if rr.sqrt() <= target {
        return outcome(0, rr, false);
    }
    mg.vcycle(a);
    let mut rho = dot_mixed(r, mg.solution());
    p.par_chunks_mut(CHUNK)
        .zip(mg.solution().par_chunks(CHUNK))
        .for_each(|(p, z)| {
            p.iter_mut().zip(z).for_each(|(p, &z)| *p = f64::from(z));
        });
    for it in 1..=max_iterations {
        let pq = a.apply_dot(p, q);
        if !(pq.is_finite() && rho.is_finite()) {
            return outcome(it, f64::NAN, true);
        }
        if pq <= 0.0 {
            // Only a zero search direction has no curvature: the residual is already at the
            // rounding floor.
            return outcome(it, rr, false);
        }
        let alpha = rho / pq;
        let rhs = mg.rhs_mut();
        rr = ordered_sum(
            x.par_chunks_mut(CHUNK)
                .zip(r.par_chunks_mut(CHUNK))
                .zip(rhs.par_chunks_mut(CHUNK))
                .zip(p.par_chunks(CHUNK).zip(q.par_chunks(CHUNK)))
                .map(|(((x, r), r32), (p, q))| {
                    let mut s = 0.0;
                    for ((((x, r), r32), p), q) in x.iter_mut().zip(r).zip(r32).zip(p).zip(q) {
                        *x += alpha * p;
                        *r -= alpha * q;
                        *r32 = *r as f32;
                        s += *r * *r;
                    }
                    s
                }),
        );
        if !rr.is_finite() {
            return outcome(it, rr, true);
        }
        if rr.sqrt() <= target {
            return outcome(it, rr, false);
        }
        mg.vcycle(a);
        let rho_new = dot_mixed(r, mg.solution());
        let beta = rho_new / rho;
        rho = rho_new;
        p.par_chunks_mut(CHUNK)
            .zip(mg.solution().par_chunks(CHUNK))
            .for_each(|(p, z)| {
                p.iter_mut()
                    .zip(z)
                    .for_each(|(p, &z)| *p = f64::from(z) + beta * *p);
            });
    }
    outcome(max_iterations, rr, false)
}
