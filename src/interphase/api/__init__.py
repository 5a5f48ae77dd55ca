"""The Python API: what the `campaign` command does, from a script or a notebook. The command is a
parser and a printer over these functions (one per verb), so both take the same input, refuse the
same input with the same InputError and return the same numbers.

    import interphase as ip
    c = ip.load_campaign("campaigns/quick.toml")          # validated, nothing runs
    cases = ip.plan(c)                                     # [PlannedCase]: case_id, label, case, ...
    ip.run(c)                                              # RunReport; resumable, as `campaign run`
    ip.status(c)                                           # DataFrame, one row per planned case
    df = ip.summaries(c)                                   # DataFrame, one row per finished run
    ens = ip.ensembles(c)                                  # DataFrame, one row per physical case
    a = ip.predict("profile.csv", soil="soils/karlsruhe-fine-sand.toml", friction=0.3, normal_stress=200e3)
    print(a.paragraph())                                   # Answer: δ, its two intervals and their parts
    d = ip.predict_dem("profile.csv", 0.2, "soils/karlsruhe-fine-sand-2d.toml")  # the DEM instead (runs)
    r = ip.lab_record("lab/soils/karlsruhe-fine-sand/drained-triaxial/TMD11.dat")   # dict: φ_peak, ψ_max, …

The rest is here too (interphase.api.NAME): surfaces (`theta_a`, `make_profile`, `plot_profile`),
one case (`render`, `run_case`), campaigns (`stop`, `crosscheck`, `compare`, `pack`, `report`,
`animations`), soils (`element`, `cell`, `records`, `density`, `calibrate`, `validate`).

Arguments are SI (m, Pa, m/s; friction as a coefficient; angles in degrees only where the name says
`_deg`), whatever unit the command's option takes. One kind of result, one type: a table is a
DataFrame; one result per stress, record or table written is a list of dicts; one result is a dict
(numbers, strings and paths: what the command's --json prints, plus the few keys only its text
reads, each named in the function's docstring) or, where it has behaviour of its own, its object
(`Campaign`, `PlannedCase`, `RunReport`, `CrosscheckReport`, `Answer`). Angles in
tables are in degrees as the column names say (`*_deg`; ψ from vertical, docs/methods.md). Bad input
raises `interphase.errors.InputError` naming the option as the command spells it, and the fix.
A campaign function takes a campaign file's path or a loaded `Campaign`, and `runs=` where the runs
folder is not the one the file names (`--runs` of the command). Nothing heavy is imported until a
function is called; the checks every function makes first are interphase.api.checks.
"""

from interphase.api.answers import predict, predict_dem
from interphase.api.campaigns import (animations, compare, crosscheck, ensembles, load_campaign, pack, plan, report,
                                      run, runs_folder, status, stop, summaries)
from interphase.api.cases import render, run_case
from interphase.api.soils import calibrate, cell, density, element, lab_record, records, records_markdown
from interphase.api.surfaces import PROFILE_KINDS, make_profile, plot_profile, theta_a
from interphase.api.validation import validate

__all__ = ["load_campaign", "plan", "run", "stop", "status", "summaries", "ensembles", "runs_folder", "crosscheck",
           "compare", "pack", "report", "animations", "render", "run_case", "theta_a", "make_profile",
           "plot_profile", "PROFILE_KINDS", "predict", "predict_dem", "element", "cell", "records", "records_markdown", "density",
           "calibrate", "validate", "lab_record"]
