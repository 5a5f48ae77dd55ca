"""The criterion (and the DEM on a soil card) against laboratory interface tests: `campaign validate`.
A lab file is lab/README.md's CSV, one row per published test with its source; δ in degrees,
stresses in Pa (the tables' kPa columns say so)."""

from __future__ import annotations

import os
from pathlib import Path

from interphase.api import checks
from interphase.errors import InputError

PathLike = str | os.PathLike


#: shipped soil cards by a pattern of a laboratory soil's name (soils/ beside the lab file's folder, or
#: of the source tree): the 3D card of a sand that has two; only the sand the card was calibrated on
#: (Ottawa 20/30, the study's, is not Ottawa F-65)
SHIPPED_CARDS = ((r"ottawa\s*f-?65", "ottawa-f65.toml"), (r"karlsruhe", "karlsruhe-fine-sand.toml"))


def _shipped_card(soils, lab_path: Path):
    """The one shipped card whose name matches every soil of a lab file, or None."""
    import re

    found = set()
    roots = (lab_path.resolve().parent / "soils", lab_path.resolve().parent.parent / "soils",
             Path(__file__).resolve().parents[3] / "soils")
    for soil in soils:
        name = next((card for key, card in SHIPPED_CARDS if re.search(key, str(soil).lower())), None)
        found.add(next((r / name for r in roots if name and (r / name).is_file()), None))
    return found.pop() if len(found) == 1 else None


def _validation_card(table, soil, simulate: bool, notes: list):
    from interphase.soil import load_card

    card = load_card(soil) if soil else None
    if card is None:
        shipped = _shipped_card(sorted(set(table.rows["soil"])), table.path)
        card = load_card(shipped) if shipped else None
        if card is not None:
            notes.append(f"soil card: {card.path} (shipped, chosen by the soil's name; soil= to choose)")
        elif simulate or table.rows["soil_phi_peak"].isna().any():
            raise InputError(f"no single shipped card for the soils {', '.join(sorted(set(table.rows['soil'])))}",
                             where="--soil", fix="give --soil soils/NAME.toml")
    if card is not None and card.quick:
        notes.append(f"soil card {card.path} is a --quick calibration: a first look, not a calibrated soil")
    return card


def validate(lab: PathLike, *, soil: PathLike | None = None, fit: str | None = None, simulate: bool = False,
             seeds: int = 3, output: PathLike | None = None, runs: PathLike | None = None,
             executor: str | None = None, jobs: int | None = None, rerun_failed: bool = False,
             stream=None) -> dict:
    """The criterion (and with `simulate`, the DEM on the soil card) against a laboratory file
    (lab/README.md; docs/validation.md), as `campaign validate`. Returns a dict: table (DataFrame, one
    row per test: δ measured, predicted with its interval, both baselines, errors [°]), skill
    (DataFrame), largest_miss, notes, folder and files written (validation.csv, skill.csv,
    validation.md, validation.png/.pdf under `output`, default runs/validate/<file name> beside the
    lab file; --simulate's runs in `runs`, default runs/validate/<file name>/runs beside it). A
    folder holding another validation is refused (InputError), one holding this same one is kept."""
    from interphase.analysis.validation import largest_miss, predict_rows, skill
    from interphase.campaign.folders import validate_folders
    from interphase.lab import read_lab
    from interphase.criterion_fits import criterion_model

    checks.seeds(seeds)
    table = read_lab(lab)
    (out, out_from), (runs_at, runs_from) = validate_folders(table.path, output, runs)
    _check_validation_folder(out)
    notes: list[str] = [f"folder {out} ({out_from})"]
    card = _validation_card(table, soil, simulate, notes)
    models: dict = {}
    model_for = lambda mu: models[mu] if mu in models else models.setdefault(mu, criterion_model(mu, fit))
    df = predict_rows(table, model_for, card)
    notes += sorted({f"criterion: {m.source}" for m in models.values()})
    if simulate:
        from interphase.campaign.validate import simulate as _simulate, with_dem

        notes.append(f"DEM runs in {runs_at} ({runs_from})")
        df = with_dem(df, _simulate(table, card, range(1, seeds + 1), output=runs_at, executor=executor,
                                    jobs=jobs, stream=stream, rerun_failed=rerun_failed))
    sk = skill(df)
    files, kept = _write_validation(out, df, sk)
    return {"lab": str(table.path), "rows": len(df), "folder": out, "folder_from": out_from, "notes": notes,
            "table": df, "skill": sk, "largest_miss": largest_miss(df), "files": files, "kept": kept}


VALIDATION_FILES = ("validation.csv", "skill.csv", "validation.md")


def _check_validation_folder(out: Path) -> None:
    """Refuse a folder that holds anything but a validation (and its runs/): nothing finished is replaced."""
    from interphase.campaign.folders import next_free

    if not out.is_dir():
        return
    other = [p.name for p in out.iterdir() if p.name != "runs" and p.name not in VALIDATION_FILES
             and not p.name.startswith("validation.")]
    if other:
        raise InputError(f"{out} is not empty and holds no validation ({', '.join(sorted(other)[:3])} …)",
                         where=f"-o {out}", fix=f"give a new or empty folder, e.g. -o {next_free(out)}")


def _write_validation(out: Path, df, sk) -> tuple[list, bool]:
    """Write the tables and the figure into `out`; ([files], kept). A finished validation there is
    kept when it is this one (the same tables), else refused: it is never replaced."""
    from interphase.campaign.folders import next_free
    from interphase.report.validation import markdown, validation_figure

    cols = {"row": "line", "soil": "soil", "surface": "surface", "normal_stress_kpa": "σn [kPa]", "theta_a_deg": "θa [°]",
            "delta_measured_deg": "δ lab [°]", "delta_predicted_deg": "δ criterion [°]", "delta_lo_deg": "lo",
            "delta_hi_deg": "hi", "error_predicted_deg": "error [°]", "delta_rule_deg": "δ rule [°]",
            "delta_soil_deg": "δ = φ [°]", "delta_fitted_rule_deg": "δ fitted rule [°]"}
    if "delta_dem_deg" in df:
        cols |= {"delta_dem_deg": "δ DEM [°]", "error_dem_deg": "DEM error [°]"}
    texts = {"validation.csv": df.to_csv(index=False), "skill.csv": sk.to_csv(index=False),
             "validation.md": markdown(df, cols) + "\n" + markdown(sk, {
                 "subset": "rows", "prediction": "prediction", "n": "n", "rms_deg": "rms [°]",
                 "max_abs_deg": "max [°]", "within_4": "share within 4°"})}
    held = {name: (out / name).read_text() for name in VALIDATION_FILES if (out / name).is_file()}
    if held:
        if held == texts:
            return [out / name for name in VALIDATION_FILES] + sorted(out.glob("validation.p*")), True
        raise InputError(f"{out} holds another validation (its tables differ from this one's); it is kept",
                         where=f"-o {out}", fix=f"write this one to a new folder, e.g. -o {next_free(out)} "
                         "(--simulate's runs are reused: they live in --runs)")
    out.mkdir(parents=True, exist_ok=True)
    for name, text in texts.items():
        (out / name).write_text(text)
    return [out / name for name in VALIDATION_FILES] + list(validation_figure(df, out)), False
