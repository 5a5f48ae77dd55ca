"""Paper-ready tables: each written as CSV, Markdown and a LaTeX (booktabs) fragment.

Headers carry their units ("θr, surface [°]"); angles are ψ, degrees from vertical, unless a header
says ccw. The LaTeX fragment is one `tabular` (no float, so a paper \\input's it inside its own
table environment) ending with a provenance note row: package, engine and template versions, date.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd


@dataclass
class Table:
    name: str                  # file stem, e.g. "table_6_1_inputs"
    title: str
    df: pd.DataFrame
    notes: list[str] = field(default_factory=list)


# ---- formatting ------------------------------------------------------------------------------------
def _fmt(v, digits: int = 4) -> str:
    if v is None:
        return ""
    if isinstance(v, (bool, np.bool_)):
        return "yes" if v else "no"
    if isinstance(v, (int, np.integer)):
        return str(int(v))
    if isinstance(v, (float, np.floating)):
        if not math.isfinite(v):
            return "–"
        return f"{v:.{digits}g}"
    return str(v)


_TEX_ESC = {"\\": r"\textbackslash{}", "&": r"\&", "%": r"\%", "$": r"\$", "#": r"\#", "_": r"\_",
            "{": r"\{", "}": r"\}", "~": r"\textasciitilde{}", "^": r"\^{}"}
_TEX_UNI = {"θ": r"$\theta$", "φ": r"$\phi$", "μ": r"$\mu$", "δ": r"$\delta$", "ψ": r"$\psi$", "°": r"$^\circ$",
            "≥": r"$\geq$", "≤": r"$\leq$", "–": "--", "—": "---", "·": r"$\cdot$", "₊": r"$_+$", "−": "-",
            "²": r"$^2$", "₅₀": r"$_{50}$", "≈": r"$\approx$", "×": r"$\times$", "²": r"$^2$"}


def tex_escape(text: str) -> str:
    out = "".join(_TEX_ESC.get(ch, ch) for ch in str(text))
    for k, v in _TEX_UNI.items():
        out = out.replace(k, v)
    return out


def to_markdown(table: Table, provenance: str) -> str:
    cols = [str(c) for c in table.df.columns]
    md_cell = lambda s: s.replace("|", "\\|")
    lines = [f"**{table.title}**", "", "| " + " | ".join(md_cell(c) for c in cols) + " |",
             "|" + "|".join("---" for _ in cols) + "|"]
    for row in table.df.itertuples(index=False):
        lines.append("| " + " | ".join(md_cell(_fmt(v)) for v in row) + " |")
    lines.append("")
    lines += [f"{n}  " for n in table.notes]
    lines.append(f"_{provenance}_")
    return "\n".join(lines) + "\n"


def to_latex(table: Table, provenance: str) -> str:
    n = max(1, len(table.df.columns))
    align = "".join("r" if pd.api.types.is_numeric_dtype(table.df[c]) and not pd.api.types.is_bool_dtype(table.df[c])
                    else "l" for c in table.df.columns) or "l"
    lines = [f"% {tex_escape(table.title)}", f"\\begin{{tabular}}{{{align}}}", r"\toprule",
             " & ".join(tex_escape(c) for c in table.df.columns) + r" \\", r"\midrule"]
    for row in table.df.itertuples(index=False):
        lines.append(" & ".join(tex_escape(_fmt(v)) for v in row) + r" \\")
    lines.append(r"\bottomrule")
    for note in [*table.notes, provenance]:
        lines.append(f"\\multicolumn{{{n}}}{{l}}{{\\footnotesize {tex_escape(note)}}} \\\\")
    lines.append(r"\end{tabular}")
    return "\n".join(lines) + "\n"


def write_table(table: Table, folder: Path, provenance: str) -> list[Path]:
    """Write NAME.csv, NAME.md and NAME.tex into `folder`; returns the paths."""
    folder.mkdir(parents=True, exist_ok=True)
    paths = [folder / f"{table.name}.{ext}" for ext in ("csv", "md", "tex")]
    table.df.to_csv(paths[0], index=False)
    paths[1].write_text(to_markdown(table, provenance), encoding="utf-8")
    paths[2].write_text(to_latex(table, provenance), encoding="utf-8")
    return paths


# ---- the report's tables ---------------------------------------------------------------------------
_PARAM_HEAD = {"rt": "Rt/D50 [-]", "sr": "Sr/D50 [-]", "sw": "Sw/D50 [-]", "au": "Au/D50 [-]", "ar": "Ar [-]",
               "rtmax": "Rtmax/D50 [-]", "friction_ps": "tan φμ [-]", "gradation": "gradation", "seed": "seed",
               "kind": "profile"}


def _values_text(values) -> str:
    vals = sorted({v for v in values if v is not None}, key=lambda v: (isinstance(v, str), v if not isinstance(v, str) else 0, str(v)))
    return ", ".join(_fmt(v) for v in vals)


def input_tables(campaign) -> list[Table]:
    """Tables 6.1 and 6.2 from a loaded campaign (schema.Campaign): what each group sweeps and keeps.

    6.1 style: one row per group: swept variables with their values, and the profile parameters of the
    study's regular triangles (Rt, Sr, Sw) — constant value, or "varied".
    6.2 style: the random (Group 4 kind) profiles: Au, Ar, Rtmax per experiment name."""
    rows, random_cols = [], {}
    for g in campaign.groups:
        cases = [c for c in campaign.cases if c.group == g.name and c.role != "box"]
        if not cases:
            continue
        per_var: dict[str, list] = {}
        for c in cases:
            for k, v in c.values:
                per_var.setdefault(k, []).append(v if not isinstance(v, tuple) else _spec_text(dict(v)))
        specs = [c.case.profile for c in cases]
        row = {"group": g.name, "cases": len(cases),
               "variables": "; ".join(f"{_PARAM_HEAD.get(k.split('.')[-1], k)} = {_values_text(v)}"
                                      for k, v in per_var.items() if k != "name")}
        for p in ("rt", "sr", "sw"):
            vals = {dict(s.params).get(p) for s in specs if s.kind == "sawtooth"}
            vals.discard(None)
            row[_PARAM_HEAD[p]] = "varied" if len(vals) > 1 else (_fmt(float(next(iter(vals)))) if vals else "–")
        kinds = sorted({s.kind for s in specs})
        row["profiles"] = ", ".join(kinds)
        rows.append(row)
        for c in cases:
            s = c.case.profile
            if s.kind == "random":
                name = dict(c.values).get("name") or c.case.name or f"seed {dict(s.params).get('seed')}"
                random_cols[str(name)] = {_PARAM_HEAD[p]: float(dict(s.params)[p]) for p in ("au", "ar", "rtmax")}
    out = [Table("table_6_1_inputs", f"Table 6.1 style: variables and constants per group ({campaign.name})",
                 pd.DataFrame(rows), ["Sizes in units of D50; constant values, or 'varied' where the group sweeps them."])]
    if random_cols:
        df = pd.DataFrame(random_cols)
        df.insert(0, "variable", df.index)
        out.append(Table("table_6_2_random", f"Table 6.2 style: random-profile parameters ({campaign.name})",
                         df.reset_index(drop=True), ["Each segment: Au and Ar·Au times a random multiplier (surface.profiles)."]))
    return out


def _spec_text(d: dict) -> str:
    kind = d.pop("kind", "?")
    return kind + ("(" + ", ".join(f"{k}={_fmt(v)}" for k, v in sorted(d.items())) + ")" if d else "")


RESULT_COLUMNS = (
    ("label", "case"), ("seeds", "seeds"), ("friction_ps", "tan φμ [-]"), ("gradation", "gradation"),
    ("theta_a_deg_92", "θa > 92° [°]"), ("theta_a_deg_90", "θa ≥ 90° [°]"), ("rnc", "Rnc(D50) [-]"),
    ("peak_stress_ratio", "tan δ peak [-]"), ("peak_stress_ratio_iv", "tan δ 95%"), ("tan_phi", "tan φ box [-]"),
    ("efficiency", "E [-]"), ("efficiency_iv", "E 95%"),
    ("theta_r_surface_deg", "θr surface [°]"), ("theta_r_surface_deg_iv", "θr 95%"),
    ("theta_n_surface_deg", "θn surface [°]"), ("lee_share_surface", "lee share [-]"),
    ("theta_r_region_deg", "θr region [°]"), ("stress_ratio_region", "−σxz/σzz region [-]"),
    ("shear_disp_at_peak_mm", "u at peak [mm]"), ("shear_band_d50", "shear band [D50]"),
    ("inertial_number", "I [-]"),
)
#: quantities whose 95 % interval the results tables print beside them ("[lo, hi]")
RESULT_INTERVALS = ("peak_stress_ratio", "efficiency", "theta_r_surface_deg")


def _interval_text(lo, hi) -> str:
    lo, hi = pd.to_numeric(lo, errors="coerce"), pd.to_numeric(hi, errors="coerce")
    return "" if not (math.isfinite(lo) and math.isfinite(hi)) else f"[{_fmt(lo, 3)}, {_fmt(hi, 3)}]"


#: an efficiency above this gets a note in the tables: the interface is stronger than its soil's box test
E_NOTE = 1.2


def ensembles_table(df: pd.DataFrame) -> Table:
    """The seed-ensemble table (report.ensembles.ensemble_table) as a report table."""
    return Table("ensembles", "Seed ensembles: tan δ, tan φ and E at the peak and the critical state, 95 % intervals",
                 df, ["Peak: the maximum of the seed-mean curve (smoothed over 0.5 D50), interval Student t over the "
                      "seeds' values there; critical state: mean of the last 40 % of the shear, t interval; E: "
                      "bootstrap of the ratio of seed means (docs/methods.md, Seed ensembles). θr: mean of the "
                      "seeds' peak-snapshot θr at the surface (ψ, degrees from vertical), t interval."])


def findings_tables(points: pd.DataFrame) -> list[Table]:
    """The cross-group findings (analysis.findings) that the points can answer: the > 92° filter
    (Fig. 6.7), Rnc's uniqueness (Fig. 6.5), Group 2's θa by spacing. None without Group 1."""
    from interphase.analysis import findings as F

    if points.empty or "group" not in points or not (points["group"] == F.REFERENCE).any():
        return []
    ref = ("Reference: the bilinear (plateau) line fitted to Group 1's regular saw-teeth at each friction; "
           "rms, mean and largest residual of each group's physical cases (seed means) about it. A group on "
           "the line scatters like Group 1 itself.")
    out = []
    fc = F.filter_collapse(points)
    if len(fc):
        out.append(Table("finding_filter_collapse", "Fig. 6.7: tan δ about Group 1's line against θa, all normals "
                         "(≥ 90°) and flat ones left out (> 92°)", fc,
                         [ref, "The study: Groups 2 and 5 leave the line with ≥ 90° and join it with > 92°."]))
    rn = F.rnc_uniqueness(points)
    if len(rn):
        out.append(Table("finding_rnc", "Fig. 6.5: E about Group 1's line against Rnc(D50), and against θa (> 92°)",
                         rn, [ref, "The study: Rnc gives no unique correlation (Groups 2, 4, 5 deviate)."]))
    sp = F.spaced_theta_a(points)
    if len(sp):
        out.append(Table("finding_spaced_theta_a", "Group 2: θa by flat spacing Sr/D50, with tan δ and θr per "
                         "friction", sp, ["θa from the particle-centroid trace (D50), degrees from vertical; "
                                          "the study: θa (> 92°) ≈ 42° whatever Sr."]))
    return out


def results_tables(points: pd.DataFrame) -> list[Table]:
    """One results table per group, one row per physical case (SeedEnsemble.points: seed means; angles
    ψ in degrees; θa = 0 for non-dilative), with its seed count and the 95 % intervals of tan δ, E
    and θr. A run-level table (no `seeds` column) is printed as it is, one row per run."""
    pts = points.copy()
    pts["shear_disp_at_peak_mm"] = pd.to_numeric(pts.get("shear_disp_at_peak", np.nan), errors="coerce") * 1e3
    for c in RESULT_INTERVALS:
        if f"{c}_lo" in pts and f"{c}_hi" in pts:
            pts[f"{c}_iv"] = [_interval_text(lo, hi) for lo, hi in zip(pts[f"{c}_lo"], pts[f"{c}_hi"])]
    per_case = "seeds" in pts
    out = []
    for grp, g in pts.groupby("group", sort=True):
        cols = [(k, h) for k, h in RESULT_COLUMNS if k in g.columns]
        df = g.sort_values([c for c in ("friction_ps", "gradation", "label") if c in g.columns])[[k for k, _ in cols]]
        df.columns = [h for _, h in cols]
        notes = ["Angles ψ, degrees from vertical (positive toward −x); θa = 0 marks a non-dilative surface."]
        if per_case:
            notes.append("One row per physical case: the mean over its seeds (runs). tan δ, tan φ and E are the seed "
                         "ensemble's (peak of the seed-mean curve; E with its box tests' bootstrap interval), as in the "
                         "ensembles table, which also has the critical state; other columns: the mean of the seeds' "
                         "values. 95 % intervals: Student t over the seeds (E: bootstrap); none for one seed.")
        e = pd.to_numeric(g.get("efficiency", pd.Series(dtype=float)), errors="coerce")
        if (e > E_NOTE).any():
            walls = "" if (g.get("device", pd.Series(dtype=str)) == "periodic").all() else (
                "; in the walled device the side walls confine the soil above a rough surface beyond the box "
                "test's state")
            notes.append(f"{int((e > E_NOTE).sum())} case(s) with E > {E_NOTE:g}{walls} (docs/strength.md): see "
                         "their interval and the ensembles table's note.")
        what = "physical cases" if per_case else "interface cases"
        seeds = f", {int(pd.to_numeric(g['seeds']).sum())} runs" if per_case else ""
        out.append(Table(f"results_{_safe(grp)}", f"Results, group {grp} ({len(df)} {what}{seeds})",
                         df.reset_index(drop=True), notes))
    return out


def coefficient_table(fit_results) -> Table:
    """Fitted coefficients with their intervals (bootstrap percentile; c also by profile likelihood)."""
    rows = []
    for fr in fit_results:
        f = fr.fit
        row = {"figure": fr.spec.figure, "y": fr.spec.y, "x": fr.spec.x, "model": fr.spec.model, "slice": fr.slice,
               "n": fr.n}
        if f is None:
            row |= {"b0": np.nan, "b1": np.nan, "b2": np.nan, "c": np.nan, "c 95% (profile)": "", "c 95% (bootstrap)": "",
                    "R² [-]": np.nan, "note": fr.reason}
        else:
            iv = lambda lo, hi: f"[{_fmt(lo)}, {_fmt(hi)}]"
            coef = list(f.coef) + [np.nan] * (3 - len(f.coef))
            civ = list(f.coef_interval) + [(np.nan, np.nan)] * (3 - len(f.coef_interval))
            row |= {"b0": coef[0], "b0 95%": iv(*civ[0]), "b1": coef[1], "b1 95%": iv(*civ[1]),
                    "b2": coef[2], "b2 95%": iv(*civ[2]) if f.model == "hinge" else "",
                    "c": f.c, "c 95% (profile)": iv(*f.c_interval_profile),
                    "c 95% (bootstrap)": iv(*f.c_interval_bootstrap), "bootstrap": f.bootstrap,
                    "c 95% (residual)": iv(*f.extra["c_interval_residual"]) if "c_interval_residual" in f.extra
                    else "", "R² [-]": f.r2, "note": ""}
        rows.append(row)
    df = pd.DataFrame(rows)
    order = ["figure", "y", "x", "model", "slice", "n", "b0", "b0 95%", "b1", "b1 95%", "b2", "b2 95%", "c",
             "c 95% (profile)", "c 95% (bootstrap)", "bootstrap", "c 95% (residual)", "R² [-]", "note"]
    df = df.reindex(columns=[c for c in order if c in df.columns])
    return Table("correlations", "Bilinear correlations: hinge y = b0 + b1·x + b2·(x − c)₊, plateau y = b0 + b1·min(x, c)",
                 df, ["x, c in the x column's units (angles ψ in degrees unless ccw); n: physical cases (seed "
                      "means). Intervals 95 %: coefficients and c by the bootstrap the 'bootstrap' column names — "
                      "seed: every physical case's seeds (and its box tests') drawn with replacement, means refitted; "
                      "residual: fitted + resampled residuals (where fewer than half the cases have two seeds) — c "
                      "also by profile likelihood (F test) and, beside a seed bootstrap, by the residual bootstrap "
                      "on the same means (docs/methods.md §7)."])


def _safe(name) -> str:
    return "".join(ch if ch.isalnum() or ch in "-_" else "_" for ch in str(name))
