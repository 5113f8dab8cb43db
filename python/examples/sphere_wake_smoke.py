"""Smoke past the sphere with boundary-layer turbulence (the README's demo scene) run from
Python, and a slice of its smoke at mid-height drawn with Matplotlib.

    python python/examples/sphere_wake_smoke.py [END_TIME] [FIGURE.png] [RUN_FOLDER]

Run from the repository root after `./dev demo` (which precomputes scenes/db/sphere.h5).
"""

import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt

import eddy

end = float(sys.argv[1]) if len(sys.argv) > 1 else 4.0
figure = sys.argv[2] if len(sys.argv) > 2 else "sphere_wake_smoke.png"
out = sys.argv[3] if len(sys.argv) > 3 else "out/abl_sphere_wake_py"

scene = eddy.Scene.load("scenes/abl_sphere_wake.toml", overrides={"time.end": end})
sim = eddy.Simulation(scene, out=out)
sim.run(progress=True)
print(f"t = {sim.time:.2f} s after {sim.steps} steps; last row: {sim.metrics()['kinetic_energy']:.4g} J")

(x0, y0, z0), h, (nx, ny, nz) = sim.grid_geometry
smoke = sim.smoke[:, :, nz // 2]  # indexed [i, j, k]: x, y at the middle z layer
plt.figure(figsize=(8, 4))
plt.imshow(smoke.T, origin="lower", extent=(x0, x0 + nx * h, y0, y0 + ny * h), cmap="magma")
plt.colorbar(label="smoke density")
plt.xlabel("x (m)")
plt.ylabel("y (m)")
plt.title(f"smoke at z = {z0 + (nz // 2 + 0.5) * h:.2f} m, t = {sim.time:.2f} s")
plt.savefig(figure, dpi=120, bbox_inches="tight")
print(f"wrote {figure}")
