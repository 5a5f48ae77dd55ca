"""Grain-size distributions and contact-parameter estimates (time step, overlap).

Units: diameters in m, density kg/m³, moduli Pa, times s.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from interphase.errors import InputError

#: the study's two gradations (D50 = 0.7 mm), uniform by number in diameter between the bounds
NAMED_GRADATIONS = {
    "mono": (0.665e-3, 0.735e-3),
    "poly": (0.35e-3, 1.05e-3),
}


@dataclass(frozen=True)
class Gradation:
    """Grain sizes. Either `name` ('mono' | 'poly', uniform by number between the study's bounds),
    or `sizes` (diameters, m) with `fractions` (number fractions, summing to 1): a user list."""

    name: str = "mono"
    sizes: tuple[float, ...] = ()
    fractions: tuple[float, ...] = ()

    def __post_init__(self):
        if self.sizes:
            if len(self.sizes) != len(self.fractions):
                raise InputError("gradation sizes and fractions differ in length", where="case.gradation",
                                 fix="give one number fraction per diameter")
            if any(not (math.isfinite(d) and d > 0) for d in self.sizes):
                raise InputError("gradation sizes must be positive diameters in m", where="case.gradation.sizes")
            if any(f < 0 for f in self.fractions) or abs(sum(self.fractions) - 1) > 1e-6:
                raise InputError("gradation fractions must be ≥ 0 and sum to 1", where="case.gradation.fractions")
        elif self.name not in NAMED_GRADATIONS:
            raise InputError(f"unknown gradation {self.name!r}", where="case.gradation",
                             fix=f"use one of {', '.join(NAMED_GRADATIONS)} or a user list of sizes and fractions")

    @property
    def d_min(self) -> float:
        return min(self.sizes) if self.sizes else NAMED_GRADATIONS[self.name][0]

    @property
    def d_max(self) -> float:
        return max(self.sizes) if self.sizes else NAMED_GRADATIONS[self.name][1]

    def sample(self, n: int, rng: np.random.Generator) -> np.ndarray:
        """n diameters [m]."""
        if self.sizes:
            return rng.choice(np.asarray(self.sizes), size=n, p=np.asarray(self.fractions))
        lo, hi = NAMED_GRADATIONS[self.name]
        return rng.uniform(lo, hi, size=n)

    def canonical(self):
        if self.sizes:
            return {"sizes": [float(s) for s in self.sizes], "fractions": [float(f) for f in self.fractions]}
        return self.name


def rayleigh_time(radius: float, density: float, shear_modulus: float, poisson: float) -> float:
    """Rayleigh wave time T_R = π r sqrt(ρ/G) / (0.1631 ν + 0.8766) [s]."""
    return math.pi * radius * math.sqrt(density / shear_modulus) / (0.1631 * poisson + 0.8766)


def youngs_modulus(shear_modulus: float, poisson: float) -> float:
    """E = 2G(1 + ν) [Pa]."""
    return 2.0 * shear_modulus * (1.0 + poisson)


def sieve_gradation(sieves, percent_finer, *, per_bin: int = 3) -> Gradation:
    """A user Gradation of spheres from a laboratory sieve curve: sieve sizes [m] (ascending) with the
    percentage by mass finer than each. The mass between two sieves is spread evenly in log d (the
    curve drawn straight on its usual semi-log axes) over `per_bin` sub-bins, each represented by its
    geometric-mean diameter; number fractions ∝ mass / d³. What lies below the first sieve or above
    the last is left out (the caller chooses the sieves: the tails set the time step and the count
    of the smallest grains). Sizes and fractions rounded to 4 digits, the last fraction closing the sum."""
    s, m = np.asarray(sieves, float), np.asarray(percent_finer, float)
    if s.size < 2 or np.any(np.diff(s) <= 0) or np.any(np.diff(m) < 0):
        raise InputError("sieve sizes must ascend and their percentages finer must not fall",
                         where="sieve_gradation", fix="give the sieve curve in ascending size")
    sizes, mass = [], []
    for a, b, dm in zip(s[:-1], s[1:], np.diff(m)):
        edges = np.geomspace(a, b, per_bin + 1)
        sizes += list(np.sqrt(edges[:-1] * edges[1:]))
        mass += [dm / per_bin] * per_bin
    d = np.array([float(f"{x:.4g}") for x in sizes])
    number = np.asarray(mass) / np.asarray(sizes) ** 3
    frac = np.round(number / number.sum(), 4)
    frac[-1] = round(1.0 - frac[:-1].sum(), 4)
    return Gradation(name="user", sizes=tuple(float(x) for x in d), fractions=tuple(float(f) for f in frac))


def mass_quantile(g: Gradation, q: float) -> float:
    """The diameter [m] below which a fraction q of the grains' mass lies (d50 at q = 0.5), read
    from the discrete sizes (the smallest size whose cumulative mass reaches q)."""
    d = np.asarray(g.sizes, float)
    w = np.asarray(g.fractions, float) * d ** 3
    o = np.argsort(d)
    cum = np.cumsum(w[o]) / w.sum()
    return float(d[o][np.searchsorted(cum, q - 1e-12)])
