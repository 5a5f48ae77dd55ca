"""The plan's inertial-number estimate warns before a run that is not quasi-static."""

import math

from interphase.analysis.quasistatic import inertial_estimate, quasi_static_speed, rate_warnings
from interphase.case import Case
from interphase.surface.spec import ProfileSpec

FLAT = ProfileSpec.make("flat")


def test_estimate_is_the_inertial_number_of_a_three_grain_band():
    c = Case(profile=FLAT, shear_velocity=0.05, normal_stress=100e3, density=2650.0)
    gamma_dot = 0.05 / (3 * c.d50)
    assert math.isclose(inertial_estimate(c), gamma_dot * c.d50 / math.sqrt(100e3 / 2650.0))
    assert math.isclose(inertial_estimate(c.replace(shear_velocity=quasi_static_speed(c))), 1e-3)


def test_the_periodic_device_shears_in_a_thicker_band():
    # measured: at 0.02 m/s every periodic run had I ≤ 6.3e-4 (band ≥ 5.1 D50); 0.02 m/s must not warn
    c = Case(profile=FLAT, device="periodic", shear_velocity=0.02)
    assert inertial_estimate(c) < 1e-3 and rate_warnings([c]) == []
    assert math.isclose(inertial_estimate(c), 0.02 / (5 * math.sqrt(100e3 / 2650.0)))
    (w,) = rate_warnings([c.replace(shear_velocity=0.05)])
    assert "periodic device" in w and "≤ 0.0307 m/s" in w


def test_warning_names_the_speed_that_fixes_it_and_counts_cases():
    fast = [Case(profile=FLAT, seed=s, shear_velocity=0.05) for s in (1, 2)]
    slow = [Case(profile=FLAT, shear_velocity=0.01)]
    (w,) = rate_warnings(fast + slow)
    assert w.startswith("2 case(s) at shear_velocity = 0.05") and "≤ 0.0184 m/s" in w
    assert rate_warnings(slow) == []
