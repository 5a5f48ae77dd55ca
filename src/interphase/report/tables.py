"""Paper-ready tables: each written as CSV, Markdown and a LaTeX (booktabs) fragment.

Headers carry their units ("θr, surface [°]"); angles are ψ, degrees from vertical, unless a header
says ccw. The LaTeX fragment is one `tabular` (no float, so a paper \\input's it inside its own
table environment) ending with note rows (wrapped at \\linewidth) and a provenance row: package,
engine and template versions, date. It is plain ASCII: Greek letters, °, ±, ≥ … become math-mode
macros ($\\delta$, $^\\circ$, $\\pm$, $\\geq$), numbers are set in math mode ($-0.39$,
$1.2\\times10^{-5}$), so it needs only booktabs (`\\usepackage{booktabs}`). tables_preview.tex
\\input's every fragment into one document (`pdflatex tables_preview.tex` shows them).
"""

from __future__ import annotations

import math
import re
import unicodedata
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd


@dataclass
class Table:
    name: str                  # file stem, e.g. "table_6_1_inputs"
    title: str
    df: pd.DataFrame           # as printed (Markdown, LaTeX, the page)
    notes: list[str] = field(default_factory=list)
    csv: pd.DataFrame | None = None    # the CSV's columns when they differ from df's (raw numbers)


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
            "{": r"\{", "}": r"\}", "~": r"\textasciitilde{}", "^": r"\^{}", "<": r"$<$", ">": r"$>$",
            "|": r"$|$"}
#: non-ASCII characters the tables use, as (LaTeX, is math); sequences first (φμ is φ with subscript μ)
_TEX_SEQ = {"φμ": (r"\phi_\mu", True), "₅₀": (r"_{50}", True), "D50": (r"D_{50}", True), "θa": (r"\theta_a", True),
            "θr": (r"\theta_r", True), "θn": (r"\theta_n", True), "σxz": (r"\sigma_{xz}", True),
            "σzz": (r"\sigma_{zz}", True), "μs": (r"\mu_s", True), "ψF": (r"\psi_F", True)}
_TEX_UNI = {"θ": r"\theta", "φ": r"\phi", "μ": r"\mu", "δ": r"\delta", "ψ": r"\psi", "σ": r"\sigma", "τ": r"\tau",
            "β": r"\beta", "Σ": r"\Sigma", "±": r"\pm", "°": r"^\circ", "≥": r"\geq", "≤": r"\leq", "·": r"\cdot",
            "₊": r"_+", "−": "-", "²": "^2", "≈": r"\approx", "×": r"\times", "→": r"\rightarrow", "∝": r"\propto",
            "√": r"\surd", "ᵀ": r"^{\mathrm{T}}", "₀": "_0", "₅": "_5", "§": r"\S"}
_TEX_TEXT = {"–": "--", "—": "---", "…": r"\ldots{}", "’": "'", "‘": "`", "“": "``", "”": "''",
             "\u00a0": "~"}


def _tex_pieces(text: str):
    """(LaTeX, is math) for each character or known sequence of `text`."""
    i = 0
    while i < len(text):
        seq = next((k for k in _TEX_SEQ if text.startswith(k, i)), None)
        if seq:
            yield _TEX_SEQ[seq]
            i += len(seq)
            continue
        ch = text[i]
        i += 1
        if ch in _TEX_UNI:
            yield _TEX_UNI[ch], True
        elif ch == "-" and i < len(text) and text[i].isdigit() and (i < 2 or not text[i - 2].isalnum()):
            yield "-", True                               # a minus sign, not a hyphen
        elif ch in _TEX_TEXT:
            yield _TEX_TEXT[ch], False
        elif ch in _TEX_ESC:
            yield _TEX_ESC[ch], False
        elif ord(ch) < 128:
            yield ch, False
        else:      # nothing the report writes; an ASCII stand-in keeps the fragment compiling
            name = unicodedata.normalize("NFKD", ch).encode("ascii", "ignore").decode() or "?"
            yield name, False


