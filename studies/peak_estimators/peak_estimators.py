"""Which estimator of a seed ensemble's peak (and of E = tan δ / tan φ) does not flatter? (issue 41)

    PYTHONPATH=src python studies/peak_estimators/peak_estimators.py [--draws 400] [--seed 1] [--trials 600]

Populations: the committed curves (docs/reproduction/precision/study/: the well-graded soil test on
40 seeds, the uniform one on 32, and the five Group 1 interface cases that the sequential run took to
9–11 seeds), and known trends carrying that noise. Each population's seeds are resampled: `--draws` subsets of n seeds without replacement
(n = 3, 5, 10, 20 up to half the population), every candidate run on each subset.

Candidates (each returns one value per seed; the estimate is their mean, its 95 % interval the
tool's `seed_interval` of those values, log scale; S_i(s) is seed i's curve smoothed over 0.5 D50):
  mean-curve max   S_i at the maximum of the subset's seed-mean curve (the tool before issue 41)
  per-seed max     max_s S_i(s)
  cross-fit        the seeds split in two halves; each half's values read at the other half's
                   seed-mean maximum (both ways; for odd n the halves differ by one)
  leave-one-out    S_i at the maximum of the other seeds' mean curve (cross-fitting with n folds;
                   the tool's peak from issue 41 until issue 39)
  bagged leave-one-out
                   S_i averaged over the maxima of 200 bootstrap means of the other seeds
                   (analysis.ensemble.peak_values, the tool's peak)
  parabola         a parabola fitted by least squares to each seed over ± 1 D50 about the seed-mean
                   curve's maximum, read at the mean parabola's vertex (a smoothed, parametric peak)
  equal counts     (E only) the mean-curve max of the interface seeds over the mean, over random
                   subsets of the soil's seeds of the SAME size, of their mean-curve max
  loo-weighted k   (--weighted) leave-one-out read over a weighted spread of near-maximal locations
                   of the other seeds' mean curve M: weights exp((M(s) − max M)/τ), τ = k × M's
                   standard error (the others' pooled sd over √(n−1)); k = 0.5, 1, 2

The reference. The quantity is the maximum μ* of the expected (infinitely many seeds) smoothed curve.
On data it is unknown but bracketed: E[mean-curve max] ≥ μ* (a maximum of a noisy curve is above the
maximum of its mean), and E[leave-one-out] ≤ μ* (each seed is read where the others put the
maximum, independently of its own noise, and the expected curve there is ≤ μ*). So on all N seeds
the reference is the middle of [leave-one-out(N), mean-curve max(N)], and the bracket's half-width
is how well it is known; E's reference is the ratio of the two sides' references. On the known-trend
populations the truth is exact and every trial draws fresh seeds (`--trials`).
Bias and spread are in % of the reference; coverage is the share of subsets whose 95 % interval
holds it (for subsets of a finite population, n ≤ N/2, an approximation). A third table needs no
reference: two DISJOINT subsets of m seeds (independent, as two campaigns would be) give each
estimator's real sd at m seeds, printed against the standard error its interval claims.
A measurement: exit 0 whatever it finds.
"""

from __future__ import annotations

import argparse
import math
import platform
import time
from pathlib import Path

import numpy as np
import pandas as pd

from interphase.campaign.results import CommittedCurves as _Curves

from interphase.analysis.ensemble import _grid, _on_grid, peak_values, ratio_interval, values_interval  # noqa: E402
from interphase.analysis.strength import PEAK_WINDOW_D50, moving_average  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
DATA = ROOT / "docs" / "reproduction" / "precision" / "study"
D50 = 0.7e-3
WINDOW = PEAK_WINDOW_D50 * D50
NAMES = ("mean-curve max", "per-seed max", "cross-fit", "leave-one-out", "bagged leave-one-out", "parabola")


# ---- the candidates: S (n seeds × grid) smoothed curves → one value per seed -------------------------
def mean_curve_max(S, grid):
    return S[:, int(np.argmax(S.mean(0)))]


def per_seed_max(S, grid):
    return S.max(1)


def cross_fit(S, grid):
    n = len(S)
    h = n // 2
    a, b = S[:h], S[h:]
    return np.concatenate([a[:, int(np.argmax(b.mean(0)))], b[:, int(np.argmax(a.mean(0)))]])


