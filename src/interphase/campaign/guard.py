"""Nothing finished is ever overwritten: the checks `campaign render` and `campaign run-case` make on
the folder they were given before they write a single file.

A case folder is one that holds case.json (every folder the runner ever started) or DONE. The rule:

- `render` (rendered inputs only) refuses every case folder, finished or not, a campaign's
  runs folder (index.sqlite) and any other folder that is not empty: rendering would replace the
  deck, recipe.json, grains and STL files a run was made from, or whatever else is there.
- `run-case` refuses a case folder of another case (other inputs, another engine or another
  recipe): the runner clears an unfinished folder before it starts, so that case's files would
  be lost, and a finished one would be reported as this case's result. A folder of the same case
  is the runner's own: finished, its result is read back (nothing is rerun); unfinished, it is
  run again (as `campaign run` does).
Each refusal is one InputError naming the folder, what it holds, and the way out.
"""

from __future__ import annotations

from pathlib import Path

from interphase.campaign import store as st
from interphase.case import Case, canonical_json
from interphase.errors import InputError


def _holds(folder: Path) -> dict | None:
    """What the case folder `folder` holds: {status, label, engine, inputs, recipe_id}, or None
    when it is no case folder."""
    if not ((folder / st.CASE_JSON).exists() or (folder / st.DONE).exists()):
        return None
    meta = st.read_json(folder / st.CASE_JSON) or {}
    rid, _ = st.run_identity(meta)
    return {"status": st.folder_status(folder), "label": meta.get("label") or meta.get("name") or "?",
            "engine": meta.get("engine"), "inputs": meta.get("inputs"), "recipe_id": rid}


def _describe(folder: Path, held: dict) -> str:
    return f"{str(folder)!r} holds a {held['status']} case ({held['engine'] or '?'} {held['label']})"


def check_render_folder(folder) -> None:
    """Refuse to render into a case folder or a campaign's runs folder (see the module docstring)."""
    folder = Path(folder)
    held = _holds(folder)
    if held is not None:
        raise InputError(f"{_describe(folder, held)}; rendering would overwrite the inputs it ran from",
                         where=f"--output {folder}", fix="render into a new folder, e.g. "
                         f"--output {folder.name}-render (a case's own inputs are in its folder already)")
    if (folder / st.INDEX).exists():
        raise InputError(f"{str(folder)!r} is a campaign's runs folder", where=f"--output {folder}",
                         fix="render into a new folder of its own")
    if folder.is_dir() and any(folder.iterdir()):
        from interphase.campaign.folders import next_free

        raise InputError(f"{str(folder)!r} is not empty: rendering would overwrite what is there",
                         where=f"--output {folder}", fix=f"render into a new or empty folder, e.g. --output "
                         f"{next_free(folder)}")


def check_run_folder(folder, case: Case, engine: str, recipe_id: str) -> str | None:
    """Refuse a folder of another case; return the status of this same case's folder (None: no
    case folder), so that the caller can say that a finished one is read back, not rerun."""
    folder = Path(folder)
    held = _holds(folder)
    if held is None:
        if folder.is_dir() and any(folder.iterdir()):
            raise InputError(f"{str(folder)!r} is not empty and is not a case folder", where=f"--output {folder}",
                             fix="give a new or empty folder (an unfinished case folder is cleared before the run)")
        return None
    same_inputs = held["inputs"] is not None and \
        canonical_json(held["inputs"]) == canonical_json(case.canonical())
    why = None
    if not same_inputs:
        why = "other inputs"
    elif held["engine"] != engine:
        why = f"engine {held['engine']}, not {engine}"
    elif held["status"] == "done" and held["recipe_id"] not in (None, recipe_id):
        why = f"recipe {held['recipe_id']}, not this version's {recipe_id}"
    if why:
        what = "its results would be reported as this case's" if held["status"] == "done" else \
            "its files would be cleared before the run"
        raise InputError(f"{_describe(folder, held)} of {why}: {what}", where=f"--output {folder}",
                         fix="give a new or empty folder for this case")
    return held["status"]
