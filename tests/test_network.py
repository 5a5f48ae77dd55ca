"""Force-network picture (PNG) and VTK PolyData of one snapshot."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from interphase.errors import InputError
from interphase.report.network import KIND_CODE, draw_network, network_polydata, write_network_vtk
from interphase.tables import CONTACT_COLUMNS, MissingColumnError


def small_table():
    rows = {
        "snapshot": [0, 0, 0, 1], "time": 0.0, "shear_disp": [0.0, 0.0, 0.0, 1e-4],
        "kind": ["pp", "ps", "pw", "pp"], "id1": [1, -1, -2, 1], "id2": [2, 1, 2, 2],
        "cx": [0.5e-3, 0.2e-3, 1.5e-3, 0.5e-3], "cz": [1e-3, 0.0, 1e-3, 1e-3],
        "nx": [1.0, 0.0, -1.0, 1.0], "nz": [0.0, 1.0, 0.0, 0.0],
        "fn": [1.0, 3.0, 0.5, 1.0], "ft": [0.0, 0.1, 0.0, 0.0],
        "fx": [1.0, -0.1, -0.5, 1.0], "fz": [0.0, 3.0, 0.0, 0.0],
        "x1": [0.0, 0.2e-3, 1.5e-3, 0.0], "z1": [1e-3, 0.0, 1e-3, 1e-3],
        "x2": [1e-3, 0.2e-3, 1e-3, 1e-3], "z2": [1e-3, 0.5e-3, 1e-3, 1e-3], "overlap": 0.0,
    }
    return pd.DataFrame(rows)[list(CONTACT_COLUMNS)]


def test_png_written_and_not_blank(tmp_path):
    import matplotlib.image as mpimg

    prof = (np.array([0.0, 0.5e-3, 1e-3, 1.5e-3]), np.array([0.0, -0.2e-3, 0.0, -0.2e-3]))
    path = draw_network(small_table(), 0, tmp_path / "net.png", profile=prof)
    img = mpimg.imread(path)
    assert img.shape[0] > 100 and img.shape[1] > 100
    # something other than white was drawn
    assert (img[..., :3] < 0.5).any()


def test_vtk_lines_carry_forces(tmp_path):
    import pyvista as pv

    c = small_table()
    path = write_network_vtk(c, 0, tmp_path / "net")
    assert path.suffix == ".vtp" and path.exists()
    mesh = pv.read(path)
    assert mesh.n_cells == 3 and mesh.n_points == 6
    assert mesh.cell_data["force"] == pytest.approx(np.hypot([1.0, -0.1, -0.5], [0.0, 3.0, 0.0]))
    assert list(mesh.cell_data["kind"]) == [KIND_CODE[k] for k in ("pp", "ps", "pw")]
    # the surface contact runs from the contact point to the grain centre
    assert mesh.points[2] == pytest.approx([0.2e-3, 0.0, 0.0])
    assert mesh.points[3] == pytest.approx([0.2e-3, 0.0, 0.5e-3])


def test_polydata_in_memory_holds_exactly_the_chosen_snapshot():
    c = small_table()
    one = network_polydata(c, 1)              # snapshot 1: the last row only
    assert one.n_cells == 1 and one.n_points == 2
    assert one.points.tolist() == [[0.0, 0.0, 1e-3], [1e-3, 0.0, 1e-3]]
    assert one.cell_data["fn"].tolist() == [1.0] and one.cell_data["kind"].tolist() == [KIND_CODE["pp"]]
    zero = network_polydata(c, 0)             # snapshot 0: the first three rows, in order
    assert zero.n_cells == 3
    assert zero.cell_data["kind"].tolist() == [KIND_CODE[k] for k in ("pp", "ps", "pw")]
    assert zero.cell_data["force"] == pytest.approx(np.hypot([1.0, -0.1, -0.5], [0.0, 3.0, 0.0]))
    assert zero.cell_data["ft"].tolist() == [0.0, 0.1, 0.0]


def test_bad_snapshot_and_missing_column(tmp_path):
    with pytest.raises(InputError, match="snapshot 7"):
        draw_network(small_table(), 7, tmp_path / "x.png")
    with pytest.raises(MissingColumnError, match="fz"):
        write_network_vtk(small_table().drop(columns="fz"), 0, tmp_path / "x.vtp")
