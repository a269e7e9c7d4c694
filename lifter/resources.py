"""The shipped data: the weights registry and files, the 2D error-model fits and the demo samples.

They are the package data of ``lifter.assets`` (the repository's ``assets/`` folder), read with
:mod:`importlib.resources`, so an installed wheel works from any folder. ``$POSELIFTER_ASSETS`` points
at another folder of the same layout instead.

Registry (``models.json``)::

    {"default": NAME, "models": {NAME: {"file": "weights/NAME.pt", "sha256": HEX, "description": ..., ...}}}

Every shipped weights file has its sha256 there; :func:`weights_bytes` checks nothing itself, the
checkpoint loader compares the hash before it reads the file (:func:`lifter.checkpoint.load_checkpoint`).
"""

from __future__ import annotations

import io
import json
import os
from dataclasses import dataclass, field
from functools import lru_cache
from importlib import resources
from importlib.abc import Traversable
from pathlib import Path
from typing import Any, Required, TypedDict, cast

import numpy as np

from ._checks import CheckpointError, PoseLifterError

ENV_VAR = "POSELIFTER_ASSETS"
REGISTRY = "models.json"


def assets_root() -> Traversable:
    """The folder holding the shipped data (``$POSELIFTER_ASSETS`` if set)."""
    env = os.environ.get(ENV_VAR)
    if env:
        return Path(env)
    try:
        return resources.files("lifter.assets")
    except ModuleNotFoundError:  # a source tree used without installing: assets/ beside lifter/
        return Path(__file__).resolve().parent.parent / "assets"


def asset(relative: str) -> Traversable:
    """A shipped file by its path inside the assets folder (``"error_model/sh_mixture.json"``)."""
    node = assets_root()
    for part in Path(relative).parts:
        node = node.joinpath(part)
    return node


def read_bytes(relative: str) -> bytes:
    """A shipped file's bytes; a missing one raises :class:`PoseLifterError` naming the fix, a missing weights file
    (``.pt``) :class:`lifter.CheckpointError` (as a damaged one does)."""
    node = asset(relative)
    if not node.is_file():
        kind = CheckpointError if relative.endswith(".pt") else PoseLifterError
        raise kind(f"shipped file {relative!r} not found in {assets_root()} (a broken install? "
                   f"reinstall poselifter, or set ${ENV_VAR} to an assets folder)")
    return node.read_bytes()


def _registry_text() -> str:
    node = asset(REGISTRY)
    if not node.is_file():
        raise PoseLifterError(f"no shipped models: {REGISTRY} not found in {assets_root()} (reinstall poselifter, "
                              f"or set ${ENV_VAR} to an assets folder)")
    return node.read_text()


class ModelEntry(TypedDict, total=False):
    """One shipped model of the registry (``models.json``), as :func:`model_entry` returns it."""

    name: Required[str]
    """The registry key (added by :func:`model_entry`)."""
    file: Required[str]
    """Weights file, relative to the assets folder (``"weights/sh_mix.pt"``)."""
    sha256: str
    """Hex sha256 of ``file``; the loader refuses the file unless it matches."""
    clean_file: str
    """A second network for ``source="clean"`` (optional), with its ``clean_sha256``."""
    clean_sha256: str
    flip_test: bool
    """The model's default for :meth:`lifter.Lifter.lift`'s ``flip_test``."""
    ensemble_files: list[str]
    """More networks for detected 2D (optional), averaged with ``file`` (:attr:`lifter.Lifter.ensemble`), with their
    ``ensemble_sha256``."""
    ensemble_sha256: list[str]
    description: str
    train_command: str
    train_minutes: float
    samples_seen: int
    metrics: dict[str, Any]
    """Recorded evaluation slices (see ``tests/test_shipped.py``)."""


class Registry(TypedDict):
    """``models.json``: the default model's name and the models by name."""

    default: str
    models: dict[str, ModelEntry]


@lru_cache(maxsize=4)
def _parse_registry(text: str) -> Registry:
    try:
        reg = json.loads(text)
    except json.JSONDecodeError as exc:
        raise PoseLifterError(f"{REGISTRY}: not valid JSON ({exc})") from None
    if not isinstance(reg, dict) or not isinstance(reg.get("models"), dict) or reg.get("default") not in reg["models"]:
        raise PoseLifterError(f"{REGISTRY}: expected {{'default': name, 'models': {{name: {{...}}}}}} with the default "
                              "among the models")
    for key, entry in reg["models"].items():
        if not isinstance(entry, dict) or not isinstance(entry.get("file"), str):
            raise PoseLifterError(f"{REGISTRY}: model {key!r} needs a 'file' (weights path inside the assets folder)")
    return cast(Registry, reg)


def registry() -> Registry:
    """The parsed ``models.json`` (read on every call, so ``$POSELIFTER_ASSETS`` changes are seen)."""
    return _parse_registry(_registry_text())


def model_names() -> list[str]:
    return sorted(registry()["models"])


def default_model_name() -> str:
    return str(registry()["default"])


def model_entry(name: str) -> ModelEntry:
    """The registry entry of a shipped model with its ``name``; ``"default"`` is the default model."""
    reg = registry()
    if name == "default":
        name = reg["default"]
    if name not in reg["models"]:
        raise PoseLifterError(f"unknown model {name!r}; shipped models: {sorted(reg['models'])} or 'default' "
                              "(your own checkpoint: pass its .pt path on the command line, or "
                              "Lifter.from_pretrained('path/to/model.pt'))")
    return {**reg["models"][name], "name": name}


