"""The engine side shared by LIGGGHTS and YADE: profiles from the environment, the time limit
from recipe.json, the failure causes of the one `execute`, the version probe. No engine runs."""

from __future__ import annotations

import pytest

from interphase.case import Case
from interphase.engines.base import EngineError, EngineProfile
from interphase.engines.device import device
from interphase.engines.liggghts import Liggghts
from interphase.engines.yade import Yade
from interphase.errors import InputError
from interphase.surface.spec import ProfileSpec

CASE = Case(profile=ProfileSpec.make("flat"), shear_modulus=50e6, n_grains=60, box_length_d50=16, box_height_d50=8,
            shear_distance=0.5e-3, snapshot_every=0.25e-3)
ENGINES = [Liggghts, Yade]


@pytest.mark.parametrize("cls", ENGINES)
def test_profile_from_the_environment(cls, monkeypatch):
    prefix = f"INTERPHASE_{cls.name.upper()}_"
    for k in ("BINARY", "LAUNCHER", "THREADS", "TIMEOUT"):
        monkeypatch.delenv(prefix + k, raising=False)
    assert cls.default_profile() == EngineProfile(binary=cls.name)
    monkeypatch.setenv(prefix + "BINARY", "/opt/x/bin/engine")
    monkeypatch.setenv(prefix + "LAUNCHER", "nice -n 5")
    monkeypatch.setenv(prefix + "THREADS", "2")
    monkeypatch.setenv(prefix + "TIMEOUT", "90")
    p = cls.default_profile()
    assert (p.binary, p.launcher, p.threads, p.timeout) == ("/opt/x/bin/engine", ("nice", "-n", "5"), 2, 90.0)
    assert cls(profile=p).command()[:3] == ["nice", "-n", "5"]
    monkeypatch.setenv(prefix + "THREADS", "two")
    with pytest.raises(InputError, match=prefix + "THREADS='two' is not an integer"):
        cls.default_profile()


@pytest.mark.parametrize("cls", ENGINES)
def test_timeout_from_the_recipe_record(cls, tmp_path):
    eng = cls(profile=EngineProfile(cls.name))
    eng.write_input(CASE, tmp_path)
    dev = device(CASE)
    r = dev.recipe
    expected = r.timeout_base + r.timeout_factor * dev.steps.most * dev.n_grains / r.throughput(cls.name)
    assert eng.timeout_for(tmp_path) == pytest.approx(expected)
    assert cls(profile=EngineProfile(cls.name, timeout=7.0)).timeout_for(tmp_path) == 7.0


@pytest.mark.parametrize("cls", ENGINES)
def test_a_missing_binary_is_not_installed(cls, tmp_path):
    eng = cls(profile=EngineProfile("no-such-engine-binary"))
    assert eng.version() == "not-installed"
    eng.write_input(CASE, tmp_path)
    with pytest.raises(EngineError) as err:
        eng.execute(tmp_path)
    assert err.value.cause == "not_installed"
    assert str(err.value) == f"[not_installed] {cls.label} binary 'no-such-engine-binary' not found"


@pytest.mark.parametrize("cls", ENGINES)
def test_a_given_version_is_not_probed(cls):
    assert cls(profile=EngineProfile("no-such-engine-binary", version="v-test")).version() == "v-test"
