"""`samara vtk` files read back with the `vtk` Python package (issue #13, verification 3):
expected cells and arrays, a beam's polyline points equal its node positions, the mode
animations of a modal results file, and the ParaView script, driven through a recording
stand-in for `paraview.simple` everywhere and run in ParaView itself where `pvpython` and
`xvfb-run` are installed (`apt-get install paraview xvfb`)."""

import os
import shutil
import subprocess
import sys
import types
from pathlib import Path

import numpy as np
import pytest
import samara
import xarray as xr

import vtkmodules.vtkIOXML as vtk  # the vtk package (examples/python/requirements.txt)
from vtkmodules.util.numpy_support import vtk_to_numpy

VTK_VERTEX, VTK_POLY_LINE, VTK_HEXAHEDRON = 1, 4, 12


def read_vtu(path: Path):
    r = vtk.vtkXMLUnstructuredGridReader()
    r.SetFileName(str(path))
    r.Update()
    grid = r.GetOutput()
    assert grid.GetNumberOfPoints() > 0, path
    return grid


def cell_points(grid, c):
    ids = grid.GetCell(c).GetPointIds()
    return [ids.GetId(k) for k in range(ids.GetNumberOfIds())]


def arrays(data):
    return {data.GetArrayName(i) for i in range(data.GetNumberOfArrays())}


@pytest.fixture(scope="module")
def blade(root, cli, tmp_path_factory):
    """The blade spin-up example cut to 0.04 s, run by the CLI and exported."""
    tmp = tmp_path_factory.mktemp("blade")
    m = samara.Model.from_file(str(root / "examples" / "blade_spinup.toml"))
    m.set("analyses.spinup.t_end", 0.04)
    f = tmp / "blade.toml"
    f.write_text(m.to_toml())
    subprocess.run([cli, "run", str(f), "--out", str(tmp / "out"), "--quiet"], check=True)
    subprocess.run([cli, "vtk", str(tmp / "out" / "spinup.nc"), "--out", str(tmp / "vtk")], check=True)
    with xr.open_dataset(tmp / "out" / "spinup.nc", engine="scipy") as ds:
        return tmp / "vtk", ds.load()


def test_blade_cells_and_arrays(blade):
    out, ds = blade
    nt = ds.sizes["time"]
    files = sorted(out.glob("spinup_*.vtu"))
    assert len(files) == nt
    beam_nodes = ds.beam_node_index.values
    assert len(beam_nodes) == 13
    for k in (0, nt - 1):
        g = read_vtu(out / f"spinup_{k:06d}.vtu")
        kind = vtk_to_numpy(g.GetCellData().GetArray("cell_kind"))
        types_ = np.array([g.GetCellType(c) for c in range(g.GetNumberOfCells())])
        n_nodes = ds.sizes["node"]
        # nodes, the joint and the body's CG as vertices; the hub's box; the beam twice
        assert list(np.bincount(kind)) == [n_nodes, 1, 1, 1, 1, 1]
        assert set(types_[kind <= 2]) == {VTK_VERTEX}
        assert set(types_[kind == 3]) == {VTK_HEXAHEDRON}
        assert set(types_[kind >= 4]) == {VTK_POLY_LINE}
        pts = vtk_to_numpy(g.GetPoints().GetData())
        # a beam's polyline points are its nodes' positions, exactly
        (line,) = np.flatnonzero(kind == 4)
        ids = cell_points(g, int(line))
        np.testing.assert_array_equal(pts[ids], ds.position.values[k][beam_nodes])
        # the sections' polyline: section positions, sectional forces and moments
        (sec,) = np.flatnonzero(kind == 5)
        ids = cell_points(g, int(sec))
        np.testing.assert_array_equal(pts[ids], ds.section_position.values[k])
        pd = g.GetPointData()
        for name in ("beam_force", "beam_moment"):
            np.testing.assert_array_equal(vtk_to_numpy(pd.GetArray(name))[ids], ds[name].values[k])
        want = {"kind", "index", "frame_x", "frame_y", "frame_z", "displacement", "velocity",
                "angular_velocity", "joint_force", "joint_moment", "beam_force", "beam_moment",
                "beam_strain", "beam_curvature", "mass"}
        assert want <= arrays(pd)
        # the joint's axes
        (joint,) = np.flatnonzero(kind == 1)
        jp = cell_points(g, int(joint))[0]
        for e, name in enumerate(("frame_x", "frame_y", "frame_z")):
            np.testing.assert_array_equal(vtk_to_numpy(pd.GetArray(name))[jp], ds.joint_axes.values[k, 0, e])
        # the box has the volume of the uniform box of the hub's mass and inertia
        (box,) = np.flatnonzero(kind == 3)
        c = pts[cell_points(g, int(box))]
        edges = [np.linalg.norm(c[1] - c[0]), np.linalg.norm(c[3] - c[0]), np.linalg.norm(c[4] - c[0])]
        np.testing.assert_allclose(edges, [np.sqrt(6 * 10 / 50)] * 3, rtol=1e-12)


