"""Inverting the void-ratio map e(preparation) (campaign/density.py): what a relative density is
turned into before any engine runs."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from interphase.campaign.density import invert_map

# the Karlsruhe card's map at 200 kPa (2-seed means), with the point seed noise put out of order
PREP = [0.0, 0.2269, 0.25, 0.5, 0.75, 1.0]
E = [0.4167, 0.5215, 0.5209, 0.6075, 0.6476, 0.672]


def test_a_target_between_two_points_is_bracketed_by_neighbours_in_preparation():
    # e 0.5112 (Dr 0.63) lies between the points at 0 and 0.2269: the straight line between them,
    # not one that skips 0.2269 because its e came out 0.0006 above the next point's
    target = 0.672 - 0.63 * (0.672 - 0.4167)
    assert invert_map(PREP, E, target) == round(0.2269 * (target - 0.4167) / (0.5215 - 0.4167), 4)


def test_the_limits_map_to_the_ends():
    assert invert_map(PREP, E, 0.4167) == 0.0 and invert_map(PREP, E, 0.672) == 1.0
    assert invert_map(PREP, E, 0.30) == 0.0 and invert_map(PREP, E, 0.9) == 1.0      # clipped, never outside
    # a point above 1 (packed denser than 1 on stiff grains) is outside the limits and never read
    assert invert_map([*PREP, 2.5], [*E, 0.60], 0.9) == 1.0
    assert invert_map([*PREP, 2.5], [*E, 0.60], 0.5) == invert_map(PREP, E, 0.5)


@given(st.lists(st.floats(0.3, 0.9), min_size=2, max_size=9), st.floats(0.25, 0.95), st.floats(0.25, 0.95))
def test_denser_targets_never_ask_for_a_looser_preparation(es, t1, t2):
    prep = np.linspace(0, 1, len(es))
    lo, hi = sorted((t1, t2))
    a, b = invert_map(prep, es, lo), invert_map(prep, es, hi)
    assert 0.0 <= a <= b <= 1.0


def test_a_map_keeps_the_points_measured_before_for_the_same_grains_and_seeds(tmp_path):
    """A map redrawn in its folder never drops a point (campaign/density.py `_mapped`): the fitted
    state a calibration measured stays on the map that later reads the record's Dr there."""
    from interphase.campaign.density import _mapped
    from interphase.campaign.element import write_campaign

    case = {"test": "triaxial", "n_grains": 150, "friction_pp": 0.43, "normal_stress": 100e3}
    path = tmp_path / "density-x-100kPa.toml"
    assert _mapped(path, case, [1, 2]) == []
    write_campaign(path, name="density-x-100kPa", case=case, sweep={"preparation": [0.0, 0.3115, 1.0], "seed": [1, 2]})
    assert _mapped(path, case, [1, 2]) == [0.0, 0.3115, 1.0]
    assert _mapped(path, case, [3, 4]) == []                                  # other seeds: a map of their own
    assert _mapped(path, {**case, "friction_pp": 0.5}, [1, 2]) == []           # other grains, likewise


def test_a_picked_preparation_is_kept_for_its_map_and_dropped_with_other_grains_or_seeds(tmp_path):
    """The preparation a Dr was read at is recorded beside the map and returned as it is by later
    calls on the same map (campaign/density.py `_Picks`), so a record read again (more seeds, its
    report) shears the specimens it sheared before; another card's grains or other map seeds start
    afresh."""
    from interphase.campaign.density import _Picks

    case = {"test": "triaxial", "n_grains": 150, "friction_pp": 0.43, "normal_stress": 100e3,
            "gradation": {"sizes": [1e-4, 2e-4], "fractions": [0.5, 0.5]}}
    path = tmp_path / "density-x-100kPa.toml"
    lim = (0.53, 0.83)
    first = _Picks(path, case, [1, 2])
    assert first.get(0.7847, lim) is None
    first.put(0.7847, lim, 0.1115)
    assert _Picks(path, case, [1, 2]).get(0.7847, lim) == 0.1115
    assert _Picks(path, case, [1, 2]).get(0.63, lim) is None                      # another Dr: not picked yet
    assert _Picks(path, case, [1, 2]).get(0.7847, (0.64, 0.83)) is None           # another density scale
    assert _Picks(path, case, [3, 4]).get(0.7847, lim) is None                    # other map seeds
    assert _Picks(path, {**case, "friction_pp": 0.5}, [1, 2]).get(0.7847, lim) is None   # other grains
    again = _Picks(path, case, [1, 2])
    again.put(0.63, lim, 0.2269)
    assert sorted(_Picks(path, case, [1, 2]).picks.values()) == [0.1115, 0.2269]


