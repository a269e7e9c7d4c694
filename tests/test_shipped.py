"""The shipped weights: the registry, their integrity, and that they reproduce the numbers recorded in
assets/models.json (and quoted in the README) on the every-50th-frame slice."""

from __future__ import annotations

from pathlib import Path

import pytest
from conftest import requires_h36m

from lifter import CheckpointError, Lifter, available_models
from lifter.detections import with_sh_detections
from lifter.evaluate import evaluate_lifter
from lifter.resources import asset, registry

ROOT = Path(__file__).resolve().parents[1]
# Tolerance: the slice is re-evaluated with the same weights; differences come only from float
# summation order (threads, BLAS), far below these bounds.
TOL_MM = 0.3
MAX_WEIGHTS_BYTES = 40e6


def _slices() -> list[tuple[str, str]]:
    try:
        reg = registry()
    except Exception:  # noqa: BLE001 - no assets: the registry test reports it
        return []
    return [(name, key) for name, e in sorted(reg["models"].items()) for key, m in e.get("metrics", {}).items()
            if m["stride"] == 50]


def test_registry_and_every_model_loads_with_its_checksum():
    reg = registry()
    assert reg["default"] in reg["models"]
    for name, entry in reg["models"].items():
        size = asset(entry["file"]).stat().st_size if hasattr(asset(entry["file"]), "stat") else 0
        assert size <= MAX_WEIGHTS_BYTES, f"{name}: {size / 1e6:.1f} MB > 40 MB"
        assert len(entry["sha256"]) == 64
    assert Lifter.from_pretrained().name == reg["default"]
    for name in available_models():
        Lifter.from_pretrained(name)


def test_a_damaged_shipped_file_is_refused(tmp_path, monkeypatch):
    """4 KB flipped in the middle of the default's weights: the checksum refuses it before torch reads it."""
    import shutil

    src = Path(str(asset("models.json"))).parent
    dst = tmp_path / "assets"
    shutil.copytree(src, dst, ignore=shutil.ignore_patterns("*.png", "demo"))
    entry = registry()["models"][registry()["default"]]
    f = dst / entry["file"]
    data = bytearray(f.read_bytes())
    mid = len(data) // 2
    data[mid:mid + 4096] = bytes(b ^ 0x5A for b in data[mid:mid + 4096])
    f.write_bytes(bytes(data))
    monkeypatch.setenv("POSELIFTER_ASSETS", str(dst))
    with pytest.raises(CheckpointError, match="damaged or was replaced") as exc:
        Lifter.from_pretrained()
    assert "reinstall poselifter" in str(exc.value)


@requires_h36m
@pytest.mark.parametrize("name,key", _slices())
def test_shipped_weights_reproduce_recorded_metrics(h36m, name, key):
    rec = registry()["models"][name]["metrics"][key]
    samples = h36m.load_protocol(1, "test", stride=rec["stride"])
    if rec["inputs"] == "sh":
        samples, _ = with_sh_detections(samples, data=h36m)
    assert len(samples) == rec["learned"]["num_samples"]
    learned, analytic = evaluate_lifter(Lifter.from_pretrained(name), samples, analytic_root=True, progress=False,
                                        source=rec["source"], flip_test=rec.get("flip_test", False))
    for k in ("mpjpe", "pa_mpjpe", "mrpe"):
        assert getattr(learned, k) == pytest.approx(rec["learned"][k], abs=TOL_MM), k
        assert getattr(analytic, k) == pytest.approx(rec["analytic_root"][k], abs=TOL_MM), k
