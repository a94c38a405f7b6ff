"""A 16-case sweep on a local Dask cluster equals 16 sequential CLI runs (`samara sweep`,
which runs the cases one after the other); a failing case is recorded while the others
complete."""

import csv
import subprocess

import numpy as np
import pytest
import samara
import xarray as xr

distributed = pytest.importorskip("distributed")

MASSES = [0.5, 1.0, 2.0, 4.0]
LENGTHS = [0.5, 1.0, 1.5, 2.0]


@pytest.fixture(scope="module")
def client():
    cluster = distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None)
    c = distributed.Client(cluster)
    yield c
    c.close()
    cluster.close()


@pytest.fixture()
def pendulum(root, tmp_path):
    m = samara.load(str(root / "examples" / "pendulum.toml"))
    m.set("analyses.swing.t_end", 0.5)
    f = tmp_path / "pendulum.toml"
    f.write_text(m.to_toml())
    return f


def test_sixteen_cases_on_dask_equal_sixteen_cli_runs(cli, client, pendulum, tmp_path):
    grid = {"bodies.bob.mass": MASSES, "nodes.bob.position[0]": LENGTHS}
    ds = samara.sweep(str(pendulum), grid, client=client)
    assert dict(ds.sizes)["bodies.bob.mass"] == 4 and dict(ds.sizes)["nodes.bob.position[0]"] == 4
    assert (ds.case_status == "completed").all()

    params = tmp_path / "params.toml"
    params.write_text(
        "[grid]\n"
        f'"bodies.bob.mass" = {MASSES}\n'
        f'"nodes.bob.position[0]" = {LENGTHS}\n'
    )
    out = tmp_path / "cli"
    subprocess.run([cli, "sweep", str(pendulum), "--grid", str(params), "--out", str(out)], check=True)
    rows = list(csv.DictReader(open(out / "index.csv")))
    assert len(rows) == 16
    for row in rows:
        assert row["status"] == "completed"
        mass, length = float(row["bodies.bob.mass"]), float(row["nodes.bob.position[0]"])
        case = ds.sel({"bodies.bob.mass": mass, "nodes.bob.position[0]": length})
        ref = samara.open_results(out / row["directory"] / "swing.nc")
        for name, var in ref.data_vars.items():
            mine = case[name]
            assert mine.dims == var.dims, name
            assert np.asarray(mine.values).tobytes() == np.asarray(var.values).tobytes(), (name, mass, length)
    # The swept values reached the model: a longer pendulum swings slower.
    x = ds.position.isel(node=0, vec3=0, time=-1).sel({"bodies.bob.mass": 1.0})
    assert np.all(np.diff(x.values / np.array(LENGTHS)) > 0)
    assert float(ds.body_mass.sel({"bodies.bob.mass": 2.0}).isel(body=0)[0]) == 2.0


def test_a_failing_case_is_recorded_and_the_others_complete(cli, client, pendulum, tmp_path):
    cases = [{"bodies.bob.mass": m} for m in (1.0, -1.0, 2.0)]
    ds = samara.sweep(str(pendulum), cases=cases, client=client)
    assert list(ds.case_status.values) == ["completed", "error", "completed"]
    assert "bodies.bob.mass" in ds.case_error.values[1] and "mass" in ds.case_error.values[1]
    assert ds.case_error.values[0] == ""
    assert np.isnan(ds.position.isel(case=1)).all()
    assert np.isfinite(ds.position.isel(case=[0, 2])).all()
    assert list(ds["bodies.bob.mass"].values) == [1.0, -1.0, 2.0]

    params = tmp_path / "params.toml"
    params.write_text("".join(f'[[cases]]\n"bodies.bob.mass" = {c["bodies.bob.mass"]}\n' for c in cases))
    r = subprocess.run([cli, "sweep", str(pendulum), "--grid", str(params), "--out", str(tmp_path / "cli")])
    assert r.returncode == 2
    rows = list(csv.DictReader(open(tmp_path / "cli" / "index.csv")))
    assert [r["status"] for r in rows] == ["completed", "error", "completed"]
    assert "bodies.bob.mass" in rows[1]["error"]


def test_bad_sweeps_are_refused(pendulum):
    with pytest.raises(ValueError, match="either parameters"):
        samara.sweep(str(pendulum))
    with pytest.raises(ValueError, match="no analysis"):
        samara.sweep(str(pendulum), {"bodies.bob.mass": [1.0]}, analysis="nope")
    from samara.sweeps import expand

    with pytest.raises(ValueError, match="same paths"):
        expand(cases=[{"a": 1}, {"b": 2}])
    cases, names = expand({"a": [1, 2], "b": [3, 4, 5]})
    assert names == ["a", "b"] and len(cases) == 6 and cases[1] == {"a": 1, "b": 4}
