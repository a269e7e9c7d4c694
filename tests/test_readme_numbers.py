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


RESULTS = README.parent / "docs" / "results"


def _table(text: str, title: str) -> dict[str, list[str]]:
    """Rows of the markdown table under the line starting with ``title``: first cell -> the other cells."""
    lines = text[text.index(title):].splitlines()[1:]
    rows: dict[str, list[str]] = {}
    for ln in lines:
        if not ln.startswith("|"):
            break
        cells = [c.strip() for c in ln.strip("|").split("|")]
        if not set(cells[0]) <= {"-"}:
            rows[cells[0]] = cells[1:]
    return rows


def test_app_focal_cautions_quote_docs_wrong_focal_for_the_default():
    """The app's short-focal caution and its Z/f small print quote docs/results/wrong_focal.txt (``python
    scripts/wrong_focal.py``) for the shipped default (a review: the test held the text's numbers as literals)."""
    from poselifter_app.core import SHORT_FOCAL_MEASURED, Z_PER_F_DETAIL

    text = (RESULTS / "wrong_focal.txt").read_text()
    name = default_model_name()
    pa = _table(text, "2220 test samples")
    heads, row = pa["model"], pa[name]
    col = {h: float(v) for h, v in zip(heads, row)}
    quoted = re.search(r"mean PA-MPJPE (\d+) / (\d+) / (\d+) mm at ×0\.5 / ×0\.25 / ×0\.1 of the true focal, (\d+) at",
                       SHORT_FOCAL_MEASURED)
    assert quoted, SHORT_FOCAL_MEASURED
    assert [float(v) for v in quoted.groups()] == pytest.approx(
        [col["x0.5"], col["x0.25"], col["x0.1"], col["x1"]], abs=0.5)
    z = _table(text, "Z * f_true / f_used")
    ratios = {h: float(v) for h, v in zip(z["model"], z[f"{name}, source='clean'"])}
    median = re.search(r"median Z/f \+(\d+) / \+(\d+) / \+(\d+) %", SHORT_FOCAL_MEASURED)
    assert median, SHORT_FOCAL_MEASURED
    assert [float(v) for v in median.groups()] == pytest.approx(
        [100 * (ratios[k] - 1) for k in ("x0.5", "x0.25", "x0.1")], abs=0.5)
    within = re.search(r"within (\d+) % from ×0\.5 to ×6", Z_PER_F_DETAIL)
    assert within, Z_PER_F_DETAIL
    for rowname in (f"{name}, source='clean'", f"{name}, source='detected'"):
        r = {h: float(v) for h, v in zip(z["model"], z[rowname])}
        worst = max(abs(r[k] - 1) for k in ("x0.5", "x1", "x2", "x4", "x6"))
        assert 100 * worst <= float(within.group(1)), (rowname, worst)


def test_the_person_score_floor_lies_between_the_measured_scores():
    """MIN_PERSON_SCORE lies above the lower quartile of the 'people' BlazePose invents on empty crops and below
    the lowest score of the demo photos' people, as docs/results/empty_crops.txt measured for the shipped default
    (``python scripts/empty_crops.py``; a review: the test compared with literals copied from the file)."""
    from lifter.detect import DOUBTFUL_SCORE, MIN_PERSON_SCORE

    text = (RESULTS / "empty_crops.txt").read_text()
    assert f"the default model {default_model_name()}" in text.splitlines()[0]
    invented = re.search(r"quartiles ([\d.]+) / ([\d.]+) / ([\d.]+)", text)
    real = re.search(r"demo photos' largest person, mean score of the 17 joints: min ([\d.]+)", text)
    assert invented and real, text
    assert float(invented.group(1)) < MIN_PERSON_SCORE < DOUBTFUL_SCORE < float(real.group(1))
