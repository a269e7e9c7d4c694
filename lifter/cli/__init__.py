"""``poselifter``: the command line. Each sub-command parses its arguments and calls the library.

``train`` (:mod:`.train`), ``evaluate`` (:mod:`.evaluate`), ``fit-noise`` (:mod:`.fit_noise`), ``lift``
(:mod:`.lift`) and ``models`` (:mod:`.models`). Usage errors and bad input exit with code 2 and a message naming the
problem.
"""

from __future__ import annotations

import argparse
import importlib
import re
import sys
import warnings
from collections.abc import Sequence

from .. import __version__
from .._checks import PoseLifterError, PoseLifterWarning

COMMANDS: dict[str, tuple[str, str]] = {
    "train": ("train", "train a lifter on Human3.6M (also under torchrun)"),
    "evaluate": ("evaluate", "evaluate lifters on Human3.6M and print the results table"),
    "fit-noise": ("fit_noise", "fit the Gaussian + uniform 2D error model to real SH detections"),
    "lift": ("lift", "lift photos, videos or 2D keypoint files to absolute 3D poses (JSON, optional GLB / BVH)"),
    "models": ("models", "list the shipped models and check their weights files' sha256"),
}
"""Sub-command -> (its module in this package, its one-line help). A module is imported only to build its own
sub-command's parser (:func:`build_parser`): ``poselifter --help`` and ``poselifter lift --help`` do not wait for
torch."""


def build_parser(command: str | None = None) -> argparse.ArgumentParser:
    """The ``poselifter`` parser; with ``command`` (a name of :data:`COMMANDS`), only that sub-command's arguments
    are built (and only its module imported), the others listed by name and help."""
    parser = argparse.ArgumentParser(prog="poselifter", description="PoseLifter: absolute 3D pose from 2D keypoints")
    parser.add_argument("--version", action="version", version=f"poselifter {__version__}")
    sub = parser.add_subparsers(dest="command", required=True)
    for name, (module, help_text) in COMMANDS.items():
        if command is None or command == name:
            importlib.import_module(f".{module}", __name__).add_parser(sub)
        else:
            sub.add_parser(name, help=help_text)
    return parser


def _command(argv: Sequence[str] | None) -> str:
    """The sub-command named in ``argv`` (the first argument, as the top level's only options, ``--version`` and
    ``--help``, take no value); "" if none is named."""
    args = sys.argv[1:] if argv is None else list(argv)
    return next((a for a in args if not a.startswith("-")), "")


def _parse(parser: argparse.ArgumentParser, argv: Sequence[str] | None) -> argparse.Namespace:
    """The arguments, with ``lift``'s inputs also read after its options (``lift a.json --out DIR b.json``: argparse
    takes a positional list once, so inputs after an option were "unrecognized"; an option taking several values,
    ``--focal F [F]``, still takes a number after it); anything else left over is an error from the sub-command's
    own parser, with its usage."""
    args, extra = parser.parse_known_args(_joined_negative_values(parser, argv))
    if not extra:
        return args
    subs = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))  # noqa: SLF001
    own = subs.choices.get(args.command, parser)
    if args.command == "lift" and not any(e.startswith("-") and e != "-" for e in extra):
        args.inputs = [*args.inputs, *extra]
        return args
    own.error(f"unrecognized arguments: {' '.join(extra)}")
    raise AssertionError("unreachable")  # (error() exits)


_NEGATIVE_VALUE = re.compile(r"^-\.?\d")


def _joined_negative_values(parser: argparse.ArgumentParser, argv: Sequence[str] | None) -> list[str]:
    """``argv`` with a long option that takes one value (or an abbreviation of one) joined to a value that starts
    with a minus sign and a digit (``--pp-shift -100,80`` -> ``--pp-shift=-100,80``): argparse takes ``-1`` for a
    number but ``-100,80`` for an option, and said "expected one argument" (a researcher trial's ``--focal-scales
    -1,1``, refused by name now). Nothing after a bare ``--`` is touched."""
    args = list(sys.argv[1:] if argv is None else argv)
    subs = next((a for a in parser._actions if isinstance(a, argparse._SubParsersAction)), None)  # noqa: SLF001
    own = subs.choices.get(args[0]) if subs is not None and args else None
    if own is None:
        return args
    takes_one = {o for a in own._actions for o in a.option_strings  # noqa: SLF001
                 if o.startswith("--") and a.nargs is None and isinstance(a, argparse._StoreAction)}  # noqa: SLF001
    every = {o for a in own._actions for o in a.option_strings}  # noqa: SLF001
    out: list[str] = []
    i = 0
    while i < len(args):
        if args[i] == "--":
            return out + args[i:]
        word = args[i]
        named = [o for o in every if o.startswith(word)] if word.startswith("--") and len(word) > 2 else []
        option = word if word in every else named[0] if len(named) == 1 else None  # (argparse takes abbreviations)
        if option in takes_one and i + 1 < len(args) and _NEGATIVE_VALUE.match(args[i + 1]):
            out.append(f"{word}={args[i + 1]}")
            i += 2
        else:
            out.append(word)
            i += 1
    return out


def _stdout_reader_gone() -> bool:
    """Whether stdout is a pipe whose reader has closed it (poll reports an error on it); True where that cannot be
    asked (no poll: Windows), as the broken pipe is then most likely stdout's."""
    import select

    if not hasattr(select, "poll"):
        return True
    try:
        poller = select.poll()
        poller.register(sys.stdout.fileno(), select.POLLOUT)
        return any(ev & (select.POLLERR | select.POLLHUP) for _, ev in poller.poll(0))
    except (OSError, ValueError):
        return True


def _note(message: Warning | str, category: type[Warning], filename: str, lineno: int, file: object = None,
          line: str | None = None) -> None:
    """``warnings.showwarning`` for the commands: a :class:`PoseLifterWarning` as a ``note:`` line on stderr (a
    researcher trial read ``.venv/bin/poselifter:6: PoseLifterWarning: ... sys.exit(main())``); others as Python
    shows them."""
    if issubclass(category, PoseLifterWarning):
        print(f"note: {message}", file=sys.stderr)
    else:
        print(warnings.formatwarning(message, category, filename, lineno, line), end="", file=sys.stderr)


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser(_command(argv))
    args = _parse(parser, argv)
    try:
        with warnings.catch_warnings():  # the lifter's notes as note: lines, not Python's file:line form
            warnings.showwarning = _note
            return int(args.func(args) or 0)
    except (PoseLifterError, FileNotFoundError) as exc:
        print(f"poselifter {args.command}: error: {exc}", file=sys.stderr)
        return 2
    except BrokenPipeError:  # (output piped into `head` and the like, which closed the pipe: not an error of ours)
        import os

        if not _stdout_reader_gone():
            raise  # (another pipe broke, not stdout: a real error)
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())  # (else Python's exit flush of stdout fails again, with a message)
        return 141  # (128 + SIGPIPE, what a shell reports for a command that died of a closed pipe)
    except KeyboardInterrupt:  # (Ctrl-C: one line, not a traceback through the libraries' threads)
        lost = " (no checkpoint was written)" if args.command == "train" else ""  # (before or after the loop)
        print(f"poselifter {args.command}: interrupted{lost}", file=sys.stderr)
        return 130
