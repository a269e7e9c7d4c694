"""Pure session transitions: what a tab's state becomes after a user action (no viser here).

Every function takes a :class:`~poselifter_app.core.SessionState` (never modified) and returns a new one, or
raises :class:`lifter.PoseLifterError` with a message for the user (the caller keeps the previous state).
:func:`apply_controls` is the one transition for the value controls: given the values the GUI holds *now*
(the last ones received), it returns the state they describe, so a burst of events ends on its last value
whatever order the callbacks run in.
"""

from __future__ import annotations

import re
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from lifter import PoseLifterError
from lifter.skeleton import JOINT_NAMES, NUM_JOINTS

from .core import (
    MAX_CLOUD_SAMPLES,
    MAX_SEED,
    NOISE_MAX,
    SessionState,
    check_joint,
    clamp_focal,
    clamp_noise,
    focal_max,
    focal_min,
)
from .keys import (
    NO_PHOTO,
    demo_key,
    frame_of,
    h36m_key,
    motion_key,
    parse_h36m,
    parse_photo_entry,
    sequence_of,
    source_of,
    with_frame,
)
from .samples import Sample, track_number

INPUT_KINDS: tuple[str, ...] = ("gt", "detected")


def input_options(sample: Sample) -> list[str]:
    """The 2D inputs ``sample`` offers: ground truth (``"gt"``) when it has exact 2D, ``"detected"`` when it has a
    detection (an upload's own 2D counts as one). Demo samples offer only ``["gt"]``."""
    opts = ["gt"] if sample.has_gt_2d else []
    if sample.detected_2d is not None or not sample.has_gt_2d:
        opts.append("detected")
    return opts


def input_choices(sample: Sample) -> list[str]:
    """What the 2D-input dropdown offers on ``sample``: :func:`input_options`, and both on every frame of a Human3.6M
    sequence and camera that has detections (:attr:`Sample.sequence_detected`; a training subject's cover every 5th
    frame: the dropdown, rebuilt frame by frame during playback, flipped between one and two entries and could not
    be used; a frame without one falls back, said once: :func:`no_detection_note`)."""
    opts = input_options(sample)
    return list(INPUT_KINDS) if sample.has_gt_2d and sample.sequence_detected else opts


def input_label(sample: Sample, kind: str) -> str:
    """What the 2D-input dropdown shows for ``kind`` (``"gt"`` / ``"detected"``) on ``sample``: "ground truth", and
    for ``"detected"`` "SH detection" on Human3.6M frames, "uploaded 2D" for an uploaded keypoint file, "detected
    2D" for a photo's or video's detection ("detected / uploaded 2D" where the sample does not say). Another
    ``kind`` is shown as it is."""
    if kind == "gt":
        return "ground truth"
    if kind != "detected":
        return kind
    if source_of(sample.key) == "h36m":
        return "SH detection"
    up = getattr(sample, "upload", None)
    what = getattr(up, "kind", None)
    return {"keypoints": "uploaded 2D", "image": "detected 2D", "video": "detected 2D"}.get(str(what),
                                                                                            "detected / uploaded 2D")


INPUT_OF_LABEL: dict[str, str] = {"ground truth": "gt", "SH detection": "detected", "uploaded 2D": "detected",
                                  "detected 2D": "detected", "detected / uploaded 2D": "detected"}
"""The 2D input (``"gt"`` / ``"detected"``) of each label :func:`input_label` gives."""


def no_detection_note(sample: Sample) -> str:
    """Said (once per sequence) when the SH detection was chosen and a Human3.6M frame has none."""
    return (f"no 2D detection for {sample.label}; using ground-truth 2D where a frame has none (the detection is "
            "used again where there is one; the training subjects' detections cover every 5th frame; said once per "
            "sequence)")


