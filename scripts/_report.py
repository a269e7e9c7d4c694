"""What the measurement scripts share: a report printed and, when asked, written atomically
(:func:`lifter.io.write_atomic`: a crash never leaves a partial file in docs/results/)."""

from __future__ import annotations

from pathlib import Path

from lifter.io import write_atomic


def emit(text: str, out: Path | None) -> None:
    """Print ``text``; also write it (and a final newline) to ``out`` when given, creating its folder."""
    print(text)
    if out is not None:
        out.parent.mkdir(parents=True, exist_ok=True)
        write_atomic(out, text + "\n")
