"""The help formatter of every ``poselifter`` sub-command."""

from __future__ import annotations

import argparse
from pathlib import Path

from .._text import plain_text

__all__ = ["HelpFormatter", "add_h36m_arguments", "h36m_help", "plain_text", "positive_int"]


class HelpFormatter(argparse.ArgumentDefaultsHelpFormatter):
    """Shows an option's default after its help, unless the help states it already (``default ...``) or there
    is none to show (None, False: an unset option or a flag)."""

    def _get_help_string(self, action: argparse.Action) -> str | None:
        text = action.help or ""
        if "default" in text.lower() or action.default in (None, False) or action.required:
            return text
        return super()._get_help_string(action)


def positive_int(text: str) -> int:
    """argparse ``type=``: an integer >= 1 (the option name is added by argparse)."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected an integer >= 1, got {text!r}") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"must be >= 1, got {value}")
    return value


def h36m_help(what: str = "Human3.6M folder") -> str:
    """``--h36m``'s help: the folder used without it, resolved (:func:`lifter.data.default_h36m_dir`; a trial read
    "../shared/data/h36m" as relative to the working folder, which it is not in a source checkout)."""
    import os

    from ..data import default_h36m_dir

    folder = default_h36m_dir().resolve()
    if os.environ.get("POSELIFTER_H36M"):
        return f"{what} (default: $POSELIFTER_H36M, {folder})"
    return f"{what} (default: {folder}, or $POSELIFTER_H36M when set)"


def add_h36m_arguments(parser: argparse.ArgumentParser, *, stride: int) -> None:
    """``--h36m DIR`` (None: :func:`lifter.data.default_h36m_dir`) and ``--stride N`` (every N-th frame at 50 fps,
    >= 1), as the analysis scripts under ``scripts/`` take them."""
    parser.add_argument("--h36m", type=Path, default=None, help=h36m_help("Human3.6M data folder"))
    parser.add_argument("--stride", type=positive_int, default=stride, help=f"frame stride at 50 fps "
                        f"(default {stride})")