def for_sample(state: SessionState, sample: Sample, *, input_pref: str) -> tuple[SessionState, str | None]:
    """The state showing ``sample``: drags reset, focal to its camera's; model, noise, seed, cloud size and the
    analytic toggle kept. 2D input: ``input_pref`` when the sample has it, else the other one (with a note when
    a detection is missing); an upload (no ground-truth 2D) always uses its own 2D."""
    opts = input_options(sample)
    kind = input_pref if input_pref in opts else opts[0]
    new = SessionState(sample=sample, model=state.model, input_kind=kind, noise_level=state.noise_level,
                       seed=state.seed, cloud_samples=state.cloud_samples, analytic=state.analytic)
    # (from a sample with ground-truth 2D: after an upload the preference for detections says nothing)
    note = no_detection_note(sample) if state.sample.has_gt_2d and fell_back(new, input_pref=input_pref) else None
    return new, note


def fell_back(state: SessionState, *, input_pref: str) -> bool:
    """Whether ``state`` shows ground-truth 2D where detections were preferred because its Human3.6M frame has no
    detection (a demo sample never has one, and its dropdown says so): :func:`no_detection_note`'s case."""
    return input_pref == "detected" and state.input_kind != "detected" and source_of(state.sample.key) == "h36m"


def with_input(state: SessionState, kind: str) -> SessionState:
    """2D input ``"gt"`` or ``"detected"``: its own 2D, with the joints dragged on it before on this sample
    (:attr:`SessionState.input_drags`; the current input's drags are kept there in turn). Raises when the sample
    does not have that 2D."""
    if kind not in INPUT_KINDS:
        raise PoseLifterError(f"unknown 2D input {kind!r}; expected one of {list(INPUT_KINDS)}")
    if kind == state.input_kind:
        return state
    kept = dict(state.input_drags)
    if state.dragged:
        kept[state.input_kind] = (np.array(state.keypoints, np.float64, copy=True), frozenset(state.dragged))
    back = kept.pop(kind, None)
    new = state.evolve(input_kind=kind, dragged=set() if back is None else set(back[1]), input_drags=kept)
    base = new.base_keypoints()  # raises: no detection / no ground truth
    new.keypoints = base.copy() if back is None else back[0].copy()
    return new


def with_model(state: SessionState, name: str, *, known: Callable[[str], object]) -> SessionState:
    """Lift with model ``name``; ``known(name)`` raises :class:`PoseLifterError` for unknown names."""
    if name == state.model:
        return state
    known(name)
    return state.evolve(model=name)


def with_focal(state: SessionState, value: float) -> tuple[SessionState, str | None]:
    """Focal length ``alpha`` (px). Out of the slider's range: clamped, with a note. Not finite: refused."""
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise PoseLifterError(f"focal length must be a number of px, got {value!r}") from None
    if not np.isfinite(v):
        raise PoseLifterError(f"focal length {value!r} is not a finite number; kept {state.focal_px:.0f} px")
    v, note = clamp_focal(v, lo=focal_min(state.sample), hi=focal_max(state.sample))
    if note is None and (v == state.focal_px or v == round(state.focal_px, 1)):  # (the box shows 0.1 px)
        return state, None
    if v == state.focal_px:  # clamped to the value in use (e.g. -500 at the minimum): said, and the box put back
        return state, note
    return state.evolve(focal_px=v), note


def with_noise(state: SessionState, level: float) -> tuple[SessionState, str | None]:
    """Mixture-noise level in ``[0, NOISE_MAX]`` (clamped with a note; not finite: refused)."""
    try:
        v = float(level)
    except (TypeError, ValueError):
        raise PoseLifterError(f"noise level must be a number in [0, {NOISE_MAX:g}], got {level!r}") from None
    if not np.isfinite(v):
        raise PoseLifterError(f"noise level {level!r} is not a finite number; kept {state.noise_level:g}")
    v, note = clamp_noise(v)
    return (state if v == state.noise_level else state.evolve(noise_level=v)), note


