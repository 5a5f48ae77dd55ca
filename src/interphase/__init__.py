"""interphase-dem: DEM interface-shear campaigns and the anisotropy-based failure criterion.

The Python API (interphase.api; the `campaign` command does the same):

    import interphase as ip
    c = ip.load_campaign("campaigns/quick.toml")    # checked, nothing runs; c.output = its runs folder
    ip.plan(c)                                      # the planned runs with their case ids
    ip.run(c)                                       # run what is not finished (resumable)
    ip.status(c)                                    # DataFrame: one row per planned case
    ip.summaries(c)                                 # DataFrame: one row per finished run
    ip.ensembles(c)                                 # DataFrame: one row per physical case (seeds pooled)
    ip.predict("profile.csv", soil="soils/NAME.toml", friction=0.2, normal_stress=200e3)   # the answer (Answer)
    ip.predict("profile.csv", fit="study", d50=0.7e-3, friction=0.2)   # on the study's simulated discs
    ip.predict_dem("profile.csv", 0.2, "soils/NAME.toml")  # the DEM on the profile instead (runs)
    ip.element("soils/NAME.toml", 100e3, seeds=3)   # the soil's φ_peak, φ_cs, ψ_max (docs/soils.md)
    ip.calibrate("TARGET.toml")                     # grain parameters from a laboratory soil → a card
    ip.validate("lab/FILE.csv", soil="soils/NAME.toml")   # the criterion against laboratory tests
    ip.lab_record("lab/soils/ottawa-f65/FILE.csv")  # a laboratory triaxial record: φ_peak, ψ_max, end
interphase.api has the rest, one function per `campaign` command (theta_a, render, report, cell, …).
An example that runs end to end: docs/api_example.py.

Units are SI inside the code (m, N, Pa, s, radians); profile generators take sizes in D50 units.
Angles follow docs/methods.md §0: θ counterclockwise from +x, ψ = θ − 90° (tilt from vertical, positive
toward −x, the shear-resisting side); public outputs name which reading they carry.
Bad input raises interphase.errors.InputError (the file, the field and the fix).
"""

from interphase.api import (calibrate, element, ensembles, lab_record, load_campaign, plan, predict, predict_dem,
                            run, status, summaries, validate)
from interphase.errors import InputError
from interphase.version import __version__

__all__ = ["load_campaign", "plan", "run", "status", "summaries", "ensembles", "predict", "predict_dem", "element",
           "calibrate",
           "validate", "lab_record", "InputError",
           "__version__"]
