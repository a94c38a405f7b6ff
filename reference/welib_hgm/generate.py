"""Reference solution of the HGM (Hansen-Gaunaa-Madsen, OpenFAST UAMod 4) dynamic-stall model
for a DU21-A17 section pitching through stall, computed with welib (E. Branlard, NREL),
an implementation independent of samara. See SOURCE.txt for what this produces and why.

Run (welib 4.2.1 does not build as a wheel; its modules are imported from the sdist):
    pip download welib==4.2.1 --no-deps --no-clean   # or unpack welib-4.2.1.tar.gz
    WELIB_SRC=<unpacked welib-4.2.1 directory> python3 generate.py
Writes du21_dense.dat and du21_pitching_k008.csv next to this script.
"""

import importlib.util
import os
import sys

import numpy as np
from scipy.integrate import solve_ivp

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.join(HERE, "..", "..")
AIRFOIL = os.path.join(ROOT, "reference", "nrel5mw", "aero", "Airfoils", "DU21_A17.dat")

# --- welib's two modules, imported from the source distribution --------------------------
src = os.environ.get("WELIB_SRC")
if not src:
    sys.exit("set WELIB_SRC to the unpacked welib-4.2.1 source directory")
pkg = os.path.join(src, "welib", "airfoils")


def load(name, path, package=None):
    spec = importlib.util.spec_from_file_location(name, path)
    mod = importlib.util.module_from_spec(spec)
    if package:
        mod.__package__ = package
    sys.modules[name] = mod
    spec.loader.exec_module(mod)
    return mod


# DynamicStall.py does `from .Polar import Polar`: register a minimal package for it.
import types

pkgmod = types.ModuleType("welib_airfoils")
pkgmod.__path__ = [pkg]
sys.modules["welib_airfoils"] = pkgmod
# Polar.py imports welib.tools/polar_file lazily only for file reading (not used here).
Polar = load("welib_airfoils.Polar", os.path.join(pkg, "Polar.py"), "welib_airfoils")
DS = load("welib_airfoils.DynamicStall", os.path.join(pkg, "DynamicStall.py"), "welib_airfoils")

# --- the airfoil: DU21_A17's table, resampled linearly on a fine grid --------------------
# AeroDyn (InterpOrd = 1, the file's default) and welib both interpolate the table and
# the separation curves linearly between knots; samara uses a C1 cubic. Resampling the
# table linearly every 0.05 deg over -20 ... 40 deg (keeping every original knot) makes
# the three interpolations agree to ~1e-4 in cl, so the comparison tests the model.
lines = open(AIRFOIL).read().splitlines()
k = next(i for i, l in enumerate(lines) if l.split()[1:2] == ["NumAlf"])
n = int(lines[k].split()[0])
rows = [list(map(float, l.split()[:4])) for l in lines[k + 1 :] if l.strip() and not l.strip().startswith("!")][:n]
rows = np.array(rows)
a_orig = rows[:, 0]
fine = np.round(np.arange(-20.0, 40.0 + 1e-9, 0.05), 2)
fine = fine[np.min(np.abs(fine[:, None] - a_orig[None, :]), axis=1) > 1e-3]
# No knot at alpha0 itself (welib's cl/(cla (alpha - alpha0)) is 0/0 there).
fine = fine[np.abs(fine - (-4.2)) > 1e-3]
alpha_deg = np.union1d(a_orig, fine)
cl = np.interp(alpha_deg, a_orig, rows[:, 1])
cd = np.interp(alpha_deg, a_orig, rows[:, 2])
cm = np.interp(alpha_deg, a_orig, rows[:, 3])

# The file's UA coefficients (DU21_A17.dat, NREL 5-MW); Cd0 = cd(alpha0) of the table as
# welib takes it (the file says 0.006).
ALPHA0_DEG, C_NALPHA = -4.2, 6.2047
A1, A2, B1, B2, T_F0, T_P = 0.3, 0.7, 0.14, 0.53, 3.0, 1.7
cd0 = float(np.interp(ALPHA0_DEG, alpha_deg, cd))

dense = os.path.join(HERE, "du21_dense.dat")
with open(dense, "w") as f:
    f.write("! DU21_A17 (NREL 5-MW, reference/nrel5mw/aero/Airfoils/DU21_A17.dat) resampled linearly\n")
    f.write("! every 0.05 deg over -20 ... 40 deg by reference/welib_hgm/generate.py (original knots kept)\n")
    f.write("          1   NumTabs\n")
    f.write("       0.75   Re\n          0   UserProp\nTrue          InclUAdata\n")
    f.write(f"{ALPHA0_DEG:>11}   alpha0\n{C_NALPHA:>11}   C_nalpha\n{T_F0:>11}   T_f0\n{T_P:>11}   T_p\n")
    f.write(f"{B1:>11}   b1\n{B2:>11}   b2\n{A1:>11}   A1\n{A2:>11}   A2\n{cd0!r:>11}   Cd0\n")
    f.write(f"{len(alpha_deg):>11}   NumAlf\n")
    for a, l, d, m in zip(alpha_deg, cl, cd, cm):
        f.write(f"{a:9.2f} {float(l)!r} {float(d)!r} {float(m)!r}\n")

