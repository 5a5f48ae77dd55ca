"""A physical case has an id (interphase.case.physical_id: the canonical case without its seed),
set at plan time, carried by the index and the summaries table, and what every seed ensemble pools
by — not a regex on the label."""

from pathlib import Path

import numpy as np
import pandas as pd

from interphase.analysis.ensemble_table import box_pools, ensemble_tables
from interphase.campaign.plan import plan
from interphase.campaign.results import with_physical_ids
from interphase.campaign.schema import load_campaign
from interphase.case import Case, Start, physical_id
from interphase.surface.spec import ProfileSpec

ROOT = Path(__file__).resolve().parents[1]
FLAT = ProfileSpec("flat")


def test_the_id_is_the_case_without_its_seed():
    c = Case(profile=FLAT)
    assert physical_id(c) == physical_id(c.replace(seed=7)) == physical_id(c.replace(name="A"))
    assert physical_id(c) != physical_id(c.replace(normal_stress=50e3))
    assert physical_id(c) != physical_id(c.replace(friction_ps=0.5))
    # a specimen taken from another engine's run: the run's id carries its seed, the engine does not
    s1, s2 = (c.replace(seed=s, start=Start("liggghts", f"id{s}")) for s in (1, 2))
    assert physical_id(s1) == physical_id(s2) != physical_id(c)
    assert physical_id(s1) != physical_id(c.replace(start=Start("yade", "id1")))


def test_the_plan_gives_every_seed_of_a_case_its_id(tmp_path):
    f = tmp_path / "c.toml"
    f.write_text('[campaign]\nname = "c"\nengines = ["liggghts"]\n[case]\ntest = "interface"\nn_grains = 50\n'
                 'profile = {kind = "flat"}\n[sweep]\nseed = [1, 2, 3]\nnormal_stress = [50e3, 100e3]\n')
    planned = plan(load_campaign(f), identity=lambda name: "r")
    iface = [p for p in planned if p.role == "interface"]
    assert len({p.label for p in iface}) == 3          # the label does not name the stress ...
    assert len({p.physical_id for p in iface}) == 2    # ... the physical id does
    assert all(p.physical_id == physical_id(p.case) and p.meta()["physical_id"] == p.physical_id for p in planned)
    box = [p for p in planned if p.role == "box"]
    assert len({p.physical_id for p in box}) == 2 and len(box) == 6


class _Curves:
    """A store's `curve` from a seed-dependent synthetic stress-ratio curve."""

    def __init__(self, level: dict):
        self.level = level

    def curve(self, cid):
        x = np.linspace(0, 6e-3, 200)
        return x, self.level[cid] * (1 - np.exp(-x / 5e-4))


def test_ensembles_pool_by_physical_id_not_by_the_label():
    """Two stresses of one surface share a label; pooled by the label they were one case of six
    seeds, by the physical id two cases of three."""
    rows, level = [], {}
    for sigma, base in (("a", 0.4), ("b", 0.6)):
        level[f"box{sigma}"] = 0.5
        for s in (1, 2, 3):
            level[f"{sigma}{s}"] = base + 0.01 * s
            rows.append(dict(case_id=f"{sigma}{s}", label=f"interface-flat-mu0.2-mono-s{s}", group="g",
                             test="interface", engine="liggghts", d50=0.7e-3, pair_id=f"box{sigma}",
                             physical_id=f"pid-{sigma}", device="periodic", theta_r_surface_deg=10.0,
                             theta_a_deg_92=0.0))
        rows.append(dict(case_id=f"box{sigma}", label="box-mono-s1", group="box", test="box", engine="liggghts",
                         d50=0.7e-3, physical_id=f"box-{sigma}", device="periodic"))
    summ = pd.DataFrame(rows)
    table = ensemble_tables(summ, _Curves(level))[0]
    assert sorted(table["physical_id"]) == ["pid-a", "pid-b"] and list(table["seeds"]) == [3, 3]
    assert table.set_index("physical_id")["tan_delta"].round(2).to_dict() == {"pid-a": 0.42, "pid-b": 0.62}
    # box tests pool by their own physical id (and engine)
    assert box_pools(summ) == {"boxa": ("boxa",), "boxb": ("boxb",)}
    # a table without the column (written before it): pooled by name, as before
    old = ensemble_tables(summ.drop(columns="physical_id"), _Curves(level))[0]
    assert list(old["seeds"]) == [6]


def test_committed_summaries_get_their_ids_from_the_plan_and_pool_as_by_name():
    """docs/reproduction/summaries.csv predates the column: the plan fills it in for every row, and
    on the study the ids pool exactly the seeds the names did (the report's numbers stay)."""
    summ = pd.read_csv(ROOT / "docs" / "reproduction" / "summaries.csv", dtype={"case_id": str, "pair_id": str})
    assert "physical_id" not in summ
    out = with_physical_ids(summ.copy(), plan(load_campaign(ROOT / "campaigns" / "study.toml")))
    assert out["physical_id"].notna().all()
    name = out["label"].str.replace(r"-s\d+$", "", regex=True)
    assert out.groupby(["group", name])["physical_id"].nunique().eq(1).all()
    assert out.groupby("physical_id")["label"].apply(lambda v: v.str.replace(r"-s\d+$", "", regex=True).nunique()).eq(1).all()
