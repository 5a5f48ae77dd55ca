"""Engine cross-check: every case of a campaign run with LIGGGHTS and YADE, judged on seed ensembles.

    report = crosscheck("campaigns/crosscheck.toml")      # runs (or reuses) both engines' cases
    report.judged                                         # one verdict per physical case × metric
    report.table                                          # those rows + one information row per seed
    report.markdown()                                     # the verdict table (docs/crosscheck.md)
    report.passed                                         # every judged metric agrees, every case finished

The campaign file is an ordinary campaign (`campaign run` reads it too) plus a `[crosscheck]` table of
tolerances, which `campaign run` never sees (its lines are blanked before the schema reads the file,
so every other line keeps its number in error messages):

    [crosscheck]
    critical_ratio_abs = 0.03  # critical-state stress ratio (residual_stress_ratio): absolute
    angle_deg = 3.0            # θr over the loaded snapshots (ψ, degrees from vertical): absolute
    overlap_rel = 0.10         # mean contact overlap: × the mean of the two engines
    stress_ratio_rel = 0.10    # optional: judge the peak stress ratio too (else reported only)
    peak_angle_deg = 3.0       # optional: judge θr, θn at the peak snapshot too (else reported only)
    judged_in = {critical_ratio_abs = ["sliding"]}   # optional: a tolerance judges only these groups'
                               # cases (campaign [[group]] names, "box" for the soil tests); elsewhere
                               # its metric is reported with its interval

The verdict. A physical case is a case label without its `-s<seed>` suffix; its seeds are the
packings both engines finished. With `[campaign] specimen_from = "liggghts"` (the standard set) YADE
shears the very specimen LIGGGHTS consolidated for that seed (interphase.case.Start), so a pair
differs by the contact law under shear, not by two consolidations. Per metric, the PAIRED difference YADE − LIGGGHTS (same packing seed)
is averaged over those seeds with its 95 % t interval, and the interval is set against ±tolerance
(interphase.analysis.difference, paired=True): agree (inside), differ (entirely outside), undecided
(straddles, or fewer than 2 seeds; `seeds_needed` is the seed count whose interval would decide at
the scatter of the differences seen). A relative tolerance becomes an absolute one per physical
case: rel × ½(|mean LIGGGHTS| + |mean YADE|). Single seeds are rows of information, never a verdict.

Metrics (from each case's summary.json, interphase.analysis.summary row keys). Judged by default — time
averages, whose paired scatter at a few hundred grains is small enough to decide (docs/crosscheck.md):
residual_stress_ratio (mean over the last 20 % of the shear), theta_r_surface_mean_deg,
overlap_mean_d50 [D50]. Reported only unless their optional tolerance is set: peak_stress_ratio (one
stick–slip event at this size), theta_r_surface_deg and theta_n_surface_deg (one snapshot), and
always shear_disp_at_peak [m], dilation_at_peak [m]. A metric neither engine defines for a case (θ of
a box test) is left out of the verdict.
Runs go through interphase.campaign.run.run_campaign, so finished cases (DONE) are reused. The
engines are values (engines.base.EngineSpec), made once from their names unless given: a test
passes a YADE of its own (a deliberately mis-mapped one) as it would pass any argument.
"""

from __future__ import annotations

import math
import os
import re
import sys
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from interphase.analysis.difference import VERDICTS, difference
from interphase.errors import InputError

ENGINES = ("liggghts", "yade")
#: tolerances that judge by default: time averages, whose paired scatter is small (docs/crosscheck.md)
DEFAULT_TOLERANCES = {"critical_ratio_abs": 0.03, "angle_deg": 3.0, "overlap_rel": 0.10}
#: tolerances that judge only when a [crosscheck] table sets them: single-snapshot / peak values, whose
#: seed scatter is that of one stick–slip event (without them these metrics are reported only)
OPTIONAL_TOLERANCES = ("stress_ratio_rel", "peak_angle_deg")
TOLERANCE_KEYS = (*DEFAULT_TOLERANCES, *OPTIONAL_TOLERANCES)
TABLE_KEYS = (*TOLERANCE_KEYS, "judged_in")
#: (row key, unit, how compared: "rel" | "abs" | None, tolerance key); a metric whose tolerance key is
#: not among the tolerances in force is reported (difference and interval), not judged
METRICS = (
    ("residual_stress_ratio", "-", "abs", "critical_ratio_abs"),
    ("theta_r_surface_mean_deg", "deg", "abs", "angle_deg"),
    ("overlap_mean_d50", "D50", "rel", "overlap_rel"),
    ("peak_stress_ratio", "-", "rel", "stress_ratio_rel"),
    ("theta_r_surface_deg", "deg", "abs", "peak_angle_deg"),
    ("theta_n_surface_deg", "deg", "abs", "peak_angle_deg"),
    ("shear_disp_at_peak", "m", None, None),
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
        if key not in TABLE_KEYS:
            raise InputError(f"unknown key {key!r} in [crosscheck]", where=f"{where}:{line}",
                             fix=f"allowed keys: {', '.join(TABLE_KEYS)}")
        if key == "judged_in":
            tolerances[key] = _judged_in(value, f"{where}:{line}")
            continue
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value) or value <= 0:
            raise InputError(f"[crosscheck].{key} must be a positive number, got {value!r}", where=f"{where}:{line}",
                             fix="e.g. critical_ratio_abs = 0.03, angle_deg = 3.0, overlap_rel = 0.10")
        tolerances[key] = float(value)
    blanked = lines[:start] + ["#\n"] * (end - start) + lines[end:]
    return "".join(blanked), tolerances