def tex_escape(text: str) -> str:
    r"""`text` as plain-ASCII LaTeX: specials escaped, Greek letters and symbols as math-mode macros,
    consecutive math pieces joined in one $…$ (so "φμ" is $\phi_\mu$, never $$)."""
    out, math_run = [], []
    for tex, is_math in _tex_pieces(str(text)):
        if is_math:
            math_run.append(tex)
            continue
        if math_run:
            out.append("$" + _join_math(math_run) + "$")
            math_run = []
        out.append(tex)
    if math_run:
        out.append("$" + _join_math(math_run) + "$")
    return "".join(out)


def _join_math(pieces: list[str]) -> str:
    out = ""
    for p in pieces:
        if re.search(r"\\[A-Za-z]+$", out) and p[:1].isalpha():     # \mu x, not \mux
            out += " "
        out += p
    return out


_NUMBER = re.compile(r"^(-?)(\d+(?:\.\d*)?)(?:e([+-]?\d+))?$")


def tex_number(text: str) -> str:
    r"""A formatted number in math mode ($-0.39$, $1.2\times10^{-5}$); other text through tex_escape."""
    m = _NUMBER.match(text)
    if not m:
        return tex_escape(text)
    sign, mant, exp = m.groups()
    body = f"{sign}{mant}" + (rf"\times10^{{{int(exp)}}}" if exp else "")
    return f"${body}$"


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


def _right_aligned(col: pd.Series) -> bool:
    """Numbers (or numbers with their interval, "0.42 [0.40, 0.44]") are set flush right."""
    if pd.api.types.is_bool_dtype(col):
        return False
    if pd.api.types.is_numeric_dtype(col):
        return True
    cells = [str(v) for v in col if v is not None and str(v) not in ("", "–", "nan")]
    return bool(cells) and all(re.match(r"^[-−]?\d", c) for c in cells)


def to_latex(table: Table, provenance: str) -> str:
    r"""One booktabs `tabular` (see the module doc): plain ASCII, notes and provenance as full-width
    rows wrapped at \linewidth."""
    n = max(1, len(table.df.columns))
    align = "".join("r" if _right_aligned(table.df[c]) else "l" for c in table.df.columns) or "l"
    lines = [f"% {tex_escape(table.title)}", f"\\begin{{tabular}}{{{align}}}", r"\toprule",
             " & ".join(tex_escape(c) for c in table.df.columns) + r" \\", r"\midrule"]
    for row in table.df.itertuples(index=False):
        lines.append(" & ".join(tex_number(_fmt(v)) for v in row) + r" \\")
    lines.append(r"\bottomrule")
    for note in [*table.notes, provenance]:
        lines.append(f"\\multicolumn{{{n}}}{{@{{}}p{{\\linewidth}}@{{}}}}{{\\footnotesize {tex_escape(note)}}} \\\\")
    lines.append(r"\end{tabular}")
    return "\n".join(lines) + "\n"


PREVIEW = r"""%% every table of the report in one document: pdflatex tables_preview.tex
\documentclass[10pt]{article}
\usepackage[a3paper,landscape,margin=1.5cm]{geometry}
\usepackage{booktabs}
\usepackage{graphicx}
\pagestyle{empty}
\begin{document}
%s
\end{document}
"""


def write_preview(tables: list[Table], folder: Path) -> Path:
    """tables_preview.tex: each fragment under its title, scaled down to the page width when wider."""
    body = []
    for t in tables:
        body.append(f"\\section*{{{tex_escape(t.title)}}}\n\\noindent\\resizebox{{\\ifdim\\width>\\linewidth"
                    f"\\linewidth\\else\\width\\fi}}{{!}}{{\\input{{{t.name}.tex}}}}\n\\clearpage")
    path = folder / "tables_preview.tex"
    path.write_text(PREVIEW % "\n".join(body), encoding="ascii")
    return path


def write_table(table: Table, folder: Path, provenance: str) -> list[Path]:
    """Write NAME.csv (table.csv when given, else df), NAME.md and NAME.tex into `folder`."""
    folder.mkdir(parents=True, exist_ok=True)
    paths = [folder / f"{table.name}.{ext}" for ext in ("csv", "md", "tex")]
    (table.csv if table.csv is not None else table.df).to_csv(paths[0], index=False)
    paths[1].write_text(to_markdown(table, provenance), encoding="utf-8")
    paths[2].write_text(to_latex(table, provenance), encoding="ascii")
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


