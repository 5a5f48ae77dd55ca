"""Regenerate tests/data/raw_liggghts/ and tests/data/raw_yade/: the raw files of a tiny real run of
each engine (the files its reader reads, nothing else) and reference.json, what the reader must
make of them. tests/test_readers_recorded.py runs the reader contract on them without any engine.

Run: .venv/bin/python tests/data/make_raw_outputs.py [liggghts|yade ...]   (about 20 s each here)
The case: a flat surface, μs = 0.2, 60 uniform grains in a 16 × 8 D50 box, G = 50 MPa, 0.5 mm of
shear at 0.05 m/s, contact snapshots every 0.25 mm (three: the start of shear, 0.25 and 0.5 mm).
Rerun it whenever an engine's output files or its metadata (the recipe record) change.
"""

from __future__ import annotations

import json
import shutil
import sys
import tempfile
from pathlib import Path

import pandas as pd

from interphase.case import Case
from interphase.engines.base import get_engine
from interphase.surface.spec import ProfileSpec

HERE = Path(__file__).parent
CASE = Case(test="interface", profile=ProfileSpec.make("flat"), friction_ps=0.2, shear_modulus=50e6, n_grains=60,
            box_length_d50=16, box_height_d50=8, shear_distance=0.5e-3, snapshot_every=0.25e-3, seed=1)
#: what the engines write besides their outputs (inputs, logs, meshes): not kept
INPUTS = {".stl", ".data", ".log", ".deck", ".py", ".j2"}
#: the engines' own logs and the driver's inputs, by name
SKIP = {"in.deck", "engine.log", "stdout.txt", "stderr.txt", "log.liggghts", "case.json"}


def reference(res) -> dict:
    """Counts and first/last snapshot values of the tables a reader made (SI, analysis frame)."""
    c, h, p = res.contacts, res.history, res.particles
    snaps = sorted(int(s) for s in c.snapshot.unique())

    def snap(k: int) -> dict:
        s = c[c.snapshot == k]
        return {"snapshot": k, "time": float(s.time.iloc[0]), "shear_disp": float(s.shear_disp.iloc[0]),
                "rows": {kind: int((s.kind == kind).sum()) for kind in ("pp", "ps", "pw")},
                "sum_fx": {kind: float(s.fx[s.kind == kind].sum()) for kind in ("pp", "ps", "pw")},
                "sum_fz": {kind: float(s.fz[s.kind == kind].sum()) for kind in ("pp", "ps", "pw")},
                "max_overlap": float(s.overlap.max())}

    def hrow(i: int) -> dict:
        return {k: float(v) for k, v in h.iloc[i].items()}

    return {"case": CASE.canonical(), "n_contact_rows": len(c), "snapshots": snaps,
            "first_snapshot": snap(snaps[0]), "last_snapshot": snap(snaps[-1]),
            "n_history_rows": len(h), "first_history": hrow(0), "last_history": hrow(-1),
            "n_particle_rows": len(p), "n_grains_first": int((p.snapshot == p.snapshot.min()).sum()),
            "n_grains_last": int((p.snapshot == p.snapshot.max()).sum()),
            "last_particles_mean": {k: float(p[p.snapshot == p.snapshot.max()][k].mean())
                                    for k in ("x", "z", "vx", "vz", "radius")}}


def make(engine_name: str) -> Path:
    eng = get_engine(engine_name)
    out = HERE / f"raw_{engine_name}"
    with tempfile.TemporaryDirectory() as tmp:
        eng.write_input(CASE, tmp)
        eng.execute(tmp)
        kept = [f for f in sorted(Path(tmp).iterdir())
                if f.is_file() and f.suffix not in INPUTS and f.name not in SKIP]
        if out.exists():
            shutil.rmtree(out)
        out.mkdir()
        for f in kept:
            shutil.copy2(f, out / f.name)
    res = eng.read_results(out)          # the reader on exactly the kept files
    ref = reference(res) | {"engine": engine_name, "engine_version": eng.version(),
                            "files": sorted(f.name for f in kept)}
    (out / "reference.json").write_text(json.dumps(ref, indent=1))
    sizes = {f.name: f.stat().st_size for f in out.iterdir()}
    print(engine_name, f"{sum(sizes.values()) / 1e3:.0f} kB", sizes)
    return out


if __name__ == "__main__":
    pd.set_option("display.width", 200)
    for name in sys.argv[1:] or ["liggghts", "yade"]:
        make(name)
