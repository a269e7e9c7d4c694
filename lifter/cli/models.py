"""``poselifter models``: the shipped models, which is the default, and whether their weights files are intact.

Lists each model of the registry (:mod:`lifter.resources`) with its networks, their files, sizes and sha256, each
file hashed against the registry (:func:`lifter.resources.check_model_files`). Exit code 1 when a file is damaged
or missing or a model's registry entry is one the loader refuses (the fix: reinstall poselifter); 2 for an unknown
name, or a registry (``models.json``) that cannot be read at all.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

from .. import __version__
from .. import resources as assets
from .._checks import PoseLifterError
from . import COMMANDS
from ._help import HelpFormatter


def add_parser(sub: argparse._SubParsersAction) -> argparse.ArgumentParser:
    """Register the ``models`` sub-command on an ``add_subparsers()`` object."""
    p = sub.add_parser("models", help=COMMANDS["models"][1], formatter_class=HelpFormatter,
                       description="List the shipped models (the default first), each network's weights file with "
                       "its size and sha256, and check every file against the registry's sha256 (exit code 1 when "
                       "one is damaged or missing). The records of poselifter lift name the same sha256 in "
                       "model_info.")
    p.add_argument("names", nargs="*", metavar="NAME",
                   help="only these models (a name, or 'default'); with one name, its full description and "
                   "training commands")
    p.add_argument("--json", action="store_true", help="print the listing as JSON instead")
    p.set_defaults(func=run_models)
    return p


def _first_sentence(text: str) -> str:
    head = text.split(". ")[0].strip()
    return head if head.endswith(".") else head + "."


def command_matches(command: str, weights: Any, *, stored: Any = None) -> str:
    """Whether the ``poselifter train`` ``command`` a network was trained with, read with today's options, gives the
    config its weights file ``weights`` stores (``"same"``), another (``"differs"``: defaults changed or options
    added since), or is refused by them (``"refused"``: an option renamed since), or cannot be told (``"unknown"``:
    not a ``poselifter train`` command, or one whose ``--config`` or ``--init`` file is not here). A fine-tune's
    config is resolved as ``train`` resolves it (:func:`lifter.cli.train.fine_tune_config`). Times and paths
    (``--max-minutes``, ``--out``, ``--h36m``) do not count; nor does what the code does with the same config."""
    import contextlib
    import io
    import shlex
    from dataclasses import replace

    from ..config import TrainConfig, config_from_args
    from . import build_parser
    from .train import fine_tune_config, load_option

    words = shlex.split(command)
    if words[:2] != ["poselifter", "train"]:
        return "unknown"
    try:
        with contextlib.redirect_stderr(io.StringIO()):  # (argparse's refusal of an option renamed since)
            args = build_parser("train").parse_args(words[1:])
    except SystemExit:
        return "refused"
    try:
        base = TrainConfig.load(args.config) if args.config is not None else None
        stored = stored if stored is not None else TrainConfig.load(Path(weights))
        given = config_from_args(args, base)
        if given.init is not None:
            given = fine_tune_config(given, load_option("--init", given.init, args), args)[0]
    except (PoseLifterError, OSError):
        return "unknown"
    untimed = lambda c: replace(c, schedule=replace(c.schedule, max_minutes=None))  # noqa: E731
    return "same" if untimed(given) == untimed(stored) else "differs"


def _missing_init(init: str | None) -> str:
    """For a repeat line: what a stored config's ``--init`` needs when it is neither shipped nor a file here."""
    if init is None or init in assets.model_names() or init == "default" or Path(init).is_file():
        return ""
    return f" (needs its --init {init}, which is not shipped)"


