"""Engine cross-check: every case of a campaign run with LIGGGHTS and YADE, compared metric by metric.

    report = crosscheck("campaigns/crosscheck.toml")      # runs (or reuses) both engines' cases
    report.table                                          # one row per case × metric
    report.markdown()                                     # the table of docs/crosscheck.md

The campaign file is an ordinary campaign (`campaign run` reads it too) plus a `[crosscheck]` table of
tolerances, which `campaign run` never sees (its lines are blanked before the schema reads the file,
so every other line keeps its number in error messages):

    [crosscheck]
    stress_ratio_rel = 0.10    # peak stress ratio (tan δ; box tests tan φ): |Δ| / mean of the two engines
    angle_deg = 3.0            # θr, θn at the surface (ψ, degrees from vertical): |Δ|

Metrics (from each case's summary.json, interphase.analysis.summary row keys): peak_stress_ratio,
shear_disp_at_peak [m], theta_r_surface_deg (at the peak snapshot), theta_r_surface_mean_deg (over the
loaded snapshots), theta_n_surface_deg [deg, ψ], dilation_at_peak [m]. Those with a tolerance pass
or fail; the others are reported with their differences.
Runs go through interphase.campaign.run.run_campaign, so finished cases (DONE) are reused.
"""

from __future__ import annotations

import math
import os
import re
import sys
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

import pandas as pd

from interphase.errors import InputError

ENGINES = ("liggghts", "yade")
DEFAULT_TOLERANCES = {"stress_ratio_rel": 0.10, "angle_deg": 3.0}
#: (row key, unit, how compared: "rel" | "abs" | None, tolerance key)
METRICS = (
    ("peak_stress_ratio", "-", "rel", "stress_ratio_rel"),
    ("shear_disp_at_peak", "m", None, None),
    ("theta_r_surface_deg", "deg", "abs", "angle_deg"),
    ("theta_r_surface_mean_deg", "deg", "abs", "angle_deg"),
    ("theta_n_surface_deg", "deg", "abs", "angle_deg"),
    ("dilation_at_peak", "m", None, None),
)
_HEADER = re.compile(r"^\s*\[")
_XC_HEADER = re.compile(r"^\s*\[\s*crosscheck\s*\]\s*(#.*)?$")


def split_crosscheck(text: str, where: str) -> tuple[str, dict]:
    """(campaign text with the [crosscheck] lines blanked, validated tolerances [located errors])."""
    lines = text.splitlines(keepends=True)
    start = next((i for i, ln in enumerate(lines) if _XC_HEADER.match(ln)), None)
    tolerances = dict(DEFAULT_TOLERANCES)
    if start is None:
        return text, tolerances
    end = next((i for i in range(start + 1, len(lines)) if _HEADER.match(lines[i])), len(lines))
    try:
        table = tomllib.loads("".join(lines[start:end]))["crosscheck"]
    except tomllib.TOMLDecodeError as exc:
        raise InputError(f"TOML syntax error in [crosscheck]: {exc}", where=f"{where}:{start + 1}") from None
    for key, value in table.items():
        line = next((start + 1 + k for k, ln in enumerate(lines[start:end]) if re.match(rf"^\s*{re.escape(key)}\s*=", ln)),
                    start + 1)
        if key not in DEFAULT_TOLERANCES:
            raise InputError(f"unknown key {key!r} in [crosscheck]", where=f"{where}:{line}",
                             fix=f"allowed keys: {', '.join(DEFAULT_TOLERANCES)}")
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value) or value <= 0:
            raise InputError(f"[crosscheck].{key} must be a positive number, got {value!r}", where=f"{where}:{line}",
                             fix="e.g. stress_ratio_rel = 0.10 (10 %), angle_deg = 3.0")
        tolerances[key] = float(value)
    blanked = lines[:start] + ["#\n"] * (end - start) + lines[end:]
    return "".join(blanked), tolerances


def load(path: str | os.PathLike, output=None):
    """(Campaign, tolerances, path of the campaign text `campaign run` can read, cleanup())."""
    from interphase.campaign.schema import load_campaign

    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as exc:
        raise InputError(f"cannot read the campaign file ({exc.strerror})", where=str(path),
                         fix="give the path of an existing .toml file") from None
    _, tol = split_crosscheck(text, str(path))   # validates [crosscheck]; the schema skips that table
    return load_campaign(path, output=output), tol, path, lambda: None