INTERVAL_NOTE = ("95 % intervals in brackets, over the seeds: tan δ, tan φ and other positive ratios on the log "
                 "scale (never below 0), E as a ratio of seed means (log scale, Welch), angles ψ a Student-t "
                 "interval clipped to [−90°, 90°]; none with fewer than 3 seeds (docs/methods.md, Seed ensembles).")


def _with_interval(v, lo, hi, digits: int) -> str:
    """"0.421 [0.401, 0.441]"; the value alone without a finite interval; "–" without a value."""
    v, lo, hi = (pd.to_numeric(x, errors="coerce") for x in (v, lo, hi))
    if not math.isfinite(v):
        return "–"
    if math.isfinite(lo) and math.isfinite(hi):
        return f"{v:.{digits}f} [{lo:.{digits}f}, {hi:.{digits}f}]"
    return f"{v:.{digits}f}"


#: the ensembles table as printed: (header, raw column, digits)
ENSEMBLE_SHOWN = (("tan δ peak [-]", "tan_delta", 3), ("tan δ critical [-]", "tan_delta_cs", 3),
                  ("tan φ peak [-]", "tan_phi", 3), ("tan φ critical [-]", "tan_phi_cs", 3),
                  ("E peak [-]", "E", 3), ("E critical [-]", "E_cs", 3), ("θr surface [°]", "theta_r_deg", 1))


def ensembles_table(df: pd.DataFrame) -> Table:
    """The seed-ensemble table (analysis.ensemble_table.ensemble_table) as a report table: each value with its
    interval in one cell (the CSV keeps the raw columns, `_lo`/`_hi` beside each value)."""
    shown = pd.DataFrame({"group": df["group"], "case": df["case"],
                          "seeds (interface / box)": [f"{int(a)} / {int(b)}" for a, b in zip(df["seeds"], df["box_seeds"])]})
    for head, col, digits in ENSEMBLE_SHOWN:
        lo, hi = (f"{col}_lo", f"{col}_hi") if col != "theta_r_deg" else ("theta_r_lo", "theta_r_hi")
        shown[head] = [_with_interval(v, a, b, digits) for v, a, b in zip(df[col], df[lo], df[hi])]
    shown["θa > 92° [°]"] = [_fmt(v, 3) for v in pd.to_numeric(df["theta_a_deg_92"], errors="coerce")]
    shown["note"] = df["note"].fillna("")
    return Table("ensembles", "Seed ensembles: tan δ, tan φ and E at the peak and the critical state, 95 % intervals",
                 shown.reset_index(drop=True),
                 ["Peak: bagged leave-one-out, each seed's curve (smoothed over 0.5 D50) read where bootstrap means of "
                  "the other seeds peak, the mean of those values (docs/methods.md); "
                  "critical state: mean of the last 40 % of the shear; E = tan δ / tan φ of the seed means; θr: mean "
                  "of the seeds' peak-snapshot θr at the surface (ψ, degrees from vertical).", INTERVAL_NOTE],
                 csv=df)


