"""Bolton's (1986) target against values worked by hand, and against the card's sand."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from interphase.analysis.bolton import dilatancy_index, triaxial

ROOT = Path(__file__).resolve().parents[1]


def test_the_index_by_hand():
    # Dr 0.8 at p′ 100 kPa: 0.8 (10 − ln 100) − 1 = 0.8 × 5.3948 − 1 = 3.3159
    assert float(dilatancy_index(0.8, 100e3)) == pytest.approx(3.3159, abs=1e-4)
    # loose or high stress: no dilation (kept at 0), and never above 4
    assert float(dilatancy_index(0.1, 100e3)) == 0.0
    assert float(dilatancy_index(1.0, 1e3)) == 4.0


def test_the_fixed_point_by_hand():
    """Dr 0.8, σ3′ 100 kPa, φ_crit 33.1° (the Karlsruhe sand): by hand, p′ 100 → 386.7 → 337.1 → 341.7 kPa,
    I_R 3.316 → 2.234 → 2.344 → 2.333, φ_max → 40.1°; r = 0.3 × 2.333 = 0.700, ψ = asin(0.700/2.700) = 15.0°."""
    s = triaxial(0.8, 100e3, 33.1)
    assert s.index == pytest.approx(2.333, abs=2e-3)
    assert s.mean_stress == pytest.approx(341.2e3, rel=3e-3)
    assert s.phi_peak_deg == pytest.approx(40.10, abs=0.01)
    assert s.psi_max_deg == pytest.approx(15.03, abs=0.05)
    r = (1 + math.sin(math.radians(s.phi_peak_deg))) / (1 - math.sin(math.radians(s.phi_peak_deg)))
    assert s.mean_stress == pytest.approx(100e3 * (1 + 2 * r) / 3, rel=1e-8)     # a fixed point


def test_loose_sand_is_non_dilative_and_strength_falls_with_stress():
    loose = triaxial(0.2, 100e3, 33.1)
    assert loose.index == 0 and loose.phi_peak_deg == 33.1 and loose.psi_max_deg == 0
    dense = [triaxial(0.9, p, 33.1).phi_peak_deg for p in (50e3, 100e3, 200e3, 400e3)]
    assert all(a > b for a, b in zip(dense, dense[1:]))


def test_the_card_records_target():
    """The Karlsruhe card's φ_crit and one of its records: TMD11 (Dr 0.567, σ3′ 50 kPa) targets
    φ_max − φ_c = 3 I_R with I_R from the fixed point (between its σ3′ and 4 σ3′ bounds)."""
    import tomllib

    card = tomllib.loads((ROOT / "soils" / "karlsruhe-fine-sand.toml").read_text())
    phi_c = card["target"]["phi_cs_deg"]
    rec = next(v for v in card["verification"] if v["record"] == "TMD11.dat")
    s = triaxial(rec["relative_density"], rec["confining_stress"], phi_c)
    hi = float(dilatancy_index(rec["relative_density"], rec["confining_stress"]))
    lo = float(dilatancy_index(rec["relative_density"], 4 * rec["confining_stress"]))
    assert lo < s.index < hi
    assert s.phi_peak_deg == pytest.approx(phi_c + 3 * s.index)