@dataclass
class CrosscheckReport:
    campaign: str
    output: Path
    tolerances: dict
    table: pd.DataFrame                 # case, role, metric, unit, liggghts, yade, abs_diff, rel_diff, tolerance, passed
    missing: list = field(default_factory=list)   # (label, engine, status) of cases without a summary

    @property
    def judged(self) -> pd.DataFrame:
        """The rows that decide pass/fail: seed means where cases repeat over seeds, else single cases."""
        t = self.table
        if (t["seeds"] > 1).any():
            return t[t["seeds"] > 1]
        return t

    @property
    def passed(self) -> bool:
        checked = self.judged.dropna(subset=["passed"])
        return not self.missing and bool(checked["passed"].astype(bool).all())

    def markdown(self, all_rows: bool = False) -> str:
        """The deciding rows (seed means if any; `all_rows` adds every single case) as Markdown;
        values are mean ± sd over seeds where there are several."""
        t = self.table if all_rows else self.judged
        head = ("| case | metric | LIGGGHTS | YADE | abs diff | rel diff | tolerance | pass |\n"
                "|---|---|---|---|---|---|---|---|\n")
        rows = []
        for r in t.itertuples():
            tol = "" if r.tolerance is None or (isinstance(r.tolerance, float) and math.isnan(r.tolerance)) else (
                f"{r.tolerance:.0%} rel" if r.kind == "rel" else f"{r.tolerance:g} {r.unit} abs")
            ok = "" if r.passed is None or (isinstance(r.passed, float) and math.isnan(r.passed)) else (
                "yes" if r.passed else "**NO**")
            rows.append(f"| {r.case} | {r.metric} | {_fmt(r.liggghts, r.liggghts_sd)} | {_fmt(r.yade, r.yade_sd)} | {_fmt(r.abs_diff)} | "
                        f"{_fmt_pct(r.rel_diff)} | {tol} | {ok} |")
        miss = "".join(f"\n- {lab} ({eng}): {st}" for lab, eng, st in self.missing)
        return head + "\n".join(rows) + ("\n\nCases without a result:" + miss if miss else "") + "\n"

    def to_json(self) -> dict:
        return {"campaign": self.campaign, "output": str(self.output), "tolerances": self.tolerances,
                "passed": self.passed, "missing": [list(m) for m in self.missing],
                "rows": self.table.astype(object).where(self.table.notna(), None).to_dict(orient="records")}


def _fmt(v, sd=None) -> str:
    if v is None or (isinstance(v, float) and not math.isfinite(v)):
        return "—"
    if sd is not None and isinstance(sd, float) and math.isfinite(sd):
        return f"{v:.4g} ± {sd:.2g}"
    return f"{v:.4g}"


def _fmt_pct(v) -> str:
    return "—" if v is None or (isinstance(v, float) and not math.isfinite(v)) else f"{v:.1%}"


def compare(summaries: dict[str, dict[str, dict]], roles: dict[str, str], tolerances: dict) -> pd.DataFrame:
    """summaries[label][engine] = summary row → comparison table (one row per case × metric).

    rel_diff = |a − b| / mean(|a|, |b|) (symmetric: neither engine is the reference)."""
    rows = []
    for label, by_engine in summaries.items():
        a, b = by_engine.get("liggghts", {}), by_engine.get("yade", {})
        for key, unit, kind, tol_key in METRICS:
            va, vb = _num(a.get(key)), _num(b.get(key))
            diff = abs(va - vb) if math.isfinite(va) and math.isfinite(vb) else math.nan
            mean = 0.5 * (abs(va) + abs(vb))
            rel = diff / mean if math.isfinite(diff) and mean > 0 else math.nan
            tol = tolerances.get(tol_key) if tol_key else None
            if tol is None or not math.isfinite(diff):
                passed = None
            else:
                passed = bool((rel if kind == "rel" else diff) <= tol)
            rows.append({"case": label, "role": roles.get(label, ""), "metric": key, "unit": unit, "kind": kind,
                         "liggghts": va, "yade": vb, "abs_diff": diff, "rel_diff": rel, "tolerance": tol,
                         "passed": passed, "seeds": int(a.get("_seeds", 1)),
                         "liggghts_sd": _num(a.get(key + "_sd")), "yade_sd": _num(b.get(key + "_sd"))})
    return pd.DataFrame(rows, columns=["case", "role", "metric", "unit", "kind", "liggghts", "yade", "abs_diff",
                                       "rel_diff", "tolerance", "passed", "seeds", "liggghts_sd", "yade_sd"])


