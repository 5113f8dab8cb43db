//! Smoothed particle hydrodynamics: kernel, neighbour search, pressure solvers, boundaries, viscosity.
