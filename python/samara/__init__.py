"""samara: flexible multibody dynamics from Python.

Load a model (a TOML file or text, or a dict with the layout of a model file), run its
analyses, get the results as :class:`xarray.Dataset` objects holding exactly what the
NetCDF files of ``samara run`` hold (same variables, units and attributes)::

    import samara
    results = samara.run("examples/pendulum.toml")      # {analysis name: Dataset}
    swing = results["swing"]
    swing.position.sel(node="bob").plot.line(x="time")

Models are validated by the rules of a model file; an invalid one raises
:class:`ModelError`, whose ``diagnostics`` give the path of the offending value
(``bodies.bob.mass``) and, for a file, its line and column. Runs release the GIL, call an
optional ``progress(analysis, fraction)`` callback and stop cleanly on Ctrl-C
(``KeyboardInterrupt``). :func:`sweep` runs a parameter grid on Dask. See docs/python.md.
"""

from __future__ import annotations

import io
import os
from pathlib import Path
from typing import Any, Callable, Dict, List, Mapping, NamedTuple, Optional, Union

from ._samara import Model, ModelError, SamaraError
from ._samara import check_isa_variable as _check_isa_variable
from ._samara import version as _engine_version

# SAMARA_ISA narrows the compiled copies the engine's kernels run (base, avx, fma, avx512;
# README, "Benchmarks"). The engine ignores a value that names no copy; as the `samara`
# command does, refuse it here rather than run silently with the widest copy.
_check_isa_variable()

__all__ = [
    "Model",
    "ModelError",
    "SamaraError",
    "SolverError",
    "load",
    "run",
    "open_results",
    "displacement",
    "linearize",
    "Linearization",
    "sweep",
    "__version__",
]

__version__ = _engine_version()

ModelLike = Union[Model, str, "os.PathLike[str]", Mapping[str, Any]]
Progress = Union[bool, Callable[[str, float], Any], None]


class SolverError(SamaraError):
    """An analysis stopped before its end (the solver failed, or the state became non-finite).

    ``results`` holds the datasets computed until then (``attrs["status"] == "failed"``,
    ``attrs["failure"]`` says why), like the files ``samara run`` keeps on exit status 2.
    """

    def __init__(self, message: str, results: Dict[str, Any]):
        super().__init__(message)
        self.results = results


def load(source: ModelLike, base_dir: Union[str, "os.PathLike[str]", None] = None) -> Model:
    """A :class:`Model` from a file path, TOML text, a dict, or a Model (returned as is).

    A string is a path unless it holds a newline or ``=``, then it is TOML text.
    ``base_dir`` locates the files a TOML text or dict model names (section files).
    Raises :class:`ModelError` if the model is invalid.
    """
    if isinstance(source, Model):
        return source
    if isinstance(source, Mapping):
        return Model.from_dict(dict(source), base_dir=None if base_dir is None else str(base_dir))
    if isinstance(source, str) and ("\n" in source or "=" in source):
        label = None if base_dir is None else str(Path(base_dir) / "<string>")
        return Model.from_toml(source, label)
    if isinstance(source, (str, os.PathLike)):
        return Model.from_file(str(source))
    raise TypeError(f"cannot make a model from {type(source).__name__}")


def open_results(source: Union[bytes, str, "os.PathLike[str]"]):
    """A results file (path or bytes) as an in-memory :class:`xarray.Dataset`.

    Reads with xarray's ``scipy`` engine (NetCDF-3), as documented in docs/results.md.
    """
    import xarray as xr

    handle = io.BytesIO(source) if isinstance(source, (bytes, bytearray)) else str(source)
    with xr.open_dataset(handle, engine="scipy") as ds:
        return ds.load()


def _progress_callback(progress: Progress):
    if progress is None or progress is False:
        return None, None
    if progress is True:
        try:
            from tqdm.auto import tqdm
        except ImportError:  # pragma: no cover - tqdm is optional
            return None, None
        bars: Dict[str, Any] = {}

        def update(name: str, fraction: float) -> None:
            bar = bars.get(name)
            if bar is None:
                bar = bars[name] = tqdm(total=1000, desc=name, leave=False)
            bar.n = int(round(fraction * 1000))
            bar.refresh()

        def close() -> None:
            for bar in bars.values():
                bar.close()

        return update, close
    if callable(progress):
        return progress, None
    raise TypeError("progress must be None, True (a tqdm bar) or a callable(analysis, fraction)")


