"""θa for a 10⁶-point measured-like profile at D50/dx = 500, and time vs N (figure in bench/out).

Run: .venv/bin/python bench/bench_theta_a.py   (prints a Markdown table for BENCHMARKS.md)
"""

from __future__ import annotations

import platform
import time
import timeit
from pathlib import Path

import numpy as np

from interphase.surface.normals import theta_a
from interphase.surface.profiles import Profile
from interphase.surface.trace import centroid_trace

D50 = 0.7e-3
DX = D50 / 500


def measured_like(n: int, seed: int = 0) -> Profile:
    """A rough random profile: a smoothed random walk, a few µm to 0.3 mm relief."""
    rng = np.random.default_rng(seed)
    z = np.cumsum(rng.normal(0, 1, n))
    z = np.convolve(z, np.ones(50) / 50, mode="same") * 2e-6
    return Profile(np.arange(n) * DX, z - z.mean())


def best_of(fn, repeat=3) -> float:
    """The shortest wall time [s] of `repeat` calls of fn (timeit, the garbage collector left on as in a real run)."""
    return min(timeit.repeat(fn, setup="gc.enable()", number=1, repeat=repeat))


def main():
    rows = []
    for n in (10**4, 10**5, 3 * 10**5, 10**6):
        p = measured_like(n)
        t_trace = best_of(lambda: centroid_trace(p, D50, dx=DX))
        t_all = best_of(lambda: theta_a(p, D50, 92, dx=DX))
        rows.append((n, t_trace, t_all))
    print(f"machine: {platform.processor() or platform.machine()}, {__import__('os').cpu_count()} cores, "
          f"numpy {np.__version__}")
    print("| points | trace [s] | θa + Rn + Rnc + slope [s] |\n|---|---|---|")
    for n, a, b in rows:
        print(f"| {n:,} | {a:.3f} | {b:.3f} |")
    out = Path(__file__).with_name("out")
    out.mkdir(exist_ok=True)
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(5, 3.5))
    ns = [r[0] for r in rows]
    ax.loglog(ns, [r[1] for r in rows], "o-", label="centroid trace")
    ax.loglog(ns, [r[2] for r in rows], "s-", label="theta_a (all outputs)")
    ax.axhline(1.0, color="0.5", ls="--", lw=1, label="target 1 s at 10⁶")
    ax.set_xlabel("profile points (D50/dx = 500)")
    ax.set_ylabel("wall time [s]")
    ax.legend()
    fig.tight_layout()
    fig.savefig(Path(__file__).with_name("theta_a_time.png"), dpi=110)


if __name__ == "__main__":
    main()
