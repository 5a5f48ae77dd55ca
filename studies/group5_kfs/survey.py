"""Group 5 on the Karlsruhe sand (issue 72 item 2): the survey behind the two campaign files, no engine.

    python studies/group5_kfs/survey.py [--check]

At the sand's D50 0.14 mm and the 3D card's cell (30 × 10 D50 of surface: 4.2 × 1.4 mm), writes in
results/:
  scans.csv        every instrument file shipped or in /work/shared/data/profiles: kind, size, step;
                   whether it holds the cell along x and along y (surface.patch.cut_window: the
                   window is cut or refused) and is sampled no coarser than answer.MAX_STEP_D50·D50
                   (0.5 D50: a valley narrower than a grain lies unseen between samples); the rows of
                   the files outside the repository are re-derived only where that folder exists
  pool.csv         the qualifying scan's window lattice (the rule: README and the 3D file's header):
                   per axis, windows with corners every nx/5 steps along the shear and ny/2 across
                   (the turned grid of surface.patch.oriented for +x and +y), free of missing points,
                   with the edge-match score (patch.edge_mismatch); those scoring ≤ MAX_SCORE (the
                   pool) with θa (filter 92) of the closed window read both ways (patch.close_slopes,
                   patch.theta_a_patch); the best-closing window of every position (role default)
  windows.csv      the chosen windows × both senses of their axis, each read as the 3D case shears
                   it (Case.surface_patch of group5_kfs_3d.toml's case, patch.theta_a_patch "+x"):
                   edge score, closure, θa > 92° and ≥ 90°, the share of the trace steeper than 2°,
                   lines with a θa of their own, relief (peak to valley, rms) and rms slope along
                   the shear; beside it the quasi-2D line through the window's middle as
                   group5_kfs_2d.toml shears it (θa of Case.sheared_surface, the summary's reading)
                   and where that line's sheared stretch lies against the window
  selfaffine.csv   the self-affine lines of group5_kfs_2d.toml (H 0.8): θa, relief, rms slope
  predictions.csv  every planned interface case of both files: θa as the summary will read it
                   (analysis.summary_stages.profile_features), the criterion's δ (the card's own fit
                   and soil test: the chain `campaign predict --soil` runs, answer._answer), the no-fit
                   rule min(φμ + θa, φ) and the flat's min(φμ, φ)
--check writes nothing and fails if a committed table differs from its re-derivation.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import math
import warnings
from pathlib import Path

import numpy as np
import pandas as pd

from interphase.answer import MAX_STEP_D50, _answer, load_soil
from interphase.analysis.criterion import ProfilePrediction, predict, rule_delta
from interphase.analysis.summary_stages import profile_features
from interphase.campaign.plan import plan
from interphase.campaign.results import settle_tables
from interphase.campaign.schema import load_campaign
from interphase.card_state import soil_state
from interphase.criterion_fits import criterion_model
from interphase.errors import InputError
from interphase.soil import criterion_fit
from interphase.surface.patch import (Patch, close_slopes, cut_window, edge_mismatch, fill_small_holes, oriented,
                                      theta_a_patch)
from interphase.surface.readers import read_scan

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
RESULTS = HERE / "results"
SHIPPED = ROOT / "campaigns" / "profiles"
SHARED = Path("/work/shared/data/profiles")
SCAN = SHIPPED / "frt-1.frt"                  # the one scan that qualifies (scans.csv)
FILE_3D, FILE_2D = HERE / "group5_kfs_3d.toml", HERE / "group5_kfs_2d.toml"
SOIL_3D, SOIL_2D = ROOT / "soils" / "karlsruhe-fine-sand.toml", ROOT / "soils" / "karlsruhe-fine-sand-2d.toml"
D50 = 0.14e-3                                 # the Karlsruhe sand's (both cards)
L_D50, W_D50 = 30.0, 10.0                     # the 3D card's cell (studies/kfs_group1_3d)
MAX_SCORE = 0.6                               # the pool's edge-match limit (README: why)
TIE_DEG = 0.01                                # windows whose θa agree this closely share one feature


def _quiet():
    warnings.simplefilter("ignore")
    return contextlib.redirect_stdout(io.StringIO())


# ---- 1. the scans ------------------------------------------------------------------------------------
def scans_table() -> pd.DataFrame | None:
    files = sorted(SHIPPED.glob("*.*"))
    if SHARED.is_dir():
        files += sorted(p for p in SHARED.glob("*.*") if not (SHIPPED / p.name).exists())
    rows = []
    for p in files:
        if p.suffix == ".md":
            continue
        with _quiet():
            scan = read_scan(str(p), None)
        hx = float(np.median(np.diff(scan.x)))
        hy = float(np.median(np.diff(scan.y))) if scan.areal else math.nan
        row = dict(file=p.name, where="campaigns/profiles" if p.parent == SHIPPED else "shared data",
                   kind="areal" if scan.areal else "line", points=str(np.shape(scan.heights)),
                   length_x_mm=round(1e3 * float(scan.x[-1] - scan.x[0]), 4),
                   length_y_mm=round(1e3 * float(scan.y[-1] - scan.y[0]), 4) if scan.areal else math.nan,
                   step_x_um=round(1e6 * hx, 4), step_y_um=round(1e6 * hy, 4) if scan.areal else math.nan)
        step = max(hx, hy) if scan.areal else hx
        row["step_d50"] = round(step / D50, 4)
        row["step_ok"] = bool(step <= MAX_STEP_D50 * D50)
        for axis in ("x", "y"):
            if not scan.areal:
                row[f"holds_cell_{axis}"], row[f"why_{axis}"] = False, "a line: no relief across the shear"
                continue
            try:
                with _quiet():
                    cut_window(scan, D50, L_D50 * D50, W_D50 * D50, f"+{axis}")
                row[f"holds_cell_{axis}"], row[f"why_{axis}"] = True, ""
            except InputError as exc:
                row[f"holds_cell_{axis}"], row[f"why_{axis}"] = False, exc.message
        row["qualifies"] = bool(row["step_ok"] and (row["holds_cell_x"] or row["holds_cell_y"]))
        rows.append(row)
    return pd.DataFrame(rows)


# ---- 2. the pool and the chosen windows -------------------------------------------------------------------
def _read(patch: Patch) -> dict:
    t = theta_a_patch(patch, D50, (92, 90))
    return {s: t[s] for s in ("+x", "-x")}


def pool_table(scan) -> pd.DataFrame:
    rows = []
    for axis in ("x", "y"):
        Z, hx, hy, I, J = oriented(scan, f"+{axis}")
        Zf = fill_small_holes(Z, hx, hy, D50)
        nx, ny = int(round(L_D50 * D50 / hx)), int(round(W_D50 * D50 / hy))
        score = edge_mismatch(Zf, nx, ny)
        best = np.unravel_index(int(np.argmin(score)), score.shape)
        for a in range(0, score.shape[0], nx // 5):
            for b in range(0, score.shape[1], ny // 2):
                if not np.isfinite(score[a, b]):       # holds missing points
                    continue
                plus = minus = math.nan
                if score[a, b] <= MAX_SCORE:            # in the pool: read; outside it, only counted
                    w = Zf[a:a + nx + 1, b:b + ny + 1]
                    u = close_slopes(w, hx, hy)
                    t = _read(Patch(np.arange(nx + 1) * hx, np.arange(ny + 1) * hy, u, "w", "+x", (0.0, 0.0),
                                    math.nan, math.nan, math.nan))
                    plus, minus = t["+x"][92].theta_a_deg, t["-x"][92].theta_a_deg
                ci, cj = min(I[a, b], I[a + nx, b + ny]), min(J[a, b], J[a + nx, b + ny])
                rows.append(dict(axis=axis, a=a, b=b, x0_mm=round(1e3 * float(scan.x[ci]), 4),
                                 y0_mm=round(1e3 * float(scan.y[cj]), 4), score=round(float(score[a, b]), 6),
                                 theta_plus=plus, theta_minus=minus))
        ci, cj = min(I[best], I[best[0] + nx, best[1] + ny]), min(J[best], J[best[0] + nx, best[1] + ny])
        rows.append(dict(axis=axis, a=int(best[0]), b=int(best[1]), x0_mm=round(1e3 * float(scan.x[ci]), 4),
                         y0_mm=round(1e3 * float(scan.y[cj]), 4), score=round(float(score[best]), 6),
                         theta_plus=math.nan, theta_minus=math.nan, role="default"))
    df = pd.DataFrame(rows)
    df["theta_plus"], df["theta_minus"] = df["theta_plus"].round(4), df["theta_minus"].round(4)
    df["role"] = df.get("role", pd.Series(dtype=object)).fillna("pool")
    df["in_pool"] = (df["role"] == "pool") & (df["score"] <= MAX_SCORE)
    df["dilative_both"] = df["theta_plus"].notna() & df["theta_minus"].notna()
    df["theta_mean"] = ((df["theta_plus"] + df["theta_minus"]) / 2).round(4)
    df["chosen"] = ""
    for axis, g in df[df["in_pool"] & df["dilative_both"]].groupby("axis"):
        med = float(np.median(g["theta_mean"]))
        for role, target in (("low", g["theta_mean"].min()), ("median", med), ("high", g["theta_mean"].max())):
            near = g[(g["theta_mean"] - target).abs() <= (g["theta_mean"] - target).abs().min() + TIE_DEG]
            df.loc[near.sort_values(["score", "a", "b"]).index[0], "chosen"] = role
    df.loc[df["role"] == "default", "chosen"] = "default"
    return df


def chosen(pool: pd.DataFrame) -> list[dict]:
    """The chosen windows in the campaign files' order: per axis default, low, median, high."""
    order = {"default": 0, "low": 1, "median": 2, "high": 3}
    c = pool[pool["chosen"] != ""].copy()
    c["k"] = c["chosen"].map(order)
    return [dict(r) for _, r in c.sort_values(["axis", "k"]).iterrows()]


