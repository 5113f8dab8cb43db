//! Connected components of the unknowns that touch no Dirichlet cell or side: on each of them
//! the Poisson matrix is singular (constants are its null space), so the right-hand side must
//! have zero mean there and the solution is fixed by asking for zero mean.
//!
//! Labelling works on runs (maximal stretches of unknowns along a row) with union-find, so its
//! cost grows with the number of runs, not of cells.

use super::layout::Layout;
use super::stencil::{DirichletTable, Problem, FLUID};

/// A run of unknowns `[start, start + len)` (flat indices) in singular component `component`.
#[derive(Clone, Copy, Debug)]
struct Run {
    start: usize,
    len: usize,
    component: usize,
}

/// The singular components of a problem.
#[derive(Clone, Debug, Default)]
pub(crate) struct SingularComponents {
    runs: Vec<Run>,
    /// Cells per component.
    sizes: Vec<usize>,
}

fn find(parent: &mut [usize], mut a: usize) -> usize {
    while parent[a] != a {
        parent[a] = parent[parent[a]];
        a = parent[a];
    }
    a
}

fn union(parent: &mut [usize], a: usize, b: usize) {
    let (ra, rb) = (find(parent, a), find(parent, b));
    if ra != rb {
        parent[ra.max(rb)] = ra.min(rb);
    }
}

impl SingularComponents {
    pub fn new(p: &Problem, dirichlet: &DirichletTable) -> Self {
        let l: Layout = p.layout;
        let nz = l.n[2];
        // Runs of each row, as (k0, k1), and the first run of each row.
        let mut runs: Vec<(usize, usize)> = Vec::new();
        let mut row_start = Vec::with_capacity(l.rows() + 1);
        for row in 0..l.rows() {
            row_start.push(runs.len());
            let cells = &p.kinds[row * nz..(row + 1) * nz];
            let mut k = 0;
            while k < nz {
                if cells[k] == FLUID {
                    let k0 = k;
                    while k < nz && cells[k] == FLUID {
                        k += 1;
                    }
                    runs.push((k0, k));
                } else {
                    k += 1;
                }
            }
        }
        row_start.push(runs.len());
        let mut parent: Vec<usize> = (0..runs.len()).collect();
        let row_runs = |row: usize| row_start[row]..row_start[row + 1];
        for i in 0..l.n[0] {
            for j in 0..l.n[1] {
                let row = i * l.n[1] + j;
                let here = row_runs(row);
                if l.periodic[2] && nz > 1 && here.len() > 1 {
                    let (first, last) = (here.start, here.end - 1);
                    if runs[first].0 == 0 && runs[last].1 == nz {
                        union(&mut parent, first, last);
                    }
                }
                let up_rows = [
                    l.step(0, i, true).map(|a| a * l.n[1] + j),
                    l.step(1, j, true).map(|b| i * l.n[1] + b),
                ];
                for other in up_rows.into_iter().flatten() {
                    let there = row_runs(other);
                    let (mut a, mut b) = (here.start, there.start);
                    while a < here.end && b < there.end {
                        let (ra, rb) = (runs[a], runs[b]);
                        if ra.0 < rb.1 && rb.0 < ra.1 {
                            union(&mut parent, a, b);
                        }
                        if ra.1 <= rb.1 {
                            a += 1;
                        } else {
                            b += 1;
                        }
                    }
                }
            }
        }
        let mut anchored = vec![false; runs.len()];
        for row in 0..l.rows() {
            for r in row_runs(row) {
                let (k0, k1) = runs[r];
                if (k0..k1).any(|k| dirichlet.get(row * nz + k) != [0; 3]) {
                    let root = find(&mut parent, r);
                    anchored[root] = true;
                }
            }
        }
        let mut label = vec![usize::MAX; runs.len()];
        let mut out = Self::default();
        for row in 0..l.rows() {
            for r in row_runs(row) {
                let root = find(&mut parent, r);
                if anchored[root] {
                    continue;
                }
                if label[root] == usize::MAX {
                    label[root] = out.sizes.len();
                    out.sizes.push(0);
                }
                let (k0, k1) = runs[r];
                out.sizes[label[root]] += k1 - k0;
                out.runs.push(Run {
                    start: row * nz + k0,
                    len: k1 - k0,
                    component: label[root],
                });
            }
        }
        out
    }

    /// Number of singular components.
    pub fn len(&self) -> usize {
        self.sizes.len()
    }

    /// Subtracts from `v` its mean over each singular component; returns the mean of largest
    /// magnitude that was removed (0 when there is no singular component).
    pub fn remove_means(&self, v: &mut [f64]) -> f64 {
        let mut sums = vec![0.0; self.sizes.len()];
        for r in &self.runs {
            sums[r.component] += v[r.start..r.start + r.len].iter().sum::<f64>();
        }
        let means: Vec<f64> = sums
            .iter()
            .zip(&self.sizes)
            .map(|(s, &n)| s / n as f64)
            .collect();
        for r in &self.runs {
            let m = means[r.component];
            v[r.start..r.start + r.len].iter_mut().for_each(|x| *x -= m);
        }
        means
            .into_iter()
            .fold(0.0, |acc: f64, m| if m.abs() > acc.abs() { m } else { acc })
    }
}
