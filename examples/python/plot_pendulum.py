"""Open a samara results file with xarray and plot it with matplotlib.

    cargo run --release -- run examples/pendulum.toml
    python3 examples/python/plot_pendulum.py examples/out/pendulum/swing.nc swing.png

Needs: pip install -r examples/python/requirements.txt
"""
import sys

import matplotlib

matplotlib.use("Agg")  # no display needed
import matplotlib.pyplot as plt
import numpy as np
import xarray as xr


def main(results: str, figure: str) -> None:
    # samara writes NetCDF-3 (64-bit offset); scipy's reader needs no C library.
    ds = xr.open_dataset(results, engine="scipy")
    names = [bytes(n).decode().rstrip("\x00") for n in ds.node_name.values]
    node = names.index("bob") if "bob" in names else 0
    t = ds.time.values
    x = ds.position.isel(node=node).values  # (time, 3)
    energy = ds.kinetic_energy.values + ds.potential_energy.values

    fig, ax = plt.subplots(3, 1, sharex=True, figsize=(7, 7))
    ax[0].plot(t, x[:, 0], label="x")
    ax[0].plot(t, x[:, 2], label="z")
    ax[0].set_ylabel(f"{names[node]} position [{ds.position.attrs['units']}]")
    ax[0].legend()
    if "joint_force" in ds:
        f = ds.joint_force.isel(joint=0).values
        ax[1].plot(t, np.linalg.norm(f, axis=1))
        ax[1].set_ylabel("|joint force| [N]")
    ax[2].plot(t, energy - energy[0])
    ax[2].set_ylabel("energy error [J]")
    ax[2].set_xlabel("time [s]")
    fig.suptitle(f"{ds.attrs['model']} / {ds.attrs['analysis']} ({ds.attrs['status']})")
    fig.tight_layout()
    fig.savefig(figure, dpi=100)
    # One line for scripts and tests: final time, final position, energy drift.
    print(f"t_end={t[-1]:.6f} x={x[-1, 0]:.9f} z={x[-1, 2]:.9f} max_energy_error={np.abs(energy - energy[0]).max():.3e}")


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit("usage: plot_pendulum.py RESULTS.nc FIGURE.png")
    main(sys.argv[1], sys.argv[2])
