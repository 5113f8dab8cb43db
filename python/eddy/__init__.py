"""eddy from Python: load scenes, step them, read their fields as NumPy arrays, and look up
artificial-boundary-layer databases. Thin bindings over the Rust library (the one
implementation); see docs/src/python.md.

A field a scene does not have (particles on a grid scene, smoke without a source) reads None."""

from typing import NamedTuple, Tuple

from ._eddy import Database, Scene, SceneError, Simulation, __version__, precompute


class GridGeometry(NamedTuple):
    """A MAC grid's lattice, as `Simulation.grid_geometry` and the grid frames' root attributes
    give it: cell (i, j, k) spans origin + spacing * [i, i + 1] x [j, j + 1] x [k, k + 1], and
    the grid's arrays are indexed [i, j, k] (x, y, z) with shape `dims`."""

    origin: Tuple[float, float, float]
    """The grid's lowest corner, m."""
    spacing: float
    """The edge of a (cubic) cell, m."""
    dims: Tuple[int, int, int]
    """Cells along x, y and z."""


__all__ = ["Database", "GridGeometry", "Scene", "SceneError", "Simulation", "__version__",
           "precompute"]
