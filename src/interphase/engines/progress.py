"""How far a running LIGGGHTS case has got, read from its own files while it runs.

Every deck (templates/liggghts) runs in stages: a first `run` (settle or consolidate), a consolidation
loop of `run` chunks until the platen holds its stress (`label consolidate` … `label consolidated`),
then the main stage, the last `run` before `label finish`: the shear of a box or interface case, the
axial compression of a cell test. The main stage prints its first step to shear_start.txt, and its
rows go to history.txt with the step first; before it, the thermo lines of log.liggghts carry the step.
So: (stage, share done) = ("prepare", step / first run) → ("consolidate", None) → (main, (step −
start) / main run). A YADE folder (params.json, no in.deck) has no reader here: None.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

_RUN = re.compile(r"^\s*run\s+(\d+)", re.M)
TAIL_BYTES = 4096          # a thermo or history line is < 200 bytes: the tail holds the last one


@dataclass(frozen=True)
class Stage:
    name: str                  # "prepare", "consolidate", "shear", "compression", "finishing"
    share: float | None        # of this stage done [0, 1]; None where its length is not known ahead

    def text(self) -> str:
        return self.name if self.share is None else f"{self.name} {100 * self.share:.0f} %"


@lru_cache(maxsize=256)
def _deck_plan(deck: Path, mtime_ns: int) -> tuple[int, int, str] | None:
    """(first run's steps, main stage's steps, main stage's name) of a rendered deck."""
    text = deck.read_text()
    runs = [int(n) for n in _RUN.findall(text.split("label finish")[0])]
    if len(runs) < 2:
        return None
    return runs[0], runs[-1], "compression" if "fix deform" in text else "shear"


def _last_step(path: Path, header: str | None = None) -> int | None:
    """The first integer of the last line of `path` that starts with one (thermo or history rows)."""
    try:
        with open(path, "rb") as fh:
            fh.seek(0, 2)
            size = fh.tell()
            fh.seek(max(0, size - TAIL_BYTES))
            tail = fh.read().decode(errors="replace").splitlines()
    except OSError:
        return None
    for line in reversed(tail[1:] if len(tail) > 1 else tail):
        head = line.split(maxsplit=1)
        if head and head[0].isdigit():
            return int(head[0])
    return None


def liggghts_stage(folder: Path) -> Stage | None:
    """The stage of the LIGGGHTS case running in `folder` and its share done; None before the
    engine has written anything, or for a folder without a deck."""
    folder = Path(folder)
    deck = folder / "in.deck"
    try:
        plan = _deck_plan(deck, deck.stat().st_mtime_ns)
    except OSError:
        return None
    if plan is None:
        return None
    first, main, name = plan
    start = _last_step(folder / "shear_start.txt")
    if start is not None:
        step = _last_step(folder / "history.txt")
        done = 0.0 if step is None else min(max((step - start) / main, 0.0), 1.0)
        return Stage(name, done) if done < 1.0 else Stage("finishing", None)
    step = _last_step(folder / "log.liggghts")
    if step is None:
        return Stage("prepare", 0.0)
    return Stage("prepare", min(step / first, 1.0)) if step < first else Stage("consolidate", None)