def _judged_in(value, where: str) -> dict[str, tuple[str, ...]]:
    fix = 'e.g. judged_in = {critical_ratio_abs = ["sliding"]}: a tolerance key → a list of group names'
    if not isinstance(value, dict):
        raise InputError(f"[crosscheck].judged_in must be a table, got {value!r}", where=where, fix=fix)
    out = {}
    for k, groups in value.items():
        if k not in TOLERANCE_KEYS:
            raise InputError(f"[crosscheck].judged_in: unknown tolerance {k!r}", where=where,
                             fix=f"one of {', '.join(TOLERANCE_KEYS)}")
        if not isinstance(groups, list) or not groups or not all(isinstance(g, str) for g in groups):
            raise InputError(f"[crosscheck].judged_in.{k} must be a non-empty list of group names, got {groups!r}",
                             where=where, fix=fix)
        out[k] = tuple(groups)
    return out


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
    campaign = load_campaign(path, output=output)
    known = {g.name for g in campaign.groups} | {"box"}
    for k, groups in tol.get("judged_in", {}).items():
        if unknown := sorted(set(groups) - known):
            raise InputError(f"[crosscheck].judged_in.{k}: no group {', '.join(map(repr, unknown))} in the campaign",
                             where=str(path), fix=f"groups: {', '.join(sorted(known))}")
    return campaign, tol, path, lambda: None


#: columns of CrosscheckReport.table. level "ensemble": one judged row per physical case × metric
#: (liggghts, yade = means over the paired seeds); level "seed": one information row per seed case.
COLUMNS = ["level", "case", "physical", "seed", "role", "metric", "unit", "kind", "seeds", "liggghts", "yade",
           "liggghts_sd", "yade_sd", "diff", "diff_lo", "diff_hi", "rel_diff", "pair_r", "tolerance",
           "tolerance_rule", "verdict", "seeds_needed", "more_seeds"]


