"""The starting lattice refuses a cell too small for a graded soil's largest grains, naming the
length it needs in D50 (2.5 lattice pitches of 1.02 d_max), not a figure for uniform grains."""

from __future__ import annotations

import pytest

from interphase.case import Case
from interphase.engines.packing import lattice_packing, lattice_packing_3d
from interphase.errors import InputError
from interphase.material import Gradation

# the Karlsruhe fine sand's sieve curve (soils/karlsruhe-fine-sand.toml): d_max 0.2271 mm = 1.62 D50
SIZES = [8.263e-05, 8.925e-05, 9.641e-05, 0.0001039, 0.0001119, 0.0001204, 0.0001299, 0.0001405, 0.000152,
         0.00017, 0.0001964, 0.0002271]
FRACTIONS = [0.0938, 0.0744, 0.059, 0.1075, 0.0863, 0.0692, 0.1921, 0.1517, 0.1199, 0.0223, 0.0144, 0.0094]


@pytest.mark.parametrize("device", ["periodic", "periodic3d"])
def test_a_cell_too_short_for_the_largest_grains_names_the_length_it_needs(device):
    grains = Gradation(name="user", sizes=tuple(SIZES), fractions=tuple(FRACTIONS))
    depth = {"box_depth_d50": 6} if device == "periodic3d" else {}
    case = Case(test="box", device=device, d50=1.4e-4, gradation=grains, box_length_d50=4, box_height_d50=6, **depth)
    pack = lattice_packing if device == "periodic" else lattice_packing_3d
    with pytest.raises(InputError, match=r"at least 4\.2 D50 .*\(1\.62 D50\)") as err:
        pack(case, 0.0, case.box_length, 0.0)
    assert err.value.where == "case.box_length_d50"
    ok = Case(test="box", device=device, d50=1.4e-4, gradation=grains, box_length_d50=4.3, box_height_d50=6, **depth)
    assert pack(ok, 0.0, ok.box_length, 0.0).x.size > 0
