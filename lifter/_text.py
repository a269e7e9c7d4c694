"""Text helpers: docstrings as plain text for ``--help`` (torch-free: ``poselifter-app --help`` uses it without
loading a model), notes as sentences."""

from __future__ import annotations

import re


def plain_text(doc: str | None) -> str:
    """A module docstring as help text: reStructuredText roles and literals (``:class:`a.B```, ````x````) shown
    as their plain names."""
    text = re.sub(r":[a-z]+:`~?([^`]+)`", r"\1", doc or "")
    return re.sub(r"``([^`]+)``", r"\1", text)


def largest_lifted(max_people: int) -> str:
    """The end of the note when more people were found than ``max_people`` are lifted."""
    return ("the largest is lifted (max_people)" if max_people == 1
            else f"the {max_people} largest are lifted (max_people)")


def sentence(note: str) -> str:
    """``note`` ending in one full stop (notes that end in ".", "?" or "!" get none added), for notes joined into
    one message."""
    note = note.rstrip()
    return note if note.endswith((".", "?", "!")) else note + "."