def spec_table(win: dict, sense: str) -> dict:
    """The campaign's profile table of a window sheared along `sense` of its axis."""
    d = {"kind": "file", "path": "../../campaigns/profiles/frt-1.frt", "areal": True,
         "direction": f"{sense}{win['axis']}"}
    if win["chosen"] != "default":
        d["window"] = [round(win["x0_mm"] * 1e-3, 9), round(win["y0_mm"] * 1e-3, 9)]
    return d


def line_table(scan, win: dict, sense: str) -> dict:
    """The quasi-2D counterpart: the scan's grid line along the window's axis through its middle."""
    h = float(np.median(np.diff(scan.y if win["axis"] == "x" else scan.x)))
    across = win["y0_mm"] if win["axis"] == "x" else win["x0_mm"]
    index = int(round(across * 1e-3 / h)) + int(round(W_D50 * D50 / h)) // 2
    d = {"kind": "file", "path": "../../campaigns/profiles/frt-1.frt", "axis": win["axis"], "line": index}
    if sense == "-":
        d["direction"] = "-"
    return d


def windows_table(scan, pool: pd.DataFrame, cases_2d: dict) -> pd.DataFrame:
    """The chosen windows as group5_kfs_3d.toml's cases shear them (Case.surface_patch), refusing a
    file whose areal profiles are not exactly the rule's windows × both senses."""
    patches = {}
    for p in planned(FILE_3D):
        prof = p.case.profile
        if prof.kind == "file" and prof.areal:
            key = (prof.direction, None if prof.window is None else tuple(round(1e3 * v, 4) for v in prof.window))
            patches.setdefault(key, p.case)
    rows, asked = [], set()
    for win in chosen(pool):
        for sense in "+-":
            t = spec_table(win, sense)
            key = (t["direction"], None if "window" not in t else tuple(round(1e3 * v, 4) for v in t["window"]))
            asked.add(key)
            if key not in patches:
                raise SystemExit(f"{FILE_3D.name} has no case on the window {key} the rule chooses")
            with _quiet():
                patch = patches[key].surface_patch()
                r = _read(patch)["+x"]
            z = patch.z[:-1, :-1]
            slope = np.diff(patch.z, axis=0) / np.diff(patch.x)[:, None]
            line = line_table(scan, win, sense)
            c2 = cases_2d.get((line["axis"], line["line"], line.get("direction", "+")))
            if c2 is None:
                raise SystemExit(f"{FILE_2D.name} has no case on the line {line} through the window {key}")
            row = dict(window=f"{win['axis']}-{win['chosen']}", role=win["chosen"], direction=t["direction"],
                       x0_mm=round(1e3 * patch.origin[0], 4), y0_mm=round(1e3 * patch.origin[1], 4),
                       grid=f"{patch.z.shape[0] - 1} x {patch.z.shape[1] - 1}", edge_score=round(patch.mismatch, 4),
                       closure_rms_nm=round(1e9 * patch.closure_rms, 3), closure_max_nm=round(1e9 * patch.closure_max, 3),
                       theta_a_92=round(r[92].theta_a_deg, 4), theta_a_90=round(r[90].theta_a_deg, 4),
                       kept_share_92=round(r[92].kept_fraction, 5), lines_dilative=r[92].n_runs_dilative,
                       lines=r[92].n_runs, relief_pv_um=round(1e6 * float(z.max() - z.min()), 4),
                       relief_pv_d50=round(float(z.max() - z.min()) / D50, 5), rms_height_um=round(1e6 * float(z.std()), 4),
                       rms_slope=round(float(np.sqrt(np.mean(slope ** 2))), 5),
                       line_axis=line["axis"], line_index=line["line"], line_direction=line.get("direction", "+"),
                       window_start_mm=round(win["x0_mm"] if win["axis"] == "x" else win["y0_mm"], 4))
            row.update(c2)
            rows.append(row)
    if set(patches) != asked:
        raise SystemExit(f"{FILE_3D.name} shears windows the rule does not choose: {sorted(set(patches) - asked)}")
    return pd.DataFrame(rows)