def test_a_refit_of_the_same_name_keeps_each_cards_map_and_takes_over_an_unnamed_one(tmp_path):
    """Two cards of one name in one runs folder (a target refitted: its card is written under the
    same name into the same folder) each keep their own map file and picks, so a Dr read again on the
    first card finds the preparation its checks ran at; a map written under the name alone is taken
    over by the grains and seeds it belongs to, and by no others."""
    from interphase.campaign.density import _map_file, _Picks
    from interphase.campaign.element import write_campaign
    from interphase.soil import load_card

    text = ('[soil]\nname = "sand"\nd50 = 0.00014\ngradation = {{sizes = [0.000112, 0.00014, 0.000168], '
            'fractions = [0.3, 0.4, 0.3]}}\nshear_modulus = 50e6\nfriction_pp = {mu}\nrolling_friction = 0.1\n'
            'preparation = 0.2\n\n[cell]\ntest = "triaxial"\nn_grains = 150\n')
    (tmp_path / "a").mkdir(), (tmp_path / "b").mkdir()
    (tmp_path / "a" / "sand.toml").write_text(text.format(mu=0.45))
    (tmp_path / "b" / "sand.toml").write_text(text.format(mu=0.47))
    first, refit = load_card(tmp_path / "a" / "sand.toml"), load_card(tmp_path / "b" / "sand.toml")
    runs = tmp_path / "runs"
    runs.mkdir()
    (pa, ca), (pb, cb) = _map_file(first, 100e3, None, runs, [1, 2]), _map_file(refit, 100e3, None, runs, [1, 2])
    assert pa != pb and pa.name.startswith("density-sand-100kPa-")
    assert _map_file(first, 100e3, None, runs, [3, 4])[0] != pa                      # other map seeds
    _Picks(pa, ca, [1, 2]).put(0.78, (0.5, 0.8), 0.1115)
    _Picks(pb, cb, [1, 2]).put(0.78, (0.5, 0.8), 0.2269)
    assert _Picks(*_map_file(first, 100e3, None, runs, [1, 2]), [1, 2]).get(0.78, (0.5, 0.8)) == 0.1115
    # an unnamed map of the first card's grains (as written before the name carried them), in a new folder
    old = tmp_path / "old"
    old.mkdir()
    legacy = old / "density-sand-100kPa.toml"
    write_campaign(legacy, name=legacy.stem, case=ca, sweep={"preparation": [0.0, 0.3115, 1.0], "seed": [1, 2]})
    _Picks(legacy, ca, [1, 2]).put(0.78, (0.5, 0.8), 0.3115)
    path, case = _map_file(first, 100e3, None, old, [1, 2])
    assert path != legacy and _Picks(path, case, [1, 2]).get(0.78, (0.5, 0.8)) == 0.3115
    path, case = _map_file(refit, 100e3, None, old, [1, 2])
    assert not path.exists() and _Picks(path, case, [1, 2]).get(0.78, (0.5, 0.8)) is None


PREP5 = [0.0, 0.25, 0.5, 0.75, 1.0]


