"""Every script in ``scripts/`` and ``benchmarks/`` still imports: its top level runs (imports from ``lifter``,
module constants) without calling ``main``. A name moved inside the library otherwise breaks a script only when
someone reruns it to reproduce a README number."""

from __future__ import annotations

import os
import runpy
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SCRIPTS = sorted([*ROOT.glob("scripts/*.py"), *ROOT.glob("benchmarks/*.py")])


@pytest.mark.parametrize("path", SCRIPTS, ids=[f"{p.parent.name}/{p.name}" for p in SCRIPTS])
def test_script_imports(path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    if path.name == "compare_legacy_blazepose.py":
        pytest.importorskip("mediapipe")
    monkeypatch.setattr(sys, "argv", [str(path)])
    monkeypatch.syspath_prepend(str(path.parent))
    env = dict(os.environ)
    try:
        namespace = runpy.run_path(str(path), run_name="imported_by_test")
    finally:  # some set thread-count variables at import
        os.environ.clear()
        os.environ.update(env)
    assert callable(namespace.get("main")), f"{path.name}: no main()"
