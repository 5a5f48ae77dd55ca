"""Where the soil and prediction commands write: the campaigns' rule (campaign/schema.py), for
`element`, `calibrate` and `validate`.

- A folder or file given on the command line (`--runs`, `-o`) is used as given.
- Else it is resolved relative to the file the command reads — the soil card, the calibration
  target (its [target] `card` and `runs` keys, relative to the target file, else the defaults
  beside it), the laboratory file — never the current folder.
- Every path comes with where it came from, which the command prints beside it.
- `--runs` governs every run a command makes (the calibration's final element tests too).

A finished output is never replaced: `next_free` suggests the new name a refusal offers.
"""

from __future__ import annotations

import os
from pathlib import Path

Located = tuple[Path, str]


def _abs(path) -> Path:
    return Path(os.path.abspath(path))


def given(path, flag: str) -> Located:
    return _abs(path), f"given on the command line ({flag})"


def beside(file, rel: str, flag: str) -> Located:
    """`rel` in the folder of `file`, said as the default."""
    file = Path(file)
    return _abs(file.resolve().parent / rel), f"the default {rel} beside {file.name} ({flag} to change)"


def next_free(path) -> Path:
    """`path` itself if free, else the first of NAME-2.EXT, NAME-3.EXT, … that does not exist."""
    path = Path(path)
    if not path.exists():
        return path
    n = 2
    while (path.with_name(f"{path.stem}-{n}{path.suffix}")).exists():
        n += 1
    return path.with_name(f"{path.stem}-{n}{path.suffix}")


def element_runs(card_path, name: str, runs=None) -> Located:
    """The element test's runs folder: --runs, else runs/element/NAME beside the soil card."""
    return given(runs, "--runs") if runs is not None else beside(card_path, f"runs/element/{name}", "--runs")


def _stated(target, key: str) -> Located | None:
    """[target] KEY of a calibration target: a path relative to the target file, with its line."""
    from interphase.soil import _line_of

    value = target.raw.get("target", {}).get(key)
    if value is None:
        return None
    line = _line_of(target.path.read_text(), "target", key)
    p = Path(value)
    return _abs(p if p.is_absolute() else target.path.resolve().parent / p), \
        f"[target] {key} of {target.path}" + (f":{line}" if line else "")


def quick_name(path: Path) -> Path:
    return path.with_name(f"{path.stem}-quick{path.suffix}")


def calibrate_folders(target, quick: bool, card=None, runs=None) -> tuple[Located, Located]:
    """((card path, from), (runs folder, from)) of a calibration. Defaults: [target] card and runs,
    else soils/NAME.toml and runs/calibrate/NAME beside the target file; `--quick` inserts
    "-quick" in both (NAME-quick.toml): a quick card never takes a full card's name."""
    name = target.name + ("-quick" if quick else "")
    if card is not None:
        card_at = given(card, "-o")
    else:
        stated = _stated(target, "card")
        card_at = (quick_name(stated[0]) if quick else stated[0], stated[1] + (", with -quick" if quick else "")) \
            if stated else beside(target.path, f"soils/{name}.toml", "[target] card or -o")
    if runs is not None:
        runs_at = given(runs, "--runs")
    else:
        stated = _stated(target, "runs")
        runs_at = (_abs(str(stated[0]) + "-quick") if quick else stated[0], stated[1] + (", with -quick" if quick
                                                                                       else "")) \
            if stated else beside(target.path, f"runs/calibrate/{name}", "[target] runs or --runs")
    return card_at, runs_at


def validate_folders(lab_path, output=None, runs=None) -> tuple[Located, Located]:
    """((validation folder, from), (--simulate's runs folder, from)). Defaults beside the lab file:
    runs/validate/STEM and runs/validate/STEM/runs; the runs folder does not follow -o, so that a
    validation written to a new folder reuses the DEM runs it already has."""
    stem = Path(lab_path).stem
    out = given(output, "-o") if output is not None else beside(lab_path, f"runs/validate/{stem}", "-o")
    runs_at = given(runs, "--runs") if runs is not None else beside(lab_path, f"runs/validate/{stem}/runs", "--runs")
    return out, runs_at
