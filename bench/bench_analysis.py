"""Benchmark: anisotropy + average stress for 10⁶ contacts (target: under 1 s together).

Run: .venv/bin/python bench/bench_analysis.py  — prints a Markdown table for BENCHMARKS.md.
A synthetic ContactTable of N contacts in one snapshot (10 % 'ps'), box 0.1 m × 0.05 m, grains of
0.7 mm; best of 3 wall-clock runs per step.
"""

from __future__ import annotations

import timeit

import numpy as np
import pandas as pd

from interphase.analysis.anisotropy import region_anisotropy, surface_anisotropy, tensor_method
from interphase.analysis.stress import average_stress
from interphase.tables import CONTACT_COLUMNS


def table(n: int, seed: int = 0, snapshots: int = 1) -> pd.DataFrame:
    rng = np.random.default_rng(seed)
    th = rng.uniform(0, 2 * np.pi, n)
    nx, nz = np.cos(th), np.sin(th)
    fn = rng.gamma(2.0, 0.5, n)
    ft = 0.3 * fn * rng.uniform(-1, 1, n)
    x1, z1 = rng.uniform(0, 0.1, n), rng.uniform(0, 0.05, n)
    kind = np.where(rng.random(n) < 0.1, "ps", "pp")
    nz = np.where(kind == "ps", np.abs(nz), nz)
    return pd.DataFrame({
        "snapshot": rng.integers(0, snapshots, n), "time": 0.0, "shear_disp": 0.0,
        "kind": pd.Categorical(kind, categories=["pp", "ps", "pw"]), "id1": np.arange(n), "id2": np.arange(n) + n,
        "cx": x1 + 0.35e-3 * nx, "cz": z1 + 0.35e-3 * nz, "nx": nx, "nz": nz, "fn": fn, "ft": ft,
        "fx": fn * nx - ft * nz, "fz": fn * nz + ft * nx, "x1": x1, "z1": z1,
        "x2": x1 + 0.7e-3 * nx, "z2": z1 + 0.7e-3 * nz, "overlap": 1e-6,
    })[list(CONTACT_COLUMNS)]


def best(fn, repeat=3) -> float:
    """The shortest wall time [s] of `repeat` calls of fn (timeit, the garbage collector left on as in a real run)."""
    return min(timeit.repeat(fn, setup="gc.enable()", number=1, repeat=repeat))


def main():
    rect = (0.0, 0.1, 0.005, 0.019)
    print("| contacts | tensor method [s] | surface (θr, θn, fabric) [s] | region anisotropy [s] | average stress [s] | anisotropy + stress [s] |")
    print("|---|---|---|---|---|---|")
    for n in (10_000, 100_000, 1_000_000):
        c = table(n)
        t_tensor = best(lambda: tensor_method(c["nx"], c["nz"], c["fn"], c["ft"]))
        t_surf = best(lambda: surface_anisotropy(c))
        t_reg = best(lambda: region_anisotropy(c, rect))
        t_str = best(lambda: average_stress(c, rect))
        t_all = best(lambda: (surface_anisotropy(c), region_anisotropy(c, rect), average_stress(c, rect)))
        print(f"| {n:,} | {t_tensor:.3f} | {t_surf:.3f} | {t_reg:.3f} | {t_str:.3f} | {t_all:.3f} |")
    c = table(1_000_000, snapshots=13)
    t13 = best(lambda: (surface_anisotropy(c), region_anisotropy(c, rect), average_stress(c, rect)))
    print(f"\n10⁶ contacts over 13 snapshots (grouped sums, one pass): {t13:.3f} s")


if __name__ == "__main__":
    main()
