"""The contract every engine reader honours (MDAnalysis style: one class, inherited per reader).

A subclass provides a session-scoped fixture `finished` returning (folder, Results) for a finished
tiny interface case with a flat surface, read by that engine's reader; every test below then runs on it.
A subclass on recorded raw files (tests/data/raw_*, tests/test_readers_recorded.py) also overrides
`reference` with the recorded reference.json: counts and first/last snapshot values the reader must
reproduce; a live run has none.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from interphase.tables import CONTACT_COLUMNS, HISTORY_COLUMNS, PARTICLE_COLUMNS


class ReaderContract:
    def test_columns_in_contract_order(self, finished):
        _, res = finished
        assert tuple(res.contacts.columns) == CONTACT_COLUMNS
        assert tuple(res.history.columns) == HISTORY_COLUMNS
        assert res.particles is None or tuple(res.particles.columns) == PARTICLE_COLUMNS

    def test_kinds_and_ids(self, finished):
        _, res = finished
        c = res.contacts
        assert set(c.kind.astype(str).unique()) <= {"pp", "ps", "pw"}
        assert (c.kind == "pp").any() and (c.kind == "ps").any()
        walls = c[c.kind != "pp"]
        assert (walls.id1 < 0).all() and (walls.id2 > 0).all()     # wall = −1 − index, particle id ≥ 1
        assert (c[c.kind == "pp"].id1 > 0).all()

    def test_unit_normals_and_force_components(self, finished):
        _, res = finished
        c = res.contacts
        np.testing.assert_allclose(np.hypot(c.nx, c.nz), 1.0, atol=1e-6)
        np.testing.assert_allclose(c.fn, c.fx * c.nx + c.fz * c.nz, atol=1e-9)
        np.testing.assert_allclose(c.ft, -c.fx * c.nz + c.fz * c.nx, atol=1e-9)

    def test_analysis_frame_on_a_flat_surface(self, finished):
        """Normals of surface contacts point up into the grains; grains are pressed (fn > 0); the
        surface resists the soil's +x motion, so the force on the grains points −x on average."""
        _, res = finished
        ps = res.contacts[res.contacts.kind == "ps"]
        assert (ps.nz > 0.9).all() and (ps.fn > 0).all()
        late = ps[ps.snapshot == ps.snapshot.max()]
        assert late.fx.sum() < 0
        h = res.history
        assert (h.surface_fx.iloc[len(h) // 2:] > 0).mean() > 0.9      # force ON the surface: +x
        assert (h.surface_fz.iloc[len(h) // 2:] < 0).all()               # pressed down

    def test_snapshots_are_ordered_in_time(self, finished):
        _, res = finished
        snap = res.contacts.groupby("snapshot")[["time", "shear_disp"]].first()
        assert list(snap.index) == list(range(len(snap)))
        assert np.all(np.diff(snap.time.to_numpy()) > 0) and np.all(np.diff(snap.shear_disp.to_numpy()) > 0)
        assert np.all(np.diff(res.history.time.to_numpy()) > 0)

    def test_history_and_particles_are_finite(self, finished):
        _, res = finished
        assert np.isfinite(res.history[list(HISTORY_COLUMNS)].to_numpy(float)).all()
        if res.particles is not None:
            p = res.particles
            assert np.isfinite(p[["x", "z", "vx", "vz", "radius"]].to_numpy()).all()
            assert (p.groupby("snapshot").id.nunique() == p.id.nunique()).all()

    def test_parquet_roundtrip(self, finished, tmp_path):
        _, res = finished
        res.contacts.to_parquet(tmp_path / "c.parquet")
        back = pd.read_parquet(tmp_path / "c.parquet")
        pd.testing.assert_frame_equal(back, res.contacts, check_categorical=False)

    @pytest.fixture
    def reference(self):
        return None

    def test_matches_the_recorded_reference(self, finished, reference):
        if reference is None:
            pytest.skip("a live run has no recorded reference")
        _, res = finished
        c, h, p = res.contacts, res.history, res.particles
        approx = lambda v: pytest.approx(v, rel=1e-9, abs=1e-15)
        assert len(c) == reference["n_contact_rows"]
        assert sorted(int(k) for k in c.snapshot.unique()) == reference["snapshots"]
        for which in ("first_snapshot", "last_snapshot"):
            ref = reference[which]
            s = c[c.snapshot == ref["snapshot"]]
            assert float(s.time.iloc[0]) == approx(ref["time"]) and float(s.shear_disp.iloc[0]) == approx(ref["shear_disp"])
            for kind, n in ref["rows"].items():
                sel = s.kind == kind
                assert int(sel.sum()) == n, (which, kind)
                assert float(s.fx[sel].sum()) == approx(ref["sum_fx"][kind]), (which, kind)
                assert float(s.fz[sel].sum()) == approx(ref["sum_fz"][kind]), (which, kind)
            assert float(s.overlap.max()) == approx(ref["max_overlap"])
        assert len(h) == reference["n_history_rows"]
        for i, which in ((0, "first_history"), (-1, "last_history")):
            assert {k: float(v) for k, v in h.iloc[i].items()} == {k: approx(v) for k, v in reference[which].items()}
        assert len(p) == reference["n_particle_rows"]
        assert int((p.snapshot == p.snapshot.min()).sum()) == reference["n_grains_first"]
        assert int((p.snapshot == p.snapshot.max()).sum()) == reference["n_grains_last"]
        last = p[p.snapshot == p.snapshot.max()]
        for k, v in reference["last_particles_mean"].items():
            assert float(last[k].mean()) == approx(v), k