def _integer(value: object, what: str) -> int:
    try:
        f = float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        raise PoseLifterError(f"{what} must be an integer, got {value!r}") from None
    if not np.isfinite(f) or f != int(f):
        raise PoseLifterError(f"{what} must be an integer, got {value!r}")
    return int(f)


def with_seed(state: SessionState, seed: object) -> SessionState:
    s = _integer(seed, "seed")
    if s < 0:
        raise PoseLifterError(f"seed must be >= 0, got {s}")
    if s > MAX_SEED:
        raise PoseLifterError(f"seed must be at most {MAX_SEED} (2^32 - 1), got {s}")
    return state if s == state.seed else state.evolve(seed=s)


def with_cloud_samples(state: SessionState, n: object) -> tuple[SessionState, str | None]:
    """Noisy draws for the uncertainty cloud, a whole number in ``[0, MAX_CLOUD_SAMPLES]``: clamped with a note, as
    the sliders' typed values are (so a value still being typed waits for the typing to pause, and "257" ends at
    the maximum, not at the "25" typed on the way); not a whole number: refused."""
    k = _integer(n, "cloud samples")
    note = None
    if not 0 <= k <= MAX_CLOUD_SAMPLES:
        c = min(max(k, 0), MAX_CLOUD_SAMPLES)
        note = f"cloud samples {k} is outside [0, {MAX_CLOUD_SAMPLES}]; set to {c}"
        k = c
    return (state if k == state.cloud_samples else state.evolve(cloud_samples=k)), note


def with_joint(state: SessionState, joint: int, uv: object) -> SessionState:
    """2D joint ``joint`` moved to pixel ``uv``. Refused (never clamped) far outside the image
    (:func:`poselifter_app.core.check_joint`)."""
    j = joint_index(joint)
    p = check_joint(uv, size=state.image_size)
    new = state.evolve()
    new.keypoints[j] = p
    new.dragged.add(j)
    return new


def with_keypoints(state: SessionState, keypoints: object) -> SessionState:
    """The whole current 2D pose ``(17, 2)`` px replaced (every joint checked like a drag)."""
    kp = np.asarray(keypoints, np.float64)
    if kp.shape != (NUM_JOINTS, 2) or not np.all(np.isfinite(kp)):
        raise PoseLifterError(f"keypoints must be finite with shape (17, 2) px, got {kp.shape}")
    for j in range(NUM_JOINTS):
        check_joint(kp[j], size=state.image_size)
    return state.evolve(keypoints=kp.copy())


def input_drag_notes(old: SessionState, new: SessionState) -> list[str]:
    """What a switch of 2D input from ``old`` to ``new`` (one sample) did with dragged joints: kept for the input
    left, given back on the input chosen."""
    def joints(n: int) -> str:
        return f"{n} dragged joint{'s' if n != 1 else ''}"

    out = []
    if old.dragged:
        out.append(f"{joints(len(old.dragged))} on the {input_label(old.sample, old.input_kind)} kept for when you "
                   "switch back")
    if new.dragged:
        out.append(f"{joints(len(new.dragged))} on the {input_label(new.sample, new.input_kind)} given back "
                   "(reset dragged joints undoes them)")
    return out


def reset_joints(state: SessionState) -> SessionState:
    """Undo the selected person's drags."""
    return state.evolve(keypoints=state.base_keypoints().copy(), dragged=set())


_PERSON_LABEL = re.compile(r"person (\d+)(?: \(([^()]{0,60})\))?")


def sequence_of_subject(sequences: Sequence[str], wanted: str) -> str:
    """The sequence of a subject's ``sequences`` (Human3.6M names: ``"Phoning"``, ``"Phoning 2"``) to open for the
    one ``wanted`` (the sequence picker's, from the subject shown before): itself when the subject has it; else the
    first take of the same action (S9 'Phoning' -> S11 'Phoning 2'); else the subject's first sequence."""
    if wanted in sequences:
        return wanted
    action = wanted.rstrip("0123456789").rstrip()
    return next((q for q in sequences if q.rstrip("0123456789").rstrip() == action), sequences[0])


