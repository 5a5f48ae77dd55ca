"""Errors shared by every layer.

`InputError` is bad input from a user (a file, a field, an option): the CLI prints its message
alone and exits with code 2, never a traceback. Messages name where (file, line, field or option)
and say how to fix it.
"""

from __future__ import annotations


class InputError(ValueError):
    """Bad user input. `where` is the file/option/field, `fix` says what to do about it."""

    def __init__(self, message: str, *, where: str | None = None, fix: str | None = None):
        self.where = where
        self.message = message
        self.fix = fix
        text = f"{where}: {message}" if where else message
        if fix:
            text = f"{text} — {fix}"
        super().__init__(text)
