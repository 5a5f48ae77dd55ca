"""One case outside a campaign: its engine input files (`campaign render`) and one run of it
(`campaign run-case`). A case file is TOML with a [case] table (Case fields, SI units); it is checked
as `campaign run` checks a campaign's cases, and its warnings (implausible values, unstated
settings) are written to `stream` (default stderr) before anything is written or run."""

from __future__ import annotations

import os
import sys
from pathlib import Path

PathLike = str | os.PathLike

#: the tables a finished case folder holds (Parquet)
CASE_TABLES = ("contacts", "history", "particles", "series")
#: the summary values run-case returns
RUN_CASE_VALUES = ("peak_stress_ratio", "shear_disp_at_peak", "peak_at_end", "peak_snapshot", "theta_r_surface_deg",
                   "theta_r_surface_mean_deg", "surface_force_angle_deg")


def _case_file(path: PathLike) -> tuple:
    """(Case, warnings) of a case file: the checks `campaign run` makes on a campaign's cases."""
    from interphase.campaign.checks import case_file_warnings, load_case_file

    case = load_case_file(path)
    return case, case_file_warnings(path, case)


def _warn(warnings: list[str], stream) -> None:
    for w in warnings:
        print(f"warning: {w}", file=stream or sys.stderr)


def render(case: PathLike, output: PathLike, *, engine: str = "liggghts", stream=None) -> dict:
    """Write a case's engine input files into `output` (new or empty; never a case folder: nothing
    finished is overwritten) without running it: {folder, files (sorted names), warnings}."""
    from interphase.campaign.guard import check_render_folder
    from interphase.engines.base import get_engine

    eng = get_engine(engine)
    loaded, warnings = _case_file(case)
    check_render_folder(output)
    _warn(warnings, stream)
    files = eng.write_input(loaded, output)
    return {"folder": os.fspath(output), "files": sorted(files), "warnings": warnings}


def run_case(case: PathLike, output: PathLike, *, engine: str = "liggghts", stream=None) -> dict:
    """Render, run and read one case in `output` (new or empty, or this same case's folder: finished,
    it is read back, not rerun). Returns {status (done, failed, …), folder, warnings} and, when
    failed, cause and message; when done, skipped (read back), the summary.json and every table's
    path, and the summary's peak values (stress ratio [-], shear displacement at the peak [m], θr
    [°])."""
    from interphase.campaign.runner import run_single

    folder = Path(output)
    loaded, warnings = _case_file(case)
    _warn(warnings, stream)
    res = run_single(loaded, engine, folder)
    if res["status"] != "done":
        return {"status": res["status"], "cause": res["cause"], "message": res["message"], "folder": str(folder),
                "warnings": warnings}
    row = res["summary"]
    return {"status": "done", "folder": str(folder), "skipped": res["skipped"], "summary": str(folder / "summary.json"),
            **{name: str(folder / f"{name}.parquet") for name in CASE_TABLES},
            **{k: row.get(k) for k in RUN_CASE_VALUES}, "warnings": warnings}
