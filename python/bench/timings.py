"""Timings for docs/python.md (not a test): the pendulum example through Python and
through the CLI, and a 16-case sweep on 1 and 2 Dask workers.

    python python/bench/timings.py [target/release/samara]
"""

import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import samara

ROOT = Path(__file__).resolve().parents[2]
PENDULUM = ROOT / "examples" / "pendulum.toml"


def best(f, n=5):
    times = []
    for _ in range(n):
        t = time.perf_counter()
        f()
        times.append(time.perf_counter() - t)
    return min(times), statistics.median(times)


def main(cli):
    with tempfile.TemporaryDirectory() as tmp:
        cli_t = best(lambda: subprocess.run([cli, "run", str(PENDULUM), "--out", tmp, "--quiet"], check=True, capture_output=True))
    py_t = best(lambda: samara.run(str(PENDULUM)))
    print(f"pendulum (10 s, 10,000 steps): CLI {cli_t[0]:.3f} s (median {cli_t[1]:.3f}), "
          f"Python samara.run {py_t[0]:.3f} s (median {py_t[1]:.3f})")

    from distributed import Client, LocalCluster

    model = samara.load(str(PENDULUM))
    model.set("analyses.swing.t_end", 100.0)
    model.set("analyses.swing.output_every", 100)
    grid = {"bodies.bob.mass": [0.5, 1.0, 2.0, 4.0], "nodes.bob.position[0]": [0.5, 1.0, 1.5, 2.0]}
    result = {}
    for workers in (1, 2):
        with LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=None) as cluster, Client(cluster) as client:
            client.run(lambda: __import__("samara"))  # warm the workers' imports
            t = time.perf_counter()
            ds = samara.sweep(model, grid, client=client)
            result[workers] = time.perf_counter() - t
            assert (ds.case_status == "completed").all()
    print(f"16-case sweep (pendulum, 100 s = 100,000 steps each, every 100th recorded): 1 worker {result[1]:.2f} s, 2 workers {result[2]:.2f} s, "
          f"speed-up {result[1] / result[2]:.2f}")


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else str(ROOT / "target" / "release" / "samara"))
