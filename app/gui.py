"""Typed groups of GUI handles, one per part of the panel, and the builder of a tab's panels.

Layout (made for 1400 x 900 and larger): the controls in the main panel, docked right, as tabs
(**Lift** — model, focal, noise; **Sample** — source, pickers, playback; **Drag** — 2D joints; **File** —
upload / download); the numbers in a second panel docked above it (**Readout**), which never scrolls with the
controls: the readout (``Focal N px``, root, canonical depth, spread, errors), status messages and a small
side / top view of the lifted pose (the 3D response while dragging head-on).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, cast

import numpy as np
import viser

from lifter.detect import MIN_PERSON_SCORE
from lifter.skeleton import JOINT_NAMES

from .core import CLOUD_SAMPLES, DEFAULT_SEED, FOCAL_MAX_PX, FOCAL_MIN_PX, MAX_CLOUD_SAMPLES, MAX_SEED, NOISE_MAX
from .keys import NO_PHOTO, H36MKey
from .video import VIDEO_MAX_SECONDS

if TYPE_CHECKING:  # (not exported at viser 1.1.1's top level; annotations only)
    from viser._gui_handles import GuiProgressBarHandle

SOURCE_LABELS: dict[str, str] = {"demo": "demo sample", "motion": "demo motion", "h36m": "Human3.6M",
                                 "upload": "upload"}
"""Sample sources (keys of :attr:`SampleGui.source` options are the labels' keys)."""
SPEED_MIN, SPEED_MAX = 0.1, 4.0
LEGEND = ("<small>3D: lifted joints and their uncertainty clouds in each joint's colour (subject's left blue, "
          "right red/orange, centre grey) · <b style='color:#28c83c'>ground truth</b> · "
          "<b style='color:#ff8c00'>analytic root</b> · <b style='color:#c8a800'>root ray / trajectory</b>. "
          "2D: <b style='color:#28c83c'>ground truth</b> · <b style='color:#f09600'>detected</b> · "
          "<b style='color:#a03cdc'>noisy (lifted)</b> · current joints in their joint colours.</small>")


@dataclass
class ReadoutGui:
    """The readout panel: numbers, messages and the side / top view of the lifted pose."""

    panel: Any
    readout: viser.GuiMarkdownHandle
    status: viser.GuiMarkdownHandle
    response: viser.GuiImageHandle
    spread: viser.GuiMarkdownHandle


@dataclass
class SampleGui:
    source: viser.GuiDropdownHandle[str]
    demo: viser.GuiDropdownHandle[str]
    input: viser.GuiDropdownHandle[str]
    image: viser.GuiImageHandle
    subject: viser.GuiDropdownHandle[str] | None
    sequence: viser.GuiDropdownHandle[str] | None
    camera: viser.GuiDropdownHandle[str] | None
    photo: viser.GuiDropdownHandle[str] | None

    @property
    def h36m_pickers(self) -> list[Any]:
        return [h for h in (self.subject, self.sequence, self.camera, self.photo) if h is not None]


@dataclass
class PlayGui:
    frame: viser.GuiSliderHandle[int]
    position: GuiProgressBarHandle = field(repr=False)  # (viser 1.1.1's repr of it raises: it has no label)
    """Where in the sequence the frame shown is (0–100 %): it moves while playing; the frame box does not (a frame
    sent to the box while someone types in it mixes with the keys), and shows the frame once playback stops."""
    play: viser.GuiButtonHandle
    speed: viser.GuiSliderHandle[float]
    trail: viser.GuiCheckboxHandle
    info: viser.GuiMarkdownHandle


FOCAL_STEPS: tuple[str, str] = ("÷ 2", "× 2")
"""The focal buttons' labels: halve, double (:class:`LiftGui`)."""


@dataclass
class LiftGui:
    model: viser.GuiDropdownHandle[str]
    focal: viser.GuiSliderHandle[float]
    focal_steps: viser.GuiButtonGroupHandle
    """Halve or double the focal length (a teacher trial: the slider is linear, 100-500 px about 15 screen pixels of
    its track)."""
    focal_reset: viser.GuiButtonHandle
    auto_frame: viser.GuiCheckboxHandle
    analytic: viser.GuiCheckboxHandle
    gt: viser.GuiCheckboxHandle
    overview: viser.GuiButtonHandle


@dataclass
class NoiseGui:
    level: viser.GuiSliderHandle[float]
    cloud: viser.GuiSliderHandle[int]
    seed: viser.GuiNumberHandle[int]
    resample: viser.GuiButtonHandle


@dataclass
class JointGui:
    person: viser.GuiDropdownHandle[str]
    """Which person of the image is draggable (``"person 1"`` = the largest); disabled with one person."""
    joint: viser.GuiDropdownHandle[str]
    uv: viser.GuiVector2Handle
    head_on: viser.GuiButtonHandle
    undo: viser.GuiButtonHandle
    """Undo the last drag (a mouse drag from press to release, a typed position, or a reset) of the pose shown."""
    reset: viser.GuiButtonHandle


@dataclass
class FileGui:
    upload: viser.GuiUploadButtonHandle
    min_score: viser.GuiSliderHandle[float]
    about: viser.GuiMarkdownHandle
    download_json: viser.GuiButtonHandle
    download_glb: viser.GuiButtonHandle


@dataclass
class Gui:
    """All GUI handles of one tab."""

    readout: ReadoutGui
    sample: SampleGui
    play: PlayGui
    lift: LiftGui
    noise: NoiseGui
    joints: JointGui
    files: FileGui

    def value_handles(self) -> list[Any]:
        """The value controls whose last value :func:`poselifter_app.session.apply_controls` applies."""
        return [self.lift.model, self.sample.input, self.lift.focal, self.noise.level, self.noise.seed,
                self.noise.cloud, self.lift.analytic, self.joints.person]


def build_gui(gui: viser.GuiApi, *, demo_names: list[str], sources: list[str], models: list[str], model: str,
              h36m: Any | None, error_model_name: str, max_upload_mib: int) -> Gui:
    """Build a tab's panels (see the module docstring) on ``gui`` (a client's or the server's GUI)."""
    main = gui.main_panel
    main.dock_right()
    main.set_width(400)
    panel = gui.add_panel()
    with panel.add_tab("Readout", viser.Icon.GAUGE):
        # the side / top views first: long notes and people lines below them never push them out of sight while
        # dragging (a user trial: after a two-person upload only their top border showed)
        response = gui.add_image(np.full((120, 360, 3), 255, np.uint8), label=None, format="jpeg", jpeg_quality=80)
        readout = ReadoutGui(panel=panel, readout=gui.add_markdown(""), status=gui.add_markdown(""), response=response,
                             spread=gui.add_markdown(""))
        gui.add_markdown(LEGEND)
        # The slider's value bubble covers the field above it while dragging; the number box beside each slider
        # shows the value already (viser's client renders HTML as given: this style applies to the page).
        gui.add_html("<style>.mantine-Slider-label{display:none !important}</style>")
    panel.dock_above(main)

    tabs = gui.add_tab_group()
    with tabs.add_tab("Lift", viser.Icon.ADJUSTMENTS):
        lift = LiftGui(
            model=gui.add_dropdown("model", models or ["(none)"], initial_value=model or (models or ["(none)"])[0],
                                   hint="shipped weights (assets/models.json)"
                                   + (f"; the app opened on {model}" if model else "")),
            focal=gui.add_slider("focal length (px)", FOCAL_MIN_PX, FOCAL_MAX_PX, 1.0, 1000.0,
                                 # (1k and 2k: a browser trial's teacher found 500-2000 px a 50-px stretch
                                 # of the track, without a landmark)
                                 marks=((FOCAL_MIN_PX, "100"), (1000.0, "1k"), (2000.0, "2k"), (FOCAL_MAX_PX, "6k")),
                                 # (short: its tooltip stays up while the box is typed in, over the readout)
                                 hint="f in px (sqrt(fx fy)): the person slides along its viewing rays (the root's in "
                                      "yellow), farther as f grows. A paper model (gt) keeps Z = f * Z/f exactly; the "
                                      "default reads the rays too, so its Z/f shifts (readout)"),
            focal_steps=gui.add_button_group("focal", FOCAL_STEPS,
                                             hint="halve or double the focal length (within the slider's range): "
                                                  "the person twice as near or far, Z = f * Z/f"),
            focal_reset=gui.add_button("reset focal to camera", hint="back to the sample camera's focal length"),
            auto_frame=gui.add_checkbox("keep skeleton in view", True,
                                        hint="reframe the 3D view when the lifted skeleton leaves it"),
            analytic=gui.add_checkbox("analytic root", False,
                                      hint="also show the weak-perspective analytic-root skeleton (dashed orange)"),
            gt=gui.add_checkbox("show ground truth", True),
            overview=gui.add_button("reset 3D view", icon=viser.Icon.HOME,
                                    hint="camera and person in view, from behind the camera"),
        )
        noise = NoiseGui(
            level=gui.add_slider("noise level", 0.0, NOISE_MAX, 0.05, 0.0, marks=((0.0, "0"), (1.0, "1"), (3.0, "3")),
                                 hint="mixture 2D noise: 0 clean · 1 as fitted · 3 exaggerated"),
            cloud=gui.add_slider("cloud samples", 0, MAX_CLOUD_SAMPLES, 1, CLOUD_SAMPLES,
                                 marks=((0, "0"), (MAX_CLOUD_SAMPLES, f"{MAX_CLOUD_SAMPLES}")),
                                 hint="noisy 2D draws lifted for the per-joint uncertainty clouds"),
            seed=gui.add_number("seed", DEFAULT_SEED, step=1, min=0, max=MAX_SEED),
            resample=gui.add_button("resample noise", hint="seed + 1"),
        )
        gui.add_markdown(f"<small>error model: {error_model_name}</small>")
    with tabs.add_tab("Sample", viser.Icon.PHOTO):
        src_opts = [SOURCE_LABELS[s] for s in sources if s != "upload"]  # ("upload" joins after the first one)
        source = gui.add_dropdown("source", src_opts, initial_value=src_opts[0])
        demo = gui.add_dropdown("demo sample", demo_names, initial_value=demo_names[0])
        if h36m is not None:
            subj = [f"S{s}" for s in h36m.subjects]
            subject = gui.add_dropdown("subject", subj, initial_value=subj[-2] if len(subj) > 1 else subj[0])
            seqs = h36m.sequences(int(subject.value[1:]))
            sequence = gui.add_dropdown("sequence", seqs, initial_value=seqs[0])
            camera = gui.add_dropdown("camera", list(h36m.camera_ids), initial_value=h36m.camera_ids[0])
            photos = [NO_PHOTO] + [H36MKey(*f).photo_entry for f in h36m.photo_frames()]
            photo = gui.add_dropdown("frame with photo", photos, initial_value=NO_PHOTO)
        else:
            subject = sequence = camera = photo = None
        play = PlayGui(
            frame=gui.add_slider("frame", 0, 1, 1, 0, hint="frame of the sequence (Human3.6M at 50 fps, demo motion "
                                 "at 25 fps, an uploaded video or keypoint sequence at its own rate; frames "
                                 "with nobody are left out). While playing, the bar below shows the frame and "
                                 "the box is left to you (empty until you type or drag): type a frame there (or "
                                 "drag) to jump, and playback goes on from it; paused, the box shows the frame"),
            position=gui.add_progress_bar(0.0),
            play=gui.add_button("play", icon=viser.Icon.PLAYER_PLAY, hint="play / pause the sequence"),
            speed=gui.add_slider("speed", SPEED_MIN, SPEED_MAX, 0.05, 1.0, marks=((SPEED_MIN, "0.1×"), (1.0, "1×"),
                                                                                   (SPEED_MAX, "4×"))),
            trail=gui.add_checkbox("root trajectory", True, hint="draw the lifted root's path in camera space"),
            info=gui.add_markdown(""),
        )
        inp = gui.add_dropdown("2D input", ["ground truth", "SH detection"], initial_value="ground truth",
                               hint="ground-truth 2D, or the Stacked-Hourglass detection (Human3.6M frames that have "
                                    "one)")
        image = gui.add_image(np.zeros((60, 80, 3), np.uint8), label="input 2D", format="jpeg", jpeg_quality=85)
        sample = SampleGui(source=source, demo=demo, input=cast(viser.GuiDropdownHandle[str], inp), image=image,
                           subject=subject, sequence=sequence, camera=camera, photo=photo)
    with tabs.add_tab("Drag", viser.Icon.HAND_FINGER):
        gui.add_markdown("<small>Drag the joints on the image plane in the 3D view. <b>head-on image view</b> looks "
                         "straight at them for precise dragging; the readout's side / top views show the 3D "
                         "response.</small>")
        joints = JointGui(
            head_on=gui.add_button("head-on image view", icon=viser.Icon.ZOOM_IN,
                                   hint="look straight at the 2D joints on the image plane"),
            person=cast(viser.GuiDropdownHandle[str], gui.add_dropdown(
                "person", ["person 1"], initial_value="person 1", disabled=True,
                hint="photos with several people: whose joints are draggable (1 = largest; in a video, the track's "
                     "number); everyone is lifted into the same camera space")),
            joint=gui.add_dropdown("joint", list(JOINT_NAMES), initial_value=JOINT_NAMES[0]),
            uv=gui.add_vector2("joint (u, v) px", (0.0, 0.0), step=1.0,
                               hint="type a position to move the joint (applied when the typing pauses)"),
            undo=gui.add_button("undo last drag", hint="the joints as they were before the last drag, typed position "
                                "or reset of this pose"),
            reset=gui.add_button("reset dragged joints"),
        )
    with tabs.add_tab("File", viser.Icon.FILE):
        files = FileGui(
            upload=gui.add_upload_button(
                "upload photo, video or keypoint JSON", icon=viser.Icon.UPLOAD,
                mime_type="image/*,video/*,.json,application/json",
                hint=f"a photo (everyone's 2D joints by MediaPipe BlazePose, draggable), a short video (played with "
                     f"every person's skeleton and root trajectory; the first {VIDEO_MAX_SECONDS:g} s) or a 2D "
                     f"keypoint JSON (one pose, several people or 'frames') as `poselifter lift` reads it; at most "
                     f"{max_upload_mib} MiB"),
            min_score=gui.add_slider("min person score", 0.0, 1.0, 0.05, MIN_PERSON_SCORE,
                                     marks=((0.0, "0"), (MIN_PERSON_SCORE, f"{MIN_PERSON_SCORE:g}"), (1.0, "1")),
                                     hint="for the next upload: a detected person (or a keypoint file's person with "
                                          "0-1 scores) whose mean joint score is below this is left out as no person; "
                                          "0 keeps every one (BlazePose gives real people 0.84-1 in photos)"),
            download_json=gui.add_button("download result (JSON)", icon=viser.Icon.DOWNLOAD,
                                         hint="the current lift with the fields `poselifter lift` writes (everyone "
                                              "in the image; for an uploaded video the whole sequence)"),
            download_glb=gui.add_button("download skeleton (GLB)", icon=viser.Icon.DOWNLOAD,
                                        hint="the lifted skeletons as meshes (metres, y-up; a video: animated)"),
            # (viser's buttons show no hints: a trial saw neither the upload limits nor the GLB's frame)
            about=gui.add_markdown(f"<small>Uploads: at most {max_upload_mib} MiB; a video's first "
                                   f"{VIDEO_MAX_SECONDS:g} s. JSON: the fields of `poselifter lift` (mm, camera frame: "
                                   "+x right, +y down, +z forward). GLB: metres, y-up, (x, -y, -z) of the JSON's "
                                   "frame.</small>"),
        )
    # One decimal in the focal and joint boxes: with the precision viser derives from step 1 (0 digits) the box drops
    # a typed decimal point, so "1144.5" arrived as 11445 px. The step stays 1 px (arrow keys, slider).
    lift.focal.precision = 1
    joints.uv.precision = 1
    return Gui(readout=readout, sample=sample, play=play, lift=lift, noise=noise, joints=joints, files=files)
