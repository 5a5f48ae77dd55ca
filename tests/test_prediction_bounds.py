"""Issue 40 item 3: a prediction stays inside its data. A friction outside the fitted ones is refused
(exit 2, naming what the fits cover) instead of silently taking the pooled fit (δ 18.4° at μ 0.5,
then 11.8° at 0.6 and 0.9); on a flat δ is min(φμ, φ) — never above atan μ (Coulomb), within 0.5°
of it where μ < tan φ (it was 12.0° at μ 0.2, and 23.6° in `validate` on a lab flat) — on every
shipped fit; no prediction is below the flat-surface value, and δ is monotone in μ."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from interphase.analysis.criterion import fitted_frictions, predict
from interphase.cli import main
from interphase.criterion_fits import criterion_model

ROOT = Path(__file__).resolve().parents[1]
DEKTAK = str(ROOT / "tests" / "data" / "dektak-1.csv")
SHIPPED = ["study", "study-figures"]   # the reproduction's fits (criterion_reproduction.json) and the study's readings


@pytest.fixture(scope="module")
def saw(tmp_path_factory):
    prof = tmp_path_factory.mktemp("prof") / "saw45.txt"
    assert main(["profile", "sawtooth", "--rt", "1", "--sw", "2", "-o", str(prof)]) == 0
    return str(prof)


def test_a_friction_outside_the_fits_exits_2_naming_the_range(saw, capsys):
    capsys.readouterr()
    for mu in ("0.6", "0.9", "0.01"):
        assert main(["predict", saw, "--d50", "0.7", "--friction", mu, "--json", "--fit", "study"]) == 2
        err = capsys.readouterr().err
        assert "--friction" in err and "0.05–0.5" in err and "θa 0.0–73.7°" in err and "Traceback" not in err
    assert main(["predict", saw, "--d50", "0.7", "--friction", "0.9", "--json", "--fit", "study-figures"]) == 0


@pytest.mark.parametrize("fit", SHIPPED)
@pytest.mark.parametrize("tan_phi", [None, math.tan(math.radians(36.0))])
def test_on_a_flat_delta_is_atan_mu_never_above(fit, tan_phi):
    for mu in (0.05, 0.2):
        model = criterion_model(mu, fit, tan_phi)
        assert mu < model.tan_phi
        p = predict(model, mu, math.nan, math.nan)
        phi_mu = math.degrees(math.atan(mu))
        assert p.branch == "non-dilative"
        assert p.delta_deg <= phi_mu + 1e-9 and abs(p.delta_deg - phi_mu) <= 0.5, (fit, mu, p.delta_deg)
        assert p.delta_interval_deg[1] <= phi_mu + 1e-9 or math.isnan(p.delta_interval_deg[1])
        assert p.tan_delta == pytest.approx(p.efficiency * p.tan_phi)


@pytest.mark.parametrize("fit", SHIPPED)
def test_monotone_in_friction_and_never_below_the_flat(fit):
    mus = fitted_frictions(criterion_model(0.2, fit)) or [0.05, 0.5]
    grid = np.linspace(mus[0], mus[-1], 19)
    top = 73.0 if fit == "study" else 60.0
    for a in [math.nan, *np.linspace(0.0, top, 30)]:
        deltas = []
        for mu in grid:
            model = criterion_model(mu, fit)
            p = predict(model, mu, a, a)
            flat = math.degrees(math.atan(min(mu, model.tan_phi)))
            assert p.delta_deg >= flat - 1e-9, (fit, a, mu)
            deltas.append(p.delta_deg)
        assert all(b >= c - 1e-9 for c, b in zip(deltas, deltas[1:])), (fit, a, np.round(deltas, 2))


def test_validate_on_a_lab_flat_is_not_above_the_surface_friction(tmp_path, capsys):
    lab = tmp_path / "lab.csv"
    lab.write_text("soil,d50_mm,surface,asperity_height_mm,asperity_width_mm,root_spacing_mm,normal_stress_kpa,"
                   "delta_peak_deg,soil_phi_peak_deg,source,table_or_figure\n"
                   "Ottawa 20/30 sand (synthetic),0.72,flat,,,,100,12,36,synthetic test row,none\n")
    code = main(["validate", str(lab), "-o", str(tmp_path / "v"), "--json"])
    out = capsys.readouterr()
    assert code == 0, out.err
    (row,) = json.loads(out.out)["table"]
    assert row["delta_predicted_deg"] == pytest.approx(math.degrees(math.atan(0.2)), abs=1e-6)
