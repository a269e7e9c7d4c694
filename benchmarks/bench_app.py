#!/usr/bin/env python
"""Benchmarks of the app, server side: drag -> updated scene with the per-joint uncertainty clouds, and playback.

Starts the app on 127.0.0.1 (free port), connects one fake browser tab (a real viser ClientHandle),
sets the noise level to 1 (64 noisy draws lifted per update) and fires ``--events`` drag events on
the left wrist through the joint's registered ``on_drag`` callback. Each event is timed from the call
until the callback returns: pixel from the pointer ray, lift of 1 + 64 poses in one batch, analytic
root off, metrics, the 2D panel image, the per-joint clouds, the readout with its side / top views and every
scene update queued for the client.

Playback: the demo motion (17 joints, no Human3.6M needed) is played on the same tab for ``--play-seconds`` at
25 redraws per second (noise level 0, and again at noise level 1 with the cloud), and, where the data are present,
Human3.6M S9 "Walking 1" (50-fps frames, every 2nd shown) on a headless view; reported: frames shown per second and
the server-side time of each frame (sample, lift, scene, readout).

Video (``--video clip.mp4``): the clip is uploaded on the same tab (the real BlazePose detector: lifted, tracked,
smoothed) and played; the upload's time per frame and the playback are reported, not checked.

Models (``--compare NAME [NAME ...]``): the drag run is repeated on the same tab with each named model in turn, in
rounds of 50 events that alternate between the models, so that the machine's speed of the moment is shared; the
ratio of each model's p50 to the app's default's is reported (the absolute milliseconds follow the machine, the
ratio follows the code). Playback is timed on the default only.

Usage: ``OMP_NUM_THREADS=1 python benchmarks/bench_app.py [--events 300] [--threads 1] [--target-ms 25]
[--compare universal] [--video clip.mp4] [--json out.json]``
Exit status 1 when the drag p95 exceeds the target or a noise-free playback shows fewer than 24 frames per second
(unless ``--no-check``; the noise-1 playback, 65 poses lifted per frame, is reported only).
"""

from __future__ import annotations

import argparse
import gc
import json
import platform
import time

