"""Dependencies point one way: the library never imports its CLI, the error model knows nothing of the API or
the dataset, and the numpy-only modules import without torch."""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

import pytest

LIFTER = Path(__file__).resolve().parent.parent / "lifter"


def _imports(path: Path) -> set[str]:
    """Absolute names of the lifter modules ``path`` imports (anywhere in the file)."""
    rel = path.relative_to(LIFTER.parent).with_suffix("")
    package = list(rel.parts[:-1])  # the package a relative import starts from (also for __init__.py)
    out: set[str] = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            out.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom):
            base = package[: len(package) - node.level + 1] if node.level else []
            mod = ".".join(base + ([node.module] if node.module else []))
            out.add(mod)
            out.update(f"{mod}.{a.name}" for a in node.names)
    return {m for m in out if m == "lifter" or m.startswith("lifter.")}


def test_the_library_never_imports_its_cli():
    """Only the CLI package itself and ``python -m lifter`` (lifter/__main__.py, the CLI's entry point) may."""
    offenders = [str(p.relative_to(LIFTER)) for p in LIFTER.rglob("*.py")
                 if "cli" not in p.relative_to(LIFTER).parts and p.name != "__main__.py"
                 and any(m == "lifter.cli" or m.startswith("lifter.cli.") for m in _imports(p))]
    assert not offenders, offenders


def test_the_app_never_imports_the_cli():
    app = LIFTER.parent / "app"
    offenders = []
    for p in app.rglob("*.py"):
        for node in ast.walk(ast.parse(p.read_text())):
            names = [a.name for a in node.names] if isinstance(node, ast.Import) else \
                [node.module or ""] if isinstance(node, ast.ImportFrom) else []
            offenders += [f"{p.name}: {n}" for n in names if n == "lifter.cli" or n.startswith("lifter.cli.")]
    assert not offenders, offenders


def test_the_import_check_sees_relative_imports():
    assert "lifter.api" in _imports(LIFTER / "cli" / "evaluate.py")
    assert "lifter.normalization" in _imports(LIFTER / "noise.py")


def test_noise_imports_neither_api_nor_data():
    bad = {m for m in _imports(LIFTER / "noise.py")
           if m.split(".")[:2] in (["lifter", "api"], ["lifter", "data"], ["lifter", "train"])}
    assert not bad, bad


@pytest.mark.parametrize("module", ["lifter.metrics", "lifter.camera", "lifter.keypoints", "lifter.normalization",
                                    "lifter.skeleton", "lifter.analytic", "lifter.resources"])
def test_numpy_modules_import_without_torch(module):
    code = ("import sys; sys.modules['torch'] = None\n"  # any `import torch` now raises ImportError
            f"import {module}\n"
            "import lifter, numpy as np\n"
            "s = lifter.demo_sample('walking')\n"
            "assert float(lifter.mpjpe(s.pose_3d + 1.0, s.pose_3d)) == 0.0\n"
            "assert lifter.mirror(lifter.mirror(s.keypoints_2d)).tolist() == s.keypoints_2d.tolist()\n")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr


def test_torch_names_still_resolve_lazily():
    import lifter

    assert lifter.Lifter.__name__ == "Lifter"
    assert callable(lifter.checkpoint.save_checkpoint)
    with pytest.raises(AttributeError):
        lifter.no_such_name  # noqa: B018


@pytest.mark.parametrize("argv", [["--help"], ["lift", "--help"], ["--version"], ["lfit"]])
def test_cli_help_does_not_import_torch(argv):
    """``poselifter --help`` took 2.5 s (a developer trial): building the parser imported every sub-command's module,
    and with them torch. Now only the named sub-command's module is imported, and ``lift``'s parser needs no torch.
    A misspelled sub-command is refused as quickly, naming the choices."""
    code = ("import sys; sys.modules['torch'] = None\n"
            "from lifter.cli import main\n"
            f"sys.exit(main({argv!r}))\n")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    if argv == ["lfit"]:
        assert proc.returncode == 2 and "invalid choice: 'lfit'" in proc.stderr and "'lift'" in proc.stderr
    else:
        assert proc.returncode == 0, proc.stderr
        assert "poselifter" in proc.stdout


def test_cli_builds_every_sub_command_when_asked():
    """The full parser (no command named) still has each sub-command's own options; the lazy one lists the others."""
    from lifter.cli import COMMANDS, build_parser

    full, lazy = build_parser(), build_parser("lift")
    subs = [a for a in full._actions if a.__class__.__name__ == "_SubParsersAction"][0]
    lazy_subs = [a for a in lazy._actions if a.__class__.__name__ == "_SubParsersAction"][0]
    assert set(subs.choices) == set(lazy_subs.choices) == set(COMMANDS)
    assert "--protocol" in subs.choices["fit-noise"].format_help()
    assert "--protocol" not in lazy_subs.choices["fit-noise"].format_help()
    assert subs.choices["lift"].format_help() == lazy_subs.choices["lift"].format_help()


def test_the_package_version_is_one():
    """A developer trial: two builds of different code both said 0.2.0, so pip kept the older one without a word.
    The version is bumped with each release; lifter.__version__ and pyproject.toml's must agree."""
    import tomllib

    import lifter

    with open(Path(__file__).resolve().parents[1] / "pyproject.toml", "rb") as f:
        assert tomllib.load(f)["project"]["version"] == lifter.__version__
