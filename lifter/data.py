"""Human3.6M data: camera-frame 3D poses and their distorted 2D projections, by protocol.

Reads the repackaged H36M folder (default ``../shared/data/h36m``, or ``$POSELIFTER_H36M``):
``poses3d_world_17j_mm.npz``, ``cameras.json`` and optionally ``detections2d_sh_16j_px.npz``.

* 3D: world mm -> camera frame with each camera's ``R, t`` (``X_cam = R X_world + t``), mm.
* 2D: the projection **with the camera's lens distortion** (how H36M's own 2D annotations are
  made), px, in the 1000 x 1000 (or 1000 x 1002) image; or, with ``lens="pinhole"``, the ideal pinhole
  projection of the same 3D (what an undistorted photo shows; :meth:`PoseSamples.undistort` maps H36M's 2D and
  its detections there).
* Frames are taken at ``stride`` from frame 0 of each 50-fps sequence.

The data are licensed for non-commercial research and are never copied into the project.
"""

from __future__ import annotations

import json
import os
import re
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, fields
from pathlib import Path
from typing import Any, Literal, get_args

import numpy as np

from ._checks import PoseLifterError
from .camera import Camera, canonical_depth_from_depth, undistort_pixels, world_to_camera


def _default_h36m_dir(package_parent: Path) -> Path:
    """``../shared/data/h36m`` beside the project when ``package_parent`` (the folder holding ``lifter/``) is a
    source checkout (it has ``pyproject.toml``: an editable install); else, for an installed wheel (site-packages),
    relative to the working folder."""
    base = package_parent.parent if (package_parent / "pyproject.toml").is_file() else Path("..")
    return base / "shared" / "data" / "h36m"


DEFAULT_H36M_DIR = _default_h36m_dir(Path(__file__).resolve().parent.parent)
"""The Human3.6M folder when neither ``--h36m`` nor ``$POSELIFTER_H36M`` names one (:func:`_default_h36m_dir`)."""

PROTOCOLS: dict[int, tuple[tuple[int, ...], tuple[int, ...]]] = {
    1: ((1, 5, 6, 7, 8), (9, 11)),
    2: ((1, 5, 6, 7, 8, 9), (11,)),
}
"""Protocol -> (training subjects, test subjects)."""


def trained_protocol(net: Any) -> int | None:
    """The Human3.6M protocol (:data:`PROTOCOLS`) a network's checkpoint says it was trained on: its training
    config's ``data.protocol`` (1, the default, when the config leaves it out), or an older checkpoint's
    ``meta["train_config"]["protocol"]`` (the paper-table models'); None where the checkpoint does not say.
    ``net``: a :class:`lifter.Lifter` (its ``train_config`` and ``meta``)."""
    for cfg in (getattr(net, "train_config", None), (getattr(net, "meta", None) or {}).get("train_config")):
        if not isinstance(cfg, dict):
            continue
        data = cfg.get("data")
        p = data.get("protocol", 1) if isinstance(data, dict) else cfg.get("protocol")
        if p in PROTOCOLS:
            return int(p)
    return None


ACTIONS: tuple[str, ...] = (
    "Directions",
    "Discussion",
    "Eating",
    "Greeting",
    "Phoning",
    "Posing",
    "Purchases",
    "Sitting",
    "SittingDown",
    "Smoking",
    "Photo",
    "Waiting",
    "Walking",
    "WalkDog",
    "WalkTogether",
)
"""The 15 H36M actions in the column order of the paper's Table 5."""

CAMERA_IDS: tuple[str, ...] = ("54138969", "55011271", "58860488", "60457274")

Lens = Literal["h36m", "pinhole"]
"""Which 2D a network learned and is given: ``"h36m"`` H36M's own 2D, with its cameras' lens distortion (1.2-1.3 px
per joint on average, 7 px at the 99th percentile, up to 22 px at the image border, Protocol 1 at stride 5; the
paper's models); ``"pinhole"`` the ideal pinhole projection, i.e. undistorted
2D (the default lifter's networks). Users' 2D from undistorted photos is pinhole 2D."""
LENSES: tuple[str, ...] = get_args(Lens)
MISSING_TEST_SEQUENCES: tuple[str, ...] = ("S9/Discussion 1",)