import numpy as np


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--events", type=int, default=300)
    p.add_argument("--warmup", type=int, default=20)
    p.add_argument("--threads", type=int, default=1, help="torch threads")
    p.add_argument("--cloud", type=int, default=64)
    p.add_argument("--target-ms", type=float, default=25.0)
    p.add_argument("--play-seconds", type=float, default=8.0)
    p.add_argument("--no-h36m", action="store_true",
                   help="skip the Human3.6M playback run even if the data are present")
    p.add_argument("--no-check", action="store_true")
    p.add_argument("--compare", nargs="*", default=[], metavar="MODEL",
                   help="also time the drags with these models (the app's model menu), alternating with the default "
                        "in rounds of 50 events; reports each one's p50 / p95 and p50 ratio to the default's")
    p.add_argument("--video", default=None, help="also upload this video on the tab (the real detector, the `detect` "
                   "extra) and play it: upload time per frame and playback are reported (not checked)")
    p.add_argument("--json", default=None, help="also write the result to this JSON file")
    args = p.parse_args()

    import torch
    import viser
    from poselifter_app.scene import image_plane
    from poselifter_app.testing import FakeTab, local_server, wait_for
    from poselifter_app.viewer import PoseLifterApp
    from poselifter_app.viser_hooks import drag_callback

    torch.set_num_threads(args.threads)
    server = local_server()
    app = PoseLifterApp(server, h36m_root=None)
    tab = FakeTab(server)
    gc.freeze()  # as poselifter-app does after startup (app/main.py)
    try:
        assert wait_for(lambda: len(app.views) == 1), "fake tab did not connect"
        view = next(iter(app.views.values()))
        view.gui.noise.cloud.value = args.cloud
        view.gui.noise.level.value = 1.0
        assert view.frame is not None and view.frame.cloud is not None and view.frame.cloud.shape[0] == args.cloud
        default_model = view.state.model
        models = [default_model, *[m for m in args.compare if m != default_model]]
        unknown = [m for m in models if m not in view.gui.lift.model.options]
        if unknown:
            raise SystemExit(f"--compare: unknown model(s) {unknown}; the app offers "
                             f"{list(view.gui.lift.model.options)}")
        j = 13
        cb = drag_callback(view.scene.pose.joints2d[j])
        cam = view.state.sample.camera
        R = np.asarray(cam.R)
        C = -R.T @ np.asarray(cam.t) / 1000.0
        start = view.state.keypoints[j].copy()
        by_model: dict[str, list[float]] = {m: [] for m in models}

        def use(model: str) -> None:
            if view.state.model != model:
                view.gui.lift.model.value = model  # the model menu, as a click does
                assert wait_for(lambda: view.state.model == model), f"the app did not switch to {model}"
            assert view.state.noise_level == 1.0 and view.state.cloud_samples == args.cloud, \
                "the switch changed the noise"

        def drag(i: int) -> float:
            uv = start + 60.0 * np.array([np.cos(i / 7.0), np.sin(i / 5.0)])
            p_world = R.T @ image_plane(view.state, uv) + C
            ev = viser.SceneNodeDragEvent(client=view.target, client_id=view.target.client_id,
                                          target=view.scene.pose.joints2d[j],
                                          phase="update", instance_index=None, start_position=tuple(p_world),
                                          start_screen_pos=(0.5, 0.5), end_position=tuple(p_world),
                                          end_screen_pos=(0.5, 0.5), button="left", modifier=None)
            n = view.update_count
            t0 = time.perf_counter()
            cb(ev)
            dt = time.perf_counter() - t0
            assert view.update_count == n + 1, "the drag did not update the skeleton"
            return 1e3 * dt

        for model in models:
            use(model)
            for i in range(args.warmup):
                drag(i)
        done = 0
        while done < args.events:  # rounds of 50 events, alternating the models on the same machine moment
            n_round = min(50, args.events - done)
            for model in models:
                use(model)
                drag(done)  # (the first drag after a switch is not timed)
                by_model[model] += [drag(args.warmup + done + i) for i in range(n_round)]
            done += n_round
        use(default_model)
        drag(0)
        compute_ms, scene_ms = view.timing.compute_ms, view.timing.scene_ms
        times = by_model[default_model]
        compared = {m: {"p50_ms": round(float(np.percentile(v, 50)), 2),
                        "p95_ms": round(float(np.percentile(v, 95)), 2),
                        "p50_ratio_to_default": round(float(np.percentile(v, 50) / np.percentile(times, 50)), 3)}
                    for m, v in by_model.items() if m != default_model}
        t = np.array(times)
        play = {}
        from poselifter_app.samples import default_h36m_root

        def play_for(pv, seconds: float) -> dict:
            pv.play_ms.clear()
            pv.play_shown.clear()
            pv.gui.play.play.value = True  # click: play (a demo still plays the demo motion)
            time.sleep(seconds)
            pv.gui.play.play.value = True  # pause
            shown, ms = np.array(pv.play_shown), np.array(pv.play_ms)
            if len(ms) < 2:
                return {"frames": int(len(ms)), "fps": 0.0}
            return {"frames": int(len(ms)), "fps": round(float((len(shown) - 1) / (shown[-1] - shown[0])), 2),
                    "frame_ms_p50": round(float(np.percentile(ms, 50)), 2),
                    "frame_ms_p95": round(float(np.percentile(ms, 95)), 2), "frame_ms_max": round(float(ms.max()), 2),
                    "slowest_frame": int(np.argmax(ms)), "first_frame_ms": round(float(ms[0]), 2)}

        for level in (0.0, 1.0):
            view.select_demo("walking")
            view.gui.noise.level.value = level
            play[f"demo_motion_noise_{level:g}"] = play_for(view, args.play_seconds)
        if args.video:
            from pathlib import Path

            view.gui.noise.level.value = 0.0
            t0 = time.perf_counter()
            ok = view.load_upload(Path(args.video).name, Path(args.video).read_bytes())
            up_s = time.perf_counter() - t0
            assert ok, view.messages[-1]
            seq = view.sequence()
            play["video_upload"] = {"file": Path(args.video).name, "frames": seq.num_frames,
                                    "upload_s": round(up_s, 2),
                                    "upload_ms_per_frame": round(1e3 * up_s / seq.num_frames, 1),
                                    "pipeline_ms_per_frame": round(1e3 * (seq.record.seconds_per_frame or 0), 1),
                                    "playback": play_for(view, args.play_seconds)}
        if default_h36m_root() is not None and not args.no_h36m:  # (read at run time, never copied)
            h_server = local_server()
            h_tab = None
            try:
                h_app = PoseLifterApp(h_server, h36m_root=default_h36m_root())
                h_tab = FakeTab(h_server)
                assert wait_for(lambda: len(h_app.views) == 1), "fake tab did not connect"
                hv = next(iter(h_app.views.values()))
                assert h_app.h36m is not None
                hv.select_h36m(subject=9, sequence="Walking 1", camera=h_app.h36m.camera_ids[0], frame=0)
                play["h36m_S9_Walking_1_noise_0"] = play_for(hv, args.play_seconds)
            finally:
                if h_tab is not None:
                    h_tab.close()
                h_server.stop()
        res = {"events": len(t), "cloud": args.cloud, "threads": args.threads,
               "p50_ms": round(float(np.percentile(t, 50)), 2),
               "p95_ms": round(float(np.percentile(t, 95)), 2), "max_ms": round(float(t.max()), 2),
               "mean_ms": round(float(t.mean()), 2), "target_p95_ms": args.target_ms,
               "last_compute_ms": round(compute_ms, 2), "last_scene_ms": round(scene_ms, 2),
               "model": default_model, "compared": compared, "cpu": platform.processor() or platform.machine(),
               "playback_target_fps": 25.0, "playback": play}
        print(json.dumps(res))
        if args.json:
            with open(args.json, "w") as fh:
                json.dump(res, fh, indent=1)
    finally:
        tab.close()
        server.stop()
    if not args.no_check and res["p95_ms"] > args.target_ms:
        print(f"FAIL: p95 {res['p95_ms']} ms > {args.target_ms} ms")
        return 1
    if not args.no_check and any(v["fps"] < 24.0 for k, v in res["playback"].items() if k.endswith("noise_0")):
        print(f"FAIL: playback below 24 fps: {res['playback']}")
        return 1
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
