"""Runs through Python equal `samara run` bit for bit; models from files, text and dicts;
progress callback; the GIL is released during a run."""

import subprocess
import threading
import time
from pathlib import Path

import numpy as np
import pytest
import samara
import xarray as xr
from conftest import assert_bitwise_equal


def shortened(root: Path, example: str, tmp: Path, **values) -> Path:
    """The example with some values changed (short runs), written beside `tmp`."""
    m = samara.Model.from_file(str(root / "examples" / example))
    for path, v in values.items():
        m.set(path, v)
    out = tmp / Path(example).name
    out.write_text(m.to_toml())
    return out


CASES = [
    # dynamic, joint coordinate, diagnostics off
    ("pendulum.toml", {"analyses.swing.t_end": 0.5}),
    # static (load continuation) then dynamic starting from it; beams and sectional output
    ("loaded_cantilever.toml", {"analyses.released.t_end": 0.01}),
    # driven prismatic, spring-damper coordinates with stops, many joint types
    ("landing_gear.toml", {}),
    # static only, beams
    ("curved_cantilever.toml", {}),
    # modal (dense and sparse eigensolvers, arrays that are not time records)
    ("verification/cantilever_modal.toml", {}),
]


@pytest.mark.parametrize("example,values", CASES, ids=[c[0] for c in CASES])
def test_every_analysis_equals_the_cli_bit_for_bit(root, cli, tmp_path, example, values):
    model_file = shortened(root, example, tmp_path, **values)
    if example == "landing_gear.toml":
        m = samara.Model.from_file(str(model_file))
        for a in m.analyses:
            if m.get(f"analyses.{a}.type") == "dynamic":
                m.set(f"analyses.{a}.t_end", m.get(f"analyses.{a}.step") * 20)
        model_file.write_text(m.to_toml())
    out = tmp_path / "cli"
    subprocess.run([cli, "run", str(model_file), "--out", str(out), "--quiet"], check=True)
    results = samara.run(str(model_file))
    assert list(results) == samara.load(str(model_file)).analyses
    kinds = set()
    for name, ds in results.items():
        kinds.add(ds.attrs["analysis_type"])
        with xr.open_dataset(out / f"{name}.nc", engine="scipy") as ref:
            assert_bitwise_equal(ds, ref.load())
        assert ds.attrs["status"] == "completed"
    assert kinds  # at least one analysis compared


def test_every_analysis_type_is_covered():
    kinds = set()
    for example, _ in CASES:
        text = (Path(__file__).resolve().parents[2] / "examples" / example).read_text()
        kinds |= {t for t in ("static", "dynamic", "modal") if f'type = "{t}"' in text}
    assert kinds == {"static", "dynamic", "modal"}


def test_one_analysis_and_the_ones_it_starts_from(root, tmp_path):
    f = shortened(root, "loaded_cantilever.toml", tmp_path, **{"analyses.released.t_end": 0.01})
    released = samara.run(str(f), "released")
    both = samara.run(str(f))
    assert isinstance(released, xr.Dataset)
    assert_bitwise_equal(released, both["released"])
    with pytest.raises(ValueError, match="no analysis 'nope'"):
        samara.run(str(f), "nope")


def test_out_writes_the_same_file_as_the_cli(root, cli, tmp_path):
    f = shortened(root, "pendulum.toml", tmp_path, **{"analyses.swing.t_end": 0.2})
    ds = samara.run(str(f), "swing", out=tmp_path / "py")
    subprocess.run([cli, "run", str(f), "--out", str(tmp_path / "cli"), "--quiet"], check=True)
    with xr.open_dataset(tmp_path / "py" / "swing.nc", engine="scipy") as a, xr.open_dataset(
        tmp_path / "cli" / "swing.nc", engine="scipy"
    ) as b:
        assert_bitwise_equal(a.load(), b.load())
        assert_bitwise_equal(ds, a)


def test_text_dict_and_file_models_give_the_same_results(root, tmp_path):
    f = shortened(root, "pendulum.toml", tmp_path, **{"analyses.swing.t_end": 0.2})
    from_file = samara.run(str(f), "swing")
    from_text = samara.run(f.read_text(), "swing")
    from_dict = samara.run(samara.Model.from_file(str(f)).to_dict(), "swing")
    for ds in (from_text, from_dict):
        # only the model_file attribute (a file model names its file) may differ
        assert_bitwise_equal(ds, from_file, ignore_attrs={"wall_time", "model_file"})
        assert "model_file" not in ds.attrs
    assert from_file.attrs["model_file"] == str(f)


def test_a_model_built_in_python(tmp_path):
    model = {
        "model": {"name": "pendulum", "gravity": [0.0, 0.0, -9.81]},
        "nodes": [{"name": "bob", "position": [1.0, 0.0, 0.0]}],
        "bodies": [{"name": "bob", "node": "bob", "mass": 2.0, "inertia": [[1e-3, 0, 0], [0, 1e-3, 0], [0, 0, 1e-3]]}],
        "joints": [
            {"name": "pivot", "type": "revolute", "node_a": "ground", "node_b": "bob", "position": [0.0, 0.0, 0.0], "axis": [0.0, 1.0, 0.0]}
        ],
        "analyses": [{"name": "swing", "type": "dynamic", "t_end": 0.1, "step": 1e-3, "rho_inf": 0.9}],
    }
    m = samara.load(model)
    assert m.name == "pendulum" and m.analyses == ["swing"]
    assert m.get("bodies.bob.mass") == 2.0
    m.set("bodies.bob.mass", 3.0)
    assert m.get("bodies.bob.mass") == 3.0
    ds = samara.run(m, "swing")
    assert float(ds.body_mass[0]) == 3.0
    assert ds.sizes["time"] == 101