def _card_on_maps(tmp_path, monkeypatch, soil: str, density_table: str, base, shift: dict):
    """A card with `soil` fields and a [density] table, and `density.void_ratio_map` replaced by maps
    e(PREP5) = base − shift[stress] (with any `also` points interpolated): which void ratio the
    inversion aims at is what the tests read (each real map point is a token run, tested in
    test_cell.py). Returns (density module, card, runs folder)."""
    from interphase.campaign import density
    from interphase.soil import load_card

    path = tmp_path / "card.toml"
    path.write_text('[soil]\nd50 = 0.00014\ngradation = {sizes = [0.000112, 0.00014, 0.000168], '
                    'fractions = [0.3, 0.4, 0.3]}\n' + soil + "\n[density]\n" + density_table)
    base = np.asarray(base, float)

    def stand_in(card, stress, seeds, also=(), **kw):
        points = sorted({*PREP5, *also})
        return points, np.interp(points, PREP5, base - shift[stress])

    monkeypatch.setattr(density, "void_ratio_map", stand_in)
    out = tmp_path / "runs"
    out.mkdir()
    return density, load_card(path), out


def test_a_relative_density_is_one_void_ratio_at_every_stress(tmp_path, monkeypatch):
    """The limits a Dr is read on are the card's index limits ([density], measured at the reference
    stress), not the map's ends at the test's stress: on a map that compresses with stress the same Dr
    asks for the same e after consolidation (a looser preparation at the higher stress), as the
    laboratory's Dr0 does. The maps are stand-ins (each real map point is a token run, tested in
    test_cell.py); what is tested is which void ratio the inversion aims at."""
    base, shift = [0.53, 0.64, 0.73, 0.78, 0.83], {100e3: 0.01, 400e3: 0.05}   # denser at the higher stress
    density, card, out = _card_on_maps(
        tmp_path, monkeypatch, 'name = "sand"\nshear_modulus = 500e6\nfriction_pp = 0.44\nrolling_friction = 0.46\n'
        'preparation = 0.39\n\n[cell]\ntest = "triaxial"\nn_grains = 150\n',
        "reference_stress = 10000.0\ne_min = 0.53\ne_max = 0.83\nlab_span = 0.5\n", base, shift)
    prep, base = PREP5, np.asarray(base)
    target = 0.83 - 0.5 * 0.8 * (0.83 - 0.53)           # Dr 0.8 on the index limits, lab_span 0.5: e 0.71
    picked = {}
    for s in shift:
        p, limits = density.preparation_at(card, 0.8, s, [1, 2], output=out)
        assert limits == pytest.approx((0.83 - 0.5 * 0.30, 0.83))
        assert np.interp(p, prep, base - shift[s]) == pytest.approx(target, abs=1e-3)
        picked[s] = p
    assert picked[400e3] > picked[100e3]
    assert density.own_relative_density(card, 400e3, [1, 2], picked[400e3], output=out) == pytest.approx(0.4, abs=0.01)


def test_a_card_that_reads_dr_at_the_tests_stress_aims_at_that_maps_own_span(tmp_path, monkeypatch):
    """[density] dr_limits = "test" (grains that compress far more than the sand): the limits are the
    ends of the map at the test's stress, so a Dr is the same share of that map's span at every
    stress (the index limits in the card are not read)."""
    base, shift = [0.134, 0.17, 0.20, 0.222, 0.238], {100e3: 0.0, 200e3: 0.03}
    density, card, out = _card_on_maps(
        tmp_path, monkeypatch, 'name = "discs"\nshear_modulus = 50e6\nfriction_pp = 0.45\nrolling_friction = 0.6\n'
        'preparation = 0.44\n\n[cell]\ntest = "biaxial"\nn_grains = 150\n',
        'reference_stress = 10000.0\ne_min = 0.17\ne_max = 0.28\nlab_span = 1.0\ndr_limits = "test"\n', base, shift)
    prep, base = PREP5, np.asarray(base)
    for s in shift:
        p, limits = density.preparation_at(card, 0.5, s, [1, 2], output=out)
        assert limits == pytest.approx((0.134 - shift[s], 0.238 - shift[s]))
        assert np.interp(p, prep, base - shift[s]) == pytest.approx(0.186 - shift[s], abs=1e-3)
