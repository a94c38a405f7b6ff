import os
from typing import Any, Callable, Dict, List, Mapping, NamedTuple, Optional, Sequence, Union, overload

import scipy.sparse

import xarray

from ._samara import Model as Model, ModelError as ModelError, SamaraError as SamaraError

__version__: str

ModelLike = Union[Model, str, "os.PathLike[str]", Mapping[str, Any]]
Progress = Union[bool, Callable[[str, float], Any], None]

class SolverError(SamaraError):
    results: Dict[str, xarray.Dataset]
    def __init__(self, message: str, results: Dict[str, xarray.Dataset]) -> None: ...

def load(source: ModelLike, base_dir: Union[str, "os.PathLike[str]", None] = None) -> Model: ...
@overload
def run(
    model: ModelLike,
    analysis: None = None,
    *,
    out: Union[str, "os.PathLike[str]", None] = None,
    progress: Progress = None,
    raise_on_failure: bool = True,
) -> Dict[str, xarray.Dataset]: ...
@overload
def run(
    model: ModelLike,
    analysis: str,
    *,
    out: Union[str, "os.PathLike[str]", None] = None,
    progress: Progress = None,
    raise_on_failure: bool = True,
) -> xarray.Dataset: ...
def open_results(source: Union[bytes, str, "os.PathLike[str]"]) -> xarray.Dataset: ...
def displacement(ds: xarray.Dataset, node: Optional[str] = None) -> xarray.DataArray: ...
class Linearization(NamedTuple):
    """M ÿ + G ẏ + K y + Bᵀ μ = 0, B y = 0 as scipy.sparse CSC matrices; ``unknowns`` names y."""

    M: scipy.sparse.csc_matrix
    G: scipy.sparse.csc_matrix
    K: scipy.sparse.csc_matrix
    B: scipy.sparse.csc_matrix
    unknowns: List[str]

def linearize(model: ModelLike, analysis: Optional[str] = None) -> Linearization:
    """The linearized matrices about a modal analysis's state (or the initial state)."""
    ...

def sweep(
    model: ModelLike,
    parameters: Optional[Mapping[str, Sequence[Any]]] = None,
    *,
    cases: Optional[Sequence[Mapping[str, Any]]] = None,
    analysis: Optional[str] = None,
    client: Any = None,
    n_workers: Optional[int] = None,
    progress: bool = False,
) -> xarray.Dataset: ...
