"""The help formatter of every ``poselifter`` sub-command."""

from __future__ import annotations

import argparse
import re


class HelpFormatter(argparse.ArgumentDefaultsHelpFormatter):
    """Shows an option's default after its help, unless the help states it already (``default ...``) or there
    is none to show (None, False: an unset option or a flag)."""

    def _get_help_string(self, action: argparse.Action) -> str | None:
        text = action.help or ""
        if "default" in text.lower() or action.default in (None, False) or action.required:
            return text
        return super()._get_help_string(action)


def plain_text(doc: str | None) -> str:
    """A module docstring as help text: reStructuredText roles and literals (``:class:`a.B```, ````x````) shown
    as their plain names."""
    text = re.sub(r":[a-z]+:`~?([^`]+)`", r"\1", doc or "")
    return re.sub(r"``([^`]+)``", r"\1", text)
