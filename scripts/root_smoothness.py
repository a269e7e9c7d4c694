"""How smoothly a lifter's root depth follows the camera (a user trial found the default's detected networks rough).

On Protocol 1's test poses (S9, S11, every ``--stride``-th frame, all four cameras), seen through pinhole cameras
with their true intrinsics (exact 2D, so only the lifter varies), the 2D is kept and the camera is changed a little:

- ``pp +10 px y`` / ``pp +10 px x``: the principal point moved by 10 px (the camera turned by about 0.5 deg; the
  same scene, so the root depth should not move): ``|Z' / Z - 1|``;
- ``focal x1.02``: the focal length 2 % longer (the same 2D is then a person 2 % farther): ``|Z' / (1.02 Z) - 1|``.

Each in %, as the median, 95th and 99th percentile and maximum over the poses, for each model told ``--source``;
beside it the model's MRPE on the same exact 2D. Models: shipped names, checkpoint paths, or ``label=path``.

    python scripts/root_smoothness.py [MODEL ...] [--source detected] [--stride 50] [--h36m PATH]
"""

from __future__ import annotations

import argparse

import numpy as np

from lifter import Lifter
from lifter.camera import project
from lifter.cli._help import add_h36m_arguments
from lifter.cli.evaluate import split_label
from lifter.data import H36M


def smoothness(lifter: Lifter, kp: np.ndarray, focal: np.ndarray, pp: np.ndarray, truth: np.ndarray, *,
               source: str) -> dict[str, np.ndarray | float]:
    """Per-pose changes (%) of the root depth for each camera change; ``mrpe`` (mm) at the true camera."""
    def z(f: np.ndarray, c: np.ndarray) -> np.ndarray:
        return lifter.lift(kp, focal=f, principal_point=c, source=source, warn=False).root

    r0 = z(focal, pp)
    out: dict[str, np.ndarray | float] = {"mrpe": float(np.linalg.norm(r0 - truth, axis=-1).mean())}
    out["pp +10 px y"] = 100 * np.abs(z(focal, pp + [0.0, 10.0])[:, 2] / r0[:, 2] - 1)
    out["pp +10 px x"] = 100 * np.abs(z(focal, pp + [10.0, 0.0])[:, 2] / r0[:, 2] - 1)
    out["focal x1.02"] = 100 * np.abs(z(focal * 1.02, pp)[:, 2] / (1.02 * r0[:, 2]) - 1)
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("models", nargs="*", default=["default"])
    ap.add_argument("--source", choices=["detected", "clean"], default="detected")
    add_h36m_arguments(ap, stride=50)
    args = ap.parse_args()
    data = H36M(args.h36m)
    s = data.load_protocol(1, "test", stride=args.stride)
    f, c = s.focal.astype(np.float64), s.principal_point.astype(np.float64)
    kp = project(s.pose_3d.astype(np.float64), focal=f, principal_point=c)  # pinhole: exact for these cameras
    print(f"Protocol 1 test poses, stride {args.stride} ({len(s)} poses, 4 cameras, exact pinhole 2D), told "
          f"{args.source!r}: root depth change in % (median / p95 / p99 / max) when only the camera changes")
    print("| model | MRPE (mm) | pp +10 px y | pp +10 px x | focal x1.02 |\n|---|---|---|---|---|")
    for spec in args.models:
        label, ref = split_label(spec)
        m = Lifter.load(ref)
        r = smoothness(m, kp, f, c, s.root.astype(np.float64), source=args.source)
        cells = [" / ".join(f"{v:.2f}" for v in (np.median(r[k]), *np.percentile(r[k], [95, 99]), np.max(r[k])))
                 for k in ("pp +10 px y", "pp +10 px x", "focal x1.02")]
        print(f"| {label} | {r['mrpe']:.1f} | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main()
