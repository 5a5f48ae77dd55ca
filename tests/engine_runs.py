"""Tiny quasi-2D cases and their real runs, cached per session: what tests/test_liggghts.py and
tests/test_yade_engine.py share (each engine's tests run the same cases)."""

from __future__ import annotations

from interphase.case import Case
from interphase.surface.spec import ProfileSpec

#: 200 grains of shear modulus 50 MPa (soft, for a large time step) in a 20 × 10 D50 box: seconds of
#: engine time per mm of shear; each test file adds its shear distance and snapshot spacing [m]
TINY_GRAINS = dict(shear_modulus=50e6, n_grains=200, box_length_d50=20, box_height_d50=10)


def tiny_case(base: dict, test: str = "interface", profile=("flat", {}), **kw) -> Case:
    """A Case of `base` (Case fields) with `kw` over it; `profile` is (kind, parameters), ignored
    by a box test (no rough surface)."""
    spec = None if test == "box" else ProfileSpec.make(profile[0], **profile[1])
    return Case(test=test, profile=spec, **(base | kw))


def cached_runner(engine, tmp_path_factory, prefix: str):
    """run(case) → (folder, Results) with `engine`: each distinct case (by its canonical form) is
    written, executed and read once per session, in a fresh folder named after `prefix`."""
    cache = {}

    def run(case: Case):
        key = repr(case.canonical())
        if key not in cache:
            folder = tmp_path_factory.mktemp(prefix)
            engine.write_input(case, folder)
            engine.execute(folder)
            cache[key] = (folder, engine.read_results(folder))
        return cache[key]
    return run