@dataclass
class CrosscheckReport:
    campaign: str
    output: Path
    tolerances: dict
    table: pd.DataFrame                 # COLUMNS: ensemble rows (verdicts) first, then per-seed rows
    missing: list = field(default_factory=list)   # (label, engine, status) of cases without a summary

    @property
    def ensembles(self) -> pd.DataFrame:
        """One row per physical case × metric (judged and reported-only)."""
        return self.table[self.table["level"] == "ensemble"]

    @property
    def seeds(self) -> pd.DataFrame:
        """One information row per seed case × metric (never a verdict)."""
        return self.table[self.table["level"] == "seed"]

    @property
    def judged(self) -> pd.DataFrame:
        """The rows that decide: physical case × judged metric, each with a verdict."""
        e = self.ensembles
        return e[e["verdict"].notna()]

    def counts(self) -> dict[str, int]:
        v = self.judged["verdict"]
        return {k: int((v == k).sum()) for k in VERDICTS}

    @property
    def passed(self) -> bool:
        """True only if every judged metric of every physical case agrees and every case finished."""
        j = self.judged
        return not self.missing and len(j) > 0 and bool((j["verdict"] == "agree").all())

    @property
    def outcome(self) -> str:
        """In words: "agree" (every judged row agrees, every case finished), "differ: …" (a row is
        decided apart), "incomplete: …" (a case has no result), else "undecided: N more seeds" (the
        most any undecided row needs: the engines are not shown apart, the seeds would tell)."""
        j, c = self.judged, self.counts()
        if self.passed:
            return "agree: every judged metric"
        if c["differ"]:
            return f"differ: {c['differ']} of {len(j)} judged rows"
        if self.missing or not len(j):
            return f"incomplete: {len(self.missing)} case runs without a result"
        more = pd.to_numeric(j.loc[j["verdict"] == "undecided", "more_seeds"], errors="coerce").dropna()
        need = f"{int(more.max())} more seeds" if len(more) else "more seeds (how many: not estimable from these)"
        return f"undecided: {need} ({c['undecided']} of {len(j)} rows undecided, none differ)"

    def summary(self) -> str:
        c = self.counts()
        return (f"verdict: {self.outcome} — {len(self.judged)} judged rows (physical case × "
                f"metric): {c['agree']} agree, {c['differ']} differ, {c['undecided']} undecided; "
                f"{len(self.missing)} case runs without a result")

    def markdown(self, all_rows: bool = False) -> str:
        """The verdict table: per physical case and metric, each engine's mean ± sd over the paired
        seeds, the paired difference YADE − LIGGGHTS with its 95 % interval, the correlation of the
        pairs, the tolerance, the verdict and the seeds that would decide an undecided row. `all_rows` adds the per-seed rows."""
        head = ("| case | metric | seeds | LIGGGHTS | YADE | YADE − LIGGGHTS [95 % CI] | pairs r | tolerance | "
                "verdict | seeds needed |\n|---|---|---|---|---|---|---|---|---|---|\n")
        rows = [f"| {r.physical} | {r.metric} | {r.seeds} | {_fmt(r.liggghts, r.liggghts_sd)} | "
                f"{_fmt(r.yade, r.yade_sd)} | {_fmt_ci(r.diff, r.diff_lo, r.diff_hi)} | "
                f"{f'{r.pair_r:+.2f}' if _finite(r.pair_r) else ''} | {_fmt_tol(r)} | "
                f"{_fmt_verdict(r.verdict)} | {_fmt_needed(r)} |" for r in _defined(self.ensembles).itertuples()]
        out = head + "\n".join(rows) + "\n"
        if all_rows and len(self.seeds):
            out += ("\nPer seed (information only; the verdict is the ensemble's above):\n\n"
                    "| case | metric | LIGGGHTS | YADE | YADE − LIGGGHTS | rel |\n|---|---|---|---|---|---|\n")
            out += "\n".join(f"| {r.case} | {r.metric} | {_fmt(r.liggghts)} | {_fmt(r.yade)} | {_fmt(r.diff)} | "
                             f"{_fmt_pct(r.rel_diff)} |" for r in _defined(self.seeds).itertuples()) + "\n"
        miss = "".join(f"\n- {lab} ({eng}): {st}" for lab, eng, st in self.missing)
        if miss:
            out += "\nCases without a result:" + miss + "\n"
        return out + "\n" + self.summary() + "\n"

    def to_json(self) -> dict:
        def records(t):
            return t.astype(object).where(t.notna(), None).to_dict(orient="records")
        return {"campaign": self.campaign, "output": str(self.output), "tolerances": self.tolerances,
                "passed": self.passed, "outcome": self.outcome, "verdicts": self.counts(),
                "missing": [list(m) for m in self.missing],
                "rows": records(self.ensembles), "seed_rows": records(self.seeds)}


def _defined(t: pd.DataFrame) -> pd.DataFrame:
    """Rows where at least one engine has a value (θ of a box test is nobody's: not printed)."""
    return t[t["liggghts"].notna() | t["yade"].notna()]


def _finite(v) -> bool:
    try:
        return v is not None and not isinstance(v, bool) and math.isfinite(float(v))
    except (TypeError, ValueError):        # pd.NA, strings
        return False


def _fmt(v, sd=None) -> str:
    if not _finite(v):
        return "—"
    if _finite(sd):
        return f"{v:.4g} ± {sd:.2g}"
    return f"{v:.4g}"


def _fmt_ci(d, lo, hi) -> str:
    if not _finite(d):
        return "—"
    return f"{d:+.3g} [{lo:+.3g}, {hi:+.3g}]" if _finite(lo) else f"{d:+.3g} [no interval]"


def _fmt_tol(r) -> str:
    if not _finite(r.tolerance):
        return "reported" if not isinstance(r.verdict, str) else "—"
    return f"±{r.tolerance:.3g} ({r.tolerance_rule})"


def _fmt_verdict(v) -> str:
    return "" if not isinstance(v, str) else (v if v == "agree" else f"**{v}**")