def leave_one_out(S, grid):
    """S_i at the maximum of the other seeds' mean curve (the tool's peak from issue 41 to issue 39)."""
    n = len(S)
    if n == 1:
        return S.max(1)
    others = (S.sum(0)[None, :] - S) / (n - 1)
    return S[np.arange(n), np.argmax(others, axis=1)]


def bagged(S, grid):
    return peak_values(S)[0]          # the tool's peak (analysis.ensemble)


def parabola(S, grid):
    at = int(np.argmax(S.mean(0)))
    band = np.abs(grid - grid[at]) <= 2 * D50 / 2 + 1e-12
    u = (grid[band] - grid[at]) / D50
    coef = np.polyfit(u, S[:, band].T, 2)                # (3, n): each seed's parabola
    c2, c1, _ = coef.mean(1)
    v = -c1 / (2 * c2) if c2 < 0 else 0.0
    v = float(np.clip(v, u.min(), u.max()))
    return coef[0] * v * v + coef[1] * v + coef[2]


def loo_weighted(S, grid, k: float = 1.0):
    """Leave-one-out with each seed read as a weighted mean of its curve over the locations where
    the other seeds' mean curve is near its maximum (weights from the others only, so it cannot
    read high either)."""
    n = len(S)
    if n < 3:
        return leave_one_out(S, grid)
    out = np.empty(n)
    for i in range(n):
        others = np.delete(S, i, 0)
        m = others.mean(0)
        tau = k * others.std(0, ddof=1).mean() / math.sqrt(n - 1)
        w = np.exp((m - m.max()) / tau)
        out[i] = (w * S[i]).sum() / w.sum()
    return out


CANDIDATES = dict(zip(NAMES, (mean_curve_max, per_seed_max, cross_fit, leave_one_out, bagged, parabola)))


def add_weighted() -> None:
    """The --weighted candidates (the module doc)."""
    global NAMES
    for k in (0.5, 1.0, 2.0):
        CANDIDATES[f"loo-weighted k={k:g}"] = (lambda kk: lambda S, g: loo_weighted(S, g, kk))(k)
    NAMES = tuple(CANDIDATES)


# ---- populations ----------------------------------------------------------------------------------
def smoothed(curves) -> tuple[np.ndarray, np.ndarray]:
    grid = _grid(curves, 400)
    mat = _on_grid(curves, grid)
    return grid, np.array([moving_average(grid, r, WINDOW) for r in mat])


def populations() -> list[dict]:
    s = pd.read_csv(DATA / "summaries.csv")
    store = _Curves(DATA / "curves.parquet")
    out = []
    for pid, g in s[s["test"] == "box"].groupby("physical_id"):
        grid, S = smoothed([store.curve(c) for c in g["case_id"]])
        out.append(dict(name=f"soil test, {g['gradation'].iloc[0]}", kind="soil", pid=pid, grid=grid, S=S))
    iface = s[s["test"] == "interface"]
    for pid, g in iface.groupby("physical_id"):
        if len(g) >= 9:
            grid, S = smoothed([store.curve(c) for c in g["case_id"]])
            box = s[(s["case_id"].isin(g["pair_id"]))]["physical_id"].iloc[0]
            name = str(g["label"].iloc[0]).replace("interface-periodic-sawtooth-", "").rsplit("-s", 1)[0]
            out.append(dict(name=name, kind="interface", pid=pid, box=box, grid=grid, S=S))
    return out


def reference(pop) -> tuple[float, float]:
    """(middle, half-width) of the bracket [leave-one-out(N), mean-curve max(N)]."""
    lo = float(leave_one_out(pop["S"], pop["grid"]).mean())
    hi = float(mean_curve_max(pop["S"], pop["grid"]).mean())
    return (lo + hi) / 2, (hi - lo) / 2


# ---- the study ------------------------------------------------------------------------------------
def subsets(N: int, n: int, draws: int, rng) -> np.ndarray:
    return np.array([rng.choice(N, n, replace=False) for _ in range(draws)])


