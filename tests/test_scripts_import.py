"""Every script in ``scripts/`` and ``benchmarks/`` still imports: its top level runs (imports from ``lifter``,
module constants) without calling ``main``. A name moved inside the library otherwise breaks a script only when
someone reruns it to reproduce a README number."""

from __future__ import annotations

import os
import runpy
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]
SCRIPTS = sorted(p for p in [*ROOT.glob("scripts/*.py"), *ROOT.glob("benchmarks/*.py")]
                 if not p.name.startswith("_"))  # (scripts/_report.py: a helper the scripts import)


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


def test_eval_cascade_quick_table_flip_switch(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """``scripts/eval_cascade.py --flip-test / --no-flip-test`` reaches every lifter of its quick table, an
    ensemble written ``a.pt+b.pt`` included; without it each model keeps its own default (off for these)."""
    from conftest import random_pose_cam, tiny_lifter

    from lifter.camera import project
    from lifter.checkpoint import save_checkpoint

    monkeypatch.syspath_prepend(str(ROOT / "scripts"))
    ns = runpy.run_path(str(ROOT / "scripts" / "eval_cascade.py"), run_name="imported_by_test")
    a, b = tiny_lifter(32, seed=3), tiny_lifter(32, seed=4)
    pa = save_checkpoint(tmp_path / "a.pt", a.net, a.codec)
    pb = save_checkpoint(tmp_path / "b.pt", b.net, b.codec)
    rng = np.random.default_rng(0)
    gt3d = random_pose_cam(rng, 4)
    focal, pp = np.full((4, 2), 1145.0), np.tile([512.0, 515.0], (4, 1))
    gt2d = project(gt3d, focal=1145.0, principal_point=(512.0, 515.0))
    args = ([str(pa), f"{pa}+{pb}"], gt2d + 3.0, np.ones(4, bool), gt2d, gt2d, gt3d, focal, pp, np.zeros((4, 5)))
    own, off, on = (ns["quick_table"](*args, flip_test=f) for f in (None, False, True))
    assert own.splitlines()[2:] == off.splitlines()[2:] and on.splitlines()[2:] != off.splitlines()[2:]
    assert "flip test on in every lifter" in on.splitlines()[0] and "flip test" not in own.splitlines()[0]
    assert f"| {pa}+{pb} |" in on


def test_detector_crops_box_is_a_grown_square_clipped_to_the_image() -> None:
    ns = runpy.run_path(str(ROOT / "scripts" / "detector_crops.py"), run_name="imported_by_test")
    crop_box = ns["crop_box"]
    assert crop_box(np.array([400.0, 300.0, 100.0, 200.0]), 0.25, 1000, 1000) == (300, 250, 600, 550)  # 300 px square
    assert crop_box(np.array([10.0, 20.0, 100.0, 200.0]), 0.5, 1000, 250) == (0, 0, 260, 250)  # clipped at 0 and H


def test_bench_tracking_scores_switches_and_swaps(monkeypatch: pytest.MonkeyPatch) -> None:
    """``benchmarks/bench_tracking.py``'s counts: a person under the other's track counts as a swap for every frame
    of it, a new id for the same person as a switch, and each track once."""
    from types import SimpleNamespace

    monkeypatch.syspath_prepend(str(ROOT / "benchmarks"))
    import bench_tracking

    def frame(*ids: int) -> SimpleNamespace:
        return SimpleNamespace(people=[SimpleNamespace(track_id=i) for i in ids])

    # person 0 on track 1 throughout; person 1 on track 2, then on track 3 (frames 2-3), then on track 2 again
    frames = [frame(1, 2), frame(1, 2), frame(1, 3), frame(1, 3), frame(2)]
    who = [[0, 1], [0, 1], [0, 1], [0, 1], [1]]
    assert bench_tracking.score(frames, who) == {"switches": 2, "wrong_frames": 0, "person_frames": 9, "tracks": 3}
    # the two swap tracks for three frames: 2 switches each way, and three frames each under the other's track
    frames = [frame(1, 2)] * 4 + [frame(2, 1)] * 3
    who = [[0, 1]] * 7
    assert bench_tracking.score(frames, who) == {"switches": 2, "wrong_frames": 6, "person_frames": 14, "tracks": 2}
    # box geometry: a box wholly inside another is hidden entirely; disjoint boxes not at all
    inner, outer = np.array([1.0, 1.0, 2.0, 2.0]), np.array([0.0, 0.0, 3.0, 3.0])
    assert bench_tracking.hidden_share(inner, outer) == 1.0
    assert bench_tracking.hidden_share(inner, inner + 5) == 0.0
