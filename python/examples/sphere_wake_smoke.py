"""Smoke past the sphere with boundary-layer turbulence (the README's demo scene) run from
Python, and a slice of its smoke at mid-height drawn with Matplotlib.

    python python/examples/sphere_wake_smoke.py [--end 4.0] [--figure sphere_wake_smoke.png]

Run from the repository root after `./dev demo` (which precomputes scenes/db/sphere.h5).
"""

import argparse

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt

import eddy

args = argparse.ArgumentParser(description=__doc__.splitlines()[0])
args.add_argument("--end", type=float, default=4.0, help="simulated time, s")
args.add_argument("--figure", default="sphere_wake_smoke.png", help="the PNG to write")
args.add_argument("--out", default="out/abl_sphere_wake_py", help="the run's output folder")
args.add_argument("--database", help="the sphere's database (default: the scene's db/sphere.h5)")
args = args.parse_args()

overrides = {"time.end": args.end}
if args.database:
    overrides["obstacles.0.abl.database"] = args.database
scene = eddy.Scene.load("scenes/abl_sphere_wake.toml", overrides=overrides)
sim = eddy.Simulation(scene, out=args.out)
sim.run(progress=True)
energy = sim.metrics()["kinetic_energy"]  # one value a step
print(f"t = {sim.time:.2f} s after {sim.steps} steps, kinetic energy {energy[-1]:.4g} J "
      f"(largest {energy.max():.4g} J)")

grid = sim.grid_geometry  # eddy.GridGeometry(origin, spacing, dims)
(x0, y0, z0), h, (nx, ny, nz) = grid.origin, grid.spacing, grid.dims
smoke = sim.smoke[:, :, nz // 2]  # indexed [i, j, k]: x and y at the middle layer of z
plt.figure(figsize=(8, 4))
plt.imshow(smoke.T, origin="lower", extent=(x0, x0 + nx * h, y0, y0 + ny * h), cmap="magma")
plt.colorbar(label="smoke density")
plt.xlabel("x (m)")
plt.ylabel("y (m)")
plt.title(f"smoke at z = {z0 + (nz // 2 + 0.5) * h:.2f} m, t = {sim.time:.2f} s")
plt.savefig(args.figure, dpi=120, bbox_inches="tight")
print(f"wrote {args.figure}")
