"""Parameter sweeps on Dask.

Every case is an independent run of the model with some values changed (addressed by
paths such as ``bodies.bob.mass`` or ``beams.blade.sections[0].stiffness[4][4]``). The
cases run as Dask tasks — on a local cluster by default, or on any
``dask.distributed.Client`` (a scheduler on a cluster, Kubernetes, SLURM through
dask-jobqueue) — and their results are combined into one :class:`xarray.Dataset` with
one new dimension per swept parameter (a grid) or a ``case`` dimension (a list).
A case that fails is recorded in ``case_status`` / ``case_error`` and the others go on.
"""

from __future__ import annotations

import itertools
from typing import Any, Dict, List, Mapping, Optional, Sequence, Tuple

import numpy as np

from . import ModelLike, load, open_results
from ._samara import Model, ModelError

__all__ = ["sweep", "run_case", "expand"]


def expand(
    parameters: Optional[Mapping[str, Sequence[Any]]] = None,
    cases: Optional[Sequence[Mapping[str, Any]]] = None,
) -> Tuple[List[Dict[str, Any]], Optional[List[str]]]:
    """The cases of a sweep: every combination of ``parameters`` (a grid, the first
    parameter varying slowest), or the list ``cases``. Returns the cases and, for a grid,
    the parameter names in order (``None`` for a list)."""
    if (parameters is None) == (cases is None):
        raise ValueError("give either parameters (a grid) or cases (a list), not both")
    if parameters is not None:
        names = list(parameters)
        if not names:
            raise ValueError("the grid has no parameters")
        values = [list(parameters[n]) for n in names]
        for n, v in zip(names, values):
            if not v:
                raise ValueError(f"parameter {n} has no values")
        return [dict(zip(names, combo)) for combo in itertools.product(*values)], names
    out = [dict(c) for c in cases]  # type: ignore[union-attr]
    if not out:
        raise ValueError("the list of cases is empty")
    keys = set(out[0])
    for i, c in enumerate(out):
        if set(c) != keys:
            raise ValueError(f"case {i} sets {sorted(c)}, case 0 sets {sorted(keys)}: every case sets the same paths")
    return out, None


def run_case(model: Model, values: Mapping[str, Any], analysis: str) -> Dict[str, Any]:
    """Runs one case (in a Dask worker): the model with ``values`` set, up to
    ``analysis``. Returns ``{"status", "error", "results"}``: status ``"completed"``,
    ``"failed"`` (the solver stopped; partial results) or ``"error"`` (no results: the
    changed model is invalid, or the run could not start)."""
    try:
        m = model.copy()
        for path, v in values.items():
            m.set(path, v)
        raw = m.run_raw(analysis, None, None)
    except KeyboardInterrupt:
        raise
    except ModelError as e:
        found = [d for d in getattr(e, "diagnostics", []) if d["severity"] == "error"]
        text = "; ".join(f"{d['path']}: {d['message']}" if d["path"] else d["message"] for d in found)
        return {"status": "error", "error": f"ModelError: {text or e}", "results": None}
    except Exception as e:  # recorded per case; the sweep goes on
        return {"status": "error", "error": f"{type(e).__name__}: {e}", "results": None}
    name, data, summary = raw[-1]
    if summary["failure"] is not None:
        return {"status": "failed", "error": summary["failure"], "results": data}
    return {"status": "completed", "error": "", "results": data}


def _nan_like(ds):
    """A dataset shaped like ``ds`` (no time records) with every float value NaN."""
    empty = ds.isel(time=slice(0, 0)).copy(deep=True)
    for name, var in empty.data_vars.items():
        if np.issubdtype(var.dtype, np.floating):
            empty[name] = var.copy(data=np.full(var.shape, np.nan))
    return empty


