"""Both readers on recorded raw output (tests/data/raw_liggghts, raw_yade: a tiny real run of each
engine, made by tests/data/make_raw_outputs.py): the reader contract and the recorded reference,
plus checks against the raw files themselves (row counts, force sums and their sign conventions).
No engine runs here."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from interphase.io import liggghts as io_liggghts
from interphase.io import yade as io_yade
from tests.reader_contract import ReaderContract

DATA = Path(__file__).parent / "data"


@pytest.fixture(scope="module")
def liggghts_recorded():
    return DATA / "raw_liggghts", io_liggghts.read_folder(DATA / "raw_liggghts")


@pytest.fixture(scope="module")
def yade_recorded():
    return DATA / "raw_yade", io_yade.read_folder(DATA / "raw_yade")


def _dump_blocks(path: Path) -> list[np.ndarray]:
    """The numeric rows of each snapshot of a LIGGGHTS `dump local` file."""
    lines = path.read_text().splitlines()
    out, i = [], 0
    while i < len(lines):
        if lines[i].startswith("ITEM: NUMBER OF ENTRIES"):
            n, j = int(lines[i + 1]), i + 2
            while not lines[j].startswith("ITEM: ENTRIES"):
                j += 1
            out.append(np.array([[float(v) for v in line.split()] for line in lines[j + 1:j + 1 + n]]))
            i = j + 1 + n
        else:
            i += 1
    return out


class _RecordedContract(ReaderContract):
    """The reader contract on a recorded raw folder: `recorded` names the module fixture holding
    (folder, Results); the folder's reference.json is the reference."""

    recorded: str

    @pytest.fixture
    def finished(self, request):
        return request.getfixturevalue(self.recorded)

    @pytest.fixture
    def reference(self, finished):
        return json.loads((finished[0] / "reference.json").read_text())


class TestLiggghtsRecorded(_RecordedContract):
    recorded = "liggghts_recorded"

    def test_rows_and_forces_match_the_dumps(self, finished):
        """Pair rows: columns 10–12 are the force on grain i (body 1), the table holds the force on
        body 2, so Σfx = −Σ col 10; wall rows: the force on the grain (body 2) as dumped."""
        folder, res = finished
        c = res.contacts
        pairs, walls = _dump_blocks(folder / "contacts_pair.dump"), _dump_blocks(folder / "contacts_wall.dump")
        assert len(pairs) == len(walls) == c.snapshot.nunique() >= 3
        for k, (pair, wall) in enumerate(zip(pairs, walls)):
            s = c[c.snapshot == k]
            pp, ww = s[s.kind == "pp"], s[s.kind != "pp"]
            assert len(pp) == len(pair) and len(ww) == len(wall)
            assert pp.fx.sum() == pytest.approx(-pair[:, 9].sum(), rel=1e-9)
            assert pp.fz.sum() == pytest.approx(-pair[:, 11].sum(), rel=1e-9)
            assert ww.fx.sum() == pytest.approx(wall[:, 9].sum(), rel=1e-6, abs=1e-12)
            assert ww.fz.sum() == pytest.approx(wall[:, 11].sum(), rel=1e-6, abs=1e-12)

    def test_grains_match_the_particle_dump(self, finished):
        folder, res = finished
        text = (folder / "particles.dump").read_text().splitlines()
        counts = [int(text[i + 1]) for i, line in enumerate(text) if line.startswith("ITEM: NUMBER OF ATOMS")]
        assert res.particles.groupby("snapshot").size().tolist() == counts


class TestYadeRecorded(_RecordedContract):
    recorded = "yade_recorded"

    def test_rows_and_forces_match_the_csv(self, finished):
        """One table row per exported interaction (none merged in this run) and the force on id2 as
        exported, snapshot by snapshot in step order."""
        folder, res = finished
        raw = pd.read_csv(folder / "contacts.csv")
        c = res.contacts
        steps = sorted(raw.step.unique())
        assert len(steps) == c.snapshot.nunique() >= 3
        for k, step in enumerate(steps):
            r, s = raw[raw.step == step], c[c.snapshot == k]
            assert len(s) == len(r)
            assert s.fx.sum() == pytest.approx(r.fx.sum(), rel=1e-9)
            assert s.fz.sum() == pytest.approx(r.fz.sum(), rel=1e-9)

    def test_grains_match_the_particle_csv(self, finished):
        folder, res = finished
        raw = pd.read_csv(folder / "particles.csv")
        assert res.particles.groupby("snapshot").size().tolist() == raw.groupby("step").size().tolist()