_SEED = re.compile(r"-s(-?\d+)$")


def seed_means(summaries: dict[str, dict[str, dict]], roles: dict[str, str]):
    """Cases that differ only in their packing seed (labels ending -s<seed>) → per-engine means over
    the seeds that BOTH engines finished, as pseudo-cases "<label> [n seeds]" (with sd columns).

    Why: single 200-grain cases scatter ~10 % between seeds (docs/engines.md); engines are compared on
    seed means, and the per-seed rows stay in the table for reference. Empty if no label repeats."""
    groups: dict[str, list[str]] = {}
    for label in summaries:
        m = _SEED.search(label.rstrip(")"))
        if m:
            base = _SEED.sub("", label.rstrip(")")) + (")" if label.endswith(")") else "")
            groups.setdefault(base, []).append(label)
    means, mroles = {}, {}
    for base, labels in groups.items():
        both = [lab for lab in labels if set(ENGINES) <= set(summaries[lab])]
        if len(labels) < 2 or not both:
            continue
        name = f"{base} [{len(both)} seeds]"
        mroles[name] = roles.get(labels[0], "")
        means[name] = {}
        for eng in ENGINES:
            row = {}
            for key, *_ in METRICS:
                vals = pd.Series([_num(summaries[lab][eng].get(key)) for lab in both], dtype=float)
                row[key] = float(vals.mean()) if vals.notna().any() else math.nan
                row[key + "_sd"] = float(vals.std()) if vals.notna().sum() > 1 else math.nan
            row["_seeds"] = len(both)
            means[name][eng] = row
    return means, mroles


def _num(v) -> float:
    try:
        return float(v) if v is not None else math.nan
    except (TypeError, ValueError):
        return math.nan


def crosscheck(path, *, jobs: int | None = None, output=None, rerun_failed: bool = False, run: bool = True,
               stream=None) -> CrosscheckReport:
    """Run (or reuse) every case with both engines, then compare their summaries."""
    from interphase.campaign import store as st
    from interphase.campaign.plan import plan
    from interphase.campaign.run import run_campaign

    stream = stream or sys.stdout
    campaign, tol, readable, cleanup = load(path, output=output)
    try:
        if run:
            for engine in ENGINES:
                report = run_campaign(readable, engine=engine, jobs=jobs, rerun_failed=rerun_failed,
                                      output=output, stream=stream, live=False)
                if report.interrupted:      # Ctrl-C / SIGTERM stops the cross-check, not one engine's half
                    raise KeyboardInterrupt
        planned = plan(campaign, list(ENGINES))
    finally:
        cleanup()
    summaries: dict[str, dict[str, dict]] = {}
    roles: dict[str, str] = {}
    missing = []
    for p in planned:
        folder = campaign.output / p.case_id
        label = p.label if p.role == "interface" else f"box ({p.label})"
        roles[label] = p.role
        data = st.read_json(folder / st.SUMMARY_JSON) if (folder / st.DONE).exists() else None
        if data is None:
            missing.append((label, p.engine, st.folder_status(folder) if folder.exists() else "not run"))
            continue
        summaries.setdefault(label, {})[p.engine] = data.get("row", data)
    table = compare(summaries, roles, tol)
    means, mroles = seed_means(summaries, roles)
    if means:
        table = pd.concat([table, compare(means, mroles, tol)], ignore_index=True)
    report = CrosscheckReport(campaign.name, campaign.output, tol, table, missing)
    campaign.output.mkdir(parents=True, exist_ok=True)
    table.to_csv(campaign.output / "crosscheck.csv", index=False)
    (campaign.output / "crosscheck.md").write_text(report.markdown())
    return report