def test_paraview_script_uses_arrays_the_files_have(blade, monkeypatch):
    """Runs the scene script against a stand-in of paraview.simple that records the calls
    and checks every array the script names against the VTU files."""
    out, _ = blade
    g = read_vtu(out / "spinup_000000.vtu")
    cell_arrays = arrays(g.GetCellData())
    point_arrays = arrays(g.GetPointData())
    calls = []

    class Proxy:
        def __init__(self, kind, **kw):
            object.__setattr__(self, "kind", kind)
            object.__setattr__(self, "props", dict(kw))
            calls.append(self)

        def __setattr__(self, k, v):
            self.props[k] = v

        def SetRepresentationType(self, t):
            self.props["representation"] = t

        def ResetCamera(self):
            calls.append("ResetCamera")

    simple = types.ModuleType("paraview.simple")

    def factory(kind):
        return lambda **kw: Proxy(kind, **kw)

    for name in ("PVDReader", "Threshold", "ExtractSurface", "Tube", "Glyph"):
        setattr(simple, name, factory(name))
    simple.GetActiveViewOrCreate = lambda *a: Proxy("View")
    simple.Show = lambda src, view=None: Proxy("Display", source=src)
    simple.ColorBy = lambda display, spec: calls.append(("ColorBy", spec))
    simple.GetAnimationScene = lambda: types.SimpleNamespace(UpdateAnimationUsingDataTimeSteps=lambda: None)
    simple.Render = lambda *a: calls.append("Render")
    simple.__all__ = [n for n in dir(simple) if not n.startswith("_")]
    pkg = types.ModuleType("paraview")
    pkg.simple = simple
    monkeypatch.setitem(sys.modules, "paraview", pkg)
    monkeypatch.setitem(sys.modules, "paraview.simple", simple)
    script = out / "spinup_scene.py"
    exec(compile(script.read_text(), str(script), "exec"), {"__file__": str(script), "__name__": "__main__"})
    proxies = [c for c in calls if isinstance(c, Proxy)]
    (reader,) = [p for p in proxies if p.kind == "PVDReader"]
    assert Path(reader.props["FileName"]) == out / "spinup.pvd"
    thresholds = [p for p in proxies if p.kind == "Threshold"]
    kinds = {p.props["LowerThreshold"] for p in thresholds}
    assert kinds == {0, 1, 3, 4, 5}
    for t in thresholds:
        assert t.props["Scalars"][0] == "CELLS" and t.props["Scalars"][1] in cell_arrays
    (glyph,) = [p for p in proxies if p.kind == "Glyph"]
    assert glyph.props["OrientationArray"][1] in point_arrays
    colored = [c[1] for c in calls if isinstance(c, tuple) and c[0] == "ColorBy"]
    assert colored and all(spec[1] in point_arrays for spec in colored)
    assert "Render" in calls


def test_mode_animation_series(root, cli, tmp_path):
    model = root / "examples" / "verification" / "cantilever_modal.toml"
    subprocess.run([cli, "run", str(model), "--out", str(tmp_path), "--quiet"], check=True)
    subprocess.run([cli, "vtk", str(tmp_path / "modes.nc"), "--out", str(tmp_path / "vtk"),
                    "--mode-frames", "12"], check=True)
    with xr.open_dataset(tmp_path / "modes.nc", engine="scipy") as ds:
        ds = ds.load()
    n_modes = ds.sizes["mode"]
    assert len(sorted((tmp_path / "vtk").glob("modes_mode_*.pvd"))) == n_modes
    x0 = ds.position.values[-1]
    size = np.linalg.norm(ds.reference_position.values.max(0) - ds.reference_position.values.min(0))
    for m in range(n_modes):
        files = sorted((tmp_path / "vtk").glob(f"modes_mode_{m + 1:02d}_*.vtu"))
        assert len(files) == 12
        # default scale: the largest displacement amplitude over the period is a tenth of
        # the model's size unless that turns some node by more than 0.5 rad
        amp = np.max([np.abs(vtk_to_numpy(read_vtu(f).GetPoints().GetData())[: len(x0)] - x0).max()
                      for f in files])
        phi = ds.mode_shape.values[m]
        t = np.abs(phi[:, :3, 0] + 1j * phi[:, :3, 1]).max()
        r = np.abs(phi[:, 3:, 0] + 1j * phi[:, 3:, 1]).max()
        s = min(0.1 * size / t if t > 0 else np.inf, 0.5 / r if r > 0 else np.inf)
        if t > 0:
            # sampled at 12 phases: the peak is within cos(π/12) of the amplitude s·t
            assert np.cos(np.pi / 12) * s * t - 1e-12 <= amp <= s * t + 1e-12


PVPYTHON, XVFB = shutil.which("pvpython"), shutil.which("xvfb-run")


@pytest.mark.skipif(PVPYTHON is None or XVFB is None, reason="ParaView (pvpython) and xvfb-run not installed")
def test_paraview_script_in_real_paraview(blade, tmp_path):
    """Runs the scene script in ParaView itself (Debian's `paraview` package, 5.11, under
    Xvfb) when it is installed: every pipeline the script builds produces cells, the beam
    tubes included, and a screenshot is rendered."""
    out, _ = blade
    check = tmp_path / "check.py"
    check.write_text(
        "import runpy, sys\n"
        "runpy.run_path(sys.argv[1])\n"
        "from paraview.simple import *\n"
        "for (name, _), src in GetSources().items():\n"
        "    src.UpdatePipeline()\n"
        "    info = src.GetDataInformation()\n"
        "    print(name, info.GetNumberOfCells())\n"
        "    assert info.GetNumberOfCells() > 0, name\n"
        "SaveScreenshot(sys.argv[2], GetActiveView(), ImageResolution=[640, 400])\n"
        "print('SCENE OK')\n"
    )
    shot = tmp_path / "scene.png"
    env = dict(os.environ, LIBGL_ALWAYS_SOFTWARE="1")
    run = subprocess.run(
        [XVFB, "-a", "-s", "-screen 0 1280x1024x24 +extension GLX", PVPYTHON, str(check),
         str(out / "spinup_scene.py"), str(shot)],
        capture_output=True, text=True, env=env, timeout=600,
    )
    assert "SCENE OK" in run.stdout, run.stdout[-2000:] + run.stderr[-2000:]
    for name in ("sections", "beams", "joint axes", "nodes"):
        assert any(line.startswith(name + " ") for line in run.stdout.splitlines()), run.stdout
    assert shot.stat().st_size > 1000