def sweep(
    model: ModelLike,
    parameters: Optional[Mapping[str, Sequence[Any]]] = None,
    *,
    cases: Optional[Sequence[Mapping[str, Any]]] = None,
    analysis: Optional[str] = None,
    client: Any = None,
    n_workers: Optional[int] = None,
    progress: bool = False,
):
    """Runs the model once per case on Dask and combines the results.

    Parameters
    ----------
    model:
        A :class:`~samara.Model`, a model file, TOML text or a dict.
    parameters:
        A grid: ``{path: values}``; every combination runs; the result has one
        dimension per path (named by the path), in the order given.
    cases:
        Instead of a grid, a list of ``{path: value}`` (every case sets the same paths);
        the result has a ``case`` dimension with one coordinate per path.
    analysis:
        The analysis whose results are combined (and the ones it starts from run before
        it); default: the model's last analysis.
    client:
        A ``dask.distributed.Client``; by default a local cluster with one process per
        core (or ``n_workers``) is started for the sweep and closed after it.
    progress:
        Print a line per finished case.

    Returns an :class:`xarray.Dataset`: the variables of the results file with the sweep
    dimensions added where values differ between cases (time histories; fixed
    variables such as ``body_mass`` only if they change), ``case_status``
    (``completed``/``failed``/``error``) and ``case_error`` per case. Cases that stopped
    early keep their records; the rest of their time axis (and every value of a case
    that never ran) is NaN. Case outputs with different output times are aligned on
    the union of the times.
    """
    import pandas as pd
    import xarray as xr

    base = load(model)
    names_all = base.analyses
    if not names_all:
        raise ValueError("the model has no analyses")
    if analysis is None:
        analysis = names_all[-1]
    elif analysis not in names_all:
        raise ValueError(f"the model has no analysis '{analysis}' (analyses: {', '.join(names_all)})")
    all_cases, grid = expand(parameters, cases)

    own = None
    if client is None:
        from distributed import Client, LocalCluster

        import os

        workers = n_workers or os.cpu_count() or 1
        own = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=None)
        client = Client(own)
    try:
        from distributed import as_completed

        futures = client.map(run_case, [base] * len(all_cases), all_cases, [analysis] * len(all_cases), pure=False)
        index = {f.key: i for i, f in enumerate(futures)}
        outcomes: List[Optional[Dict[str, Any]]] = [None] * len(all_cases)
        for fut in as_completed(futures):
            i = index[fut.key]
            try:
                outcomes[i] = fut.result()
            except Exception as e:  # a worker died: recorded, the sweep goes on
                outcomes[i] = {"status": "error", "error": f"{type(e).__name__}: {e}", "results": None}
            if progress:
                done = sum(o is not None for o in outcomes)
                print(f"sweep: case {i} {outcomes[i]['status']} ({done}/{len(all_cases)})", flush=True)
    finally:
        if own is not None:
            client.close()
            own.close()

    datasets = [None if o["results"] is None else open_results(o["results"]) for o in outcomes]  # type: ignore[index]
    template = next((d for d in datasets if d is not None), None)
    if template is None:
        errors = "; ".join(f"case {i}: {o['error']}" for i, o in enumerate(outcomes))  # type: ignore[index]
        raise RuntimeError(f"every case of the sweep failed: {errors}")
    blank = _nan_like(template)
    filled = [d if d is not None else blank for d in datasets]
    combined = xr.concat(
        filled,
        dim=pd.Index(np.arange(len(all_cases)), name="case"),
        data_vars="different",
        coords="minimal",
        compat="equals",
        join="outer",
        combine_attrs="drop_conflicts",
    )
    combined["case_status"] = ("case", np.array([o["status"] for o in outcomes], dtype=object))  # type: ignore[index]
    combined["case_error"] = ("case", np.array([o["error"] for o in outcomes], dtype=object))  # type: ignore[index]
    paths = grid if grid is not None else list(all_cases[0])
    for p in paths:
        combined = combined.assign_coords({p: ("case", [c[p] for c in all_cases])})
    combined.attrs["sweep_parameters"] = ", ".join(paths)
    combined.attrs["sweep_analysis"] = analysis
    if grid is not None:
        combined = combined.set_index(case=grid).unstack("case")
    return combined
