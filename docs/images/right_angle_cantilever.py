#!/usr/bin/env python3
"""Plots the right-angle cantilever (examples/verification/right_angle_cantilever.toml) against
the published curves of Simo & Vu-Quoc (1988) in
examples/verification/right_angle_cantilever_reference.csv.

Usage: right_angle_cantilever.py RESULTS.nc FIGURE.png   (docs/images/make.sh runs it)
"""
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import xarray as xr  # noqa: E402

results, figure = sys.argv[1], sys.argv[2]
root = Path(__file__).resolve().parents[2]
ds = xr.open_dataset(results, engine="scipy")
names = [n.decode().strip("\x00") for n in ds.node_name.values]
t = ds.time.values
rows = [
    line.split(",")
    for line in (root / "examples/verification/right_angle_cantilever_reference.csv").read_text().splitlines()
    if line and not line.startswith("#") and not line.startswith("point")
]
ref = {p: np.array([[float(r[1]), float(r[2])] for r in rows if r[0] == p]) for p in ("elbow", "tip")}
fig, ax = plt.subplots(figsize=(7.5, 3.9))
for point, color in [("elbow", "#2471a3"), ("tip", "#c0392b")]:
    z = ds.position.isel(node=names.index(point), vec3=2).values
    z = z - z[0]
    ax.plot(t, z, color=color, lw=1.6, label=f"{point}, samara")
    ax.plot(ref[point][:, 0], ref[point][:, 1], "o", color=color, ms=3.5, mfc="white",
            label=f"{point}, Simo & Vu-Quoc (1988)")
ax.set_xlabel("time")
ax.set_ylabel("out-of-plane displacement $u_3$")
ax.set_title("right-angle cantilever: elbow pulse, 2 elements of order 4 per member, h = 0.05")
ax.grid(alpha=0.3)
ax.legend(fontsize=8, ncol=4, loc="upper center", bbox_to_anchor=(0.5, -0.2), frameon=False)
fig.tight_layout()
fig.savefig(figure, dpi=110)
print(f"wrote {figure}")