def _fmt_needed(r) -> str:
    if r.verdict != "undecided":
        return ""
    if not _finite(r.seeds_needed):
        return "scatter unknown (< 2 seeds)" if r.seeds < 2 else "out of reach (> 1000)"
    return f"{int(r.seeds_needed)} ({int(r.more_seeds)} more)"


def _fmt_pct(v) -> str:
    return f"{v:+.1%}" if _finite(v) else "—"


_SEED = re.compile(r"-s(-?\d+)$")


def physical_case(label: str) -> tuple[str, int | None]:
    """(label without its -s<seed> suffix, seed); 'box (x-s2)' → ('box (x)', 2); no suffix → (label, None)."""
    closed = label.endswith(")")
    core = label[:-1] if closed else label
    m = _SEED.search(core)
    if not m:
        return label, None
    return _SEED.sub("", core) + (")" if closed else ""), int(m.group(1))


def seed_rows(summaries: dict[str, dict[str, dict]], roles: dict[str, str]) -> list[dict]:
    """One information row per seed case × metric: both engines' values, YADE − LIGGGHTS, relative
    to the mean of the two. Never judged."""
    rows = []
    for label, by_engine in summaries.items():
        phys, seed = physical_case(label)
        a, b = by_engine.get("liggghts", {}), by_engine.get("yade", {})
        for key, unit, kind, _ in METRICS:
            va, vb = _num(a.get(key)), _num(b.get(key))
            diff = vb - va if math.isfinite(va) and math.isfinite(vb) else math.nan
            mean = 0.5 * (abs(va) + abs(vb))
            rows.append({"level": "seed", "case": label, "physical": phys, "seed": seed, "role": roles.get(label, ""),
                         "metric": key, "unit": unit, "kind": kind, "seeds": 1, "liggghts": va, "yade": vb,
                         "diff": diff, "rel_diff": diff / mean if math.isfinite(diff) and mean > 0 else math.nan})
    return rows


def judge(summaries: dict[str, dict[str, dict]], roles: dict[str, str], tolerances: dict,
          groups: dict[str, str] | None = None) -> list[dict]:
    """One row per physical case × metric from its seed ensemble: paired YADE − LIGGGHTS over the
    seeds both engines finished, its 95 % interval, and (metrics with a tolerance in force for the
    case's group: `tolerances["judged_in"]`, `groups` = label → campaign group) the verdict."""
    only = tolerances.get("judged_in", {})
    ensembles: dict[str, list[str]] = {}
    for label in summaries:
        ensembles.setdefault(physical_case(label)[0], []).append(label)
    rows = []
    for phys, labels in ensembles.items():
        both = sorted((lab for lab in labels if set(ENGINES) <= set(summaries[lab])),
                      key=lambda lab: physical_case(lab)[1] or 0)
        if not both:
            continue            # no seed finished in both engines: the cases are listed as missing
        for key, unit, kind, tol_key in METRICS:
            lig = [_num(summaries[lab]["liggghts"].get(key)) for lab in both]
            yad = [_num(summaries[lab]["yade"].get(key)) for lab in both]
            row = {"level": "ensemble", "case": phys, "physical": phys, "seed": None,
                   "role": roles.get(both[0], ""), "metric": key, "unit": unit, "kind": kind}
            tol = tolerances.get(tol_key) if tol_key else None
            if tol_key in only and (groups or {}).get(both[0]) not in only[tol_key]:
                tol = None      # reported here: this tolerance judges only the listed groups
            rows.append(row | _ensemble(lig, yad, kind, tol))
    return rows


