"""θa of an areal scan (surface/areal.py): 512 × 512 self-affine scan of 12 × 12 mm at D50 0.7 mm,
and the real 500 × 500 FRT scan campaigns/profiles/frt-1.frt (31 % missing points).

Target (issue "Real surfaces as they come"): θa of a 512 × 512 areal scan at D50 0.7 mm under 2 s.
Prints the best of `REPEATS` wall times for one axis (+x and −x from one trace) and for all four
directions (both axes), reading excluded. Run: .venv/bin/python bench/bench_theta_a_areal.py
"""

from __future__ import annotations

import contextlib
import io
import timeit
import warnings
from pathlib import Path

import numpy as np

from interphase.surface.areal import theta_a_scan
from interphase.surface.base import Scan
from interphase.surface.readers import read_scan

REPEATS = 3
D50 = 0.7e-3
ROOT = Path(__file__).resolve().parents[1]


def selfaffine_scan(n: int = 512, size: float = 12e-3) -> Scan:
    with warnings.catch_warnings(), contextlib.redirect_stdout(io.StringIO()):
        warnings.simplefilter("ignore")
        from SurfaceTopography.Generation import fourier_synthesis

        t = fourier_synthesis((n, n), (size, size), hurst=0.8, rms_slope=0.3, short_cutoff=size / 100,
                              long_cutoff=size / 4, rng=1)
        h = np.asarray(t.heights(), float)
    x = np.arange(n) * (size / n)
    return Scan(h, x, x.copy(), "selfaffine-512", "m", "fourier_synthesis")


def best(fn) -> float:
    """The shortest wall time [s] of REPEATS calls of fn (timeit, the garbage collector left on as in a real run)."""
    return min(timeit.repeat(fn, setup="gc.enable()", number=1, repeat=REPEATS))


def main() -> None:
    for scan in (selfaffine_scan(), read_scan(ROOT / "campaigns" / "profiles" / "frt-1.frt")):
        res = theta_a_scan(scan, D50, (92,))
        one = best(lambda: theta_a_scan(scan, D50, (92,), axes=("x",)))
        four = best(lambda: theta_a_scan(scan, D50, (92,)))
        r = res["+x"][92]
        print(f"{scan.name.split('/')[-1]:<16} {scan.shape}  missing {scan.n_missing:6d}  step D50/{D50 / r.step:.0f}  "
              f"runs {r.n_runs} (dropped {r.n_dropped})  θa +x {r.theta_a_deg:.2f}°  "
              f"one axis {one:.2f} s  four directions {four:.2f} s")


if __name__ == "__main__":
    main()
