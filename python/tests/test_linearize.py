"""`samara.linearize`: the linearized matrices as scipy.sparse equal, bit for bit, the
Matrix Market files `write_matrices = true` makes `samara run` write (issue #13)."""

import subprocess

import numpy as np
import pytest
import samara
import scipy.io
import scipy.sparse as sp


def mtx_unknowns(path):
    """The unknown names listed in a Matrix Market file's header comment."""
    for line in path.read_text().splitlines():
        if line.startswith("% unknowns:"):
            return [item.split("=", 1)[1] for item in line.split(":", 1)[1].split()]
    raise AssertionError(f"no unknowns line in {path}")


def assert_same(a, b):
    assert a.shape == b.shape
    d = (sp.csc_matrix(a) - sp.csc_matrix(b)).tocoo()
    assert d.nnz == 0 or np.all(d.data == 0.0), np.abs(d.data).max()


def compare(model_file, analysis, cli, out):
    subprocess.run([cli, "run", str(model_file), "--out", str(out), "--quiet"], check=True)
    lin = samara.linearize(str(model_file), analysis)
    assert isinstance(lin, samara.Linearization)
    for tag in ("M", "G", "K", "B"):
        f = out / f"{analysis}.{tag}.mtx"
        ref = scipy.io.mmread(str(f))
        got = getattr(lin, tag)
        assert sp.issparse(got) and got.format == "csc"
        assert_same(got, ref)
        assert lin.unknowns == mtx_unknowns(f)
    n = len(lin.unknowns)
    assert lin.M.shape == lin.K.shape == lin.G.shape == (n, n)
    assert lin.B.shape[1] == n
    return lin


def test_cantilever_matrices_equal_the_matrix_market_files(root, cli, tmp_path):
    model = root / "examples" / "verification" / "cantilever_modal.toml"
    lin = compare(model, "axial", cli, tmp_path)
    # the model's initial state is the state of this modal analysis (no start_from, no
    # rotation): the same matrices without naming it
    free = samara.linearize(str(model))
    for tag in ("M", "G", "K", "B"):
        assert_same(getattr(free, tag), getattr(lin, tag))
    assert lin.M.nnz > 0 and lin.K.nnz > 0


def test_a_spinning_state_after_a_dynamic_run(root, cli, tmp_path):
    """start_from a (shortened) spin-up and a rotating frame: the path that runs earlier
    analyses and imposes the rotation before linearizing."""
    m = samara.Model.from_file(str(root / "examples" / "blade_spinup.toml"))
    m.set("analyses.spinup.t_end", 0.02)
    d = m.to_dict()
    d["analyses"].append(
        {"name": "spinning", "type": "modal", "start_from": "spinup", "n_modes": 2,
         "write_matrices": True, "rotation": {"axis": [0.0, 0.0, 1.0], "omega": 3.0}}
    )
    f = tmp_path / "blade.toml"
    f.write_text(samara.Model.from_dict(d).to_toml())
    lin = compare(f, "spinning", cli, tmp_path / "out")
    # a rotating frame gives gyroscopic terms: G is not zero
    assert abs(lin.G).max() > 0


def test_only_modal_analyses_say_what_to_linearize_about(root):
    m = str(root / "examples" / "pendulum.toml")
    with pytest.raises(ValueError, match="not modal"):
        samara.linearize(m, "swing")
    with pytest.raises(ValueError, match="no analysis 'nope'"):
        samara.linearize(m, "nope")
    lin = samara.linearize(m)
    # the pendulum: one node (6 unknowns), a revolute joint (5 constraint equations)
    assert lin.M.shape == (6, 6) and lin.B.shape == (5, 6)
