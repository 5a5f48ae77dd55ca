"""The Jinja environment every engine template is rendered with.

StrictUndefined: a missing value is an error, never an empty string. Values enter a deck only
through three filters: `num` (a finite int/float, written with repr precision), `neg`
(its negative) and `name` (an
identifier matching ^[A-Za-z0-9_.-]+$). Anything else — a string carrying a newline and
`shell rm -rf /`, a NaN, a list — is refused at render time, so a string can never add a command.
"""

from __future__ import annotations

import functools
import math
import re
from pathlib import Path

import jinja2

from interphase.errors import InputError

_NAME = re.compile(r"^[A-Za-z0-9_.\-]+$")


def num(value) -> str:
    """A finite number as deck text (ints stay ints; floats round-trip via repr)."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise InputError(f"template value {value!r} is not a number", where="template",
                         fix="only finite numbers enter a deck through the `num` filter")
    if not math.isfinite(value):
        raise InputError(f"template value {value!r} is not finite", where="template")
    return str(value) if isinstance(value, int) else repr(float(value))


def neg(value) -> str:
    """−value as deck text, validated like `num` first (arithmetic in a template would run on an
    unvalidated value: `(-x)|num` fails with a TypeError, not a located InputError)."""
    num(value)
    return num(-value)


def name(value) -> str:
    """A validated identifier or file name (letters, digits, _ . -)."""
    if not isinstance(value, str) or not _NAME.match(value):
        raise InputError(f"template name {value!r} is not a plain identifier", where="template",
                         fix="names may hold only letters, digits, '_', '.', '-'")
    return value


@functools.lru_cache(maxsize=None)
def environment(folder: str | Path) -> jinja2.Environment:
    """One environment per template folder, kept: Jinja then compiles each template once per process
    (its loader still reloads a template whose file changed)."""
    env = jinja2.Environment(
        loader=jinja2.FileSystemLoader(str(folder)),
        undefined=jinja2.StrictUndefined,
        autoescape=False,
        keep_trailing_newline=True,
        trim_blocks=True,
        lstrip_blocks=True,
    )
    env.filters["num"] = num
    env.filters["name"] = name
    env.filters["neg"] = neg
    return env
