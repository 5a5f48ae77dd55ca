"""A calibrated card's checks against its laboratory records, as the Markdown table docs/soils.md
prints for each card: the fitted record ([[achieved]]) and every held-out one ([[verification]]).

    PYTHONPATH=src python studies/soil_cells/card_checks.py soils/karlsruhe-fine-sand.toml

Per record: σ3′, Dr0 of the record / of the model's specimens, φ_peak and ψ_max of the record / the
model's seed mean (95 % interval) with the verdict at the card's tolerance, the model's ε1 at peak and
its angle at the end of the cell (φ_cs). Angles in degrees, strains in %.
"""

from __future__ import annotations

import argparse
import math
import tomllib
from pathlib import Path


def _iv(v, lo, hi) -> str:
    if v is None or not math.isfinite(v):
        return "–"
    return f"{v:.1f} ({lo:.1f}–{hi:.1f})" if lo is not None and math.isfinite(lo) else f"{v:.1f}"


def rows(card: dict) -> list[dict]:
    """One row per record: the fitted one first (its measured values are in [[achieved]] only)."""
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


def markdown(card: dict) -> str:
    lines = ["| record | σ3′ [kPa] | Dr0 lab / model | φ_peak lab / model [°] | verdict | ψ_max lab / model [°] "
             "| verdict | ε1 at peak [%] | φ at the end [°] |", "|---|---|---|---|---|---|---|---|---|"]
    for r in rows(card):
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


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("card", type=Path)
    a = ap.parse_args(argv)
    print(markdown(tomllib.loads(a.card.read_text())))


if __name__ == "__main__":
    main()