def test_numpy_values_are_model_values():
    np = pytest.importorskip("numpy")
    m = samara.load(str(Path(__file__).resolve().parents[2] / "examples" / "pendulum.toml"))
    m.set("bodies.bob.mass", np.float64(2.5))
    m.set("model.gravity", np.array([0.0, 0.0, -3.0]))
    m.set("analyses.swing.output_every", np.int64(10))
    assert m.get("model.gravity") == [0.0, 0.0, -3.0]
    assert m.get("analyses.swing.output_every") == 10


def test_progress_callback(root):
    calls = []
    m = samara.load(str(root / "examples" / "pendulum.toml"))
    m.set("analyses.swing.t_end", 20.0)
    samara.run(m, progress=lambda name, f: calls.append((name, f)))
    assert calls, "the callback was called"
    assert {c[0] for c in calls} == {"swing"}
    fractions = [c[1] for c in calls]
    assert fractions == sorted(fractions)
    assert fractions[-1] == 1.0


def test_the_gil_is_released_during_a_run(root):
    m = samara.load(str(root / "examples" / "pendulum.toml"))
    m.set("analyses.swing.t_end", 60.0)
    done = threading.Event()
    spins = 0

    def work():
        samara.run(m)
        done.set()

    t = threading.Thread(target=work)
    start = time.perf_counter()
    t.start()
    time.sleep(0.05)
    while not done.is_set():
        spins += 1
    elapsed = time.perf_counter() - start
    t.join()
    # Holding the GIL for the whole run would leave this thread a few switch intervals
    # (5 ms each) at most; released, it spins freely (millions of times per second).
    assert elapsed > 0.1, "the run should take long enough to measure"
    assert spins > 10_000, spins


def test_displacements_from_the_reference_configuration(root, cli, tmp_path):
    # Static: position minus the model's reference (the node positions of the file).
    f = shortened(root, "loaded_cantilever.toml", tmp_path, **{"analyses.released.t_end": 0.01})
    results = samara.run(str(f))
    loaded = results["loaded"]
    ref = loaded.reference_position.values
    names = [n.decode() for n in loaded.node_name.values]
    model = samara.load(str(f))
    for i, n in enumerate(names):
        try:
            given = model.get(f"nodes.{n}.position")
        except KeyError:
            continue  # a node a beam created
        assert list(ref[i]) == given
    u = samara.displacement(loaded)
    assert (u.values == (loaded.position - loaded.reference_position).values).all()
    tip = samara.displacement(loaded, "tip")
    assert float(tip.isel(time=-1, vec3=2)) < 0.0  # sags under its load
    # The first static record is the unloaded state: load factor 0, no displacement.
    assert float(loaded.load_factor[0]) == 0.0
    assert float(abs(u.isel(time=0)).max()) == 0.0
    assert loaded.sizes["time"] == 1 + int(model.get("analyses.loaded.load_steps"))
    # Dynamic from the model's initial state: position minus the initial position.
    swing = samara.run(str(root / "examples" / "pendulum.toml"), "swing")
    d = samara.displacement(swing, "bob")
    assert float(abs(d.isel(time=0)).max()) == 0.0
    assert (d.values == (swing.position.isel(node=0) - swing.position.isel(node=0, time=0)).values).all()
    # The CLI's channel of the same name.
    out = tmp_path / "cli"
    subprocess.run([cli, "run", str(f), "--out", str(out), "--quiet"], check=True)
    svg = tmp_path / "tip.svg"
    subprocess.run([cli, "plot", str(out / "loaded.nc"), "displacement:tip:z", "--out", str(svg)], check=True)
    assert svg.stat().st_size > 1000
    with pytest.raises(KeyError, match="no node named"):
        samara.displacement(loaded, "nope")


def test_section_reference_configuration(root):
    """The sections of the unloaded first record of a static run are the reference
    sections (`section_reference_position`/`_orientation`, computed from the model's node
    positions and orientations); the beams' node lists name the nodes root to tip."""
    ds = samara.run(str(root / "examples" / "curved_cantilever.toml"))
    ds = next(iter(ds.values()))
    assert float(ds.load_factor[0]) == 0.0
    # same nodes, same section kernel: equal to round-off (1e-12 m on a 100 m arc)
    np.testing.assert_allclose(ds.section_position.values[0], ds.section_reference_position.values, rtol=0, atol=1e-12)
    q, q0 = ds.section_orientation.values[0], ds.section_reference_orientation.values
    assert np.abs(np.abs(np.sum(q * q0, axis=1)) - 1.0).max() < 1e-12  # q and -q: one rotation
    assert ds.section_reference_position.attrs["units"] == "m"
    # the loaded sections moved away from the reference
    assert np.abs(ds.section_position.values[-1] - ds.section_reference_position.values).max() > 1.0
    idx = ds.beam_node_index.values
    names = [n.decode() if isinstance(n, bytes) else str(n) for n in ds.node_name.values]
    assert len(set(idx)) == len(idx) and set(ds.beam_node_beam.values) == {0}
    np.testing.assert_allclose(np.linalg.norm(ds.beam_node_offset.values, axis=1), 1.0, atol=1e-14)
    assert names[idx[-1]] == "tip"
