"""Ctrl-C (SIGINT) and an exception in the progress callback stop a run cleanly."""

import os
import signal
import threading
import time

import pytest
import samara


def long_pendulum(root):
    m = samara.load(str(root / "examples" / "pendulum.toml"))
    m.set("analyses.swing.t_end", 1.0e4)  # about a minute: it must be stopped
    return m


@pytest.fixture
def python_sigint_handler():
    """Python's own SIGINT handler for the test's duration. A shell starts a background
    job (`cmd &` without job control, as CI runners may) with SIGINT ignored, and Python
    then installs no handler of its own, so Ctrl-C could not reach the engine's poll."""
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    yield
    signal.signal(signal.SIGINT, previous)


def test_ctrl_c_stops_a_run(root, tmp_path, python_sigint_handler):
    m = long_pendulum(root)
    timer = threading.Timer(0.5, lambda: os.kill(os.getpid(), signal.SIGINT))
    start = time.perf_counter()
    timer.start()
    with pytest.raises(KeyboardInterrupt):
        samara.run(m, out=tmp_path)
    stopped = time.perf_counter() - start
    timer.join()
    assert stopped < 5.0, stopped
    # The file written so far is a valid results file with the records up to the stop.
    partial = samara.open_results(tmp_path / "swing.nc")
    assert 0 < partial.sizes["time"] < 10_000_001
    assert partial.attrs["status"] == "running"
    # The engine is usable afterwards.
    m.set("analyses.swing.t_end", 0.01)
    assert samara.run(m, "swing").sizes["time"] == 11


def test_an_exception_in_the_progress_callback_stops_the_run(root):
    m = long_pendulum(root)

    class Stop(Exception):
        pass

    def progress(name, fraction):
        raise Stop("enough")

    start = time.perf_counter()
    with pytest.raises(Stop):
        samara.run(m, progress=progress)
    assert time.perf_counter() - start < 5.0
