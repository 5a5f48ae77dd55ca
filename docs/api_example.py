"""The Python API end to end on a tiny campaign (a few seconds of LIGGGHTS per run): load, plan,
run, read summaries and seed ensembles as DataFrames, predict. tests/test_api.py runs it.

The `if __name__ == "__main__"` guard is needed in a script (not in a notebook): the local pool starts
its workers by spawning Python, which imports the script again.

    python docs/api_example.py [FOLDER]      # FOLDER: where the campaign file and its runs go
                                             # (default: a new temporary folder)
"""

import sys
import tempfile
from pathlib import Path

import numpy as np

import interphase as ip


def main() -> None:
    folder = Path(sys.argv[1] if len(sys.argv) > 1 else tempfile.mkdtemp(prefix="interphase-api-"))
    folder.mkdir(parents=True, exist_ok=True)

    # a toy campaign: one saw-tooth at two packing seeds, with the paired box tests (E = tan δ / tan φ);
    # ~80 grains at a softened stiffness: a smoke test of the machinery, not a result (README)
    toml = folder / "tiny.toml"
    toml.write_text("""
    [campaign]
    name = "tiny"
    [case]
    test = "interface"
    device = "periodic"
    profile = {kind = "sawtooth", rt = 1, sw = 2, sr = 0}
    shear_modulus = 50e6
    shear_velocity = 0.01
    shear_distance = 0.0006
    snapshot_every = 0.0002
    box_length_d50 = 12
    box_height_d50 = 6
    [sweep]
    seed = [1, 2]
    """)

    campaign = ip.load_campaign(toml)                 # checked at load; nothing runs
    print(f"{campaign.name}: {campaign.size} interface cases; runs folder {campaign.output}")
    for w in campaign.warnings():                     # implausible values, unstated converged settings
        print("warning:", w)

    for p in ip.plan(campaign):                       # box tests first; ids are hashes of the inputs
        print(p.case_id, p.role, p.label)

    report = ip.run(campaign, jobs=2, quiet=True)     # resumable: a second call runs nothing
    assert report.exit_code == 0, report.statuses

    print(ip.status(campaign)[["case_id", "label", "status"]].to_string(index=False))

    runs = ip.summaries(campaign)                     # one row per finished run (SI units, *_deg angles)
    print(runs[["label", "peak_stress_ratio", "theta_r_surface_mean_deg"]].to_string(index=False))

    ens = ip.ensembles(campaign)                      # one row per physical case: its seeds pooled
    print(ens.T.to_string())

    # predict: the criterion chain for a profile file (two columns x z, mm), on the study's simulated discs
    profile = folder / "sawtooth.txt"
    x = np.linspace(0.0, 14.0, 57)                    # 45° teeth, Rt = 0.7 mm (1 D50), Sw = 1.4 mm
    z = 0.7 * np.abs(((x / 1.4) % 1.0) - 0.5) * 2.0
    np.savetxt(profile, np.column_stack([x, z]), header="x_mm z_mm")
    pred = ip.predict(profile, fit="study", d50=0.7e-3, friction=0.2)      # an Answer (interphase.answer)
    print(f"θa {pred.theta_a_deg:.1f}°, θr {pred.theta_r_deg:.1f}°, E {pred.efficiency:.2f}, "
          f"tan δ {pred.tan_delta:.3f}, δ {pred.delta_deg:.1f}° ({pred.model_delta_deg_lo:.1f}–{pred.model_delta_deg_hi:.1f}°)")


if __name__ == "__main__":
    main()
