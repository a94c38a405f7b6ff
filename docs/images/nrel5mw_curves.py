#!/usr/bin/env python3
"""Draws the NREL 5-MW aerodynamic power and thrust curves: samara's rigid and flexible
rotors (from `cargo run --release -p samara --example nrel5mw_curves`) against the
OpenFAST steady tables they run at (rpm and pitch from the tables; reference/nrel5mw/).

Usage: nrel5mw_curves.py CURVES.csv FIGURE.png   (docs/images/make.sh runs it)
"""
import csv
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

curves, figure = sys.argv[1], sys.argv[2]
rows = list(csv.DictReader(open(curves)))
cases = {}
for r in rows:
    cases.setdefault(r["case"], []).append({k: float(v) for k, v in r.items() if k != "case"})

fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(10, 3.9))
style = {
    "rigid": ("samara, rigid blades", "#2471a3", "o"),
    "torsion_stiff": ("samara, flexible (stiff in torsion)", "#27ae60", "s"),
    "beamdyn": ("samara, flexible (BeamDyn, with torsion)", "#c0392b", "^"),
}
refs = {"rigid": ("OpenFAST rigid", "k", "-"), "torsion_stiff": ("OpenFAST flexible (ElastoDyn)", "0.5", "--")}
for case, (label, color, marker) in style.items():
    data = cases.get(case, [])
    w = [d["wind"] for d in data]
    ax1.plot(w, [d["power_kW"] / 1e3 for d in data], marker=marker, ls="none", color=color, label=label, ms=5)
    ax2.plot(w, [d["thrust_kN"] for d in data], marker=marker, ls="none", color=color, label=label, ms=5)
    if case in refs:
        rl, rc, rs = refs[case]
        ax1.plot(w, [d["power_ref_kW"] / 1e3 for d in data], color=rc, ls=rs, label=rl)
        ax2.plot(w, [d["thrust_ref_kN"] for d in data], color=rc, ls=rs, label=rl)
ax1.set_xlabel("wind speed [m/s]")
ax1.set_ylabel("aerodynamic power [MW]")
ax2.set_xlabel("wind speed [m/s]")
ax2.set_ylabel("rotor thrust [kN]")
for ax in (ax1, ax2):
    ax.grid(alpha=0.3)
ax1.legend(fontsize=7, loc="lower right")
fig.suptitle("NREL 5-MW rotor, steady BEM at the tables' rpm and pitch", fontsize=10)
fig.tight_layout()
fig.savefig(figure, dpi=110)
