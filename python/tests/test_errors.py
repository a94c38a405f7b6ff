"""Invalid models raise ModelError with the path of the offending value (and line and
column for files); bad paths and values raise KeyError/TypeError; solver failures."""

import pytest
import samara


PENDULUM = """
[model]
name = "pendulum"
gravity = [0.0, 0.0, -9.81]

[[nodes]]
name = "bob"
position = [1.0, 0.0, 0.0]

[[bodies]]
name = "bob"
node = "bob"
mass = 1.0
inertia = [[1e-3, 0.0, 0.0], [0.0, 1e-3, 0.0], [0.0, 0.0, 1e-3]]

[[joints]]
name = "pivot"
type = "revolute"
node_a = "ground"
node_b = "bob"
position = [0.0, 0.0, 0.0]
axis = [0.0, 1.0, 0.0]

[[analyses]]
name = "swing"
type = "dynamic"
t_end = 0.1
step = 1e-3
rho_inf = 0.9
"""


def errors(exc):
    return [d for d in exc.diagnostics if d["severity"] == "error"]


def test_a_file_error_has_file_line_column_and_path(tmp_path):
    f = tmp_path / "bad.toml"
    f.write_text(PENDULUM.replace("mass = 1.0", "mass = -1.0"))
    with pytest.raises(samara.ModelError) as e:
        samara.load(str(f))
    [d] = errors(e.value)
    assert d["file"] == str(f)
    assert d["line"] == PENDULUM.splitlines().index("mass = 1.0") + 1
    assert d["column"] == 8
    assert d["path"] == "bodies.bob.mass"
    assert "mass" in d["message"]
    assert f"{f}:{d['line']}:8" in str(e.value)
    assert isinstance(e.value, samara.SamaraError)


def test_an_unknown_reference_is_located_and_hinted(tmp_path):
    with pytest.raises(samara.ModelError) as e:
        samara.load(PENDULUM.replace('node_b = "bob"', 'node_b = "bobb"'))
    [d] = errors(e.value)
    assert d["path"] == "joints.pivot.node_b"
    assert "bobb" in d["message"]
    assert d["hint"] and "bob" in d["hint"]


def test_a_dict_error_names_the_offending_value():
    m = samara.load(PENDULUM).to_dict()
    m["bodies"][0]["inertia"][1][1] = -5.0
    with pytest.raises(samara.ModelError) as e:
        samara.load(m)
    paths = [d["path"] for d in errors(e.value)]
    assert any(p and p.startswith("bodies.bob.inertia") for p in paths), paths


def test_a_syntax_error_is_located():
    with pytest.raises(samara.ModelError) as e:
        samara.load("[model]\nname = \n")
    [d] = errors(e.value)
    assert d["line"] == 2


def test_set_validates_and_leaves_the_model_unchanged_on_error():
    m = samara.load(PENDULUM)
    with pytest.raises(samara.ModelError) as e:
        m.set("analyses.swing.step", -1.0)
    assert errors(e.value)[0]["path"] == "analyses.swing.step"
    assert m.get("analyses.swing.step") == 1e-3


def test_bad_paths_and_values():
    m = samara.load(PENDULUM)
    with pytest.raises(KeyError, match="no element named 'bobb'"):
        m.set("bodies.bobb.mass", 1.0)
    with pytest.raises(KeyError, match="out of range"):
        m.set("model.gravity[3]", 1.0)
    with pytest.raises(KeyError, match="must be a non-negative integer"):
        m.get("model.gravity[x]")
    with pytest.raises(TypeError, match="bodies.bob.mass: None"):
        m.set("bodies.bob.mass", None)
    with pytest.raises(TypeError):
        samara.load(42)


def test_a_solver_failure_keeps_the_partial_results():
    # A node with no mass, held only by a spring, cannot be accelerated consistently
    # (the case of the CLI's exit status 2).
    text = PENDULUM.replace(
        "[[analyses]]",
        '[[nodes]]\nname = "loose"\nposition = [3.0, 0.0, 0.0]\n\n[[springs]]\nname = "s"\n'
        'node_a = "bob"\nnode_b = "loose"\nstiffness = 10.0\n\n[[analyses]]',
    )
    m = samara.load(text)
    with pytest.raises(samara.SolverError) as e:
        samara.run(m)
    partial = e.value.results["swing"]
    assert partial.attrs["status"] == "failed"
    assert "failure" in partial.attrs
    again = samara.run(m, raise_on_failure=False)
    assert again["swing"].attrs["status"] == "failed"


def test_too_many_modes_is_located_before_anything_runs(tmp_path):
    # The pendulum has one degree of freedom; 5 modes are asked. Like `samara run`, the
    # Python run stops with a ModelError at the `n_modes` key instead of a runtime error.
    f = tmp_path / "modes.toml"
    f.write_text(
        PENDULUM
        + '\n[[analyses]]\nname = "modes"\ntype = "modal"\nn_modes = 5\n'
    )
    with pytest.raises(samara.ModelError) as e:
        samara.run(samara.load(str(f)))
    [d] = errors(e.value)
    assert "n_modes" in d["message"] or "modes" in d["message"]
    assert d["line"] == (PENDULUM + '\n[[analyses]]\nname = "modes"\ntype = "modal"\n').count("\n") + 1


def _import_with_isa(value, code="import samara"):
    import os
    import subprocess
    import sys

    env = dict(os.environ, SAMARA_ISA=value)
    return subprocess.run(
        [sys.executable, "-c", code], env=env, capture_output=True, text=True
    )


def test_an_unknown_instruction_set_is_refused_at_import():
    r = _import_with_isa("sse9")
    assert r.returncode != 0
    assert "ValueError" in r.stderr and 'SAMARA_ISA = "sse9"' in r.stderr
    assert "base, avx, fma, avx512" in r.stderr


def test_a_narrowed_instruction_set_runs_a_model():
    # The baseline copies run everywhere; the pendulum swings as with the widest ones
    # (round-off apart: the FMA copies round c ± ab once).
    code = (
        "import samara, sys\n"
        f"r = samara.run({PENDULUM!r})\n"
        "x = r['swing'].position.values[-1, 0]\n"
        "print(repr(float(x[0])), repr(float(x[2])))\n"
    )
    base = _import_with_isa("base", code)
    assert base.returncode == 0, base.stderr
    wide = _import_with_isa("", code)
    assert wide.returncode == 0, wide.stderr
    xb = [float(v) for v in base.stdout.split()]
    xw = [float(v) for v in wide.stdout.split()]
    assert len(xb) == 2 and all(abs(a - b) < 1e-9 for a, b in zip(xb, xw)), (xb, xw)


def test_results_that_cannot_fit_are_refused_at_the_start(tmp_path):
    # 10^12 steps of 1e-9 s, each written: at least 320 TB, more than any disk the suite
    # runs on (as `samara run`, crates/samara-cli/tests/robustness.rs).
    m = samara.load(PENDULUM.replace("t_end = 0.1", "t_end = 1e3").replace("step = 1e-3", "step = 1e-9"))
    with pytest.raises(samara.SamaraError, match="the results need at least .* output times of 320 B.* free on their disk") as e:
        samara.run(m, out=tmp_path)
    assert "output_interval" in str(e.value)
    assert list(tmp_path.iterdir()) == []
    # In memory (no `out`): refused against the available memory, not killed by it.
    with pytest.raises(samara.SamaraError, match="of memory are available to hold them") as e:
        samara.run(m)
    assert "out=DIR" in str(e.value)
