"""A person hidden for longer than the tracker's 1-s timeout: one track or two? Measured on a clip built at run
time from one of the Human3.6M demo photos (nothing from Human3.6M is written but a temporary clip, deleted after).

    python scripts/hidden_person.py [--h36m ../shared/data/h36m] [--frame 4] [--hidden 30:80]

The photo's person (the box around them, grown by 10 %) is pasted onto the photo's own background (the person
inpainted away, OpenCV's Telea) 6 px further right in each of 100 frames at 25 frames/s, and left out in the
frames ``--hidden`` (start:stop; default 2 s, as behind a wall). The clip goes through :func:`lifter.video.lift_video`
(BlazePose, the default lifter, the photo's camera) twice: with the tracks taken up again where the 3D root leads
(:data:`lifter.video.REJOIN_MAX_S`) and without (``rejoin_s=0``). Prints each track's frames and the record's gap
note.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

sys.path.insert(0, str(Path(__file__).resolve().parent))
from eval_cascade import demo_frames  # noqa: E402

from lifter.api import Lifter  # noqa: E402
from lifter.detect import get_estimator  # noqa: E402
from lifter.video import lift_video  # noqa: E402

FPS, N, STEP_PX = 25.0, 100, 6


def build_clip(image: np.ndarray, box_xywh: np.ndarray, hidden: range, path: Path) -> None:
    """The clip (module docstring) as an MJPG AVI at ``path``; ``image`` BGR."""
    import cv2

    x, y, w, h = (float(v) for v in box_xywh)
    def grown(g: float) -> tuple[int, int, int, int]:
        return (max(0, int(x - g * w / 2)), max(0, int(y - g * h / 2)), int(x + w * (1 + g / 2)),
                int(y + h * (1 + g / 2)))

    mask = np.zeros(image.shape[:2], np.uint8)
    x0, y0, x1, y1 = grown(0.25)
    mask[y0:y1, x0:x1] = 255
    background = cv2.inpaint(image, mask, 9, cv2.INPAINT_TELEA)
    x0, y0, x1, y1 = grown(0.1)
    crop = image[y0:y1, x0:x1]
    H, W = image.shape[:2]
    vw = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"MJPG"), FPS, (W, H))
    for k in range(N):
        frame = background.copy()
        if k not in hidden:
            dx = -300 + STEP_PX * k
            tx0, tx1 = max(0, x0 + dx), min(W, x1 + dx)
            if tx1 > tx0:
                frame[y0:y1, tx0:tx1] = crop[:, tx0 - (x0 + dx):tx1 - (x0 + dx)]
        vw.write(frame)
    vw.release()


def main() -> None:
    import cv2

    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--h36m", type=Path, default=None)
    ap.add_argument("--frame", type=int, default=4, help="which demo photo (index)")
    ap.add_argument("--hidden", default="30:80", help="the frames the person is hidden in, start:stop")
    ap.add_argument("--model", default="default")
    args = ap.parse_args()
    a, b = (int(v) for v in args.hidden.split(":"))
    demo, ann, focal, pp, _ = demo_frames(args.h36m)
    i = args.frame
    image = cv2.imread(str(demo / str(ann["image"][i])))
    lifter, est = Lifter.load(args.model), get_estimator("blazepose")
    print(f"{ann['image'][i]}: {N} frames at {FPS:g} frames/s, the person moving {STEP_PX} px a frame, hidden in "
          f"frames {a}-{b - 1} ({(b - a) / FPS:g} s); BlazePose, {lifter.name}, the photo's focal and principal point")
    with tempfile.TemporaryDirectory() as tmp:
        clip = Path(tmp) / "hidden.avi"
        build_clip(image, ann["bbox_xywh"][i], range(a, b), clip)
        for label, rejoin in (("taken up again where the root leads (default)", None), ("rejoin_s=0", 0.0)):
            kw = {} if rejoin is None else {"rejoin_s": rejoin}
            rec = lift_video(clip, lifter=lifter, estimator=est, focal=focal[i], principal_point=pp[i], **kw)
            print(f"\n{label}:")
            for tid, seen in sorted(rec.tracks().items()):
                idx = [f for f, _ in seen]
                runs, start = [], idx[0]
                for p, q in zip(idx, idx[1:] + [None]):
                    if q != p + 1:
                        runs.append(f"{start}-{p}" if p != start else f"{p}")
                        start = q
                z = [float(s.root[2]) for _, s in seen]
                print(f"  track {tid}: frames {', '.join(runs)} ({len(idx)} frames; root depth {min(z):.0f}-"
                      f"{max(z):.0f} mm)")
            for w in rec.warnings:
                if "found again" in w or "missing from" in w:
                    print(f"  note: {w}")
    if hasattr(est, "close"):
        est.close()


if __name__ == "__main__":
    main()
