//! Cell-grid shape, flat indexing and neighbour lookup shared by the linear solvers.
//!
//! Cells are stored flat in C order (`[i, j, k]`, k fastest), the layout of a standard
//! `Array3`. The solvers walk the grid row by row (a row is one `(i, j)` pair, contiguous in k)
//! and look up the four neighbouring rows once per row.

/// Shape and periodicity of a cell grid.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Layout {
    pub n: [usize; 3],
    pub periodic: [bool; 3],
}

/// Flat offsets of one row and of its four neighbouring rows (`None` where there is none).
#[derive(Clone, Copy, Debug)]
pub(crate) struct RowNeighbours {
    pub base: usize,
    pub xm: Option<usize>,
    pub xp: Option<usize>,
    pub ym: Option<usize>,
    pub yp: Option<usize>,
}

impl Layout {
    pub fn len(&self) -> usize {
        self.n[0] * self.n[1] * self.n[2]
    }

    /// Number of rows (cells in one x-slab times slabs, divided by the row length).
    pub fn rows(&self) -> usize {
        self.n[0] * self.n[1]
    }

    /// Cells in one x-slab (at least 1, so that it can size chunks of an empty grid).
    pub fn slab(&self) -> usize {
        (self.n[1] * self.n[2]).max(1)
    }

    pub fn index(&self, i: usize, j: usize, k: usize) -> usize {
        (i * self.n[1] + j) * self.n[2] + k
    }

    /// The coordinate one step up (`up`) or down along `axis` from `c`, wrapping on periodic
    /// axes. `None` beyond a non-periodic side, and on a periodic axis of one cell: a cell is
    /// not its own neighbour (its difference with itself is zero, so the coupling vanishes).
    #[inline]
    pub fn step(&self, axis: usize, c: usize, up: bool) -> Option<usize> {
        let n = self.n[axis];
        if up {
            if c + 1 < n {
                Some(c + 1)
            } else if self.periodic[axis] && n > 1 {
                Some(0)
            } else {
                None
            }
        } else if c > 0 {
            Some(c - 1)
        } else if self.periodic[axis] && n > 1 {
            Some(n - 1)
        } else {
            None
        }
    }

    /// Row offsets around row `(i, j)`.
    #[inline]
    pub fn row_neighbours(&self, i: usize, j: usize) -> RowNeighbours {
        let row = |i: usize, j: usize| self.index(i, j, 0);
        RowNeighbours {
            base: row(i, j),
            xm: self.step(0, i, false).map(|a| row(a, j)),
            xp: self.step(0, i, true).map(|a| row(a, j)),
            ym: self.step(1, j, false).map(|b| row(i, b)),
            yp: self.step(1, j, true).map(|b| row(i, b)),
        }
    }

    /// Colour classes that make Gauss–Seidel sweeps race-free: cells of one class are never
    /// neighbours. Parity of `i + j + k` does this except across the wrap of a periodic axis of
    /// odd length, so the last layer of such an axis is split off into its own group; the class
    /// is `2 * group + parity`, where `group` counts the odd-periodic last layers a cell is in.
    pub fn colour_groups(&self) -> usize {
        1 + (0..3).filter(|&a| self.odd_periodic(a)).count()
    }

    fn odd_periodic(&self, axis: usize) -> bool {
        self.periodic[axis] && self.n[axis] > 1 && self.n[axis] % 2 == 1
    }

    /// The group (see [`Layout::colour_groups`]) contribution of coordinate `c` on `axis`.
    #[inline]
    pub fn group_of(&self, axis: usize, c: usize) -> usize {
        usize::from(self.odd_periodic(axis) && c + 1 == self.n[axis])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn colour_classes_never_touch() {
        for n in [[3, 4, 5], [1, 2, 3], [5, 5, 1], [2, 3, 2]] {
            for periodic in [
                [true, true, true],
                [false, true, false],
                [true, false, true],
            ] {
                let l = Layout { n, periodic };
                let class = |i: usize, j: usize, k: usize| {
                    let g = l.group_of(0, i) + l.group_of(1, j) + l.group_of(2, k);
                    2 * g + (i + j + k) % 2
                };
                for i in 0..n[0] {
                    for j in 0..n[1] {
                        for k in 0..n[2] {
                            let c = [i, j, k];
                            for axis in 0..3 {
                                for up in [false, true] {
                                    if let Some(s) = l.step(axis, c[axis], up) {
                                        let mut d = c;
                                        d[axis] = s;
                                        assert_ne!(class(i, j, k), class(d[0], d[1], d[2]));
                                    }
                                }
                            }
                        }
                    }
                }
            }
        }
    }
}
