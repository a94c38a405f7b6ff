"""Shared fixtures: the repository root and the `samara` command (the CLI the Python
results are compared with). The CLI is `$SAMARA_BIN`, or target/release/samara (built
by `cargo test --release --workspace`, or here with `cargo build --release` if absent)."""

import os
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="session")
def root() -> Path:
    return ROOT


@pytest.fixture(scope="session")
def cli() -> str:
    exe = os.environ.get("SAMARA_BIN") or str(ROOT / "target" / "release" / "samara")
    if not Path(exe).exists():
        cargo = shutil.which("cargo")
        assert cargo, f"the samara command is needed: {exe} is missing and cargo is not on PATH"
        subprocess.run([cargo, "build", "--release", "-p", "samara-cli"], cwd=ROOT, check=True)
    assert Path(exe).exists(), exe
    return exe


# Global attributes that differ between two runs of the same model.
RUN_DEPENDENT = {"wall_time"}


def same_attr(x, y) -> bool:
    if isinstance(x, str) or isinstance(y, str):
        return x == y
    x, y = np.asarray(x), np.asarray(y)
    return x.dtype == y.dtype and x.tobytes() == y.tobytes()


def assert_bitwise_equal(a, b, ignore_attrs=RUN_DEPENDENT):
    """Same variables, dimensions, dtypes, attributes and bytes (NaN == NaN)."""
    assert sorted(a.variables) == sorted(b.variables)
    assert dict(a.sizes) == dict(b.sizes)
    for name in a.variables:
        va, vb = a[name], b[name]
        assert va.dims == vb.dims, name
        assert va.dtype == vb.dtype, name
        assert va.attrs.keys() == vb.attrs.keys(), name
        for k in va.attrs:
            assert same_attr(va.attrs[k], vb.attrs[k]), (name, k)
        assert np.asarray(va.values).tobytes() == np.asarray(vb.values).tobytes(), name
    ka = set(a.attrs) - set(ignore_attrs)
    kb = set(b.attrs) - set(ignore_attrs)
    assert ka == kb
    for k in ka:
        assert same_attr(a.attrs[k], b.attrs[k]), k
