"""The `campaign` command: parses arguments and calls the library; no logic of its own.

Every user error (InputError) ends with one message on stderr and exit code 2, never a traceback.
Every command that prints numbers has --json.
"""

from __future__ import annotations

import argparse
import json
import sys

from interphase import __version__
from interphase.errors import InputError


def _print_json(obj) -> None:
    print(json.dumps(obj, indent=2, sort_keys=True, default=float))


# ---- surface toolkit: theta-a, profile ------------------------------------------------------
def _add_surface(sub) -> None:
    pass


# ---- single cases and engines: render, run-case ----------------------------------------------
def _add_engine(sub) -> None:
    pass


# ---- campaigns: run, status, crosscheck --------------------------------------------------------
def _add_campaign(sub) -> None:
    pass


# ---- engine cross-check: crosscheck -----------------------------------------------------------
def _add_crosscheck(sub) -> None:
    pass


# ---- results: report, predict ------------------------------------------------------------------
def _add_report(sub) -> None:
    pass


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="campaign",
        description="DEM interface-shear campaigns (LIGGGHTS, YADE) and the θa → θr → E criterion.",
    )
    parser.add_argument("--version", action="version", version=f"interphase-dem {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    _add_surface(sub)
    _add_engine(sub)
    _add_campaign(sub)
    _add_crosscheck(sub)
    _add_report(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.func(args) or 0)
    except InputError as exc:
        print(f"campaign {args.command}: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"campaign {args.command}: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