def peak_rows(pop, ref, ns, draws, rng) -> list[dict]:
    rows = []
    for n in ns:
        idx = subsets(len(pop["S"]), n, draws, rng)
        for name, f in CANDIDATES.items():
            est, cov = [], []
            for i in idx:
                v = f(pop["S"][i], pop["grid"])
                lo, hi = values_interval(v, "tan_phi")
                est.append(v.mean())
                cov.append(lo <= ref <= hi)
            e = np.asarray(est)
            rows.append(dict(population=pop["name"], N=len(pop["S"]), n=n, estimator=name,
                             bias=100 * (e.mean() / ref - 1), spread=100 * e.std() / ref, coverage=np.mean(cov)))
    return rows


def split_rows(pop, ms, draws, rng) -> list[dict]:
    """What an m-seed estimate really scatters by, against what its interval claims: two DISJOINT
    subsets of m seeds each (independent, as two campaigns would be), their estimates' difference
    has sd √2·(the estimate's real sd); the claim is the t-interval's standard error s/√m of the
    per-seed values. ratio > 1: the interval is too narrow by that factor."""
    rows = []
    for m in ms:
        for name, f in CANDIDATES.items():
            diff, se = [], []
            for _ in range(draws):
                p = rng.permutation(len(pop["S"]))
                a, b = f(pop["S"][p[:m]], pop["grid"]), f(pop["S"][p[m:2 * m]], pop["grid"])
                diff.append(a.mean() - b.mean())
                se.append(math.sqrt((a.var(ddof=1) + b.var(ddof=1)) / 2 / m))
            real = float(np.std(diff)) / math.sqrt(2)
            rows.append(dict(population=pop["name"], m=m, estimator=name, real=real, claimed=float(np.mean(se)),
                             ratio=real / float(np.mean(se))))
    return rows


def _side(S, grid, f):
    v = f(S, grid)
    return v.mean(), v.std(ddof=1), v.size


def _equal_counts(Sa, Sb, grid_a, grid_b, rng, k=40):
    """Interface mean-curve max over the mean, over k soil subsets of the interface's size, of theirs."""
    a = mean_curve_max(Sa, grid_a)
    na = len(Sa)
    den = np.mean([mean_curve_max(Sb[rng.choice(len(Sb), na, replace=False)], grid_b).mean() for _ in range(k)])
    b = mean_curve_max(Sb, grid_b)
    return a.mean(), a.std(ddof=1), na, den, b.std(ddof=1), len(Sb)


def e_rows(iface, soil, ref_e, pairs, draws, rng) -> list[dict]:
    rows = []
    for na, nb in pairs:
        ia = subsets(len(iface["S"]), na, draws, rng)
        ib = subsets(len(soil["S"]), nb, draws, rng)
        for name in (*NAMES, "equal counts"):
            est, cov = [], []
            for i, j in zip(ia, ib):
                Sa, Sb = iface["S"][i], soil["S"][j]
                if name == "equal counts":
                    ma, sa, ka, mb, sb, kb = _equal_counts(Sa, Sb, iface["grid"], soil["grid"], rng)
                else:
                    f = CANDIDATES[name]
                    (ma, sa, ka), (mb, sb, kb) = _side(Sa, iface["grid"], f), _side(Sb, soil["grid"], f)
                lo, hi = ratio_interval(ma, sa, ka, mb, sb, kb)
                est.append(ma / mb)
                cov.append(lo <= ref_e <= hi)
            e = np.asarray(est)
            rows.append(dict(population=iface["name"], n=f"{na}/{nb}", estimator=name,
                             bias=100 * (e.mean() / ref_e - 1), spread=100 * e.std() / ref_e, coverage=np.mean(cov)))
    return rows


# ---- populations with a known peak: known trends plus the committed runs' own noise ------------------
def trends(grid) -> dict[str, np.ndarray]:
    """Three shapes a stress-ratio curve takes: "plateau" (the weak soil's: rise to 0.38 by ~3 mm, 0.365
    at the end), "hump" (a dense soil's peak: 0.60 at 2 mm over a 0.45 critical state, sd 1 mm) and
    "sharp" (the same peak, sd 0.5 mm)."""
    x = grid
    base = np.where(x <= 2e-3, 0.45 - 0.45 * (1 - x / 2e-3) ** 2, 0.45)
    return {"plateau": 0.38 - 0.31 * np.exp(-x / 0.6e-3) - 0.015 * np.clip((x - 3.4e-3) / 2.6e-3, 0, 1) ** 2,
            "hump": base + 0.15 * np.exp(-0.5 * ((x - 2e-3) / 1e-3) ** 2),
            "sharp": base + 0.15 * np.exp(-0.5 * ((x - 2e-3) / 0.5e-3) ** 2)}


