"""The criterion a prediction runs on, as data: criterion.json files (what `campaign report` writes,
and the reproduction's shipped with the package), the names `--fit` takes, and a campaign's fit on
demand. Apart from report/ so that an answer does not import the figures."""

from __future__ import annotations

import json
import math
from pathlib import Path

from interphase.analysis.criterion import CriterionModel
from interphase.errors import InputError

#: the criterion fitted on the reproduction (studies/reproduction/study_sequential.toml, the study's
#: cases to E ± 0.1; docs/reproduction.md): `studies/reproduction/refit_reproduction.py --precision --commit` writes
#: it here from the committed summaries and curves
REPRODUCTION = Path(__file__).resolve().parent / "data" / "criterion_reproduction.json"


def load_criterion(path: str | Path) -> CriterionModel:
    """A criterion.json written by `campaign report`; its source says what it was fitted on."""
    path = Path(path)
    try:
        data = json.loads(path.read_text())
    except (OSError, ValueError) as exc:
        raise InputError(f"cannot read the criterion file: {exc}", where=str(path),
                         fix="give a criterion.json written by `campaign report`, or a campaign file") from None
    model = CriterionModel.from_dict(data, where=str(path))
    about = data.get("about") or {}
    if about:
        model.source = (f"{model.source} ({about.get('physical_cases', '?')} physical cases, groups "
                        f"{', '.join(about.get('groups', [])) or '?'}; {path.name})")
    return model


def criterion_model(friction: float, fit: str | Path | None = None, tan_phi: float | None = None) -> CriterionModel:
    """The model `campaign predict` runs. `fit`: None → the reproduction's fits (REPRODUCTION);
    'study' the same, named for what it is (the study's simulated discs); 'study-figures' → the study
    defaults for `friction` (readings of its figures); a criterion.json; a campaign file (fitted on
    its finished cases). `tan_phi` (> 0) replaces the model's tan φ."""
    if fit == "study-figures":
        return CriterionModel.study_defaults(friction, tan_phi)
    if fit in (None, "study") or str(fit).endswith(".json"):
        path = REPRODUCTION if fit in (None, "study") else Path(fit)
        if fit in (None, "study") and not path.exists():
            raise InputError(f"this installation has no reproduction fits ({path} is missing)", where="--fit",
                             fix="give a campaign file or a criterion.json, or `--fit study-figures` for the study's readings")
        model = load_criterion(path)
    else:
        from interphase.report.build import fitted_model

        model = fitted_model(fit)
    if tan_phi is not None:
        model.tan_phi = tan_phi
    if not math.isfinite(model.tan_phi):
        raise InputError(f"{model.source} has no finished box test, so no tan φ", where="--fit", fix="give --tan-phi")
    return model