def line_reading(case) -> dict:
    """θa of a quasi-2D case's surface as its summary reads it, its relief, and where the sheared
    stretch of a measured line starts in the file's frame (the line's longest measured run)."""
    with _quiet():
        v = profile_features(case).values
        prof = case.sheared_surface()
    out = dict(line_theta_a_92=round(v["theta_a_deg_92"], 4), line_theta_a_90=round(v["theta_a_deg_90"], 4),
               line_length_mm=round(1e3 * float(prof.x[-1] - prof.x[0]), 4),
               line_relief_pv_um=round(1e6 * float(prof.z.max() - prof.z.min()), 4),
               line_rms_slope=round(float(np.sqrt(np.mean((np.diff(prof.z) / np.diff(prof.x)) ** 2))), 5))
    return out


def line_start_mm(scan, axis: str, index: int, direction: str) -> float:
    """Where a line profile's sheared stretch begins along its axis [mm, file frame]: the start of
    the line's longest measured run (surface.lines.line_profile), its end when mirrored."""
    from interphase.surface.lines import longest_run

    s, Z = scan.lines(axis)
    a, b = longest_run(Z[index])
    return round(1e3 * float(s[a] if direction == "+" else s[b - 1]), 4)


# ---- 3. the campaigns' cases and the criterion ------------------------------------------------------------
def _chain(card_path: Path):
    card = load_soil(card_path)
    fit = str(criterion_fit(card))
    cache = {}

    def delta(mu: float, ta92: float, ta90: float) -> dict:
        if mu not in cache:
            model = criterion_model(mu, fit)
            cache[mu] = (model, soil_state(card, model, None, None))
        model, state = cache[mu]
        p = predict(model, mu, ta92, ta90, False)
        res = ProfilePrediction(p, ta92, ta90, math.nan, False, "")
        a = _answer("case", mu, card, fit, model, state, res, D50, [])
        tp = a.tan_phi
        return dict(tan_phi=round(tp, 4), branch=a.branch, theta_r=round(a.theta_r_deg, 3), E=round(a.efficiency, 4),
                    delta=round(a.delta_deg, 3), delta_lo=round(a.model_delta_deg_lo, 3),
                    delta_hi=round(a.model_delta_deg_hi, 3),
                    rule=round(float(rule_delta(mu, 0.0 if not math.isfinite(ta92) else ta92, tp)), 3),
                    flat=round(math.degrees(math.atan(min(mu, tp))), 3))
    return delta