def noise_bank(pop) -> np.ndarray:
    """A soil population's smoothed residuals about its own seed mean, scaled by √(N/(N−1)) to the
    seeds' variance: the runs' own noise (spikes of force-chain rearrangements, correlated over
    ~0.5 D50; sd 0.035 well-graded, 0.06 uniform)."""
    S = pop["S"]
    return (S - S.mean(0)) * math.sqrt(len(S) / (len(S) - 1))


def known_rows(grid, bank, label, ns, trials, rng) -> list[dict]:
    """Each trial: n seeds = a known trend + a residual of the bank, circularly shifted by a random
    offset and of random sign (so that seeds are independent, as on data, and the noise keeps its
    shape); truth = the maximum of the trend smoothed as the tool smooths."""
    rows = []
    for shape, trend in trends(grid).items():
        smooth = moving_average(grid, trend, WINDOW)
        truth = float(smooth.max())
        for n in ns:
            res = {name: ([], []) for name in NAMES}
            for _ in range(trials):
                S = _draw(smooth, bank, grid, n, rng)
                for name, f in CANDIDATES.items():
                    v = f(S, grid)
                    lo, hi = values_interval(v, "tan_phi")
                    res[name][0].append(v.mean() / truth - 1)
                    res[name][1].append(lo <= truth <= hi)
            rows += [dict(population=f"{shape}, {label} noise (truth known)", N="∞", n=n, estimator=name,
                          bias=100 * np.mean(b), spread=100 * np.std(b), coverage=np.mean(c))
                     for name, (b, c) in res.items()]
    return rows


def _draw(smooth, bank, grid, n, rng) -> np.ndarray:
    j, shift, sign = rng.integers(0, len(bank), n), rng.integers(0, grid.size, n), rng.choice([-1, 1], n)
    return smooth[None, :] + np.array([g * np.roll(bank[a], b) for a, b, g in zip(j, shift, sign)])


