"""Typed stubs of the compiled core (``samara._samara``); see the docstrings in lib.rs."""

import os
from pathlib import Path
from typing import Any, Callable, Dict, List, Optional, Tuple, Union

_Path = Union[str, "os.PathLike[str]"]

class SamaraError(Exception):
    """Base class of samara's errors."""

class ModelError(SamaraError):
    """The model is invalid.

    ``diagnostics`` lists every finding as a dict: ``severity`` ("error"/"warning"),
    ``message``, ``hint`` (or None), ``file``, ``line`` and ``column`` (1-based, or None),
    ``path`` (the offending value, e.g. ``"bodies.bob.mass"``, or None).
    """

    diagnostics: List[Dict[str, Any]]

class Model:
    """A model: a TOML document validated by the rules of a model file."""

    def __init__(self, _text: str = ...) -> None: ...
    @staticmethod
    def from_file(path: _Path) -> "Model":
        """Reads a model file (TOML). Raises ``ModelError`` (with line and column) if invalid."""
    @staticmethod
    def from_toml(text: str, path: Optional[_Path] = None) -> "Model":
        """Parses model text; ``path`` labels errors and locates the files the model names."""
    @staticmethod
    def from_dict(data: Dict[str, Any], base_dir: Optional[_Path] = None) -> "Model":
        """A model from a dict with the layout of a model file."""
    def to_dict(self) -> Dict[str, Any]:
        """The model as a dict with the layout of a model file."""
    def to_toml(self) -> str:
        """The model as TOML text (the original text while unchanged)."""
    def get(self, path: str) -> Any:
        """The value at a path such as ``bodies.bob.mass`` or ``model.gravity[2]`` (KeyError if none)."""
    def set(self, path: str, value: Any) -> None:
        """Sets the value at a path and validates; on ModelError the model is unchanged."""
    def copy(self) -> "Model":
        """A copy that can be changed independently."""
    @property
    def name(self) -> str:
        """The model's name (``[model] name``)."""
    @property
    def analyses(self) -> List[str]:
        """The names of the analyses, in order."""
    @property
    def file(self) -> Optional[Path]:
        """The model file it was read from, if any."""
    def linearize_raw(
        self, analysis: Optional[str] = None
    ) -> Tuple[List[str], List[Tuple[str, Tuple[List[int], List[int], List[float], Tuple[int, int]]]]]:
        """The linearized matrices as coordinate triplets: ``(unknown names, [(tag, (rows,
        cols, values, shape))])`` for tags M, G, K, B, about the state of the modal
        analysis ``analysis`` (or the initial state); the GIL is released."""
        ...
    def run_raw(
        self,
        analysis: Optional[str] = None,
        out: Optional[_Path] = None,
        progress: Optional[Callable[[str, float], Any]] = None,
    ) -> List[Tuple[str, Union[bytes, Path], Dict[str, Any]]]:
        """Runs the analyses with the GIL released: ``[(name, NetCDF bytes or path, summary)]``.

        ``summary`` has steps, newton_iterations, rejected_steps, factorizations,
        wall_time, max_constraint_violation, warnings and failure (None or why).
        Ctrl-C stops the run at its next output time and raises KeyboardInterrupt.
        """

def check_isa_variable() -> None:
    """Raises ValueError if SAMARA_ISA names no compiled copy (base, avx, fma, avx512)."""

def version() -> str:
    """The version of the samara engine."""

def is_plain_file_name(path: str) -> bool:
    """Whether a name can name a results file as it is."""
