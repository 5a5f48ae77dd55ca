"""The cross-check's power on the standard set's cell: each deliberate YADE mis-mapping against the
true mapping, on the same LIGGGHTS runs (docs/crosscheck.md, "Power").

    python studies/crosscheck_power/crosscheck_power.py campaigns/crosscheck.toml --output runs/xc-platen [--seeds 3]

For each alteration (friction × 1.3 on the sliding flat, rolling resistance off on the rolling-held
flat at μs 0.5, stiffness × 4 on the sliding flat) a campaign of that one group on seeds 1…N is
written beside the output, the finished LIGGGHTS folders of the standard set's output are copied into
an output of its own (`<output>-power-<name>`), and `crosscheck()` runs YADE there with the test-only
mis-mapped engine (campaign.mismapped: no production flag), passed as an engine value. The campaign's
`specimen_from` holds: YADE shears LIGGGHTS' specimens. Prints, per alteration, the judged rows.
"""

from __future__ import annotations

import argparse
import re
from pathlib import Path

from interphase.campaign.crosscheck import crosscheck
from interphase.campaign.mismapped import copy_done, mismapped_yade

#: name → (group of the standard set, alteration, the metric it should move)
ALTERATIONS = {
    "friction": ("sliding", {"friction": 1.3}, "residual_stress_ratio"),
    "rolling": ("rolling-geometry", {"rolling": False}, "theta_r_surface_mean_deg"),
    "stiffness": ("sliding", {"stiffness": 4.0}, "overlap_mean_d50"),
}


def one_group(text: str, group: str, seeds: int) -> str:
    """The campaign text with only `group` on seeds 1…seeds (the rolling group: its flat only), no
    soil tests, and every tolerance judging everywhere (no judged_in)."""
    body, tolerances = text.split("# Tolerances of the verdict")
    head, *groups = re.split(r"(?m)^(?=\[\[group\]\])", body)
    (g,) = [g for g in groups if re.search(rf'(?m)^name = "{re.escape(group)}"', g)]
    g = re.sub(r"seed = \[[^\]]*\]", f"seed = {list(range(1, seeds + 1))}", g)
    g = g.replace('profile = [{kind = "flat"}, {kind = "sawtooth", rt = 1, sw = 2, sr = 0}]', 'profile = [{kind = "flat"}]')
    tolerances = re.sub(r"(?m)^judged_in = .*$", "", tolerances)
    return head + g + "\n[pairs]\nbox = false\n\n# Tolerances of the verdict" + tolerances


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("campaign")
    ap.add_argument("--output", required=True, help="the standard set's output (its LIGGGHTS runs are reused)")
    ap.add_argument("--seeds", type=int, default=3)
    ap.add_argument("--only", nargs="*", default=list(ALTERATIONS))
    a = ap.parse_args()
    text = Path(a.campaign).read_text()
    out_root = Path(a.output)
    for name in a.only:
        group, alteration, metric = ALTERATIONS[name]
        path = out_root.parent / f"{out_root.name}-power-{name}.toml"
        path.write_text(one_group(text, group, a.seeds))
        out = out_root.parent / f"{out_root.name}-power-{name}"
        copy_done(out_root, out)
        report = crosscheck(path, output=out, engines=("liggghts", mismapped_yade(**alteration)))
        j = report.ensembles[report.ensembles["verdict"].notna()]
        print(f"\n## {name} × {alteration} on {group} (seeds 1–{a.seeds}); should move {metric}")
        for r in j.itertuples():
            print(f"| {r.physical} | {r.metric} | {r.seeds} | {r.liggghts:.4g} | {r.yade:.4g} | {r.diff:+.3g} "
                  f"[{r.diff_lo:+.3g}, {r.diff_hi:+.3g}] | {r.pair_r:+.2f} | ±{r.tolerance:.3g} | {r.verdict} |", flush=True)


if __name__ == "__main__":
    main()
