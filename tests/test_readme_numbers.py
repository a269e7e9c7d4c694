"""The README quotes the shipped default's numbers as the registry records them (assets/models.json), and
tests/test_shipped.py re-measures the registry's every-50th-frame slices against the weights: together, the
README's numbers for the default are what the shipped weights give."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from lifter.resources import default_model_name, registry

README = Path(__file__).resolve().parents[1] / "README.md"
_NUMBER = re.compile(r"^\**(-?\d+(?:\.\d+)?)\**$")


def _default_row() -> list[float]:
    name = default_model_name()
    text = README.read_text()
    start = text.index("### Shipped models and which is the default")
    section = text[start:text.index("\n### ", start + 1)]
    rows = [ln for ln in section.splitlines() if ln.startswith(f"| **`{name}` (default)** |")]
    assert len(rows) == 1, f"README: expected one row '| **`{name}` (default)** |' in the shipped-models table"
    cells = [c.strip() for c in rows[0].strip("|").split("|")]
    return [float(m.group(1)) for c in cells if (m := _NUMBER.match(c))]


def test_readme_models_table_quotes_the_registry_for_the_default():
    metrics = registry()["models"][default_model_name()]["metrics"]
    numbers = _default_row()
    assert len(numbers) >= 6, numbers
    gt, sh = metrics["gt_clean_s5"]["learned"], metrics["sh_detected_s50"]["learned"]
    expected = [gt["mpjpe"], gt["pa_mpjpe"], gt["mrpe"], sh["mpjpe"], sh["pa_mpjpe"], sh["mrpe"]]
    assert numbers[:6] == pytest.approx([round(v, 1) for v in expected], abs=0.051)


def test_readme_must_reach_table_quotes_the_registry_for_the_default():
    gt = registry()["models"][default_model_name()]["metrics"]["gt_clean_s5"]["learned"]
    text = README.read_text()
    quoted = f"{gt['mpjpe']:.1f} / {gt['pa_mpjpe']:.1f} / {gt['mrpe']:.1f}"
    assert quoted in text, f"README does not quote the default's clean-2D numbers {quoted}"


def test_readme_app_benchmark_quotes_docs_app_bench_for_the_default():
    """The app section's drag numbers are docs/app_bench.json's, measured on the default model (a stale file,
    measured on an earlier default, was quoted for two days)."""
    import json

    bench = json.loads((README.parent / "docs" / "app_bench.json").read_text())
    assert bench["model"] == default_model_name(), (
        f"docs/app_bench.json was measured on {bench['model']!r}, the default is {default_model_name()!r}: rerun "
        "benchmarks/bench_app.py (the README's command) and update the README")
    text = README.read_text()
    quoted = f"**p50 {bench['p50_ms']:.1f} ms,\np95 {bench['p95_ms']:.1f} ms"
    assert " ".join(quoted.split()) in " ".join(text.split()), (
        f"README does not quote docs/app_bench.json's drag {quoted!r}")