def soil_tests_table(df: pd.DataFrame) -> Table:
    """The soil tests read two ways at their peak (analysis.soil_test.soil_test_readings)."""
    from interphase.analysis.soil_test import READINGS

    heads = {"phi_plane_deg": "φ on the box's plane [°]", "phi_mob_deg": "φ_mob = asin(q/p) [°]",
             "principal_deg": "σ1 from vertical [°]", "phi_mohr_plane_deg": "Mohr's plane reading [°]",
             "phi_sin_deg": "atan(sin φ_mob) [°]"}
    shown = pd.DataFrame({"soil test": df["case"], "seeds": df["seeds"]})
    for col in READINGS:
        shown[heads[col]] = [_with_interval(v, a, b, 1) for v, a, b in zip(df[col], df[col + "_lo"], df[col + "_hi"])]
    return Table("soil_tests", "Soil tests at their peak: the box's plane and the specimen's Mohr circle",
                 shown.reset_index(drop=True),
                 ["; ".join(f"{heads[c]}: {w}" for c, w in READINGS.items()) + ". A triaxial or biaxial test "
                  "reads φ_mob; the box reads its plane, tan φ_ds = sin φ_mob at σ1 45° from the vertical "
                  "(docs/soils.md, 'Direct shear and the laboratory's test on one card').", INTERVAL_NOTE],
                 csv=df)


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
                         "ensemble's (the bagged leave-one-out peak; E with its box tests' interval), as in the "
                         "ensembles table, which also has the critical state; other columns: the mean of the seeds' "
                         "values.")
            notes.append(INTERVAL_NOTE)
        e = pd.to_numeric(g.get("efficiency", pd.Series(dtype=float)), errors="coerce")
        if (e > E_NOTE).any():
            walls = "" if g.get("device", pd.Series(dtype=str)).isin(["periodic", "periodic3d"]).all() else (
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
                    "c": f.c, "c 95% (profile)": _profile_text(f, iv),
                    "c admissible": iv(*f.c_range), "c located": f.located,
                    "c 95% (bootstrap)": iv(*f.c_interval_bootstrap), "bootstrap": f.bootstrap,
                    "c 95% (residual)": iv(*f.extra["c_interval_residual"]) if "c_interval_residual" in f.extra
                    else "", "R² [-]": f.r2, "note": ""}
        rows.append(row)
    df = pd.DataFrame(rows)
    order = ["figure", "y", "x", "model", "slice", "n", "b0", "b0 95%", "b1", "b1 95%", "b2", "b2 95%", "c",
             "c 95% (profile)", "c admissible", "c located", "c 95% (bootstrap)", "bootstrap", "c 95% (residual)",
             "R² [-]", "note"]
    df = df.reindex(columns=[c for c in order if c in df.columns])
    shown = _coefficients_shown(df)
    return Table("correlations", "Bilinear correlations: hinge y = b0 + b1·x + b2·(x − c)₊, plateau y = b0 + b1·min(x, c)",
                 shown, ["x, c in the x column's units (angles ψ in degrees unless ccw); n: physical cases (seed "
                      "means). Intervals 95 %: coefficients and c by the bootstrap the 'bootstrap' column names — "
                      "seed: every physical case's seeds (and its box tests') drawn with replacement, means refitted; "
                      "residual: fitted + resampled residuals (where fewer than half the cases have two seeds) — c "
                      "also by profile likelihood (F test) and, beside a seed bootstrap, by the residual bootstrap "
                      "on the same means (docs/methods.md §7). c is searched over every break with at least "
                      "three points on each line (a point at c counts on both): 'c admissible'; a profile "
                      "interval that is that whole range reads 'not located' (the data fit any corner the "
                      "design allows), one that reaches an end of it is open there."], csv=df)


def _profile_text(f, iv) -> str:
    """The profile interval of c as a table cell: "not located" when it is the admissible range."""
    if not f.located:
        return "not located " + iv(*f.c_range)
    return iv(*f.c_interval_profile)


def _coefficients_shown(df: pd.DataFrame) -> pd.DataFrame:
    """The coefficients table as printed: each coefficient with its interval in one cell
    ("0.218 [0.200, 0.233]"), y against x in one column; the CSV keeps one column per number."""
    col = lambda c: df[c] if c in df else pd.Series("", index=df.index)
    both = lambda v, iv: "–" if not (isinstance(v, (int, float)) and math.isfinite(v)) else \
        f"{_fmt(v, 3)} {iv}".strip() if isinstance(iv, str) else _fmt(v, 3)
    out = pd.DataFrame({"figure": col("figure"), "y against x": [f"{y} against {x}" for y, x in zip(col("y"), col("x"))],
                        "model": col("model"), "slice": col("slice"), "n": col("n")})
    for b in ("b0", "b1", "b2"):
        if b in df:
            out[f"{b} [95 %]"] = [both(v, iv) for v, iv in zip(df[b], col(f"{b} 95%"))]
    if "c" in df:
        out["c [95 % profile]"] = [both(v, iv) for v, iv in zip(df["c"], col("c 95% (profile)"))]
    if "c 95% (bootstrap)" in df:
        out["c 95 % bootstrap"] = [f"{iv} ({b})" if isinstance(iv, str) and iv and isinstance(b, str) else
                                   (iv if isinstance(iv, str) else "") for iv, b in zip(df["c 95% (bootstrap)"], col("bootstrap"))]
    if "c 95% (residual)" in df:
        out["c 95 % residual"] = col("c 95% (residual)").fillna("")
    out["R² [-]"] = col("R² [-]")
    out["note"] = col("note").fillna("")
    return out


def _safe(name) -> str:
    return "".join(ch if ch.isalnum() or ch in "-_" else "_" for ch in str(name))