def known_e_rows(grid, bank, pairs, trials, rng) -> list[dict]:
    """E with a known truth: an interface of each trend shape over the "plateau" soil, both carrying
    the well-graded noise, at the study's seed counts (interface/soil)."""
    sm = {k: moving_average(grid, t, WINDOW) for k, t in trends(grid).items()}
    rows = []
    for shape in sm:
        truth = sm[shape].max() / sm["plateau"].max()
        for na, nb in pairs:
            res = {name: ([], []) for name in (*NAMES, "equal counts")}
            for _ in range(trials):
                Sa, Sb = _draw(sm[shape], bank, grid, na, rng), _draw(sm["plateau"], bank, grid, nb, rng)
                for name in res:
                    if name == "equal counts":
                        ma, sa, ka, mb, sb, kb = _equal_counts(Sa, Sb, grid, grid, rng, k=10)
                    else:
                        (ma, sa, ka), (mb, sb, kb) = _side(Sa, grid, CANDIDATES[name]), _side(Sb, grid, CANDIDATES[name])
                    lo, hi = ratio_interval(ma, sa, ka, mb, sb, kb)
                    res[name][0].append(ma / mb / truth - 1)
                    res[name][1].append(lo <= truth <= hi)
            rows += [dict(population=f"{shape} interface / plateau soil (truth known)", n=f"{na}/{nb}", estimator=name,
                          bias=100 * np.mean(b), spread=100 * np.std(b), coverage=np.mean(c))
                     for name, (b, c) in res.items()]
    return rows


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--draws", type=int, default=400)
    ap.add_argument("--trials", type=int, default=600)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--weighted", action="store_true", help="add the loo-weighted candidates")
    args = ap.parse_args(argv)
    if args.weighted:
        add_weighted()
    rng = np.random.default_rng(args.seed)
    t0 = time.time()
    pops = populations()
    refs = {p["pid"]: reference(p) for p in pops}
    rows = []
    for p in pops:
        N = len(p["S"])
        ns = [n for n in (3, 5, 10, 20) if n <= N / 2 + 0.5]
        rows += peak_rows(p, refs[p["pid"]][0], ns, args.draws, rng)
    for p in pops:
        if p["kind"] == "soil":
            label = "well-graded" if "poly" in p["name"] else "uniform"
            rows += known_rows(p["grid"], noise_bank(p), label, (3, 5, 10, 20, 40), args.trials, rng)
    splits = pd.DataFrame([r for p in pops for r in split_rows(p, [m for m in (3, 5, 10, 20) if 2 * m <= len(p["S"])],
                                                                  args.draws, rng)])
    erows = []
    soil = {p["pid"]: p for p in pops if p["kind"] == "soil"}
    for p in pops:
        if p["kind"] == "interface":
            b = soil[p["box"]]
            ref_e = refs[p["pid"]][0] / refs[b["pid"]][0]
            erows += e_rows(p, b, ref_e, ((3, 10), (3, 20), (5, 20), (10, 20)) if len(p["S"]) >= 10 else
                            ((3, 10), (3, 20), (5, 20)), args.draws, rng)
    poly = next(p for p in pops if p["kind"] == "soil" and "poly" in p["name"])
    erows += known_e_rows(poly["grid"], noise_bank(poly), ((3, 10), (3, 20), (3, 40), (10, 20)), args.trials // 2, rng)
    report(pops, refs, pd.DataFrame(rows), pd.DataFrame(erows), splits, time.time() - t0)


def report(pops, refs, peaks: pd.DataFrame, es: pd.DataFrame, splits: pd.DataFrame, seconds: float) -> None:
    print(f"# {platform.node()} {platform.machine()}, python {platform.python_version()}, "
          f"{time.strftime('%Y-%m-%d')}, {seconds:.0f} s")
    print("\n| population | seeds N | reference (bracket) |\n|---|---|---|")
    for p in pops:
        m, h = refs[p["pid"]]
        print(f"| {p['name']} | {len(p['S'])} | {m:.4f} ± {h:.4f} ({100 * h / m:.1f} %) |")
    for title, df in (("peak", peaks), ("E", es)):
        print(f"\n## {title}: bias % (spread %) [coverage of the 95 % interval], per seed count\n")
        piv = df.assign(cell=[f"{b:+.1f} ({s:.1f}) [{c:.0%}]" for b, s, c in zip(df.bias, df.spread, df.coverage)])
        for pop, g in piv.groupby("population", sort=False):
            t = g.pivot(index="estimator", columns="n", values="cell")
            t = t.reindex([e for e in (*NAMES, "equal counts") if e in t.index])
            print(f"**{pop}**\n\n| estimator | " + " | ".join(f"n = {c}" for c in t.columns) + " |")
            print("|---|" + "---|" * len(t.columns))
            for est, r in t.iterrows():
                print(f"| {est} | " + " | ".join(str(x) for x in r) + " |")
            print()
    print("\n## real sd of an m-seed peak / its interval's standard error (two disjoint subsets; > 1: too narrow)\n")
    sp = splits.assign(cell=[f"{r:.2f} ({100 * x:.2f})" for r, x in zip(splits.ratio, splits.real)])
    for pop, g in sp.groupby("population", sort=False):
        tb = g.pivot(index="estimator", columns="m", values="cell").reindex([e for e in NAMES if e in set(g.estimator)])
        print(f"**{pop}** (ratio (real sd, % points of tan))\n\n| estimator | " + " | ".join(f"m = {c}" for c in tb.columns) + " |")
        print("|---|" + "---|" * len(tb.columns))
        for est, r in tb.iterrows():
            print(f"| {est} | " + " | ".join(str(x) for x in r) + " |")
        print()
    summary = peaks.groupby(["estimator", "n"])["bias"].agg(["mean", lambda v: np.abs(v).max()]).unstack()
    print("mean bias over populations:\n", summary.round(2).to_string())


if __name__ == "__main__":
    main()
