"""The README's library example runs as written, from a folder outside the repository."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

README = Path(__file__).resolve().parent.parent / "README.md"


def first_python_example() -> str:
    m = re.search(r"^```python\n(.*?)^```", README.read_text(), flags=re.S | re.M)
    assert m, "README has no ```python example"
    return m.group(1)


def test_readme_library_example_runs_as_written(tmp_path):
    code = first_python_example()
    assert "demo_sample" in code and "from_checkpoint" in code, "the example must use shipped input and own weights"
    proc = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    mpjpe = float(re.search(r"MPJPE ([\d.]+) mm", proc.stdout).group(1))  # type: ignore[union-attr]
    assert 0 < mpjpe < 150, proc.stdout
    assert (tmp_path / "my.pt").is_file()


def test_readme_detector_arrays_example_runs_as_written(tmp_path):
    """The library section's second example (a detector's COCO rows with their scores, one ear hidden), run after the
    first, which defines ``model``."""
    blocks = re.findall(r"^```python\n(.*?)^```", README.read_text(), flags=re.S | re.M)
    second = next(b for b in blocks if "scores=" in b and "coco_result" in b)
    head, face = [960.0, 300.0], [(0, 12), (-9, 0), (9, 0), (-21, 4), (21, 4)]
    body = [(-60, 90), (60, 90), (-80, 195), (80, 195), (-90, 300), (90, 300), (-38, 315), (38, 315), (-42, 465),
            (42, 465), (-45, 600), (45, 600)]
    rows = [[head[0] + dx, head[1] + dy, 0.0 if i == 3 else 0.9] for i, (dx, dy) in enumerate(face + body)]
    setup = f"coco_result = {{'keypoints': {sum(rows, [])!r}}}\n"
    code = first_python_example() + setup + second + "print('root', res.root.round(1).tolist(), res.warnings)\n"
    proc = subprocess.run([sys.executable, "-W", "always::UserWarning", "-c", code], cwd=tmp_path, capture_output=True,
                          text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    assert "stood in for missing joint(s): l_ear from" in proc.stderr, proc.stderr
    root = [float(v) for v in re.search(r"root \[(.*?)\]", proc.stdout).group(1).split(",")]  # type: ignore[union-attr]
    assert 1000 < root[2] < 10000, proc.stdout  # (a 1.6 m person 600 px tall at f = 1500: about 4 m away)


def test_documented_checkpoint_loading_errors(tmp_path, monkeypatch):
    """What the README says of your own checkpoint: a missing path is a CheckpointError naming the file; a name
    that is neither shipped nor a file says how to load a checkpoint."""
    import pytest

    from lifter import CheckpointError, Lifter, PoseLifterError

    monkeypatch.chdir(tmp_path)
    with pytest.raises(CheckpointError, match=r"weights file not found: my.pt$"):
        Lifter.from_pretrained("my.pt")
    # a paper-table command's run, not trained yet, names the script that trains it (a researcher's trial)
    with pytest.raises(CheckpointError, match=r"runs/ablation_baseline.pt; runs/ holds .* scripts/run_ablation.sh"):
        Lifter.from_pretrained("runs/ablation_baseline.pt")
    with pytest.raises(PoseLifterError, match=r"unknown model 'mine'.*pass its .pt path"):
        Lifter.from_pretrained("mine")
