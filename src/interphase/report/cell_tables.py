"""Tables of triaxial/biaxial cell campaigns and of calibrated soil cards, as docs/soils.md prints them.

- `cell_runs(campaign)`: a cell campaign's finished runs as (summaries, curves), each run's curve
  resampled to ε1 every `STEP` (0.2 %): columns case_id, eps1, epsv, ratio (σ1′/σ3′), e (void ratio);
  strains are fractions, compression positive.
- `cell_ensembles(summ, curves, by)`: one row per physical case (the fields `by` tell apart), the
  seed ensemble of analysis.cell_ensemble.cell_result (φ_peak, ψ_max, φ at the end in degrees, e0,
  each with its 95 % interval) and the mean wall time per run [s].
- `cell_markdown`, `card_markdown`: those rows, and a card's fitted record ([[achieved]]) and held-out
  records ([[verification]]), as Markdown; angles in degrees, strains in %, σ3′ in kPa.
- `read_verification(folders)`: the rows of several `campaign element --report` folders'
  verification.csv together, one per record (a record in two: the later folder's).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pandas as pd

from interphase.analysis.cell_ensemble import cell_result

STEP = 0.002        # ε1 step of the resampled curves [-]


def cell_runs(campaign: str | Path) -> tuple[pd.DataFrame, pd.DataFrame] | None:
    """(summaries, curves) of the campaign's finished runs; None when it has none."""
    from interphase.campaign.plan import plan
    from interphase.campaign.schema import load_campaign
    from interphase.campaign.store import CampaignStore

    c = load_campaign(campaign)
    planned = {p.case_id: p for p in plan(c)}
    if not Path(c.output).exists():
        return None
    with CampaignStore(c.output) as store:
        summ = store.summaries()
        if not len(summ):
            return None
        summ = summ[summ["case_id"].isin(planned)]
        curves = []
        for cid in summ["case_id"]:
            s = pd.read_parquet(store.case_folder(cid) / "series.parquet", columns=["eps1", "epsv", "ratio", "e"])
            grid = np.arange(0, s["eps1"].max() + 1e-12, STEP)
            o = np.argsort(s["eps1"].to_numpy(), kind="stable")
            curves.append(pd.DataFrame({"case_id": cid, "eps1": grid, **{
                k: np.interp(grid, s["eps1"].to_numpy()[o], s[k].to_numpy()[o]) for k in ("epsv", "ratio", "e")}}))
    return summ, pd.concat(curves, ignore_index=True)


def cell_ensembles(summ: pd.DataFrame, curves: pd.DataFrame, by: list[str]) -> pd.DataFrame:
    """One row per physical case: its seeds' CellResult, the `by` fields, wall_s."""
    rows = []
    for key, g in summ.groupby(by, dropna=False):
        runs, e0 = [], []
        for cid in g["case_id"]:
            c = curves[curves["case_id"] == cid]
            runs.append((c["eps1"].to_numpy(), c["epsv"].to_numpy(), c["ratio"].to_numpy()))
            e0.append(float(c["e"].iloc[0]))
        r = cell_result(str(g["test"].iloc[0]), float(g["normal_stress"].iloc[0]), runs, e0)
        key = key if isinstance(key, tuple) else (key,)
        # the group's keys last: a CellResult has fields of its own by some of those names (preparation)
        rows.append({**r.to_dict(), **dict(zip(by, key)), "wall_s": float(g["elapsed"].mean())})
    return pd.DataFrame(rows)


def _iv(v, lo, hi, fmt: str = ".1f") -> str:
    """"v (lo–hi)", "v" without an interval, "–" without a value."""
    if v is None or not math.isfinite(v):
        return "–"
    return f"{v:{fmt}} ({lo:{fmt}}–{hi:{fmt}})" if lo is not None and math.isfinite(lo) else f"{v:{fmt}}"


