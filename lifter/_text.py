"""Docstrings as plain text for ``--help`` (torch-free: ``poselifter-app --help`` uses it without loading a model)."""

from __future__ import annotations

import re


def plain_text(doc: str | None) -> str:
    """A module docstring as help text: reStructuredText roles and literals (``:class:`a.B```, ````x````) shown
    as their plain names."""
    text = re.sub(r":[a-z]+:`~?([^`]+)`", r"\1", doc or "")
    return re.sub(r"``([^`]+)``", r"\1", text)
