"""A pendulum built in Python, swept over its length and gravity on a local Dask cluster.

    python examples/python/sweep_pendulum.py [FIGURE.png]

Builds the model as a dict (the layout of a model file), runs a 4 x 2 grid of
(length, gravity) with ``samara.sweep`` on a local Dask cluster, measures each case's
period from the first zero crossing of the bob's x (a quarter period after a release at
90 degrees), compares it with the closed form of the physical pendulum, and plots
period against length. Run by the test suite (examples/python/test_examples.py).
"""

import sys

import numpy as np
from scipy.special import ellipk

import samara

MASS = 1.0
INERTIA = 1e-4  # about the bob's centre of mass (kg m^2)
LENGTHS = [0.25, 0.5, 1.0, 2.0]
GRAVITIES = [9.81, 3.71]  # Earth, Mars


def pendulum(length: float = 1.0, g: float = 9.81, t_end: float = 2.0) -> dict:
    """A pendulum released horizontally: bob at (length, 0, 0), pivot about y at the origin."""
    return {
        "model": {"name": "pendulum", "gravity": [0.0, 0.0, -g]},
        "nodes": [{"name": "bob", "position": [length, 0.0, 0.0]}],
        "bodies": [
            {
                "name": "bob",
                "node": "bob",
                "mass": MASS,
                "inertia": [[INERTIA, 0.0, 0.0], [0.0, INERTIA, 0.0], [0.0, 0.0, INERTIA]],
            }
        ],
        "joints": [
            {
                "name": "pivot",
                "type": "revolute",
                "node_a": "ground",
                "node_b": "bob",
                "position": [0.0, 0.0, 0.0],
                "axis": [0.0, 1.0, 0.0],
            }
        ],
        "analyses": [{"name": "swing", "type": "dynamic", "t_end": t_end, "step": 1e-3, "rho_inf": 1.0}],
    }


def closed_form_period(length, g):
    """Physical pendulum released at 90 degrees: T = 4 sqrt(I_p / (m g L)) K(k), k = sin 45 deg."""
    i_pivot = MASS * length**2 + INERTIA
    return 4.0 * np.sqrt(i_pivot / (MASS * g * length)) * ellipk(0.5)


def quarter_period(t, x):
    """Time of the first downward zero crossing of x (linear interpolation between records)."""
    i = int(np.argmax(x <= 0.0))
    if i == 0:
        return np.nan
    return t[i - 1] + (t[i] - t[i - 1]) * x[i - 1] / (x[i - 1] - x[i])


def main(figure=None, n_workers=2):
    slowest = closed_form_period(max(LENGTHS), min(GRAVITIES)) / 4.0
    model = samara.load(pendulum(t_end=1.2 * slowest))
    ds = samara.sweep(
        model,
        {"nodes.bob.position[0]": LENGTHS, "model.gravity[2]": [-g for g in GRAVITIES]},
        n_workers=n_workers,
    )
    assert (ds.case_status == "completed").all(), ds.case_error.values
    x = ds.position.isel(node=0, vec3=0)
    period = xr_apply_quarter(ds.time.values, x) * 4.0
    expected = closed_form_period(ds["nodes.bob.position[0]"], -ds["model.gravity[2]"])
    error = np.abs(period / expected - 1.0)
    print(f"{ds.sizes['nodes.bob.position[0]'] * ds.sizes['model.gravity[2]']} cases; "
          f"largest relative period error vs closed form: {float(error.max()):.2e}")
    if figure is not None:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        fig, ax = plt.subplots(figsize=(6, 4))
        fine = np.linspace(min(LENGTHS), max(LENGTHS), 100)
        for g in GRAVITIES:
            t = period.sel({"model.gravity[2]": -g})
            ax.plot(t["nodes.bob.position[0]"], t, "o", label=f"samara, g = {g} m/s²")
            ax.plot(fine, closed_form_period(fine, g), "-", color="0.6")
        ax.plot([], [], "-", color="0.6", label="closed form (elliptic integral)")
        ax.set_xlabel("length (m)")
        ax.set_ylabel("period (s)")
        ax.set_title("Pendulum released at 90°: a 4 × 2 sweep on Dask")
        ax.legend()
        fig.tight_layout()
        fig.savefig(figure, dpi=110)
        print(figure)
    return ds, period, error


def xr_apply_quarter(t, x):
    """quarter_period over every case of a swept DataArray x(time, ...)."""
    import xarray as xr

    return xr.apply_ufunc(
        lambda xs: quarter_period(t, xs),
        x,
        input_core_dims=[["time"]],
        vectorize=True,
    )


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else None)
