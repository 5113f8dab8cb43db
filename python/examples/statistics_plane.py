"""A field of several runs' statistics (`statistics.h5`) in one plane, side by side on one
colour scale: the turbulent kinetic energy k behind the river's pillars for the runs with
boundary layers, with random seeding and with none, and the finer reference, say.

    python python/examples/statistics_plane.py A_statistics.h5 B_statistics.h5 ... \
        --labels A,B,... --axis y --at 0.075 --field k --figure k_plane.png

Each file is read with h5py as eddy writes it (docs/src/outputs.md, "Statistics"): the
lattice's `origin`, `spacing`, `dims`, and per cell `k`, `mean_velocity`, ... (NaN where no
sample found fluid: obstacles and air are left blank).
"""

import argparse

import h5py
import matplotlib
import numpy as np

matplotlib.use("Agg")
import matplotlib.pyplot as plt

AXES = "xyz"

args = argparse.ArgumentParser(description=__doc__.splitlines()[0])
args.add_argument("files", nargs="+", help="statistics.h5 files")
args.add_argument("--labels", help="a title per file, comma-separated (default: the names)")
args.add_argument("--axis", default="y", choices=list(AXES), help="the plane's normal")
args.add_argument("--at", type=float, help="where the plane crosses the axis, m (default: the middle)")
args.add_argument("--field", default="k", help="a scalar dataset, or mean_velocity.x and the like")
args.add_argument("--figure", default="statistics_plane.png", help="the PNG to write")
args = args.parse_args()
labels = args.labels.split(",") if args.labels else [f.rsplit("/", 1)[-1] for f in args.files]
if len(labels) != len(args.files):
    raise SystemExit(f"{len(labels)} labels for {len(args.files)} files")

normal = AXES.index(args.axis)
shown = [a for a in range(3) if a != normal]
name, _, part = args.field.partition(".")
planes = []
for path in args.files:
    with h5py.File(path, "r") as f:
        if f.attrs.get("format") != "eddy-statistics":
            raise SystemExit(f"{path}: not an eddy statistics file")
        origin, h, dims = f.attrs["origin"], float(f.attrs["spacing"]), f.attrs["dims"]
        if name not in f:
            raise SystemExit(f"{path}: no dataset {name!r}; it has {sorted(f)}")
        data = f[name][()]
    if part:
        data = data[..., AXES.index(part)]
    at = args.at if args.at is not None else origin[normal] + 0.5 * dims[normal] * h
    index = int(np.clip(np.floor((at - origin[normal]) / h), 0, dims[normal] - 1))
    plane = np.take(data, index, axis=normal)
    extent = [origin[shown[0]], origin[shown[0]] + dims[shown[0]] * h,
              origin[shown[1]], origin[shown[1]] + dims[shown[1]] * h]
    planes.append((plane, extent, origin[normal] + (index + 0.5) * h))

finite = np.concatenate([p[np.isfinite(p)] for p, _, _ in planes])
vmin, vmax = (0.0, np.percentile(finite, 99.5)) if name in ("k", "mean_enstrophy") else (
    np.percentile(finite, 0.5), np.percentile(finite, 99.5))
# Two panels a row, each as wide as the plane is against its height.
columns = min(2, len(planes))
rows = -(-len(planes) // columns)
width, height = planes[0][1][1] - planes[0][1][0], planes[0][1][3] - planes[0][1][2]
fig, axes = plt.subplots(rows, columns, figsize=(5.0 * columns, 5.0 * rows * height / width + 1.0),
                         squeeze=False)
for i, (ax, (plane, extent, at), label) in enumerate(zip(axes.flat, planes, labels)):
    image = ax.imshow(plane.T, origin="lower", extent=extent, vmin=vmin, vmax=vmax,
                      cmap="viridis", interpolation="nearest")
    ax.set_title(f"{label}\n{args.field} at {args.axis} = {at:.3f} m", fontsize=9)
    ax.set_xlabel(f"{AXES[shown[0]]} (m)")
    if i % columns == 0:
        ax.set_ylabel(f"{AXES[shown[1]]} (m)")
for ax in list(axes.flat)[len(planes):]:
    ax.axis("off")
units = {"k": "m²/s²", "mean_enstrophy": "1/s²", "mean_velocity": "m/s", "mean_vorticity": "1/s"}
fig.colorbar(image, ax=axes.ravel().tolist(), shrink=0.85, label=f"{args.field} ({units.get(name, '')})")
fig.savefig(args.figure, dpi=130, bbox_inches="tight")
print(args.figure)
