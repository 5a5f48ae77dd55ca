"""Grain shape in the laboratory's test: the cases of a triaxial campaign file run as spheres or as
rigid dimer clumps in YADE's periodic cell (studies/shape_and_kinematics/yade_shape_cell.py), by the LIGGGHTS cell's protocol
(engines/cell.py), and read by the same code as every triaxial curve (analysis.triaxial.shear_state).
Outside the tool's runner: a measurement of whether shape is the lever the spheres lack
(docs/soils.md, "Grain shape").

    PYTHONPATH=src python studies/shape_and_kinematics/shape_cell.py CAMPAIGN.toml --shape dimer --aspect 1.5 \
        --out runs/shape/dimer15 [--jobs 2] [--n-grains N] [--summary]

A dimer is two equal spheres of diameter a whose centres lie (aspect − 1)·a apart (length aspect·a),
a chosen so that the dimer's volume (the union) equals that of the grain diameter the card's gradation
draws: every grain keeps its volume-equivalent diameter, so sizes, solid volume and void ratio mean
the same for both shapes. Orientations are uniform on the sphere. Each case's result is
OUT/<label>.json, written whole and last: a rerun skips the cases that have one.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np
import pandas as pd

from interphase.analysis.triaxial import shear_state
from interphase.campaign.plan import case_label
from interphase.campaign.schema import load_campaign
from interphase.engines.cell import cell_lattice, cell_steps, servo_gain
from interphase.engines.yade import contact_parameters
from interphase.material import rayleigh_time
from interphase.recipe import CELL_RECIPE

HERE = Path(__file__).resolve().parent
EVERY = 20          # steps between servo evaluations (the LIGGGHTS cell: 10; the gain keeps per-update change)


def dimer_member_diameter(aspect: float) -> float:
    """a/d: the member diameter of a dimer (centres (aspect − 1)·a apart, aspect < 2) whose union has
    the volume of a sphere of diameter d."""
    s = aspect - 1.0
    r = 0.5
    h = r - s / 2                                   # each lens cap's height (s < 1: the members overlap)
    v = 2 * (4 / 3 * math.pi * r ** 3) - 2 * (math.pi * h * h * (3 * r - h) / 3)    # union, members of diameter 1
    return ((math.pi / 6) / v) ** (1 / 3)


def config(case, shape: str, aspect: float, out: Path, kinematics: str = "yade") -> dict:
    r = CELL_RECIPE
    k = dimer_member_diameter(aspect) if shape == "dimer" else 1.0
    length = aspect * k if shape == "dimer" else 1.0
    lat = dataclasses.replace(r, lattice_pitch=r.lattice_pitch * length)
    pack, size = cell_lattice(case, lat)
    d = pack.diameter
    rng = np.random.default_rng(10_000 + case.seed)
    grains = []
    if shape == "dimer":
        a = k * d
        ax = rng.normal(size=(d.size, 3))
        ax /= np.linalg.norm(ax, axis=1)[:, None]
        off = ax * ((aspect - 1.0) * a / 2)[:, None]
        c = np.stack([pack.x, pack.y, pack.z], axis=1)
        for i in range(d.size):
            grains.append([[*(c[i] - off[i]), a[i] / 2], [*(c[i] + off[i]), a[i] / 2]])
        r_min = float(a.min() / 2)
    else:
        grains = [[[x, y, z, di / 2]] for x, y, z, di in zip(pack.x, pack.y, pack.z, d)]
        r_min = float(d.min() / 2)
    solid = float(np.sum(math.pi / 6 * d ** 3))            # volume-equivalent: the same for both shapes
    dt = r.time_step_fraction * rayleigh_time(r_min, case.density, case.shear_modulus, case.poisson)
    steps, n_settle = cell_steps(case, dt, dataclasses.replace(r, servo_every=EVERY))
    s3 = case.normal_stress
    return dict(
        grains=grains, solid=solid, L=size[0], contact=contact_parameters(case),
        mu=case.friction_pp, mu_r=case.rolling_friction,
        prep=case.preparation, s3=s3, rate=case.strain_rate, eps_end=case.axial_strain, dt=dt, d50=case.d50,
        gain=servo_gain(case, dt, EVERY),
        every=EVERY, window=r.servo_window, compaction_cap=r.compaction_cap, shear_cap=r.shear_cap,
        n_consolidate=steps.n_consolidate, n_chunk=steps.n_chunk, n_chunks_max=steps.n_chunks_max,
        tolerance=r.tolerance, settle_energy=r.settle_energy, n_settle=n_settle, n_history=steps.n_history,
        check_stress=True, kinematics=kinematics, out=str(out))


def run_one(case, shape: str, aspect: float, folder: Path, kinematics: str = "yade") -> Path:
    tag = f"{case_label(case)}-mu{case.friction_pp:g}-mur{case.rolling_friction:g}"
    if kinematics != "yade":
        tag += f"-{kinematics}"
    out = folder / f"{tag}.json"
    if out.exists():
        return out
    cfg = config(case, shape, aspect, out.resolve(), kinematics)
    inp = folder / f"{tag}.in.json"
    inp.write_text(json.dumps(cfg))
    with open(folder / f"{tag}.log", "w") as log:
        subprocess.run(["yade", "-n", "-j1", "-x", str(HERE / "yade_shape_cell.py"), str(inp.resolve())],
                       stdout=log, stderr=subprocess.STDOUT, check=False, cwd=folder)
    inp.unlink(missing_ok=True)
    return out


def summary(folder: Path) -> pd.DataFrame:
    rows = []
    for f in sorted(folder.glob("*.json")):
        if f.name.endswith(".in.json"):
            continue
        res = json.loads(f.read_text())
        if res.get("error") or len(res["hist"]) < 3:
            rows.append(dict(run=f.stem, error=res.get("error") or "no history"))
            continue
        h = np.asarray(res["hist"], float)
        try:
            s = shear_state(h[:, 0], h[:, 1], h[:, 2], h[:, 3])
        except ValueError as err:
            rows.append(dict(run=f.stem, error=str(err)))
            continue
        rows.append(dict(run=f.stem, e0=res["e0"], phi_peak_deg=s.phi_peak_deg, eps1_peak=s.eps1_peak,
                         psi_max_deg=s.psi_max_deg, phi_end_deg=s.phi_end_deg, e_end=s.e_end,
                         dilatancy_end=s.dilatancy_end, eps1_last=s.eps1_last,
                         sigma3_departure_max=res["sigma3_departure_max"], wall_s=res["wall"],
                         n_spheres=res["n_spheres"]))
    return pd.DataFrame(rows)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("campaign", type=Path)
    ap.add_argument("--shape", choices=("sphere", "dimer"), default="dimer")
    ap.add_argument("--aspect", type=float, default=1.5)
    ap.add_argument("--out", type=Path, required=True)
    ap.add_argument("--jobs", type=int, default=1)
    ap.add_argument("--n-grains", type=int)
    ap.add_argument("--kinematics", choices=("yade", "remap"), default="yade",
                    help="remap: LIGGGHTS' fix deform kinematics (positions remapped, no affine velocity)")
    ap.add_argument("--summary", action="store_true", help="only read what has finished")
    a = ap.parse_args(argv)
    a.out.mkdir(parents=True, exist_ok=True)
    if not a.summary:
        cases = [c.case for c in load_campaign(a.campaign).cases if c.case.test == "triaxial"]
        if a.n_grains:
            cases = [c.replace(n_grains=a.n_grains) for c in cases]
        with ThreadPoolExecutor(a.jobs) as ex:
            list(ex.map(lambda c: run_one(c, a.shape, a.aspect, a.out, a.kinematics), cases))
    df = summary(a.out)
    pd.set_option("display.width", 200)
    print(df.to_string(index=False, float_format=lambda v: f"{v:.4g}"))
    return 0


if __name__ == "__main__":
    sys.exit(main())
