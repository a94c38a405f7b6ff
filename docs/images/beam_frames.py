#!/usr/bin/env python3
"""Draws docs/images/beam_frames.svg: the frames of a samara beam (docs/model-reference.md).

Left: a curved, twisted reference line x0(s) from the clamped root to the tip, with the
section frames (x_s along the tangent, y_s and z_s in the cross-section, turned by the twist
theta(eta)) at a few stations. Right: a cut at station s and the sectional force and moment
(beam_force, beam_moment) that the outboard part exerts on the inboard part, in section-frame
components.

Run: python3 docs/images/beam_frames.py   (needs matplotlib; writes beside this script)
"""
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.patches import FancyArrowPatch  # noqa: E402

plt.rcParams.update({"font.size": 10, "svg.fonttype": "none", "svg.hashsalt": "samara"})
COLORS = {"x": "#c0392b", "y": "#27ae60", "z": "#2471a3"}


def line(s):
    """A curved reference line (a quarter-circle-like sweep rising in z), s in [0, 1]."""
    return np.array([4.5 * s, 3.0 * s**2, 1.5 * np.sin(np.pi * s / 2)])


def tangent(s, h=1e-6):
    t = (line(s + h) - line(s - h)) / (2 * h)
    return t / np.linalg.norm(t)


def frames(stations, twist_total=np.radians(60.0), steps=400):
    """Section frames by parallel transport of the root frame plus a linear twist."""
    s_grid = np.linspace(0.0, 1.0, steps + 1)
    t0 = tangent(0.0)
    y_ref = np.array([0.0, 1.0, 0.0])
    y = y_ref - t0 * (t0 @ y_ref)
    y /= np.linalg.norm(y)
    base = [np.column_stack([t0, y, np.cross(t0, y)])]
    for a, b in zip(s_grid[:-1], s_grid[1:]):
        ta, tb = tangent(a), tangent(b)
        axis = np.cross(ta, tb)
        sn = np.linalg.norm(axis)
        r = np.eye(3)
        if sn > 1e-15:
            k = axis / sn
            ang = np.arctan2(sn, ta @ tb)
            kx = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
            r = np.eye(3) + np.sin(ang) * kx + (1 - np.cos(ang)) * kx @ kx
        base.append(r @ base[-1])
    out = []
    for s in stations:
        f = base[int(round(s * steps))]
        th = twist_total * s
        c, sn = np.cos(th), np.sin(th)
        turn = np.array([[1, 0, 0], [0, c, -sn], [0, sn, c]])
        out.append(f @ turn)
    return out


def arrow3(ax, p, v, color, label=None, lw=1.8, offset=1.12):
    ax.quiver(*p, *v, color=color, lw=lw, arrow_length_ratio=0.18)
    if label:
        ax.text(*(p + offset * v), label, color=color, fontsize=10)


fig = plt.figure(figsize=(11.5, 5.2))

# Left: reference line and section frames.
ax = fig.add_subplot(1, 2, 1, projection="3d")
ss = np.linspace(0, 1, 200)
pts = np.array([line(s) for s in ss])
ax.plot(*pts.T, color="black", lw=2.0)
stations = [0.0, 0.25, 0.5, 0.75, 1.0]
for k, (s, f) in enumerate(zip(stations, frames(stations))):
    p = line(s)
    ln = 1.0
    first = k == 3
    arrow3(ax, p, ln * f[:, 0], COLORS["x"], "$x_s$" if first else None)
    arrow3(ax, p, ln * f[:, 1], COLORS["y"], "$y_s$" if first else None)
    arrow3(ax, p, ln * f[:, 2], COLORS["z"], "$z_s$" if first else None)
    # Cross-section outline (a flat rectangle in the y_s-z_s plane).
    cy, cz = 0.45 * f[:, 1], 0.15 * f[:, 2]
    rect = np.array([p + a * cy + b * cz for a, b in [(-1, -1), (1, -1), (1, 1), (-1, 1), (-1, -1)]])
    ax.plot(*rect.T, color="#7f8c8d", lw=1.0)
# Global frame.
o = np.array([-1.0, -0.6, 0.0])
for v, c, name in [((1, 0, 0), "x", "X"), ((0, 1, 0), "y", "Y"), ((0, 0, 1), "z", "Z")]:
    arrow3(ax, o, 0.8 * np.array(v), COLORS[c], name, lw=1.2)
