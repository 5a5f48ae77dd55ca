"""Deliberately wrong YADE mappings, for measuring what the cross-check can see (campaign.crosscheck;
tests/test_crosscheck_power.py, studies/crosscheck_power/). Never a campaign's engine by name: a
mis-mapping is passed as an engine value, `crosscheck(..., engines=("liggghts", mismapped_yade(...)))`.

The YADE engine renders its input as data (params.json, engines/yade.py); `MismappedYade` alters that
data in render(), so there is no production flag: planning, case ids and runs go through the ordinary
code, and the value travels to the local executor's spawned workers (the class by reference: they
import this module). Its recipe id mixes in the alteration, so its cases never share a folder (a case
id) with the true mapping's or with another alteration's.

Alterations: `friction` multiplies the particle–surface friction coefficient (mu_ps) [-]; `rolling`
False sets rolling resistance off (eta, krot, krot_wall, mu_r 0); `stiffness` multiplies Young's
moduli of grains and walls (E, E_wall: every contact stiffness) [-].
"""

from __future__ import annotations

import copy
import hashlib
import json
import shutil
from pathlib import Path

from interphase.engines.base import EngineSpec, engine_spec
from interphase.engines.yade import Yade


def mismap(params: dict, *, friction: float = 1.0, rolling: bool = True, stiffness: float = 1.0) -> dict:
    """A copy of YADE's params.json data with the particle–surface friction × `friction`, rolling
    resistance off (`rolling=False`: eta, krot, the facet values 0) and Young's moduli (grains and
    walls: every contact stiffness) × `stiffness`."""
    p = copy.deepcopy(params)
    m = p["material"]
    m["mu_ps"] *= friction
    if not rolling:
        m.update(eta=0.0, krot=0.0, krot_wall=0.0, mu_r=0.0)
    m["E"] *= stiffness
    m["E_wall"] *= stiffness
    return p


class MismappedYade(Yade):
    """The Yade engine whose params.json is `mismap(params, **alteration)`."""

    def __init__(self, *args, alteration: tuple = (), **kwargs):
        super().__init__(*args, **kwargs)
        self.alteration = dict(alteration)

    def render(self, case):
        files = super().render(case)
        files["params.json"] = json.dumps(mismap(json.loads(files["params.json"]), **self.alteration),
                                          allow_nan=False)
        return files

    def recipe_id(self) -> str:
        mix = super().recipe_id() + json.dumps(self.alteration, sort_keys=True)
        return hashlib.sha256(mix.encode()).hexdigest()[:16]


def mismapped_yade(**alteration) -> EngineSpec:
    """This machine's YADE as an engine value whose class is MismappedYade with `alteration`."""
    return engine_spec("yade", cls=MismappedYade, options=(("alteration", tuple(sorted(alteration.items()))),))


def copy_done(src: str | Path, dst: str | Path, engine: str = "liggghts") -> None:
    """Finished case folders of `engine` from src into dst (a variant's output reuses them)."""
    src, dst = Path(src), Path(dst)
    dst.mkdir(parents=True, exist_ok=True)
    for folder in src.iterdir():
        case = folder / "case.json"
        if (folder / "DONE").exists() and case.exists() and json.loads(case.read_text())["engine"] == engine:
            shutil.copytree(folder, dst / folder.name, dirs_exist_ok=True)
