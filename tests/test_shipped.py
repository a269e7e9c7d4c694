"""The shipped weights reproduce the numbers recorded in assets/models.json and quoted in the README."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from lifter.api import ASSETS_DIR, Lifter, available_models, model_registry
from lifter.evaluate import evaluate_lifter

from conftest import requires_h36m

ROOT = Path(__file__).resolve().parents[1]
# Tolerance: the slice is re-evaluated with the same weights; differences come only from float
# summation order (threads, BLAS), far below these bounds.
TOL_MM = 0.3


def test_registry_and_default_loads():
    reg = model_registry()
    assert reg["default"] in reg["models"]
    total = sum((ASSETS_DIR / m["file"]).stat().st_size for m in reg["models"].values())
    assert total <= 40e6, f"shipped weights are {total / 1e6:.1f} MB > 40 MB"
    lifter = Lifter.from_pretrained()
    assert lifter.name == reg["default"]
    for name in available_models():
        Lifter.from_pretrained(name)


@requires_h36m
@pytest.mark.parametrize("name", sorted(model_registry()["models"]) if (ASSETS_DIR / "models.json").is_file() else [])
def test_shipped_weights_reproduce_recorded_metrics(h36m, name):
    entry = model_registry()["models"][name]
    rec = entry["metrics_gt2d_protocol1"]["slice"]
    samples = h36m.load_protocol(1, "test", stride=rec["stride"])
    assert len(samples) == rec["learned"]["num_samples"]
    learned, analytic = evaluate_lifter(Lifter.from_pretrained(name), samples, analytic_root=True, progress=False)
    for key in ("mpjpe", "pa_mpjpe", "mrpe"):
        assert getattr(learned, key) == pytest.approx(rec["learned"][key], abs=TOL_MM), key
        assert getattr(analytic, key) == pytest.approx(rec["analytic_root"][key], abs=TOL_MM), key


def test_readme_quotes_the_recorded_numbers():
    """The README's row for the default model shows the recorded full-test-set numbers."""
    reg = model_registry()
    full = reg["models"][reg["default"]]["metrics_gt2d_protocol1"]["full"]["learned"]
    readme = (ROOT / "README.md").read_text()
    expected = f"| {full['mpjpe']:.1f} | {full['pa_mpjpe']:.1f} | {full['mrpe']:.1f} |"
    assert expected in readme, f"README does not quote the default model's numbers {expected}"
    assert re.search(r"stride 5", readme)
