"""The Python examples run as tests (the README's test command runs pytest here)."""

import runpy
from pathlib import Path

HERE = Path(__file__).resolve().parent


def test_sweep_pendulum_matches_the_closed_form_and_plots(tmp_path):
    example = runpy.run_path(str(HERE / "sweep_pendulum.py"))
    figure = tmp_path / "sweep.png"
    ds, period, error = example["main"](figure, n_workers=2)
    assert figure.stat().st_size > 10_000
    # h = 1 ms, rho_inf = 1 (second order, no numerical damping): the period error is
    # O(h^2) ~ 1e-6 plus the linear interpolation of the crossing (~1e-6); 1e-4 leaves
    # room and still catches a wrong g or length (percent-level changes).
    assert float(error.max()) < 1e-4
    assert period.dims == ("nodes.bob.position[0]", "model.gravity[2]")