def person_index(value: object, *, tags: tuple[str, ...] = ()) -> int:
    """A person index from an index or a picker label ``"person k"`` (with or without its tag). A label whose tag
    is among ``tags`` (the sample's :attr:`Sample.person_tags`: ``"track 3"``) names that person wherever they are
    in this sample's order: a video's order changes from frame to frame, and a pick read on the next frame would
    otherwise select whoever is k-th there."""
    if isinstance(value, str):
        m = _PERSON_LABEL.fullmatch(value.strip())
        if m is None or int(m.group(1)) < 1:
            raise PoseLifterError(f"unknown person {value[:40]!r}; expected 'person 1', 'person 2', ...")
        k = int(m.group(1)) - 1
        if m.group(2) and m.group(2) in tags and not (k < len(tags) and tags[k] == m.group(2)):
            return tags.index(m.group(2))  # (moved in this frame's order; one in its own place is that person: two
            # people whose ids read alike, "kid" twice, are each picked)
        tracks = [track_number(t) for t in tags]
        if not m.group(2) and any(n is not None for n in tracks):  # (a tracked person is "person N" for their
            # track N in every frame: a review typed "person 2" where the picker listed "person 2 (track 2)" first,
            # and got track 3)
            numbers = [i + 1 if n is None else n for i, n in enumerate(tracks)]
            if k + 1 not in numbers:
                raise PoseLifterError(f"person {k + 1} is not in this frame: it has "
                                      + ", ".join(f"person {n}" for n in numbers))
            return numbers.index(k + 1)
        return k
    return _integer(value, "person")


def with_person(state: SessionState, person: object) -> SessionState:
    """Select person ``person`` (index, 0 = largest) of the image: their joints become the draggable ones. Every
    person's current 2D and drags are kept. Raises for an index the sample does not have."""
    k = _integer(person, "person")
    n = state.sample.num_people
    if not 0 <= k < n:
        raise PoseLifterError(f"person {k + 1} does not exist: {state.sample.label} has {n} "
                              f"{'person' if n == 1 else 'people'}")
    if k == state.person:
        return state
    others = dict(state.others)
    others[state.person] = np.array(state.keypoints, np.float64, copy=True)
    dragged = dict(state.others_dragged)
    dragged[state.person] = frozenset(state.dragged)
    kp = others.pop(k)
    mine = dragged.pop(k, frozenset())
    return state.evolve(person=k, keypoints=np.array(kp, np.float64, copy=True), dragged=set(mine), others=others,
                        others_dragged=dragged)


def follow_person(state: SessionState, tag: str) -> tuple[SessionState, bool]:
    """The state with the person the input names ``tag`` selected (a video's ``"track 3"``: the one a tab follows
    from frame to frame), and True, when ``state``'s sample has them; else ``state`` unchanged and False (that
    person is not in this frame)."""
    tags = state.sample.person_tags
    if not tag or tag not in tags:
        return state, False
    return with_person(state, tags.index(tag)), True


def joint_index(joint: object) -> int:
    """A joint index from an index or a joint name; raises for anything else (e.g. a crafted dropdown value)."""
    if isinstance(joint, str):
        if joint not in JOINT_NAMES:
            raise PoseLifterError(f"unknown joint {joint[:40]!r}; expected one of {list(JOINT_NAMES)}")
        return JOINT_NAMES.index(joint)
    try:
        j = int(joint)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        raise PoseLifterError(f"unknown joint {joint!r}") from None
    if not 0 <= j < NUM_JOINTS:
        raise PoseLifterError(f"joint index {j} out of range [0, {NUM_JOINTS})")
    return j