COMPACT_FILE = "compact.json"
"""In a copy written by ``scripts/compact_h36m.py``: ``{"keep_every": k}``, only frames at multiples of k hold poses;
or ``{"keep_every": {"S1": k1, ...}}``, per subject (a subject not named keeps every frame)."""


def default_h36m_dir() -> Path:
    """``$POSELIFTER_H36M`` if set, else :data:`DEFAULT_H36M_DIR` (``../shared/data/h36m``: from the project root
    in a source checkout, from the working folder for an installed wheel)."""
    env = os.environ.get("POSELIFTER_H36M")
    return Path(env) if env else DEFAULT_H36M_DIR


def action_of(sequence: str) -> str:
    """``"Walking 1"`` -> ``"Walking"``; ``"S9/WalkDog"`` -> ``"WalkDog"``."""
    name = sequence.split("/")[-1]
    base = re.sub(r"\s+\d+$", "", name)
    if base not in ACTIONS:
        raise ValueError(f"unknown H36M action in sequence name {sequence!r}")
    return base


@dataclass(frozen=True)
class PoseSamples:
    """A set of N H36M samples (one camera view of one frame each), all as numpy arrays.

    keypoints_2d: ``(N, 17, 2)`` float32 px, the projection of the 3D joints (ground truth): with the lens
        distortion when ``lens`` is ``"h36m"`` (H36M's own 2D), the ideal pinhole projection when ``"pinhole"``.
    pose_3d: ``(N, 17, 3)`` float32 mm, camera frame.
    focal, principal_point: ``(N, 2)`` float32 px. image_size: ``(N, 2)`` int (width, height) px.
    subject: ``(N,)`` int; action: ``(N,)`` int index into :data:`ACTIONS`;
    camera: ``(N,)`` int index into :data:`CAMERA_IDS`; frame: ``(N,)`` int, 0-based row at 50 fps;
    sequence: ``(N,)`` int index into ``sequence_names``.
    distortion: ``(N, 5)`` float32, each sample's camera's lens distortion ``(k1, k2, k3, p1, p2)``
        (:func:`lifter.camera.distort`'s form), whatever ``lens``; None for ideal pinhole cameras (samples made
        without a lens model).
    lens: which 2D ``keypoints_2d`` is (:data:`Lens`).
    """

    keypoints_2d: np.ndarray
    pose_3d: np.ndarray
    focal: np.ndarray
    principal_point: np.ndarray
    image_size: np.ndarray
    subject: np.ndarray
    action: np.ndarray
    camera: np.ndarray
    frame: np.ndarray
    sequence: np.ndarray
    sequence_names: tuple[str, ...]
    distortion: np.ndarray | None = None
    lens: Lens = "h36m"

    def __len__(self) -> int:
        return int(self.keypoints_2d.shape[0])

    @property
    def root(self) -> np.ndarray:
        """``(N, 3)`` mm: the camera-frame pelvis."""
        return self.pose_3d[:, 0]

    @property
    def relative(self) -> np.ndarray:
        """``(N, 17, 3)`` mm: the root-relative pose (root row zero)."""
        return self.pose_3d - self.pose_3d[:, :1]

    @property
    def canonical_depth(self) -> np.ndarray:
        """``(N,)`` mm at F0 = 1000 px: the canonical root depth target."""
        return canonical_depth_from_depth(self.pose_3d[:, 0, 2], focal=self.focal).astype(np.float32)

    def subset(self, index: np.ndarray) -> PoseSamples:
        kw = {f.name: getattr(self, f.name) for f in fields(self)}
        for k, v in kw.items():
            if isinstance(v, np.ndarray):
                kw[k] = v[index]
        return PoseSamples(**kw)

    @property
    def input_distortion(self) -> np.ndarray | None:
        """What to pass :meth:`lifter.Lifter.lift` as ``distortion`` with ``keypoints_2d`` (or detections made on
        H36M's images): the cameras' :attr:`distortion` for H36M's own 2D, None for pinhole 2D."""
        return self.distortion if self.lens == "h36m" else None  # (None too for samples without a lens model)

    def undistort(self, keypoints: np.ndarray) -> np.ndarray:
        """2D ``(N, J, 2)`` px seen through the samples' real cameras (H36M's 2D, detections on H36M's images)
        mapped to the ideal pinhole with the same intrinsics (:func:`lifter.camera.undistort_pixels`); row i uses
        sample i's camera. NaN joints stay NaN."""
        kp = np.asarray(keypoints, np.float64)
        if kp.ndim != 3 or kp.shape[0] != len(self) or kp.shape[-1] != 2:
            raise PoseLifterError(f"keypoints: expected shape ({len(self)}, J, 2), got {kp.shape}")
        if self.distortion is None:  # (ideal pinhole cameras: nothing to undistort)
            return kp.copy()
        return undistort_pixels(kp, focal=self.focal, principal_point=self.principal_point,
                                distortion=self.distortion.astype(np.float64))

    def with_keypoints(self, keypoints_2d: np.ndarray) -> PoseSamples:
        """A copy whose 2D inputs are replaced (e.g. by detections or noisy 2D)."""
        kw = {f.name: getattr(self, f.name) for f in fields(self)}
        kw["keypoints_2d"] = np.asarray(keypoints_2d, np.float32)
        return PoseSamples(**kw)


