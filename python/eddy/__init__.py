"""eddy from Python: load scenes, step them, read their fields as NumPy arrays, and look up
artificial-boundary-layer databases. Thin bindings over the Rust library (the one
implementation); see README.md, "Python"."""

from ._eddy import Database, Scene, SceneError, Simulation, precompute

__all__ = ["Database", "Scene", "SceneError", "Simulation", "precompute"]