# Read the numbers back as written, so welib and samara see the same table.
back = open(dense).read().splitlines()
k = next(i for i, l in enumerate(back) if l.split()[1:2] == ["NumAlf"])
tab = np.array([list(map(float, l.split())) for l in back[k + 1 :]])
alpha_deg, cl, cd, cm = tab.T

# --- welib's HGM ("MHH") model with UnsteadyAero's constants ----------------------------
P = Polar.Polar(alpha=np.radians(alpha_deg), cl=cl, cd=cd, cm=cm, radians=True)
a0, cla = np.radians(ALPHA0_DEG), C_NALPHA
# alpha0 and the lift slope from the file (as UnsteadyAero takes them), not welib's fits:
P.alpha0 = lambda *args, **kw: a0
P.cl_linear_slope = lambda *args, **kw: (cla, a0)
P._alpha0, P._linear_slope = a0, cla
CHORD = 1.0
p = DS.dynstall_mhh_param_from_polar(P, CHORD, constants="OpenFAST")
assert (p["A1"], p["A2"], p["b1"], p["b2"], p["Tf0"], p["Tp0"]) == (A1, A2, B1, B2, T_F0, T_P)
p["old_ClCd_dyn"] = False  # drag as current UnsteadyAero: (a34 - aE) cl_circ + cl_circ Tu omega
assert abs(p["Cd"](a0) - cd0) < 1e-15
# In the range this case visits, welib's f_st and cl_fs are Kirchhoff's (UnsteadyAero's
# AirfoilInfo gives the same at the knots): check at the knots from alpha0 + 1 deg to 30 deg.
sel = (alpha_deg > ALPHA0_DEG + 1) & (alpha_deg < 30)
ratio = np.clip(cl[sel] / (cla * (np.radians(alpha_deg[sel]) - a0)), 0, None)
f_k = np.clip((2 * np.sqrt(ratio) - 1) ** 2, 0, 1)
assert np.max(np.abs(P.fs[sel] - f_k)) < 1e-8, np.max(np.abs(P.fs[sel] - f_k))

# --- the motion: pitching about the quarter chord in a steady wind ----------------------
U, ALPHA_M, ALPHA_A, K = 10.0, np.radians(10.0), np.radians(8.0), 0.08
OMEGA = 2.0 * U * K / CHORD  # reduced frequency k = omega c / (2 U)
PERIOD = 2.0 * np.pi / OMEGA
CYCLES = 4
theta = lambda t: ALPHA_M + ALPHA_A * np.sin(OMEGA * t)
theta_dot = lambda t: ALPHA_A * OMEGA * np.cos(OMEGA * t)
u = {
    "U": lambda t: U,
    "U_dot": lambda t: 0.0,
    "omega": theta_dot,
    "alpha": theta,  # at the quarter chord
    # three-quarter chord: the pitch rate adds omega c/2 to the normal velocity there
    "alpha_34": lambda t: np.arctan2(U * np.sin(theta(t)) + theta_dot(t) * CHORD / 2, U * np.cos(theta(t))),
}


def integrate(rtol, atol):
    x0 = DS.dynstall_mhh_steady(0.0, u, p)
    t_eval = np.linspace((CYCLES - 1) * PERIOD, CYCLES * PERIOD, 401)
    sol = solve_ivp(
        lambda t, x: DS.dynstall_mhh_dxdt(t, x, u, p),
        (0.0, CYCLES * PERIOD),
        x0,
        method="DOP853",
        rtol=rtol,
        atol=atol,
        t_eval=t_eval,
    )
    assert sol.success, sol.message
    out = []
    for j, t in enumerate(sol.t):
        x = sol.y[:, j]
        c_l, c_d, c_m = DS.dynstall_mhh_outputs(t, x, u, p)
        out.append([t, np.degrees(theta(t)), c_l, c_d, c_m, *x])
    return np.array(out), sol.nfev


ref, nfev = integrate(1e-12, 1e-13)
loose, _ = integrate(1e-9, 1e-10)
spread = np.max(np.abs(ref[:, 2:] - loose[:, 2:]), axis=0)
print("x4 range", ref[:, 8].min(), ref[:, 8].max(), "cl range", ref[:, 2].min(), ref[:, 2].max())
print(f"{nfev} evaluations; rtol 1e-9 vs 1e-12, max |diff| cl cd cm x1..x4: {spread}")

csv = os.path.join(HERE, "du21_pitching_k008.csv")
with open(csv, "w") as f:
    f.write("# welib 4.2.1 MHH/HGM model (dynstall_mhh_dxdt, dynstall_mhh_outputs), see SOURCE.txt\n")
    f.write(f"# U = {U} m/s, c = {CHORD} m, alpha = 10 + 8 sin(omega t) deg, k = {K}, omega = {OMEGA} rad/s\n")
    f.write(f"# last of {CYCLES} cycles; solve_ivp DOP853 rtol 1e-12 atol 1e-13 (vs rtol 1e-9: {np.max(spread[:3]):.1e})\n")
    f.write("t,alpha_deg,cl,cd,cm,x1,x2,x3,x4\n")
    for r in ref:
        f.write(",".join(repr(float(v)) for v in r) + "\n")
print("wrote", dense, csv)
