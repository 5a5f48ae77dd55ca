"""YADE's prepared specimens (Case.preparation < 1), the method LIGGGHTS' deck uses: the grains are
deposited and consolidated with their grain–grain sliding friction and rolling friction multiplied
by `preparation`, and the grains' own values are restored on every grain–grain contact, and for every
contact made later, when the shear starts.

A driver of its own (the rendered driver.py of a prepared case calls `main` here), so that the
driver of every other case, and with it every YADE case id, stays as it was. Runs inside YADE (the
system python3): standard library and the yade module only.

Restored per grain–grain contact (YADE's Ip2_FrictMat_FrictMat_MindlinPhys sets these when a contact
is made): tangensOfFrictionAngle = μ, kr = krot, maxBendPl = eta·(r1 + r2)/2.
"""

from __future__ import annotations

import json
import math
import time

from interphase.engines.yade_driver import Driver


class PreparedDriver(Driver):
    def __init__(self, P: dict, y):
        prep = float(P["preparation"])
        self.own = dict(P["material"])
        deposit = dict(self.own, mu_pp=prep * self.own["mu_pp"], eta=prep * self.own["eta"])
        # eta = 0 with krot > 0 is an unlimited rolling spring in YADE (engines/yade.py): no rolling
        # resistance at all while deposited means krot = 0 too
        if deposit["eta"] <= 0:
            deposit["krot"] = 0.0
        super().__init__(dict(P, material=deposit), y)
        self.restored = None

    def step(self) -> None:
        before = self.start
        super().step()
        if before is None and self.start is not None:
            self.restore()

    def restore(self) -> None:
        """The grains' own friction on the Ip2 functor (new contacts) and on every grain–grain contact."""
        y, M = self.y, self.own
        grains = set(self.grain_ids)
        ip2 = self.O.engines[2].physDispatcher.functors[0]
        mat = {m.label: m.id for m in self.O.materials}
        ip2.frictAngle = y.MatchMaker(matches=[(mat["grain"], mat[label], math.atan(M[mu])) for label, mu in
                                               (("grain", "mu_pp"), ("surface", "mu_ps"), ("wall", "mu_pw"),
                                                ("side", "mu_side"))])
        ip2.krot, ip2.eta = M["krot"], M["eta"]
        n = 0
        for inter in self.O.interactions:
            if inter.isReal and inter.id1 in grains and inter.id2 in grains:
                ph = inter.phys
                ph.tangensOfFrictionAngle = M["mu_pp"]
                ph.kr = M["krot"]
                ph.maxBendPl = M["eta"] * 0.5 * (self.radius[inter.id1] + self.radius[inter.id2])
                n += 1
        self.restored = n
        with open("preparation.json", "w") as fh:
            json.dump({"preparation": self.P["preparation"], "restored_contacts": n, "step": self.start}, fh)


def main(params_path: str = "params.json") -> None:
    """`yade_driver.main` with the prepared driver."""
    import __main__

    import yade

    with open(params_path) as fh:
        P = json.load(fh)
    driver = PreparedDriver(P, yade)
    __main__.interphase_step = driver.step
    t0, c0 = time.time(), time.process_time()
    S = P["steps"]
    yade.O.run(S["n_consolidate"] + S["n_chunks_max"] * S["n_chunk"] + S["n_shear"] + 1, True)
    driver.finish(t0, c0)