def _ensemble(lig: list[float], yad: list[float], kind: str | None, tol: float | None) -> dict:
    a, b = np.asarray(lig, float), np.asarray(yad, float)
    ok = np.isfinite(a) & np.isfinite(b)
    out = {"seeds": int(ok.sum()), "liggghts": math.nan, "yade": math.nan, "liggghts_sd": math.nan,
           "yade_sd": math.nan, "diff": math.nan, "diff_lo": math.nan, "diff_hi": math.nan, "rel_diff": math.nan,
           "pair_r": math.nan, "tolerance": math.nan, "tolerance_rule": None, "verdict": None, "seeds_needed": None,
           "more_seeds": None}
    if not (np.isfinite(a).any() or np.isfinite(b).any()):
        return out              # neither engine defines it here (θ of a box test): not judged
    n = int(ok.sum())
    # means over the paired seeds; with no pair, each engine's own values (shown, and undecided below)
    ma, mb = ((float(a[ok].mean()), float(b[ok].mean())) if n else
              tuple(float(v[np.isfinite(v)].mean()) if np.isfinite(v).any() else math.nan for v in (a, b)))
    if n > 1:
        out.update(liggghts_sd=float(a[ok].std(ddof=1)), yade_sd=float(b[ok].std(ddof=1)))
    if n > 2 and a[ok].std() > 0 and b[ok].std() > 0:
        # how much the pairing buys: near 0, the two engines' runs of one seed are as unlike as two
        # seeds, and the paired interval is no narrower than an unpaired one (docs/crosscheck.md)
        out["pair_r"] = float(np.corrcoef(a[ok], b[ok])[0, 1])
    mean = 0.5 * (abs(ma) + abs(mb))
    if tol is None:
        abs_tol = math.inf      # reported only: the interval is information, no verdict
    elif kind == "rel":
        abs_tol = tol * mean
    else:
        abs_tol = tol
    d = difference(a[ok], b[ok], abs_tol, paired=True) if n else None
    out.update(liggghts=ma, yade=mb)
    if d is not None:
        out.update(diff=d.change, diff_lo=d.change_lo, diff_hi=d.change_hi,
                   rel_diff=d.change / mean if mean > 0 else math.nan)
    if tol is None:
        return out
    out.update(tolerance=abs_tol, tolerance_rule=f"{100 * tol:g} % of the mean" if kind == "rel" else "absolute",
               verdict=d.verdict if d is not None else "undecided")
    if out["verdict"] == "undecided" and d is not None and d.seeds_needed is not None:
        out.update(seeds_needed=int(d.seeds_needed), more_seeds=max(int(d.seeds_needed) - n, 0))
    return out


def engine_table(summaries: dict[str, dict[str, dict]], roles: dict[str, str], tolerances: dict,
            groups: dict[str, str] | None = None) -> pd.DataFrame:
    """summaries[label][engine] = summary row → the report table: the ensemble rows (verdicts) of
    `judge`, then the per-seed rows of `seed_rows`."""
    t = pd.DataFrame(judge(summaries, roles, tolerances, groups) + seed_rows(summaries, roles), columns=COLUMNS)
    return t.astype({"seed": "Int64", "seeds": "Int64", "seeds_needed": "Int64", "more_seeds": "Int64"})


def _num(v) -> float:
    try:
        return float(v) if v is not None else math.nan
    except (TypeError, ValueError):
        return math.nan


def crosscheck(path, *, jobs: int | None = None, output=None, rerun_failed: bool = False, run: bool = True,
               stream=None, engines=None) -> CrosscheckReport:
    """Run (or reuse) every case with both engines, then judge their seed ensembles (module docstring).
    `engines`: the two engines as EngineSpecs (or names), LIGGGHTS first; default ENGINES."""
    from interphase.campaign import store as st
    from interphase.campaign.plan import engine_specs, plan
    from interphase.campaign.run import run_campaign

    stream = stream or sys.stdout
    campaign, tol, readable, cleanup = load(path, output=output)
    specs = tuple(engine_specs(campaign, engines or ENGINES).values())
    try:
        if run:
            for spec in specs:
                report = run_campaign(readable, engines=[spec], jobs=jobs, rerun_failed=rerun_failed,
                                      output=output, stream=stream, live=False)
                if report.interrupted:      # Ctrl-C / SIGTERM stops the cross-check, not one engine's half
                    raise KeyboardInterrupt
        planned = plan(campaign, specs)
    finally:
        cleanup()
    summaries: dict[str, dict[str, dict]] = {}
    roles: dict[str, str] = {}
    groups: dict[str, str] = {}
    missing = []
    for p in planned:
        folder = campaign.output / p.case_id
        label = p.label if p.role == "interface" else f"box ({p.label})"
        roles[label], groups[label] = p.role, p.group
        data = st.read_json(folder / st.SUMMARY_JSON) if (folder / st.DONE).exists() else None
        if data is None:
            missing.append((label, p.engine, st.folder_status(folder) if folder.exists() else "not run"))
            continue
        summaries.setdefault(label, {})[p.engine] = data.get("row", data)
    table = engine_table(summaries, roles, tol, groups)
    report = CrosscheckReport(campaign.name, campaign.output, tol, table, missing)
    campaign.output.mkdir(parents=True, exist_ok=True)
    table.to_csv(campaign.output / "crosscheck.csv", index=False)
    (campaign.output / "crosscheck.md").write_text(report.markdown(all_rows=True))
    return report