@dataclass(frozen=True)
class ControlValues:
    """The values the GUI's value controls hold (the last ones the tab sent)."""

    model: str
    input_kind: str
    focal_px: float
    noise_level: float
    seed: object
    cloud_samples: object
    analytic: bool
    person: object = 0
    """The person picker: an index (0 = largest) or its label ``"person k"`` (k from 1)."""


@dataclass(frozen=True)
class Rejection:
    """A control value that was refused or changed: the control (:class:`ControlValues` field name), the
    value it must show again, and the message for the user."""

    control: str
    value: object
    message: str
    refused: bool = True


def apply_controls(state: SessionState, values: ControlValues, *,
                   known_model: Callable[[str], object]) -> tuple[SessionState, list[Rejection]]:
    """The state the value controls describe. Each control is applied on its own: a refused value keeps that
    part of the previous state (and is reported, with the value its control must show again); a clamped value is
    applied clamped (reported with ``refused=False``)."""
    out: list[Rejection] = []
    st = state

    def attempt(control: str, fn: Callable[[SessionState], SessionState | tuple[SessionState, str | None]],
                keep: object) -> None:
        nonlocal st
        try:
            res = fn(st)
        except PoseLifterError as exc:
            out.append(Rejection(control, keep, str(exc)))
            return
        if isinstance(res, tuple):
            st, note = res
            if note:
                out.append(Rejection(control, getattr(st, control), note, refused=False))
        else:
            st = res

    attempt("model", lambda s: with_model(s, str(values.model), known=known_model), state.model)
    attempt("input_kind", lambda s: with_input(s, str(values.input_kind)), state.input_kind)
    attempt("focal_px", lambda s: with_focal(s, values.focal_px), state.focal_px)
    attempt("noise_level", lambda s: with_noise(s, values.noise_level), state.noise_level)
    attempt("seed", lambda s: with_seed(s, values.seed), state.seed)
    attempt("cloud_samples", lambda s: with_cloud_samples(s, values.cloud_samples), state.cloud_samples)
    attempt("person", lambda s: with_person(s, person_index(values.person, tags=s.sample.person_tags)), state.person)
    if bool(values.analytic) != st.analytic:
        st = st.evolve(analytic=bool(values.analytic))
    return st, out


def same_lift(a: SessionState, b: SessionState) -> bool:
    """True when ``a`` and ``b`` give the same lift (nothing to recompute)."""
    return (a.sample is b.sample and a.model == b.model and a.input_kind == b.input_kind and a.focal_px == b.focal_px
            and a.noise_level == b.noise_level and a.seed == b.seed and a.cloud_samples == b.cloud_samples
            and a.analytic == b.analytic and np.array_equal(a.keypoints, b.keypoints) and a.person == b.person
            and a.others.keys() == b.others.keys()
            and all(np.array_equal(a.others[k], b.others[k]) for k in a.others))


@dataclass(frozen=True)
class Pick:
    """A picker's value and when it was last set (``time.time()``; 0 = never)."""

    value: Any
    t: float = 0.0


@dataclass(frozen=True)
class Picks:
    """The Sample tab's pickers: ``source`` is a key of :data:`SOURCES`; the Human3.6M ones are None without the
    data."""

    source: Pick
    demo: Pick
    frame: Pick
    subject: Pick | None = None
    sequence: Pick | None = None
    camera: Pick | None = None
    photo: Pick | None = None


SOURCES: tuple[str, ...] = ("demo", "motion", "h36m", "upload")


def clamp_frame(frame: int, num_frames: int) -> int:
    """The frame shown for ``frame`` asked for in a sequence of ``num_frames``: the nearest end past either end (said
    by the view once the typing settles). One rule for the pickers, the frame box and playback."""
    return min(max(int(frame), 0), max(int(num_frames), 1) - 1)


