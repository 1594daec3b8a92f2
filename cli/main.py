"""Entry point of the ``shrm`` command.

Each verb is two modules beside this file: ``options_<verb>.py`` defines ``HELP`` (one line)
and ``add_arguments(parser)``, built from numpy-free modules (:mod:`~shrmkit.cli.options`,
``brdf_io.names``, ``analysis.defaults``, ``render.defaults``); ``cmd_<verb>.py`` defines
``run(args) -> int``, the verb's work. They are discovered here, so adding a verb touches no
other file. A :class:`~shrmkit.brdf_io.errors.BadInputError` (or an ``OSError`` from the file
system) becomes one line on stderr and exit code 2. The console script is :func:`console_main`:
:func:`main`, then an exit without the interpreter's teardown where nothing is left to tear down
(:func:`fast_exit`).

The command line is lazy: a verb's parser module is imported only when that verb is parsed,
and its ``cmd_`` module (and with it the analysis and render stack, VTK, matplotlib...) only
when the arguments parsed and the verb runs. ``shrm --help`` lists every verb with its ``HELP``
line read from the parser module's source, ``shrm --version`` imports no verb at all;
``shrm VERB --help`` and a verb's usage errors import no numpy (issue 26, benchmarks/startup.py).

Reference: [RH02] (``data_specs/bibliography.md``).
"""

from __future__ import annotations

import argparse
import ast
import atexit
import contextlib
import difflib
import functools
import importlib
import os
import pkgutil
import re
import sys
import threading
import warnings
from pathlib import Path

from .._version import __version__
from ..brdf_io.errors import ShrmError
from . import console_state
from .terms import in_cli_terms

HERE = Path(__file__).parent


def _verbs() -> list[str]:
    """The verbs: one ``cmd_<verb>.py`` module each (and its ``options_<verb>.py``), beside this file."""
    return sorted(
        name[len("cmd_"):]
        for _, name, _ in pkgutil.iter_modules([str(HERE)])
        if name.startswith("cmd_")
    )


def _module(verb: str):
    """The verb's work, ``cmd_<verb>.py`` (imported when it runs)."""
    return importlib.import_module(f"shrmkit.cli.cmd_{verb}")


def _options(verb: str):
    """The verb's parser, ``options_<verb>.py`` (numpy-free)."""
    return importlib.import_module(f"shrmkit.cli.options_{verb}")


def _run(verb: str, args: argparse.Namespace) -> int:
    """Run ``verb`` on its parsed ``args``: its ``cmd_`` module is imported now, not at parsing."""
    return _module(verb).run(args)


def _help(verb: str) -> str:
    """The verb's ``HELP`` line, read from its parser module's source without importing it
    (imported only where the source is not at hand or ``HELP`` is not a plain string literal)."""
    try:
        tree = ast.parse((HERE / f"options_{verb}.py").read_text(encoding="utf-8"))
    except (OSError, SyntaxError, ValueError):
        return _options(verb).HELP
    for node in tree.body:
        if isinstance(node, ast.Assign):
            targets, value = node.targets, node.value
        elif isinstance(node, ast.AnnAssign) and node.value is not None:
            targets, value = [node.target], node.value
        else:
            continue
        if any(isinstance(t, ast.Name) and t.id == "HELP" for t in targets):
            if isinstance(value, ast.Constant) and isinstance(value.value, str):
                return value.value
            break
    return _options(verb).HELP


