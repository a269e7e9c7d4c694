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
