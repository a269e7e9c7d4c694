"""A second person back in view after being hidden: in which frame is the video's lift of them back? Measured on a
clip built at run time from two Human3.6M demo photos (nothing from Human3.6M is written but a temporary clip,
deleted after).

    python scripts/returning_person.py [--h36m ../shared/data/h36m] [--fps 10] [--hidden 10:20] [--frames 30]

Two demo photos of one camera, side by side (each person in their own half), are the frames of a clip at ``--fps``;
the right half is blacked out in the frames ``--hidden`` (start:stop; default 1 s at 10 fps), as a person behind a
wall. The clip goes through :func:`lifter.video.lift_video` (BlazePose, the default lifter, the left photo's camera:
the right person's 3D is not the point) with its default search schedule, and with a full search in every frame
(``search_every_s=0``). Prints, for each, the first frame from ``stop`` on whose lift has two people again, and the
milliseconds per frame.
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


def main() -> int:
    import cv2

    ap = argparse.ArgumentParser(description=(__doc__ or "").split("\n")[0])
    ap.add_argument("--h36m", type=Path, default=None)
    ap.add_argument("--fps", type=float, default=10.0)
    ap.add_argument("--hidden", default="10:20", help="start:stop frames with the right half black")
    ap.add_argument("--frames", type=int, default=30)
    args = ap.parse_args()
    start, stop = (int(v) for v in args.hidden.split(":"))
    demo, ann, focal, pp, _ = demo_frames(args.h36m)
    cam = ann["camera"][0]
    idx = [i for i in range(len(ann["image"])) if ann["camera"][i] == cam][:2]
    left, right = (cv2.imread(str(demo / str(ann["image"][i]))) for i in idx)
    model, est = Lifter.from_pretrained(), get_estimator("blazepose")
    print(f"{ann['image'][idx[0]]} + {ann['image'][idx[1]]} side by side, {args.frames} frames at {args.fps:g} fps, "
          f"the right person hidden in frames {start}-{stop - 1}; BlazePose, {model.name}")
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "two.avi"
        h, w = left.shape[:2]
        vw = cv2.VideoWriter(str(path), cv2.VideoWriter.fourcc(*"MJPG"), args.fps, (2 * w, h))
        for i in range(args.frames):
            frame = np.concatenate([left, right], axis=1)
            if start <= i < stop:
                frame[:, w:] = 0
            vw.write(frame)
        vw.release()
        for label, every in (("default search schedule", None), ("full search in every frame", 0.0)):
            kw = {} if every is None else {"search_every_s": every}
            rec = lift_video(path, lifter=model, estimator=est, focal=focal[idx[0]], principal_point=pp[idx[0]],
                             **kw)
            back = next((fr.index for fr in rec.frames if fr.index >= stop and len(fr.people) >= 2), None)
            late = "never" if back is None else f"frame {back} ({(back - stop) / args.fps:.2f} s after it is in view)"
            print(f"  {label}: two people again from {late}; {1e3 * (rec.seconds_per_frame or 0):.0f} ms per frame")
    est.close()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