def run(
    model: ModelLike,
    analysis: Optional[str] = None,
    *,
    out: Union[str, "os.PathLike[str]", None] = None,
    progress: Progress = None,
    raise_on_failure: bool = True,
):
    """Runs a model's analyses; results as :class:`xarray.Dataset`.

    Parameters
    ----------
    model:
        A :class:`Model`, a model file path, TOML text or a dict (see :func:`load`).
    analysis:
        Run only this analysis (and those it starts from) and return its Dataset;
        by default every analysis runs and a dict ``{name: Dataset}`` is returned, in
        the model's order.
    out:
        Also write the NetCDF files into this folder (``<out>/<analysis>.nc``, as
        ``samara run --out``); by default nothing touches the disk.
    progress:
        ``callable(analysis, fraction)`` called about every 50 ms, or ``True`` for a
        tqdm bar (if tqdm is installed).
    raise_on_failure:
        Raise :class:`SolverError` (holding the partial results) when an analysis stops
        early; otherwise return them (``attrs["status"] == "failed"``).

    The GIL is released while the engine runs; Ctrl-C stops the run at its next output
    time and raises ``KeyboardInterrupt``.
    """
    m = load(model)
    callback, close = _progress_callback(progress)
    try:
        raw = m.run_raw(analysis, None if out is None else str(out), callback)
    finally:
        if close is not None:
            close()
    results: Dict[str, Any] = {}
    failure = None
    for name, data, summary in raw:
        ds = open_results(data)
        results[name] = ds
        if summary["failure"] is not None and failure is None:
            failure = f"analysis '{name}' stopped early: {summary['failure']}"
    if failure is not None and raise_on_failure:
        raise SolverError(failure, results)
    if analysis is not None:
        return results[analysis]
    return results


def displacement(ds, node: Optional[str] = None):
    """Displacement of the nodes: ``position`` minus the reference position.

    Uses the results' ``reference_position`` variable (the model's node positions), so
    a static run's first record (the unloaded state) and a dynamic run's start are
    measured from the same reference. ``node`` selects one node by name.
    """
    if "reference_position" in ds:
        ref = ds["reference_position"]
    else:  # results files written before reference_position existed
        ref = ds["position"].isel(time=0)
    u = ds["position"] - ref
    u.attrs = {"units": ds["position"].attrs.get("units", "m"), "long_name": "displacement of the node"}
    u.name = "displacement"
    if node is not None:
        names = [n.decode() if isinstance(n, bytes) else str(n) for n in ds["node_name"].values]
        if node not in names:
            raise KeyError(f"no node named '{node}' (nodes: {', '.join(names)})")
        u = u.isel(node=names.index(node))
    return u


class Linearization(NamedTuple):
    """The linearized equations of motion ``M ÿ + G ẏ + K y + Bᵀ μ = 0``, ``B y = 0``
    (docs/linearized-analyses.md) as :mod:`scipy.sparse` CSC matrices.

    ``unknowns`` names each unknown y (columns of every matrix, rows of M, G, K), e.g.
    ``tip.ux``, ``tip.rz``, ``shaft.theta``; B has one row per constraint equation.
    """

    M: Any
    G: Any
    K: Any
    B: Any
    unknowns: List[str]


def linearize(model: ModelLike, analysis: Optional[str] = None) -> Linearization:
    """The linearized matrices M (mass), G (damping, gyroscopic, Coriolis), K (elastic,
    geometric, centrifugal stiffness) and B (constraint Jacobian) as scipy.sparse matrices.

    About the state of the modal analysis ``analysis`` (after the analyses it starts
    from, in its rotating frame if it has ``rotation``) — the matrices its
    ``write_matrices = true`` writes as Matrix Market files — or, without ``analysis``,
    about the model's initial state. Runs with the GIL released. Raises ``ValueError``
    for an unknown or non-modal analysis.
    """
    import scipy.sparse as sp

    m = load(model)
    names, mats = m.linearize_raw(analysis)
    out = {}
    for tag, (rows, cols, vals, shape) in mats:
        out[tag] = sp.csc_matrix((vals, (rows, cols)), shape=shape)
    return Linearization(M=out["M"], G=out["G"], K=out["K"], B=out["B"], unknowns=list(names))


def sweep(*args, **kwargs):
    """Runs a parameter sweep on Dask; see :func:`samara.sweeps.sweep`."""
    from .sweeps import sweep as _sweep

    return _sweep(*args, **kwargs)