ax.text(*(o + np.array([0.0, 0.0, -0.5])), "global", fontsize=9)
# Clamp at the root.
ax.scatter(*line(0.0), color="black", s=40)
ax.text(*(line(0.0) + np.array([0.2, 0.3, -0.6])), "root (s = 0)", fontsize=9)
ax.text(*(line(1.0) + np.array([0.2, 0.0, 0.5])), "tip (s = L)", fontsize=9)
ax.text(*(line(0.55) + np.array([0.4, 0.2, -0.9])), r"reference line $x_0(s)$, $\eta = s/L$", fontsize=9)
ax.text(*(line(0.7) + np.array([-2.6, 0.0, 1.3])), r"twist $\theta(\eta)$ about $x_s$", fontsize=9)
ax.set_xlim(-1.5, 5.2)
ax.set_ylim(-1.2, 3.8)
ax.set_zlim(-0.8, 2.6)
ax.set_box_aspect((6.7, 5.0, 3.4), zoom=1.12)
ax.view_init(elev=24, azim=-70)
ax.set_axis_off()
ax.set_title("section frames along the beam", fontsize=11)

# Right: side view of a cut at s (x_s to the right, z_s up, y_s into the page) and the
# positive sectional resultants that the outboard part exerts on the inboard part.
ax2 = fig.add_subplot(1, 2, 2)
ax2.set_xlim(-0.5, 10.5)
ax2.set_ylim(-3.8, 4.0)
ax2.set_aspect("equal")
ax2.axis("off")
ax2.set_title("beam_force, beam_moment: outboard part on inboard part", fontsize=11)
ax2.add_patch(plt.Rectangle((0.3, -0.6), 4.4, 1.2, fc="#d5dbdb", ec="black"))
ax2.add_patch(plt.Rectangle((6.0, -0.6), 4.0, 1.2, fc="#f2f3f4", ec="#7f8c8d", ls="--"))
ax2.plot([0.3, 0.3], [-1.0, 1.0], color="black", lw=3)
for yy in np.linspace(-0.9, 0.9, 6):
    ax2.plot([0.05, 0.3], [yy - 0.15, yy], color="black", lw=0.8)
ax2.text(2.5, -1.1, "inboard part", ha="center", va="top", fontsize=9)
ax2.text(8.0, -1.1, "outboard part", ha="center", va="top", fontsize=9, color="#7f8c8d")
ax2.plot([4.7, 4.7], [-0.9, 0.9], color="black", lw=1.0, ls=":")
ax2.text(4.7, -1.1, "cut at s", ha="center", va="top", fontsize=9)


def arrow2(p0, p1, color, style="-|>", lw=2.0, **kw):
    ax2.add_patch(FancyArrowPatch(p0, p1, arrowstyle=style, mutation_scale=14, color=color, lw=lw, **kw))


f0 = (4.7, 0.0)
arrow2(f0, (6.4, 0.0), COLORS["x"])
ax2.text(6.5, 0.15, "$N_1$ axial (tension +)", color=COLORS["x"], fontsize=9)
arrow2(f0, (4.7, 1.8), COLORS["z"])
ax2.text(4.85, 1.7, "$N_3$ shear along $z_s$", color=COLORS["z"], fontsize=9)
# M2 about y_s (into the page): clockwise in this view.
arrow2((3.75, 0.95), (3.75, -0.95), COLORS["y"], connectionstyle="arc3,rad=-0.9")
ax2.text(2.2, 1.45, "$M_2$ about $y_s$", color=COLORS["y"], fontsize=9)
# M1, torsion about x_s: double-headed vector.
arrow2((4.7, -1.9), (6.3, -1.9), COLORS["x"], style="-|>", lw=1.6)
arrow2((4.7, -1.9), (5.9, -1.9), COLORS["x"], style="-|>", lw=1.6)
ax2.text(6.45, -2.0, "$M_1$ torsion (about $x_s$)", color=COLORS["x"], fontsize=9)
ax2.text(0.2, 3.35, "$N_2$: shear along $y_s$; $M_3$: bending about $z_s$", fontsize=9)
ax2.text(0.2, 2.75, r"$[N;\,M] = C\,[\varepsilon;\,\kappa]$, section-frame components", fontsize=9)
# Section axes (y_s into the page).
ox, oy = 8.6, 1.6
arrow2((ox, oy), (ox + 1.1, oy), COLORS["x"], lw=1.2)
arrow2((ox, oy), (ox, oy + 1.1), COLORS["z"], lw=1.2)
ax2.plot([ox], [oy], marker="o", mfc="white", mec=COLORS["y"], ms=9)
ax2.plot([ox], [oy], marker="x", color=COLORS["y"], ms=6)
ax2.text(ox + 1.15, oy - 0.1, "$x_s$", color=COLORS["x"])
ax2.text(ox - 0.1, oy + 1.2, "$z_s$", color=COLORS["z"])
ax2.text(ox - 0.35, oy - 0.65, "$y_s$ (into page)", color=COLORS["y"], fontsize=8)
ax2.text(0.2, -3.3, "Cantilever along x, tip force $-F$ along z: $N_3 = -F$, "
         "$M_2 = F\\,(L - s) > 0$", fontsize=9)

fig.tight_layout()
out = Path(__file__).with_name("beam_frames.svg")
fig.savefig(out, metadata={"Date": None})
print(f"wrote {out}")