def cell_markdown(df: pd.DataFrame, by: list[str]) -> str:
    """The rows of `cell_ensembles` as a Markdown table."""
    def iv(r, name, fmt=".1f"):
        return _iv(r[name], r[name + "_lo"], r[name + "_hi"], fmt)

    head = "| " + " | ".join(by) + " | seeds | φ_peak [°] | ε1 at peak [%] | ψ_max [°] | φ at the end [°] | e0 | wall per run [s] |"
    lines = [head, "|" + "---|" * (len(by) + 7)]
    for _, r in df.iterrows():
        keys = " | ".join(f"{r[b]:g}" if isinstance(r[b], (int, float)) else str(r[b]) for b in by)
        lines.append(f"| {keys} | {r['n_seeds']} | {iv(r, 'phi_peak_deg')} | "
                     f"{100 * r['eps1_at_peak']:.1f} | {iv(r, 'psi_max_deg')} | {iv(r, 'phi_cs_deg')} | "
                     f"{iv(r, 'void_ratio', '.3f')} | {r['wall_s']:.0f} |")
    return "\n".join(lines)


def card_rows(card: dict) -> list[dict]:
    """One row per record of a card (its TOML as a dict): the fitted one first (its measured values
    are in [[achieved]] only)."""
    out = []
    ach = {c["quantity"]: c for c in card.get("achieved", [])}
    if ach:
        out.append({"record": Path(card["target"]["record"]).stem + " (fitted)", "stress": None,
                    "dr": (ach.get("relative_density", {}).get("laboratory"), ach.get("relative_density", {}).get("measured")),
                    **{q: (c["laboratory"], c["measured"], c.get("lo"), c.get("hi"), c.get("verdict", ""))
                       for q, c in ach.items() if q in ("phi_peak_deg", "psi_max_deg", "phi_cs_deg")},
                    "eps1": None})
    for v in card.get("verification", []):
        m, chk = v["measured"], {c["quantity"]: c for c in v["checks"]}
        out.append({"record": Path(v["record"]).stem, "stress": v["confining_stress"],
                    "dr": (v["relative_density"], m.get("relative_density")),
                    **{q: (chk[q]["laboratory"], chk[q]["measured"], chk[q].get("lo"), chk[q].get("hi"),
                           chk[q].get("verdict", "")) for q in ("phi_peak_deg", "psi_max_deg") if q in chk},
                    "phi_cs_deg": (None, m.get("phi_cs_deg"), m.get("phi_cs_deg_lo"), m.get("phi_cs_deg_hi"), ""),
                    "eps1": m.get("eps1_at_peak")})
    return out


def card_markdown(card: dict) -> str:
    """Per record: σ3′, Dr0 of the record / of the model's specimens, φ_peak and ψ_max of the record /
    the model's seed mean (95 % interval) with the verdict at the card's tolerance, the model's ε1 at
    peak and its angle at the end of the cell (φ_cs)."""
    lines = ["| record | σ3′ [kPa] | Dr0 lab / model | φ_peak lab / model [°] | verdict | ψ_max lab / model [°] "
             "| verdict | ε1 at peak [%] | φ at the end [°] |", "|---|---|---|---|---|---|---|---|---|"]
    for r in card_rows(card):
        s = "–" if r["stress"] is None else f"{r['stress'] / 1e3:.0f}"
        dr = " / ".join("–" if x is None else f"{x:.2f}" for x in r["dr"])
        cells = []
        for q in ("phi_peak_deg", "psi_max_deg"):
            lab, v, lo, hi, verdict = r.get(q, (None, None, None, None, ""))
            cells += [f"{lab:.1f} / {_iv(v, lo, hi)}" if lab is not None else "–", verdict or "–"]
        eps = "–" if r["eps1"] is None else f"{100 * r['eps1']:.1f}"
        cs = r.get("phi_cs_deg", (None, None, None, None, ""))
        lines.append(f"| {r['record']} | {s} | {dr} | {' | '.join(cells)} | {eps} | {_iv(*cs[1:4])} |")
    return "\n".join(lines)


def read_verification(folders) -> pd.DataFrame:
    """The rows of several reports' verification.csv together, one per record (a record in two: the
    later folder's)."""
    return pd.concat([pd.read_csv(Path(f) / "verification.csv") for f in folders]).drop_duplicates("record", keep="last")