@dataclass(frozen=True)
class ShippedFile:
    """One weights file of a shipped model, checked (:func:`check_model_files`)."""

    network: str
    """Its key in :meth:`lifter.Lifter.networks` (``"detected"``, ``"detected 1"``, ..., ``"clean"``)."""
    file: str
    """Path inside the assets folder."""
    sha256: str | None
    """The registry's hex sha256 (None: the registry gives none)."""
    size_bytes: int | None
    """The file's size, or None when it is missing."""
    status: str
    """``"ok"`` (its bytes hash to :attr:`sha256`), ``"damaged"`` (they do not), ``"missing"`` or ``"unchecked"``
    (no sha256 to check against)."""


def ensemble_members(entry: ModelEntry) -> list[tuple[str, str]]:
    """``(file, sha256)`` of each further detected-2D network of a registry entry (``ensemble_files`` with
    ``ensemble_sha256``), for the loader and :func:`check_model_files` alike; refused when the two lists differ in
    length (a damaged registry)."""
    files, sums = entry.get("ensemble_files", []), entry.get("ensemble_sha256", [])
    if len(sums) != len(files):
        raise PoseLifterError(f"shipped model {entry['name']!r}: ensemble_files and ensemble_sha256 differ in length "
                              "(reinstall poselifter)")
    return list(zip(files, sums))


def shipped_sha256s() -> frozenset[str]:
    """The registry's sha256 of every shipped weights file (each model's own, clean and ensemble files)."""
    out: set[str] = set()
    for name, entry in registry()["models"].items():
        e: ModelEntry = {**entry, "name": name}
        out.update(h for h in (e.get("sha256"), e.get("clean_sha256")) if isinstance(h, str))
        out.update(h for _, h in ensemble_members(e))
    return frozenset(out)


def check_model_files(name: str) -> list[ShippedFile]:
    """Each weights file of the shipped model ``name`` (``"default"``: the default), in the order of
    :meth:`lifter.Lifter.networks`, hashed against the registry: what ``poselifter models`` reports. The loader checks
    the same before it reads a file (:func:`lifter.checkpoint.load_checkpoint`). A registry entry the loader refuses
    is refused here too (:class:`PoseLifterError`, :func:`ensemble_members`)."""
    import hashlib

    entry = model_entry(name)
    detected: list[tuple[str, str | None]] = [(entry["file"], entry.get("sha256")), *ensemble_members(entry)]
    keyed = [("detected" if len(detected) == 1 else f"detected {i + 1}", f, h) for i, (f, h) in enumerate(detected)]
    if "clean_file" in entry:
        keyed.append(("clean", entry["clean_file"], entry.get("clean_sha256")))
    out = []
    for key, rel, sha in keyed:
        node = asset(rel)
        if not node.is_file():
            out.append(ShippedFile(key, rel, sha, None, "missing"))
            continue
        data = node.read_bytes()
        status = "unchecked" if sha is None else "ok" if hashlib.sha256(data).hexdigest() == sha else "damaged"
        out.append(ShippedFile(key, rel, sha, len(data), status))
    return out


# ------------------------------------------------------------------------------------------------
# Demo samples
# ------------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class DemoSample:
    """One shipped demo sample: an authored 3D pose rendered through a known camera (so its 2D is exact).

    keypoints_2d: ``(17, 2)`` px, H36M joint order. pose_3d: ``(17, 3)`` mm, camera frame (OpenCV).
    focal, principal_point: ``(2,)`` px. image_size: ``(width, height)`` px. R, t: world -> camera
    (``X_cam = R X_world + t``, mm). image: the rendered photo as JPEG bytes.
    """

    name: str
    keypoints_2d: np.ndarray
    pose_3d: np.ndarray
    focal: np.ndarray
    principal_point: np.ndarray
    image_size: tuple[int, int]
    R: np.ndarray
    t: np.ndarray
    image: bytes = field(repr=False)


@lru_cache(maxsize=1)
def _demo_arrays() -> dict[str, np.ndarray]:
    with np.load(io.BytesIO(read_bytes("demo/samples.npz"))) as d:
        return {k: d[k] for k in d.files}


def demo_sample_names() -> list[str]:
    """Names of the shipped demo samples (``"walking"``, ...)."""
    return [str(n) for n in _demo_arrays()["names"]]


def demo_sample(name: str = "walking") -> DemoSample:
    """A shipped demo sample by name (:func:`demo_sample_names`), e.g. to try the lifter without any data::

        s = demo_sample("walking")
        res = Lifter.from_pretrained().lift(s.keypoints_2d, focal=s.focal, principal_point=s.principal_point,
                                            source="clean")
    """
    names = demo_sample_names()
    if name not in names:
        raise PoseLifterError(f"unknown demo sample {name!r}; shipped: {names}")
    d, i = _demo_arrays(), names.index(name)
    w, h = (int(v) for v in d["image_size"][i])
    return DemoSample(name=name, keypoints_2d=d["keypoints_2d"][i].astype(np.float64),
                      pose_3d=d["pose_3d"][i].astype(np.float64), focal=d["focal"][i].astype(np.float64),
                      principal_point=d["principal_point"][i].astype(np.float64), image_size=(w, h),
                      R=d["R"][i].astype(np.float64), t=d["t"][i].astype(np.float64),
                      image=read_bytes(f"demo/{name}.jpg"))