def planned(path: Path):
    """The file's interface cases, one per physical case (its first seed: θa and δ do not depend on it)."""
    with _quiet():
        c = load_campaign(path)
        out, seen = [], set()
        for p in plan(c):
            if p.role == "interface" and p.physical_id not in seen:
                seen.add(p.physical_id)
                out.append(p)
        return out


def predictions_table(scan) -> tuple[pd.DataFrame, dict, pd.DataFrame]:
    rows, lines, sa = [], {}, []
    for path, soil in ((FILE_3D, SOIL_3D), (FILE_2D, SOIL_2D)):
        delta = _chain(soil)
        theta = {}
        for p in planned(path):
            label = p.case.profile.label()
            if label not in theta:                 # θa is the surface's: the same at every friction
                with _quiet():
                    theta[label] = profile_features(p.case).values
            v = theta[label]
            ta92, ta90 = v["theta_a_deg_92"], v["theta_a_deg_90"]
            row = dict(campaign=path.name, group=p.group, profile=p.case.profile.label(), friction_ps=p.case.friction_ps,
                       physical_id=p.physical_id, theta_a_92=round(ta92, 4), theta_a_90=round(ta90, 4))
            row.update(delta(p.case.friction_ps, ta92, ta90))
            rows.append(row)
            prof = p.case.profile
            if path == FILE_2D and prof.kind == "file":
                key = (prof.axis, prof.line, prof.direction)
                if key not in lines:
                    r = line_reading(p.case)
                    r["line_start_mm"] = line_start_mm(scan, prof.axis, prof.line, prof.direction)
                    lines[key] = r
            if path == FILE_2D and prof.kind == "selfaffine" and not any(s["profile"] == prof.label() for s in sa):
                r = line_reading(p.case)
                sa.append(dict(profile=prof.label(), **dict(prof.params), **r))
    return pd.DataFrame(rows).drop_duplicates(), lines, pd.DataFrame(sa)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--check", action="store_true", help="fail if a committed table differs from its re-derivation")
    args = ap.parse_args(argv)
    with _quiet():
        scan = read_scan(str(SCAN), None)
    out = {}
    scans = scans_table()
    if SHARED.is_dir():
        out[RESULTS / "scans.csv"] = scans
    else:
        print(f"{SHARED} is absent here: scans.csv is left as committed")
    pool = pool_table(scan)
    preds, lines, sa = predictions_table(scan)
    out[RESULTS / "pool.csv"] = pool
    out[RESULTS / "windows.csv"] = windows_table(scan, pool, lines)
    out[RESULTS / "selfaffine.csv"] = sa
    out[RESULTS / "predictions.csv"] = preds
    with pd.option_context("display.width", 250, "display.max_columns", 40, "display.max_rows", 200):
        for path, df in out.items():
            if path.name != "pool.csv":
                print(f"{path.name}:\n{df.to_string(index=False)}\n")
    return settle_tables(out, args.check, HERE)


if __name__ == "__main__":
    raise SystemExit(main())
