"""Regenerate tests/data/liggghts_sawtooth45/ with the current LIGGGHTS engine (about 1–2 min here).

Run: .venv/bin/python tests/data/make_liggghts_sawtooth45.py [output folder]
The case: 45° saw-tooth (Rt = D50, Sw = 2 D50), μs = 0.5, the study's well-graded material (poly,
0.35–1.05 mm: its Figures 6.3 and 6.8 are for it), 1800 grains in a 60 × 30 D50 box (longer than tall,
so that the side walls take less of the shear; the 20 D50 sampling region fits), G = 50 MPa (soft, so
that it runs in a minute), 4 mm of shear (at 3 mm its peak fell on the last snapshot, a ratio still
rising), snapshots every 0.25 mm, packing seed 1, the Case's default side walls (frictionless).
Writes contacts/history/particles Parquet and case.json (the case and the engine parameters);
the raw dumps are not kept (a few MB).
"""

from __future__ import annotations

import json
import sys
import tempfile
from pathlib import Path

from interphase.case import Case
from interphase.engines.liggghts import Liggghts
from interphase.material import Gradation
from interphase.surface.spec import ProfileSpec

CASE = Case(test="interface", profile=ProfileSpec.make("sawtooth", rt=1, sw=2, sr=0), friction_ps=0.5,
            gradation=Gradation("poly"), shear_modulus=50e6, n_grains=1800, box_length_d50=60, box_height_d50=30,
            shear_distance=4e-3, snapshot_every=0.25e-3, seed=1)


def main(out: Path) -> None:
    eng = Liggghts()
    out.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory() as tmp:
        eng.write_input(CASE, tmp)
        eng.execute(tmp)
        res = eng.read_results(tmp)
        params = json.loads(Path(tmp, "engine.json").read_text())
    res.contacts.to_parquet(out / "contacts.parquet", index=False)
    res.history.to_parquet(out / "history.parquet", index=False)
    res.particles.to_parquet(out / "particles.parquet", index=False)
    (out / "case.json").write_text(json.dumps({"case": CASE.canonical(), "engine": eng.name,
                                               "engine_version": eng.version(), "engine_params": params},
                                              indent=1, default=float))


if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else Path(__file__).parent / "liggghts_sawtooth45")
