"""Entry point of the ``shrm`` command.

Each verb lives in a module ``cli/cmd_<verb>.py`` that defines ``HELP`` (one line),
``add_arguments(parser)`` and ``run(args) -> int``; they are discovered here, so adding a
verb touches no other file. A :class:`~shrmkit.brdf_io.errors.BadInputError` (or an
``OSError`` from the file system) becomes one line on stderr and exit code 2.

Reference: R. Ramamoorthi, P. Hanrahan, "Frequency Space Environment Map Rendering",
SIGGRAPH 2002 (RH02), doi:10.1145/566654.566611.
"""

from __future__ import annotations

import argparse
import importlib
import pkgutil
import sys
from pathlib import Path

from .._version import __version__
from ..brdf_io.errors import ShrmError


def _verbs() -> list[str]:
    """The verbs: one ``cmd_<verb>.py`` module each, beside this file."""
    return sorted(
        name[len("cmd_"):]
        for _, name, _ in pkgutil.iter_modules([str(Path(__file__).parent)])
        if name.startswith("cmd_")
    )


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="shrm",
        description="Measured-BRDF toolkit: frequency-space orders (RH02), fits, SHRM rendering.",
    )
    parser.add_argument("--version", action="version", version=f"shrm {__version__}")
    sub = parser.add_subparsers(dest="verb", metavar="VERB")
    for verb in _verbs():
        module = importlib.import_module(f"shrmkit.cli.cmd_{verb}")
        p = sub.add_parser(verb, help=module.HELP, description=module.HELP)
        module.add_arguments(p)
        p.set_defaults(_run=module.run)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    if not getattr(args, "_run", None):
        parser.print_help()
        return 0
    try:
        return int(args._run(args) or 0)
    except ShrmError as err:
        print(f"shrm {args.verb}: error: {err}", file=sys.stderr)
        return 2
    except OSError as err:  # a file system refusal the verb did not turn into a BadInputError
        where = f"{err.filename}: " if err.filename else ""
        print(f"shrm {args.verb}: error: {where}{err.strerror or err}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"shrm {args.verb}: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