def run_models(args: argparse.Namespace) -> int:
    default = assets.default_model_name()
    names = [assets.model_entry(n)["name"] for n in args.names] or sorted(
        assets.model_names(), key=lambda n: (n != default, n))  # (an unknown name: error, exit 2)
    entries = {name: assets.model_entry(name) for name in names}  # (once each; repeated names once)
    rows = []
    broken: list[tuple[str, str]] = []  # (a registry entry the loader refuses: its files cannot be listed)
    for name, entry in entries.items():
        try:
            files = assets.check_model_files(name)
        except PoseLifterError as exc:
            broken.append((name, str(exc)))
            files = []
        rows.append({"name": name, "default": name == default, "description": entry.get("description", ""),
                     "networks": [{"network": f.network, "file": f.file, "size_bytes": f.size_bytes,
                                   "sha256": f.sha256, "status": f.status} for f in files]})
    bad = [(r["name"], n) for r in rows for n in r["networks"] if n["status"] in ("damaged", "missing")]
    if args.json:
        print(json.dumps({"poselifter_version": __version__, "assets": str(assets.assets_root()), "default": default,
                          "models": rows}, indent=1))
    else:
        print(f"poselifter {__version__}: shipped models in {assets.assets_root()} (default: {default})")
        for r in rows:
            size = sum(n["size_bytes"] or 0 for n in r["networks"]) / 1e6
            said = {n["status"] for n in r["networks"]}
            state = ("REGISTRY ENTRY DAMAGED" if not said else "files ok" if said == {"ok"} else
                     "files ok as far as checked (no sha256 in the registry for some)" if said <= {"ok", "unchecked"}
                     else "CHECK THE FILES BELOW")
            count = len(r["networks"])
            print(f"\n{r['name']}{'  (default)' if r['default'] else ''}: {count} network{'s' * (count != 1)}, "
                  f"{size:.1f} MB, {state}")
            for n in r["networks"]:
                mb = "-" if n["size_bytes"] is None else f"{n['size_bytes'] / 1e6:.1f} MB"
                key = "any 2D" if count == 1 else n["network"]  # (one network lifts clean and detected 2D alike)
                print(f"  {key:<11} {n['file']:<36} {mb:>8}  sha256 {n['sha256'] or '(none)'}  "
                      f"{n['status']}")
            desc = r["description"]
            if desc:
                print(f"  {desc if len(entries) == 1 else _first_sentence(desc)}")
            if len(entries) == 1:
                entry = entries[r["name"]]
                commands = {entry["file"]: entry.get("train_command"),
                            **dict(zip(entry.get("ensemble_files", []), entry.get("ensemble_train_commands", []))),
                            entry.get("clean_file", ""): entry.get("clean_train_command")}
                for n in r["networks"]:
                    key = "" if count == 1 else f" ({n['network']})"
                    c, path = commands.get(n["file"]), assets.asset(n["file"])
                    try:  # (read once, for both lines)
                        from ..config import TrainConfig

                        stored = TrainConfig.load(Path(str(path)))
                    except PoseLifterError:
                        stored = None
                    if c:
                        said = {"same": "", "differs": " (as run then; with today's options and defaults it gives "
                                "another config: repeat it from its stored config, below)",
                                "refused": " (as run then; today's options refuse it: repeat it from its stored "
                                "config, below)", "unknown": " (as run then)"}
                        print(f"  trained with{key}{said[command_matches(c, path, stored=stored)]}: {c}")
                    # (a researcher trial ran the stored command of `gt`, which now trains another kind of
                    # network, and `mixture`'s, which today's options refuse)
                    print(f"  repeat{key}: poselifter train --config {path} --out runs/{Path(n['file']).stem}_again.pt"
                          f"{_missing_init(None if stored is None else stored.init)}")
    for _, why in broken:
        print(f"poselifter models: error: {why}", file=sys.stderr)
    for name, n in bad:
        print(f"poselifter models: error: model {name!r}: {n['file']} is {n['status']}"
              + (" (its bytes do not hash to the registry's sha256)" if n["status"] == "damaged" else "")
              + ": reinstall poselifter, or restore the file",
              file=sys.stderr)
    return 1 if bad or broken else 0
