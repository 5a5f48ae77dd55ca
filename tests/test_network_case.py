"""The force-network picture of a real run (Fig. 6.2 style) and `campaign report --animate`.

Uses the quick campaign run once per session by conftest.quick_campaign (periodic device, 4
interface cases); the walled device's window and walls are checked on a small synthetic snapshot.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from matplotlib.colors import to_rgba

from interphase.case import Case
from interphase.cli import main
from interphase.report.network import COLOURS, network_figure, read_snapshot_tables, run_case
from interphase.surface.spec import ProfileSpec
from interphase.tables import CONTACT_COLUMNS


@pytest.fixture(scope="module")
def peak_run(quick_campaign):
    """(campaign, folder, summary row, Case) of the strongest interface run of the quick campaign."""
    from interphase.campaign.results import open_campaign

    campaign, store, summ = open_campaign(quick_campaign)
    try:
        rows = summ[summ["test"].astype(str) == "interface"].copy()
        rows["_p"] = pd.to_numeric(rows["peak_stress_ratio"], errors="coerce")
        row = rows.sort_values("_p").iloc[-1]
        folder = store.case_folder(str(row["case_id"]))
    finally:
        store.close()
    return campaign, folder, row, run_case(folder, campaign, str(row["label"]))


@pytest.fixture(scope="module")
def peak_figure(peak_run):
    import matplotlib.pyplot as plt

    _, folder, row, case = peak_run
    snap = int(row["peak_snapshot"])
    contacts, particles = read_snapshot_tables(folder, snap)
    fig, art = network_figure(contacts, snap, particles=particles, case=case)
    yield contacts, particles, art, case
    plt.close(fig)


@pytest.mark.liggghts
def test_report_writes_the_network_of_an_interface_case(quick_campaign, tmp_path, peak_run):
    from interphase.report import tables as T
    from interphase.report.build import build_report

    res = build_report(quick_campaign, out=tmp_path / "r", n_boot=0)
    png = tmp_path / "r" / "figures" / f"network_{T._safe(str(peak_run[2]['label']))}.png"
    assert png in res.files and png.stat().st_size > 20_000
    assert not [w for w in res.warnings if "force network" in w]


@pytest.mark.liggghts
def test_one_circle_per_grain_of_the_peak_snapshot_with_its_diameter(peak_figure):
    contacts, particles, art, case = peak_figure
    assert case is not None and case.periodic
    grains = art["grains"]
    assert len(particles) > 50 and set(particles["snapshot"]) == set(contacts["snapshot"])
    off = grains.get_offsets()
    assert off.shape == (len(particles), 2)
    np.testing.assert_allclose(off, particles[["x", "z"]].to_numpy() * 1e3)
    # EllipseCollection keeps half-widths in data units (units="xy"): the grain's radius in mm
    np.testing.assert_allclose(grains._widths, particles["radius"].to_numpy() * 1e3)
    np.testing.assert_allclose(grains._heights, particles["radius"].to_numpy() * 1e3)


@pytest.mark.liggghts
def test_line_width_follows_the_normal_force(peak_figure):
    contacts, _, art, _ = peak_figure
    widths, forces = [], []
    for kind in ("pp", "ps", "pw"):
        c = contacts[contacts["kind"].astype(str) == kind]
        if f"chains-{kind}" not in art:
            assert c.empty
            continue
        lw = np.asarray(art[f"chains-{kind}"].get_linewidths(), float)
        assert lw.size == len(c)
        widths.append(lw)
        forces.append(np.abs(c["fn"].to_numpy(float)))
    lw, fn = np.concatenate(widths), np.concatenate(forces)
    order = np.argsort(fn, kind="stable")
    assert np.all(np.diff(lw[order]) >= -1e-12)                 # monotone in |fn|
    assert lw[np.argmax(fn)] == pytest.approx(art["max_width"])  # the largest force: the widest line
    assert lw.max() == pytest.approx(art["max_width"]) and lw.min() < 0.1 * lw.max()


@pytest.mark.liggghts
def test_surface_contacts_have_their_own_colour_and_lie_on_the_drawn_surface(peak_figure):
    contacts, _, art, case = peak_figure
    ps = contacts[contacts["kind"].astype(str) == "ps"]
    assert len(ps) > 0
    col_ps = art["chains-ps"].get_colors()
    col_pp = art["chains-pp"].get_colors()
    assert np.allclose(col_ps, to_rgba(COLOURS["ps"])) and np.allclose(col_pp, to_rgba(COLOURS["pp"]))
    assert not np.allclose(col_ps[0], col_pp[0])
    # the surface is drawn where the engine had it at this snapshot: the contact points lie on it
    sx, sz = art["surface"].get_data()
    x, z = ps["x1"].to_numpy() * 1e3, ps["z1"].to_numpy() * 1e3
    inside = (x > sx.min()) & (x < sx.max())
    assert inside.sum() >= 0.8 * len(x)
    assert np.abs(np.interp(x[inside], sx, sz) - z[inside]).max() < 1e-6
    assert art["surface-fill"] is not None


@pytest.mark.liggghts
def test_window_is_the_periodic_cell_and_no_branch_spans_the_box(peak_figure):
    contacts, _, art, case = peak_figure
    xs = sorted(ln.get_xdata()[0] for ln in art["window"])
    assert xs == pytest.approx([0.0, case.box_length * 1e3])
    assert all(ln.get_gid() == "window" for ln in art["window"])
    for key, coll in art.items():
        if key.startswith("chains-"):
            segs = coll.get_segments()
            span = max(abs(s[1, 0] - s[0, 0]) for s in segs)
            assert span < 0.25 * case.box_length * 1e3, key
    # contacts across x = 0 or L exist in this run and are drawn again, fainter, at the other side
    c = contacts[contacts["kind"].astype(str) == "pp"]
    crossing = ((c[["x1", "x2"]].min(axis=1) < 0) | (c[["x1", "x2"]].max(axis=1) > case.box_length)).sum()
    if crossing:
        assert "chains-pp-images" in art and len(art["chains-pp-images"].get_segments()) >= crossing


def test_walled_device_marks_the_window_inside_the_walls():
    import matplotlib.pyplot as plt

    case = Case(profile=ProfileSpec.make("sawtooth", rt=1, sw=2, sr=0.5), device="walled", box_length_d50=20,
                box_height_d50=10)
    d = case.d50
    rows = {  # grain 1 on the surface, grains 1-2 touching, grain 2 under the platen
        "snapshot": 0, "time": 0.0, "shear_disp": 1e-3, "kind": ["ps", "pp", "pw"], "id1": [-1, 1, -2],
        "id2": [1, 2, 2], "cx": 0.0, "cz": 0.0, "nx": [0.0, 0.0, 0.0], "nz": [1.0, 1.0, -1.0],
        "fn": [2.0, 1.0, 0.5], "ft": 0.0, "fx": 0.0, "fz": [2.0, 1.0, -0.5],
        "x1": [5 * d, 5 * d, 5 * d], "z1": [0.2 * d, 1.2 * d, 2.7 * d],
        "x2": [5 * d, 5 * d, 5 * d], "z2": [1.2 * d, 2.2 * d, 2.2 * d], "overlap": 0.0,
    }
    contacts = pd.DataFrame(rows)[list(CONTACT_COLUMNS)]
    particles = pd.DataFrame({"snapshot": 0, "x": [5 * d, 5 * d], "z": [1.2 * d, 2.2 * d], "radius": 0.5 * d})
    fig, art = network_figure(contacts, 0, particles=particles, case=case)
    try:
        xs = sorted(ln.get_xdata()[0] for ln in art["window"])
        assert xs == pytest.approx([v * 1e3 for v in case.window]) and xs[0] > 0
        assert sorted(ln.get_xdata()[0] for ln in art["walls"]) == pytest.approx([0.0, case.box_length * 1e3])
        assert "grain-images" not in art and len(art["grains"].get_offsets()) == 2
        lw = {k: art[f"chains-{k}"].get_linewidths()[0] for k in ("ps", "pp", "pw")}
        assert lw["ps"] > lw["pp"] > lw["pw"] > 0
        # the surface is drawn moved −x by the snapshot's shear displacement (1 mm)
        sx, sz = art["surface"].get_data()
        s = case.surface()
        assert np.allclose(np.interp(sx * 1e-3 + 1e-3, s.x, s.z) * 1e3, sz)
        assert not np.allclose(np.interp(sx * 1e-3, s.x, s.z) * 1e3, sz)
    finally:
        plt.close(fig)


@pytest.mark.liggghts
def test_cli_animate_writes_one_frame_per_contact_snapshot(quick_campaign, peak_run, tmp_path, capsys):
    from PIL import Image

    from interphase.report import tables as T

    _, folder, row, _ = peak_run
    label = str(row["label"])
    out = tmp_path / "rep"
    assert main(["report", str(quick_campaign), "--out", str(out), "--animate", label]) == 0, capsys.readouterr().err
    gif = out / "figures" / f"animation_{T._safe(label)}.gif"
    assert gif.exists() and str(gif) in capsys.readouterr().out
    n_snap = pd.read_parquet(folder / "contacts.parquet", columns=["snapshot"])["snapshot"].nunique()
    with Image.open(gif) as im:
        assert n_snap > 3 and im.n_frames == n_snap
        assert im.size[0] > 400
    assert gif.stat().st_size < 2_000_000
    assert not (out / "index.html").exists()         # --animate writes only the animation
    # a case id prefix names the run too: --animate resolves every key with find_run before drawing
    # anything (build_animations), so the prefix is checked there, on the real summaries, without
    # drawing the same animation a second time
    from interphase.campaign.results import open_campaign
    from interphase.report.network import find_run

    _, store, summ = open_campaign(quick_campaign)
    store.close()
    assert find_run(summ, str(row["case_id"])[:8])["label"] == label
    assert find_run(summ, str(row["case_id"]))["label"] == label


@pytest.mark.liggghts
def test_cli_animate_unknown_label_exits_2_with_a_message(quick_campaign, tmp_path, capsys):
    capsys.readouterr()
    code = main(["report", str(quick_campaign), "--out", str(tmp_path / "r"), "--animate", "interface-nosuch-s9"])
    err = capsys.readouterr().err
    assert code == 2
    assert "no finished run with label or case id 'interface-nosuch-s9'" in err and "Traceback" not in err
    assert not (tmp_path / "r" / "figures").exists()


@pytest.mark.liggghts
def test_a_long_animation_is_capped_evenly(peak_run, tmp_path):
    from PIL import Image

    from interphase.report.network import animate_case

    _, folder, _, case = peak_run
    gif = animate_case(folder, tmp_path / "a.gif", case=case, max_frames=3)
    with Image.open(gif) as im:
        assert im.n_frames == 3