class H36M:
    """Lazy access to the repackaged Human3.6M folder."""

    def __init__(self, root: str | os.PathLike[str] | None = None) -> None:
        self.root = Path(root) if root is not None else default_h36m_dir()
        if not (self.root / "poses3d_world_17j_mm.npz").is_file():
            raise FileNotFoundError(
                f"Human3.6M data not found at {self.root} (expected poses3d_world_17j_mm.npz there); "
                "pass the folder (--h36m DIR on the command line, H36M(root) in Python) or set POSELIFTER_H36M"
            )
        with open(self.root / "cameras.json") as f:
            self._cameras_raw = json.load(f)["cameras"]
        self._poses = np.load(self.root / "poses3d_world_17j_mm.npz")
        self._decoded: dict[str, np.ndarray] = {}  # int16 arrays: an npz member is decompressed on every access
        compact = self.root / COMPACT_FILE
        kept = json.loads(compact.read_text())["keep_every"] if compact.is_file() else 1
        self.keep_every: int | dict[str, int] = (
            {str(k): int(v) for k, v in kept.items()} if isinstance(kept, dict) else int(kept))
        self.sequences: tuple[str, ...] = tuple(sorted(self._poses.files))

    def camera(self, subject: int, camera_id: str) -> Camera:
        c = self._cameras_raw[f"S{subject}/{camera_id}"]
        return Camera(
            focal=(float(c["f"][0]), float(c["f"][1])),
            principal_point=(float(c["c"][0]), float(c["c"][1])),
            width=int(c["w"]),
            height=int(c["h"]),
            k=tuple(float(v) for v in c["k"]),  # type: ignore[arg-type]
            p=tuple(float(v) for v in c["p"]),  # type: ignore[arg-type]
            R=np.asarray(c["R"], np.float64),
            t=np.asarray(c["t"], np.float64),
            name=f"S{subject}/{camera_id}",
        )

    def _raw(self, sequence: str) -> np.ndarray:
        arr = self._decoded.get(sequence)
        if arr is None:
            if sequence not in self._poses.files:
                raise KeyError(f"unknown H36M sequence {sequence!r}")
            arr = self._decoded[sequence] = self._poses[sequence]
        return arr

    def num_frames(self, sequence: str) -> int:
        """Number of 50-fps frames of a sequence (``"S9/Walking 1"``)."""
        return int(self._raw(sequence).shape[0])

    def poses_world(self, sequence: str, frames: np.ndarray | int | slice | None = None) -> np.ndarray:
        """``(frames, 17, 3)`` float64 mm, world frame, 50 fps (optionally only the given ``frames``)."""
        raw = self._raw(sequence)
        subject = sequence.split("/")[0]
        every = self.keep_every.get(subject, 1) if isinstance(self.keep_every, dict) else self.keep_every
        if every > 1:
            kept = np.arange(len(raw))[slice(None) if frames is None else frames]
            if np.any(np.asarray(kept) % every):
                nth = f"{every}{'th' if 10 <= every % 100 <= 20 else {1: 'st', 2: 'nd', 3: 'rd'}.get(every % 10, 'th')}"
                raise PoseLifterError(f"{self.root} is a compacted copy that keeps only every {nth} frame of "
                                      f"{subject} (see {COMPACT_FILE}); use a stride that is a multiple of "
                                      f"{every} (poselifter train: --train-stride and --val-stride; "
                                      "poselifter evaluate: --stride), or the full Human3.6M folder")
        return (raw if frames is None else raw[frames]).astype(np.float64)

    def sequences_of(self, subjects: Iterable[int]) -> list[str]:
        subs = {f"S{s}" for s in subjects}
        return [s for s in self.sequences if s.split("/")[0] in subs]

    def load(
        self,
        subjects: Sequence[int],
        *,
        stride: int = 5,
        cameras: Sequence[str] = CAMERA_IDS,
        actions: Sequence[str] | None = None,
        max_frames_per_sequence: int | None = None,
        lens: Lens = "h36m",
    ) -> PoseSamples:
        """All samples of the given subjects at a frame stride, for each camera.

        ``max_frames_per_sequence`` keeps only the first frames (after striding) of each sequence:
        small, fixed slices for tests. ``lens``: the 2D with H36M's lens distortion or the pinhole projection
        (:data:`Lens`).
        """
        if stride < 1:
            raise ValueError(f"stride must be >= 1, got {stride}")
        if lens not in LENSES:
            raise PoseLifterError(f"lens must be one of {list(LENSES)}, got {lens!r}")
        acc: dict[str, list[np.ndarray]] = {k: [] for k in ("kp", "p3", "f", "c", "wh", "s", "a", "cam", "fr", "seq",
                                                             "dist")}
        names = self.sequences_of(subjects)
        for seq_idx, seq in enumerate(names):
            subject = int(seq.split("/")[0][1:])
            action = action_of(seq)
            if actions is not None and action not in actions:
                continue
            frames = np.arange(0, self.num_frames(seq), stride)
            if max_frames_per_sequence is not None:
                frames = frames[:max_frames_per_sequence]
            world = self.poses_world(seq, frames)
            for cam_id in cameras:
                cam = self.camera(subject, cam_id)
                p3 = world_to_camera(world, cam.R, cam.t)
                kp = cam.project(p3, distortion=lens == "h36m")
                n = len(frames)
                acc["kp"].append(kp.astype(np.float32))
                acc["p3"].append(p3.astype(np.float32))
                acc["f"].append(np.tile(np.asarray(cam.focal, np.float32), (n, 1)))
                acc["c"].append(np.tile(np.asarray(cam.principal_point, np.float32), (n, 1)))
                acc["wh"].append(np.tile(np.asarray([cam.width, cam.height], np.int32), (n, 1)))
                acc["s"].append(np.full(n, subject, np.int32))
                acc["a"].append(np.full(n, ACTIONS.index(action), np.int32))
                acc["cam"].append(np.full(n, CAMERA_IDS.index(cam_id), np.int32))
                acc["fr"].append(frames.astype(np.int32))
                acc["seq"].append(np.full(n, seq_idx, np.int32))
                acc["dist"].append(np.tile(np.asarray([*cam.k, *cam.p], np.float32), (n, 1)))
        if not acc["kp"]:
            raise ValueError(f"no H36M samples for subjects={list(subjects)} actions={actions}")
        cat = {k: np.concatenate(v) for k, v in acc.items()}
        return PoseSamples(
            keypoints_2d=cat["kp"],
            pose_3d=cat["p3"],
            focal=cat["f"],
            principal_point=cat["c"],
            image_size=cat["wh"],
            subject=cat["s"],
            action=cat["a"],
            camera=cat["cam"],
            frame=cat["fr"],
            sequence=cat["seq"],
            sequence_names=tuple(names),
            distortion=cat["dist"],
            lens=lens,
        )

    def load_protocol(self, protocol: int, split: str, *, stride: int, **kw) -> PoseSamples:
        """Samples of ``split`` ("train" or "test") of Protocol 1 or 2."""
        if protocol not in PROTOCOLS:
            raise ValueError(f"unknown protocol {protocol}; expected one of {sorted(PROTOCOLS)}")
        if split not in ("train", "test"):
            raise ValueError(f"split must be 'train' or 'test', got {split!r}")
        train, test = PROTOCOLS[protocol]
        return self.load(train if split == "train" else test, stride=stride, **kw)
