"""The ``parakin`` command line (``parakin --help`` lists every command; ``parakin CMD --help``
its options).

Bad input (a wrong number of values, an unreachable pose, an unknown solver, a malformed config or
file) exits with status 2 and one line on stderr, never a traceback. SI units by default;
``--units paper`` reads and prints the units the paper uses. ``ik`` and ``fk`` take many poses or
joint vectors from a file (``--input``, CSV or .npy, one per row) and write them to one
(``--output``, atomically: :func:`parakin.io.atomic_writer`); each reads what the other writes.
An ``fk`` answer near a singularity (another solution close by) gets a one-line warning.

One module per command (``kinematics``: ik and fk, ``dynamics``, ``bench``, ``kernels``,
``pipeline``: reproduce, check, which, record, report, readme), each with an ``add_*`` function
that declares its parser and the function that runs it; what several share is in ``common``.
"""

from __future__ import annotations

import argparse
import contextvars
import sys
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from functools import cache

import numpy as np

from parakin.cli import bench, dynamics, kernel_cache, kinematics, pipeline, workspace
from parakin.cli.common import EXIT_BAD_INPUT, _Parser, parameters_of
from parakin.errors import ParakinError

__all__ = ["main", "build_parser", "parameters_of", "EXIT_BAD_INPUT"]


class _VersionAction(argparse.Action):
    """``--version``: argparse's version action, with the version looked up only when asked
    (importlib.metadata is about 10 ms of every command's start otherwise)."""

    def __init__(self, option_strings, dest=argparse.SUPPRESS, **kwargs):
        kwargs.setdefault("help", "show the program's version number and exit")
        super().__init__(option_strings, dest, nargs=0, default=argparse.SUPPRESS, **kwargs)

    def __call__(self, parser, namespace, values, option_string=None):
        print(f"parakin {_version()}")
        parser.exit()


def _version() -> str:
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("parakin")
    except PackageNotFoundError:  # running from a source tree that was never installed
        return "unknown"


@dataclass(frozen=True)
class _ByName:
    """A command's function, looked up in its module when the command runs: the parser is built
    once per process (:func:`_parser`) and a function replaced later (a test's patch) is the one
    that runs."""

    module: str
    name: str

    @classmethod
    def of(cls, func: Callable[..., int], module: str) -> _ByName:
        """``func`` by the name ``module`` (the command module that registers it) binds it to."""
        names = [k for k, v in vars(sys.modules[module]).items() if v is func]
        if len(names) != 1:
            raise TypeError(f"a command's function must be bound to one name of {module}: {func!r}")
        return cls(module, names[0])

    def __call__(self, args: argparse.Namespace) -> int:
        return getattr(sys.modules[self.module], self.name)(args)


class _Commands:
    """The subcommands as the ``add_*`` functions of the command modules declare them (``add_parser(name, help=...)``),
    each help kept here for ``parakin --help``'s command list rather than handed to argparse,
    whose help formatter measures subcommands one indent short and would push a long name's
    help onto the next line."""

    def __init__(self, action: argparse.Action) -> None:
        self.action = action
        self.helps: dict[str, str] = {}
        self.module = ""  # the command module whose ``add_*`` function runs

    def add_parser(
        self, name: str, *, func: Callable[..., int], help: str = "", **kwargs
    ) -> argparse.ArgumentParser:
        """The parser of command ``name``, which ``func(args)`` runs."""
        self.helps[name] = help
        parser = self.action.add_parser(name, **kwargs)
        parser.set_defaults(func=_ByName.of(func, self.module))
        return parser

    def listing(self) -> str:
        """``commands:`` and one line per command: its name and its help."""
        width = max(map(len, self.helps), default=0) + 2
        lines = [f"  {name:<{width}} {text}" for name, text in self.helps.items()]
        return "\n".join(["commands:", *lines])


def build_parser() -> argparse.ArgumentParser:
    """The ``parakin`` parser: one subcommand per ``add_*`` function of the command modules; ``parakin --help``
    lists them, one line each, from the parser itself."""
    parser = _Parser(
        prog="parakin",
        formatter_class=argparse.RawTextHelpFormatter,
        description="parakin: parallel-mechanism kinematics (IK/FK, solvers, benchmarks) and the "
        "reproduction of four papers.",
    )
    parser.add_argument("--version", action=_VersionAction)
    action = parser.add_subparsers(
        title="commands", dest="command", required=True, metavar="COMMAND", parser_class=_Parser
    )
    sub = _Commands(action)
    for add in (
        kinematics.add_ik,
        kinematics.add_fk,
        bench.add_bench,
        pipeline.add_readme,
        pipeline.add_reproduce,
        pipeline.add_check,
        pipeline.add_which,
        pipeline.add_record,
        pipeline.add_report,
        dynamics.add_dynamics,
        kernel_cache.add_kernels,
        workspace.add_workspace,
    ):
        sub.module = add.__module__
        add(sub)
    # the usage as argparse writes it; then the command list is ours, in the epilog
    parser.usage = parser.format_usage().removeprefix("usage: ").rstrip("\n")
    action.help = argparse.SUPPRESS
    parser.epilog = (
        sub.listing() + "\n\nparakin COMMAND --help shows a command's options. Bad input: exit "
        "status 2 and one line on stderr."
    )
    return parser


@cache
def _parser() -> argparse.ArgumentParser:
    """:func:`build_parser`, built once per process: building it costs about 3 ms (argparse looks
    for a translation of every message it registers), which a process that calls :func:`main`
    many times (the CLI's fuzz tests: about 2,500 calls) paid on every call. Parsing leaves the
    parser as it was."""
    return build_parser()


#: the exit status of a command stopped by Ctrl-C (128 + SIGINT, what a shell reports)
EXIT_INTERRUPTED = 130


def main(argv: Sequence[str] | None = None) -> int:
    args = None
    try:
        args = _parser().parse_args(argv)
        with np.errstate(all="ignore"):  # non-finite results are checked, not warned about
            return contextvars.copy_context().run(args.func, args)  # settings stay in the command
    except KeyboardInterrupt:  # Ctrl-C: one line, no traceback (files are written atomically)
        command = getattr(args, "command", None)
        print(f"parakin{' ' + command if command else ''}: interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED
    except (
        ParakinError,
        ValueError,
        KeyError,
        ArithmeticError,
        OSError,
        MemoryError,
        RecursionError,  # e.g. --config-json nested thousands deep
    ) as exc:
        print(f"parakin {args.command}: error: {_one_line(exc)}", file=sys.stderr)
        return EXIT_BAD_INPUT


def _one_line(exc: BaseException) -> str:
    """The error's message on one line (a KeyError's without quotes; an OSError's with its path)."""
    if isinstance(exc, KeyError) and exc.args:
        message = str(exc.args[0])
    elif isinstance(exc, MemoryError):
        message = f"out of memory ({exc or 'the request is too large'})"
    elif isinstance(exc, RecursionError):
        message = f"input nested too deeply ({exc})"
    elif isinstance(exc, OSError) and exc.filename is not None:
        message = f"{exc.strerror or exc}: {exc.filename}"
    else:
        message = str(exc) or type(exc).__name__
    return " ".join(message.split())