class _Parser(argparse.ArgumentParser):
    """argparse with "did you mean" for a misspelt verb or option (Python 3.14's
    ``suggest_on_error``, for the Pythons we support)."""

    def error(self, message: str) -> None:  # type: ignore[override]
        choice = re.search(r"invalid choice: '([^']*)' \(choose from (.*)\)", message)
        if choice:
            close = difflib.get_close_matches(choice.group(1), re.findall(r"'([^']*)'", choice.group(2)), n=1)
            if close:
                message += f"; did you mean '{close[0]}'?"
        unknown = re.search(r"unrecognized arguments: (.*)", message)
        if unknown:
            options = [o for action in self._actions for o in action.option_strings]
            hints = [f"'{word}' → '{close[0]}'" for word in unknown.group(1).split() if word.startswith("--")
                     for close in [difflib.get_close_matches(word.split("=")[0], options, n=1)] if close]
            if hints:
                message += f" (did you mean {', '.join(hints)}?)"
        greedy = self._greedy_options_given(message)
        if greedy:
            verb = "takes every value after it" if len(greedy) == 1 else "take every value after them"
            message += f" ({'/'.join(greedy)} {verb}: give the positional arguments first, or end the list with --)"
        super().error(message)

    def _greedy_options_given(self, message: str) -> list[str]:
        """The list-taking options (``--env A B …``) given on this command line, when ``message``
        says a positional argument is missing: one of them may have swallowed it. Empty otherwise
        (a missing ``-o/--output`` is not their doing, nor anything when none was given, when given
        as ``--env=A`` (one value), or when ``--`` ended the list)."""
        missing = re.search(r"arguments are required: (.*)", message)
        argv = list(getattr(self, "argv", []))
        if not missing or "--" in argv or all(name.startswith("-") for name in missing.group(1).split(", ")):
            return []
        given = []
        for action in self._actions:
            if action.nargs not in ("+", "*") or not action.option_strings:
                continue
            longs = [o for o in action.option_strings if o.startswith("--")]
            if any(word in action.option_strings
                   or (word.startswith("--") and len(word) > 2 and any(o.startswith(word) for o in longs))
                   for word in argv):
                given.append((longs or action.option_strings)[0])
        return sorted(given)


class _VerbParser(_Parser):
    """The parser of one verb: its parser module is imported and its arguments added on first
    use (when the verb is parsed, or by :meth:`load`); the verb's ``cmd_`` module is imported
    only when it runs (``args._run``)."""

    verb: str | None = None

    def load(self) -> _VerbParser:
        if self.verb is not None:
            verb, self.verb = self.verb, None
            _options(verb).add_arguments(self)
            self.add_argument("-q", "--quiet", action="store_true",
                              help="print nothing on stdout but what --json asks for (errors and warnings still "
                              "go to stderr; the exit status says how it went)")
            self.set_defaults(_run=functools.partial(_run, verb))
        return self

    def parse_known_args(self, args=None, namespace=None):
        self.load()
        self.argv = list(sys.argv[1:] if args is None else args)  # what error() looks through
        return super().parse_known_args(args, namespace)


def _parser(lazy: bool) -> argparse.ArgumentParser:
    parser = _Parser(
        prog="shrm",
        description="Measured-BRDF toolkit: frequency-space orders (RH02), fits, SHRM rendering.",
    )
    parser.add_argument("--version", action="version", version=f"shrm {__version__}")
    sub = parser.add_subparsers(dest="verb", metavar="VERB", parser_class=_VerbParser)
    for verb in _verbs():
        line = _help(verb)
        p = sub.add_parser(verb, help=line, description=line)
        p.verb = verb
        if not lazy:
            p.load()
    return parser


def build_parser() -> argparse.ArgumentParser:
    """The whole parser, every verb's parser module imported and its arguments added (the verbs'
    ``cmd_`` modules are imported when ``args._run(args)`` runs one)."""
    return _parser(lazy=False)


#: Longest error message printed (characters): a 6,000-character spec string or 161 KB of a file's
#: raw bytes quoted in a message is cut, with the count of what was left out (issue 30).
MAX_MESSAGE_CHARS = 500