def requested_key(p: Picks, *, shown: str, last_h36m: str | None, last_upload: str | None, sources: list[str],
                  h36m: Any | None, motion_frames: int, upload_frames: int | None = None) -> str:
    """The key of the sample the pickers ask for (``demo/<name>``, ``motion/<i>``, ``h36m/S<s>/<seq>/<cam>/<f>`` or
    the last upload's key), given the key ``shown`` now. The sample rules:

    * the source is the source picker's, unless a picker of another source (demo sample; subject, sequence,
      camera or frame with photo) was set after it: using a picker shows its source;
    * the frame slider counts for the shown sequence, or when it was moved after the source / sequence was picked;
      otherwise the motion starts at 0, a new Human3.6M sequence at 0, and coming back to Human3.6M returns to the
      last frame shown there (``last_h36m``); an uploaded video (``last_upload`` a frame ``video/<id>/<name>/<i>``
      of ``upload_frames`` frames) likewise;
    * a "frame with photo" entry set after the other Human3.6M pickers names its frame.

    Raises :class:`PoseLifterError` for values that name nothing (crafted values, nothing uploaded yet).
    """
    if p.source.value not in sources:
        raise PoseLifterError(f"unknown sample source {str(p.source.value)[:40]!r}; expected one of {sources}")
    cands = [(p.source.t, str(p.source.value)), (p.demo.t, "demo")]
    h_picks = [q for q in (p.subject, p.sequence, p.camera, p.photo) if q is not None]
    if h_picks and "h36m" in sources:
        cands.append((max(q.t for q in h_picks), "h36m"))
    src = max(cands, key=lambda c: c[0])[1]
    fr = p.frame
    if src == "demo":
        return demo_key(str(p.demo.value))
    if src == "motion":
        i = int(fr.value) if source_of(shown) == "motion" or fr.t > p.source.t else 0
        return motion_key(clamp_frame(i, motion_frames))  # (typed past an end: clamped, and said, as
        # for Human3.6M; a browser trial's 300 showed frame 44 without a word. Playback loops by its own clock.)
    if src == "upload":
        if last_upload is None:
            raise PoseLifterError("nothing uploaded yet: use the 'upload photo, video or keypoint JSON' button (File "
                                  "tab)")
        last = frame_of(last_upload) if source_of(last_upload) == "video" else None
        if last is not None and upload_frames:
            base = sequence_of(last_upload)
            i = int(fr.value) if sequence_of(shown) == base or fr.t > p.source.t else last
            return with_frame(base, clamp_frame(i, upload_frames))
        return last_upload
    assert h36m is not None and p.subject is not None and p.sequence is not None and p.camera is not None
    if p.photo is not None and p.photo.value != NO_PHOTO and p.photo.t >= max(
            q.t for q in (p.subject, p.sequence, p.camera, fr)):
        entry = parse_photo_entry(str(p.photo.value))
        if entry is None:
            raise PoseLifterError(f"unknown frame with photo {str(p.photo.value)[:60]!r}")
        return str(entry)
    if p.subject.value not in [f"S{s}" for s in h36m.subjects]:
        raise PoseLifterError(f"unknown subject {str(p.subject.value)[:20]!r}")
    subject = int(p.subject.value[1:])
    sequence = sequence_of_subject(h36m.sequences(subject), str(p.sequence.value))
    was = parse_h36m(shown) or (parse_h36m(last_h36m) if last_h36m else None)
    same_seq = was is not None and was.subject == subject and was.sequence == sequence
    if same_seq and source_of(shown) == "h36m":
        frame = int(fr.value)
    elif was is not None and same_seq:  # back to Human3.6M: its last frame, unless the slider was moved since
        frame = int(fr.value) if fr.t > p.source.t else was.frame
    else:  # another sequence: its start, unless the slider was moved since it was picked
        frame = int(fr.value) if fr.t > max(p.subject.t, p.sequence.t) else 0
    frame = clamp_frame(frame, h36m.num_frames(subject, sequence))
    return h36m_key(subject, sequence, str(p.camera.value), frame)