def shorten(text: str, limit: int = MAX_MESSAGE_CHARS) -> str:
    """``text`` on one line, cut to about ``limit`` characters: its start and end, and how many
    characters were left out in between."""
    text = " ".join(text.split("\n"))
    if len(text) <= limit:
        return text
    head, tail = text[: limit * 3 // 4], text[-(limit // 4):]
    return f"{head} … ({len(text) - len(head) - len(tail):,} characters left out) … {tail}"


def _one_line_warnings(verb: str) -> None:
    """Python warnings reach a CLI user as one plain line, ``shrm VERB: warning: …`` (no source
    file and line of the library that raised them)."""
    def show(message, category, filename, lineno, file=None, line=None) -> None:  # noqa: ANN001
        print(f"shrm {verb}: warning: {shorten(str(message))}", file=file or sys.stderr)

    warnings.showwarning = show


def main(argv: list[str] | None = None) -> int:
    parser = _parser(lazy=True)
    args, extra = parser.parse_known_args(argv)
    if extra:  # reported by the verb's parser, which knows the verb's options ("did you mean")
        verbs = next((a.choices for a in parser._actions if isinstance(a, argparse._SubParsersAction)), {})
        verb = getattr(args, "verb", None)
        ((verbs.get(verb) if verb is not None else None) or parser).error(f"unrecognized arguments: {' '.join(extra)}")
    if getattr(args, "verb", None):
        _one_line_warnings(args.verb)
    if not getattr(args, "_run", None):
        parser.print_help()
        return 0
    quiet = getattr(args, "quiet", False) and not getattr(args, "json", False)
    try:
        with open(os.devnull, "w") if quiet else contextlib.nullcontext() as sink:
            with contextlib.redirect_stdout(sink) if quiet else contextlib.nullcontext():
                return int(args._run(args) or 0)
    except ShrmError as err:
        print(f"shrm {args.verb}: error: {shorten(in_cli_terms(str(err)))}", file=sys.stderr)
        return 2
    except OSError as err:  # a file system refusal the verb did not turn into a BadInputError
        where = f"{err.filename}: " if err.filename else ""
        print(f"shrm {args.verb}: error: {where}{err.strerror or err}", file=sys.stderr)
        return 2
    except MemoryError:
        # one line, not a traceback: the input asked for more memory than this machine has
        source = next((str(getattr(args, key)) for key in ("brdf", "env", "source", "sources", "input")
                       if getattr(args, key, None)), None)
        what = f"{source}: " if source else ""
        print(f"shrm {args.verb}: error: {what}out of memory (the input or the options ask for more than this "
              "machine has; SHRM_MAX_PIXELS and SHRM_MAX_ELEMENTS cap what a file may declare)", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"shrm {args.verb}: interrupted", file=sys.stderr)
        return 130


def fast_exit(code: int) -> None:
    """End the process with ``code`` without the interpreter's teardown, when that is safe.

    Tearing down a report's modules (numpy, SciPy, matplotlib, VTK: every module dict and object
    freed one by one) costs ~0.3–0.5 s CPU of every ``shrm`` command that did real work, for memory
    the operating system frees at once. So, when only the main thread is left and no child process
    of ``multiprocessing`` is alive, the output streams are flushed, the ``atexit`` handlers run
    (logging's shutdown, temporary folders' finalizers) and the process ends with ``os._exit``.
    Otherwise, or if a stream cannot be flushed (a closed pipe), it returns and the caller exits
    the ordinary way (``sys.exit``), which reports what it must.
    """
    if threading.active_count() != 1:
        return
    children = sys.modules.get("multiprocessing")
    if children is not None and children.active_children():
        return
    if not _flushed():
        return
    atexit._run_exitfuncs()
    if not _flushed():
        return
    os._exit(code)


def _flushed() -> bool:
    """Flush stdout and stderr; False if one cannot be (a closed pipe, a full disk). A stream that
    is None (its descriptor was closed when the process started) has nothing to flush."""
    try:
        for stream in (sys.stdout, sys.stderr):
            if stream is not None:
                stream.flush()
    except (OSError, ValueError):
        return False
    return True


def console_main() -> None:
    """The ``shrm`` console script: :func:`main`, then :func:`fast_exit` with its exit code.

    BLAS gets one thread unless ``OPENBLAS_NUM_THREADS`` is set (before NumPy loads it): the
    heavy stages already run single-threaded BLAS (``analysis.threads``), and each switch back to
    two threads woke OpenBLAS's second thread to spin: 0.25 s CPU of a 3 s quick report, no wall
    time gained (benchmarks/prefilter_speed.py, target rows). ducc0's threads are unaffected."""
    if "numpy" not in sys.modules:
        os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
    console_state.CONSOLE_PROCESS = True  # this process shows no library docstrings (lean_matplotlib)
    code = main()
    fast_exit(code)
    sys.exit(code)


if __name__ == "__main__":
    console_main()
