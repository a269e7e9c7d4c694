"""The viser app: one :class:`SessionView` per browser tab, on :class:`PoseLifterApp`.

A view owns its tab's typed GUI groups (:mod:`.gui`), scene groups (:mod:`.scene`) and
:class:`~poselifter_app.core.SessionState`; what the state becomes after an action is decided by the pure
transitions of :mod:`.session`, the lift by :func:`~poselifter_app.core.compute_frame`.

**Last value wins.** viser runs GUI callbacks on a thread pool, in any order. No callback here applies "its"
value: each one only asks for a :meth:`SessionView._sync` pass (:class:`LatestWins`: at most one pass runs, and
a request that arrives during a pass makes it run once more). A pass reads what the GUI holds *now* (viser stores
values in the order they arrive) and makes the state, the scene and the readout match it. So after any burst the
last pass sees the last value of every control, in every tab.

Every callback and every public control goes through one error wrapper (:meth:`SessionView._guarded`): a
:class:`lifter.PoseLifterError` becomes a message in the readout panel (and a notification in a real tab),
refused values are put back in their control, and nothing propagates into viser's threads. viser internals
are used only in :mod:`.viser_hooks`.

**Playback leaves the frame box to the user.** The player's frames go into the frame box on the server only; the
tab sees them in a bar and a line under it, its box is empty while playing (or holds what the user typed or
dragged to), and it is sent the box's value once playback stops. A value sent to a box while someone types in it
lands between the keys.
"""

from __future__ import annotations

import contextlib
import dataclasses
import functools
import itertools
import logging
import math
import threading
import time
import traceback
from collections.abc import Callable, Iterator
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any, Final, NamedTuple

import numpy as np
import viser

from lifter import PoseLifterError
from lifter.camera import project_generic
from lifter.detect import check_min_score
from lifter.skeleton import JOINT_NAMES

from . import framing
from . import session as ss
from . import upload as up
from . import video as vid
from .core import (
    MAX_SEED,
    Frame,
    LifterPool,
    SessionState,
    app_wording,
    compute_frame,
    focal_max,
    focal_min,
    focal_text,
    lift_source,
    readout_markdown,
    spread_details,
)
from .drawing import overlay, response_image, scaled_base
from .gui import FOCAL_STEPS, SOURCE_LABELS, SPEED_MAX, SPEED_MIN, Gui, build_gui
from .keys import (
    NO_PHOTO,
    SEQUENCE_SOURCES,
    UPLOADED_SOURCES,
    demo_key,
    demo_name,
    frame_of,
    parse_h36m,
    sequence_of,
    source_of,
    upload_key,
    video_key,
)
from .noise import ErrorModelLike, default_error_model, model_name
from .playback import DemoMotion, H36MSequence, Player, SequenceSource, clamp_speed
from .samples import DemoCatalog, H36MCatalog, Sample, open_h36m
from .scene import (
    JOINT_RADIUS_M,
    Scene,
    ViewerCamera,
    build_scene,
    camera_world,
    draw_2d,
    draw_camera,
    draw_noisy_2d,
    draw_others,
    draw_others_2d,
    draw_pose,
    draw_tracks,
    draw_trail,
    framing_points,
    head_on_points,
    image_plane_depth,
    set_joint_radius,
)
from .scene import head_on as scene_head_on
from .scene import overview as scene_overview
from .video import VideoSequence
from .viser_hooks import (
    UploadBudget,
    clear_box,
    limit_uploads,
    note_typed_values,
    report_rejected_values,
    send_value,
    set_value_here,
)

log = logging.getLogger("poselifter.app")
LABEL_SOURCES = {v: k for k, v in SOURCE_LABELS.items()}

TOAST_MAX_CHARS: int = 240
"""A browser notification shows at most about this many characters of a message (a longer one is cut at a word, and
says the Readout has it whole): a browser trial read toasts whose title had scrolled away, cut mid-sentence."""


def toast_text(text: str, *, limit: int = TOAST_MAX_CHARS) -> str:
    """``text`` for a notification: as it is up to ``limit`` characters, else its start cut at a word and a pointer to
    the Readout's status line, which shows it whole."""
    if len(text) <= limit:
        return text
    cut = text[:limit].rsplit(" ", 1)[0].rstrip(" ,;:(") or text[:limit]  # (no word to cut at: mid-word)
    return f"{cut} … (the whole note: Readout)"


LONG_NOTE_SECONDS: float = 60.0
"""A note too long for its notification (:func:`toast_text`) stays in the Readout's status line at least this long
(other notes: :data:`INFO_MESSAGE_SECONDS`), so that the notification's pointer to it holds."""


NOTES_TOGETHER_SECONDS: float = 2.0
"""Notes shown within this many seconds of each other (one change's: a camera switch that drops dragged joints and
resets a typed focal) stay in the Readout's status line together, at most :data:`MAX_STATUS_NOTES`; a browser trial
read only the last of two, and nothing said the drags were gone once the notifications had closed."""

MAX_STATUS_NOTES: int = 3


@dataclass(frozen=True)
class StatusNote:
    """A message in the Readout's status line, with what clears it (:meth:`SessionView.show_message`): ``about`` a
    sequence no longer shown, a ``focal`` (px) no longer in use, a ``frame_key`` no longer shown, or (``fallback``)
    a frame with a detection shown where it said there was none. ``keep``: an upload's own message (its notes), kept
    while its sample or sequence is shown, beside later messages and errors, until ``about`` no longer holds (a
    browser trial: a video's notes went for good as it played, and a refused upload's message replaced the notes of
    the photo still shown)."""

    text: str
    error: bool = False
    about: str | None = None
    focal: float | None = None
    frame_key: str | None = None
    fallback: bool = False
    keep: bool = False


def status_text(notes: list[StatusNote]) -> str:
    """The status line's markdown for ``notes`` (each its own paragraph; "" for none). An upload's own message
    (``keep``) says it was so as uploaded: it stays while the focal length or the 2D change (a review read "Focal: focal
    from the keypoint file" under a focal length since set)."""
    return "\n\n".join(("⚠️ " if q.error else "ℹ️ As uploaded: " if q.keep else "ℹ️ ") + q.text for q in notes)


INFO_MESSAGE_SECONDS: float = 8.0
"""A note in the readout's status line (not an error) stays at least this long: the step that shows it (a camera
switch that resets the focal length) sets controls whose callbacks succeed right after it, and a success would
otherwise clear it before anyone reads it (user trial). An error is cleared by the next success."""
TYPED_WHILE_PLAYING: str = ("a joint position typed while the sequence plays is not applied: each frame brings its "
                            "own 2D; pause (play) to move a joint")
"""Said (once) when the (u, v) boxes are typed into during playback."""
DRAGGED_WHILE_PLAYING: str = ("a joint dragged while the sequence plays is not moved: each frame brings its own 2D; "
                               "pause (play) to move a joint")
"""Said once per drag begun during playback (a trial's drag was dropped by the next frame, without a word)."""

UPLOAD_REFUSED_TITLE: Final[str] = "Upload refused: the file arrived, but it cannot be used"
"""The title of the notification of a refused upload, which stays until closed: the browser has just said "File
uploaded successfully" about the transfer itself (a user trial read both as success)."""
UPLOAD_TOO_LARGE_TITLE: Final[str] = "Upload refused: the file is too large"
"""The title of the notification of an upload stopped during its transfer for its size (:data:`UPLOAD_REFUSED_TITLE`
said it had arrived, where its message said it was stopped: a user trial)."""
UPLOADS_OFF: Final[str] = ("Uploads are off: the app could not bound what viser buffers for them (its internals are "
                           "not viser 1.1.1's; install the pinned viser==1.1.1)")
"""The upload button's hint when :func:`poselifter_app.viser_hooks.limit_uploads` could not be installed."""
UPLOADS_HELD_FACTOR: Final[int] = 4
"""Every tab's unfinished uploads together may hold this many times the upload limit (80 MiB at 20 MiB), so two
tabs can each send two files at once while many raw connections cannot make the server hold more."""
UPLOAD_BUSY_TITLE: Final[str] = "Upload refused: other uploads are still arriving"
"""The title of the notification of an upload refused as it starts, while two others from the tab are still
arriving (:func:`poselifter_app.viser_hooks.limit_uploads`)."""

TYPING_SETTLE_S: float = 1.0
"""A value typed into the focal or noise box arrives keystroke by keystroke ("2", "20", "200", "2000"): one out of
its range is clamped (and the box rewritten) only when the tab has sent nothing newer for this long, so a value
being typed is not mangled half-way. Until then the tab keeps lifting with the value in use, and nothing else (a
frame of a playing sequence) rewrites the box."""
TYPING_GROW_S: float = 3.0
"""As :data:`TYPING_SETTLE_S`, for a positive value below the box's minimum: more digits can still bring it into
range ("6" on the way to "6000"), so a slow typist gets this long (user trial: after 1 s the box was rewritten to
the minimum with the cursor in front, and "6", "000" became "000100"). After it the lift uses the minimum (said),
but the box keeps what was typed until :data:`TYPING_IDLE_S`: a write into a box being typed mangles the next keys
(a user trial's "1", a 3.3 s pause, "500" became 150000) or is overtaken by them (a pause of 2.8 s while playing left
the box at 100 beside a lift at 1500)."""
UNDO_DEPTH: int = 50
"""How many drags a tab can undo (each pose's, together)."""


class _UndoStep(NamedTuple):
    """An undo snapshot: the pose's (sample key, person, 2D input), its joints ``(17, 2)`` px and dragged joints
    before a gesture changed them, and that gesture (-1: a reset)."""

    key: tuple[Any, ...]
    keypoints: np.ndarray
    dragged: frozenset[int]
    gesture: int


SHRUNK_VIEW: float = 0.4
"""After a focal change, auto reframing zooms back in when what it keeps in view (the camera, its frustum, the
skeleton) spans less than this share of the view's width and height, wherever it is in the view."""
TYPING_IDLE_S: float = 10.0
"""A positive focal below the minimum, lifted at the minimum since :data:`TYPING_GROW_S`, is written back into its
box once the tab has sent nothing for this long."""


def _same_calibration(a: Any, b: Any) -> bool:
    """Whether two :class:`lifter.Camera` see alike: the same image size, focal and principal point (to 0.5 px) and
    lens."""
    return ((a.width, a.height) == (b.width, b.height) and abs(a.alpha - b.alpha) <= 0.5
            and bool(np.allclose(a.principal_point, b.principal_point, atol=0.5))
            and bool(np.allclose((*a.k, *a.p), (*b.k, *b.p))))


def _same_camera(a: Any, b: Any, *, src: str, old_src: str) -> bool:
    """Whether camera ``a`` of a sample from source ``src`` is the camera ``b`` of the sample shown before (from
    ``old_src``), so that a chosen focal length stays: the same object (the frames of one sequence or upload); one
    Human3.6M camera, whose calibration is the same for every subject (a user trial saw a chosen focal reset across
    subjects); the walking demo's camera, which sees the demo motion too. Uploads are each their own camera, even
    under the last one's file name (a review: a corrected clip.json kept the old file's focal)."""
    if a is b:
        return True
    if src == old_src == "h36m":
        return a.name == b.name or _same_calibration(a, b)
    if {src, old_src} & set(UPLOADED_SOURCES):
        return False
    return a.name == b.name and _same_calibration(a, b) and bool(np.allclose(a.R, b.R)) and \
        bool(np.allclose(a.t, b.t))


class LatestWins:
    """Runs ``work`` when asked, never twice at once; a request made while it runs makes it run once more
    afterwards (in the thread that is running it). The caller of :meth:`request` returns at once when another
    thread is running ``work``; when no one is, it runs ``work`` itself before returning. :meth:`holding` keeps
    ``work`` from running during a block (requests made meanwhile run at its end)."""

    def __init__(self, work: Callable[[], None]) -> None:
        self._work = work
        self._run_lock = threading.Lock()
        self._flag_lock = threading.Lock()
        self._pending = False
        self._owner: int | None = None

    def request(self) -> None:
        with self._flag_lock:
            self._pending = True
        if self._owner == threading.get_ident():
            return  # inside our own pass / holding block: it runs again at the end
        while True:
            if not self._run_lock.acquire(blocking=False):
                return  # the running pass will run again
            self._owner = threading.get_ident()
            try:
                while True:
                    with self._flag_lock:
                        if not self._pending:
                            break
                        self._pending = False
                    self._work()
            finally:
                self._owner = None
                self._run_lock.release()
            with self._flag_lock:  # a request between our last check and the release
                if not self._pending:
                    return

    @contextlib.contextmanager
    def holding(self) -> Iterator[None]:
        """No pass runs inside this block (it waits for a running one); what was asked meanwhile runs after it."""
        if self._owner == threading.get_ident():
            yield
            return
        with self._run_lock:
            self._owner = threading.get_ident()
            try:
                yield
            finally:
                self._owner = None
        with self._flag_lock:
            pending = self._pending
        if pending:
            self.request()


@dataclass
class Timing:
    """Server-side timing of the last update (ms)."""

    compute_ms: float = 0.0
    scene_ms: float = 0.0
    total_ms: float = 0.0


def control(func: Callable[..., Any]) -> Callable[..., bool]:
    """A public control of :class:`SessionView` (tests drive these): runs through :meth:`SessionView._guarded`,
    returns True on success, False after showing the problem."""

    @functools.wraps(func)
    def wrapper(self: SessionView, *args: Any, **kwargs: Any) -> bool:
        return self._guarded(func, self, *args, **kwargs)

    return wrapper


class SessionView:
    """GUI, scene and state of one browser tab (or of the server itself, for headless tests).

    ``target`` is a :class:`viser.ClientHandle` (per tab, the normal case) or a :class:`viser.ViserServer` (shared;
    tests and benchmarks without a browser). Public methods are the controls in code form.
    """

    def __init__(self, app: PoseLifterApp, target: viser.ClientHandle | viser.ViserServer) -> None:
        self.app = app
        self.target = target
        self.lock = threading.RLock()
        self.messages: list[str] = []
        self.notices: list[tuple[str, str, bool]] = []
        """The last 20 notifications a tab gets: ``(title, text, sticky)`` (:meth:`show_message`)."""
        self._sticky_note: Any = None
        self._upload_left: SessionState | None = None
        """The state of a still upload (photo, keypoint file) left with corrected joints: restored on coming back."""
        self._frames_left: dict[str, SessionState] = {}
        """The states of an uploaded video's or keypoint sequence's frames left with corrected joints, by sample key:
        restored when the frame is shown again, and lifted in the download (a browser trial's drag on a frame was
        dropped on scrubbing to the next, so one frame at a time could be corrected); another sequence's go."""
        self._followed: tuple[str, str] | None = None
        """``(video key, person tag)`` of the person picked in a video (at first, its first frame's first person):
        selected again in each frame that has them (:meth:`_follow`; a trial's pick went back to the first track on
        the next frame, and a track the detector missed in one frame gave the selection to another)."""
        self._gaps_said: set[tuple[str, str]] = set()
        """The followed people whose absence from a frame was said: once per video and person (not a notification
        per gap during playback)."""
        self._message_count = 0
        self._status_lock = threading.Lock()
        """Held while a message is recorded and shown, and while the status line is checked and cleared: an upload's
        thread shows messages without :attr:`lock`, and a pass's "no message since, clear it" must not land between
        its message's count and its text. Taken after :attr:`lock` when both are held, never before."""
        self._note_until = 0.0  # (time.monotonic() until which the status line's note stays; 0 after an error)
        self._note_shown_at = -math.inf  # (time.monotonic() of the last note: NOTES_TOGETHER_SECONDS)
        self._status_notes: list[StatusNote] = []
        """The messages the status line shows (several notes of one change, or one error), each with the rules that
        clear it (:meth:`show_message`, :meth:`_clear_stale_status`)."""
        self._last_was_error = False
        self.frame: Frame | None = None
        self.timing = Timing()
        self.update_count = 0
        self.selected = 0
        self._input_pref = "gt"
        self._drags: dict[int, np.ndarray] = {}
        self._gesture = 0  # one per mouse drag (press to release), typed joint position or reset
        self._drags_gesture = 0  # the gesture of the drags queued
        self._undo: list[_UndoStep] = []
        """Undo snapshots, the last on top."""
        self._reset_request = False
        self._redraw_request = False
        self._flags = threading.Lock()
        self._frame_note: tuple[int, int, str] | None = None
        """(frame asked for, frame shown, its sequence) to be said once typing settles
        (:meth:`_note_frame_past_end`)."""
        self._typed_while_playing_at = -math.inf
        """time.monotonic() of the last (u, v) keystroke during playback (:data:`TYPED_WHILE_PLAYING`)."""
        self._play_shown: int | None = None  # (the player's last frame: Player's position while the box waits)
        self._player_write: tuple[int, float] | None = None  # the player's last frame written, and when it began
        self._frame_user_t = -math.inf  # the frame box's timestamp from the last write that was not the player's
        self._info_playing = False  # the play info line says "playing" (:meth:`_show_play_info`)
        self._typed_name: dict[int, str] = {}  # id(handle) -> its name in _typed_at (:meth:`_typed_controls`)
        self._uv_box_stale = False  # the tab's (u, v) box not sent the selected joint's moves during playback
        self._frame_box_stale = False
        """The tab's frame box does not show the server's value: playback's frames stay on the server (and in the bar
        under the box) until it stops, so none lands in the box while someone types a frame in it (:meth:`_write`),
        and the box is emptied while playing (:meth:`_clear_frame_box`)."""
        self._applied_t = -math.inf  # picks stamped up to here were read by a pass that ended (its start time)
        self._own_t: dict[int, float] = {}  # id(picker) -> the timestamp of this view's own last write to it
        self._still_frame_typed: float | None = None
        """The tab's time of the frame value typed on a still sample that was last answered (said once per value)."""
        self._due: dict[str, list[float]] = {}
        """Kind -> time.time() at which each timer of that kind still waiting fires (:meth:`_later_once`)."""
        self._held: set[tuple[str, Any]] = set()
        """(control, typed value) of the clamps whose box keeps the keys (:data:`TYPING_IDLE_S`), once said."""
        self._typed_at: dict[str, float] = {}
        """Control name -> time.time() of the tab's last value for it (browser updates only:
        :data:`TYPING_SETTLE_S`)."""
        self._typed_uv: tuple[int, int, int, int, np.ndarray] | None = None
        """The joint position being typed into the (u, v) boxes: (keystroke number, joint, sample generation, person,
        value px); applied once the typing settles (:meth:`_on_uv_event`)."""
        self._typed_seq = itertools.count()
        self._fallback_said: set[str] = set()
        """Sequences whose missing-detection note was said (once per sequence, not once per frame in playback)."""
        self._speed_typed = -1
        """The number of the speed box's last key (:meth:`_on_speed`; from :attr:`_typed_seq`)."""
        self._last_plane: np.ndarray | None = None
        self._base_key: tuple | None = None
        self._image_key: tuple | None = None
        self._base: tuple[np.ndarray, float] | None = None
        self._view_key: tuple | None = None
        self._close_up = False
        self._sample_gen = 0
        self._drag_gen: int | None = None
        self._drags_by_mouse = False  # the queued drags came from a mouse drag (not a typed position or the API)
        self._drag_refusal_said = False  # the current mouse drag's refusal was said (once per drag)
        self._last_upload: Sample | None = None
        self._last_h36m: str | None = None
        """Key of the last Human3.6M sample shown (coming back to Human3.6M goes back to that frame)."""
        self._photo: up.Photo | None = None
        self._video: VideoSequence | None = None
        """The last uploaded video / keypoint sequence (its frames are the samples ``video/<id>/<name>/<i>``)."""
        self._uploads_begun = 0
        """Uploads this tab has begun, numbered from 1 (:meth:`_superseded`)."""
        self._upload_shown = 0
        """The number of the latest upload shown: one begun before it and finished after is not shown."""
        self.gone = False
        """The tab has disconnected: a video being lifted for it stops (:meth:`_load_video`)."""
        self.last_download: tuple[str, bytes] | None = None
        """``(file name, content)`` of the last download sent (or prepared, for a headless view)."""
        self.trail: dict[int, np.ndarray] = {}
        self._trail_key: tuple | None = None
        self.player = Player(position=self._play_position, speed=self._speed,
                             show=self._show_frame, on_stop=self._player_stopped)
        self.play_ms = self.player.frame_ms
        """Server-side time of each frame shown by playback (ms)."""
        self.play_shown = self.player.shown_at
        """perf_counter() time at which each playback frame was shown."""
        self._runner = LatestWins(self._sync)
        self._pass_t0 = math.inf
        """Start of the running sync pass (time.time()); a control updated after it is not overwritten
        (:meth:`_put`)."""

        h = app.h36m
        self.gui: Gui = build_gui(
            target.gui, demo_names=list(app.demo.names), sources=app.sources, models=list(app.pool.names),
            model=app.default_model, h36m=h, error_model_name=model_name(app.error_model),
            max_upload_mib=app.max_upload_bytes // 2**20)
        self.camera = ViewerCamera(target, app.server)
        self.scene: Scene = build_scene(target.scene, on_drag=lambda j, ev: self._do(self.on_joint_drag, j, ev))
        first = app.demo.get(app.demo.names[0])
        self.state = SessionState(sample=first, model=app.default_model)
        self._wire_uploads()  # (before the first sample is drawn: an upload sent meanwhile waits for the lock, where
        # before it arrived with no callback and vanished, a security review)
        with self.lock:
            if h is not None:  # with Human3.6M the app opens on it: a frame with a photo when there is one
                s = int(self._gui_subject()[1:])
                photos = [p for p in h.photo_frames() if p[0] == s] or h.photo_frames()
                first = h.get(*photos[0]) if photos else h.get(s, self._gui_sequence(), h.camera_ids[0], 0)
            self._show_sample(first, reframe=True)
        self._wire()
        client_id = target.client_id if isinstance(target, viser.ClientHandle) else None
        report_rejected_values(target.gui, lambda msg: self.show_message(msg, error=True))
        note_typed_values(target.gui, self._typed_controls(), self._note_key, client_id=client_id)

    # ------------------------------------------------------------------------------------------
    # The one error wrapper, messages
    # ------------------------------------------------------------------------------------------
    def _guarded(self, func: Callable[..., Any], *args: Any, **kwargs: Any) -> bool:
        """Run ``func``: True on success; a :class:`PoseLifterError` (or any other error, logged) becomes a
        message and False. Never raises (callbacks run in viser's threads). A success that showed no message
        clears the status line: an error at once, a note (``ℹ️``) once it has been shown for
        :data:`INFO_MESSAGE_SECONDS` (the controls that the step showing it set call back right after it)."""
        n = self._message_count
        try:
            func(*args, **kwargs)
        except up.UploadRefused as exc:  # (beside the browser's own "File uploaded successfully": it arrived)
            self.show_message(str(exc), error=True, title=UPLOAD_REFUSED_TITLE, sticky=True)
            return False
        except PoseLifterError as exc:
            self.show_message(str(exc), error=True)
            return False
        except Exception as exc:  # noqa: BLE001 - never let a control kill the session
            log.error("%s failed:\n%s", getattr(func, "__name__", func), traceback.format_exc())
            self.show_message(f"internal error: {type(exc).__name__}: {exc}", error=True)
            return False
        with self._status_lock:
            if self._message_count == n and self.gui.readout.status.content and time.monotonic() >= self._note_until:
                # (a note stays a while: the controls it changed call back at once; an upload's own stays on)
                kept = [q for q in self._status_notes if q.keep]
                if len(kept) != len(self._status_notes):
                    self._status_notes = kept
                    self.gui.readout.status.content = status_text(kept)
        return True

    def show_message(self, text: str, *, error: bool = False, about: str | None = None,
                     focal: float | None = None, title: str | None = None, sticky: bool = False,
                     frame_key: str | None = None, fallback: bool = False, keep: bool = False) -> None:
        """Show ``text`` in the readout panel (and as a browser notification in a real tab). ``about``: the sequence
        or sample (:func:`poselifter_app.keys.sequence_of`) it is about, when that is not the one shown now (a pass
        that shows another one clears the message). ``focal``: the focal length (px) the message says was set; a
        pass that finds another one in use clears it (a user trial: "set to 1148.6 px" stayed under a focal typed
        since). ``frame_key``: the one frame it is about; a pass that shows another clears it (a browser trial read
        "frame 99999 is past the end ...; showing frame 1967" under frame 391). ``fallback``: it says the frame
        shown has no detection; a pass that shows one with it clears it. ``keep``: an upload's own message
        (:class:`StatusNote`).
        ``title``: the notification's (default: "Input problem" for an error, else "poselifter"); ``sticky``: it
        stays until closed. Every notification is also kept in :attr:`notices` ``(title, text, sticky)``.
        Notes shown within :data:`NOTES_TOGETHER_SECONDS` of each other (one change's) stay in the status line
        together, each cleared by its own rules; an error replaces them."""
        title = title or ("Input problem" if error else "poselifter")
        text = app_wording(text)
        with self._status_lock:
            now = time.monotonic()
            # (every write of the status line sets _status_notes: empty after a clear or a progress line)
            together = (not error and not self._last_was_error and now - self._note_shown_at < NOTES_TOGETHER_SECONDS
                        and bool(self._status_notes))
            note = StatusNote(text=text, error=error, focal=focal, frame_key=frame_key, fallback=fallback, keep=keep,
                              about=about if about is not None else (
                                  sequence_of(self.state.sample.key) if hasattr(self, "state") else None))
            upload = [q for q in self._status_notes if q.keep and q.text != text and not keep]  # (a new one replaces)
            kept = [q for q in self._status_notes if q.text != text and not q.keep] if together else []
            self._status_notes = [*upload, *kept[len(upload) + 1 - MAX_STATUS_NOTES:], note]
            self._note_shown_at = now if not error else -math.inf
            self.messages.append(text)
            self.messages = self.messages[-20:]
            self.notices = [*self.notices[-19:], (title, text, sticky)]
            self._message_count += 1
            self._note_until = (now + LONG_NOTE_SECONDS if sticky else 0.0) if error else max(
                self._note_until if together else 0.0,
                now + (LONG_NOTE_SECONDS if len(text) > TOAST_MAX_CHARS else INFO_MESSAGE_SECONDS))
            # (a refused upload stays: during playback every frame's pass would clear it at once; a browser trial)
            self._last_was_error = error
            try:
                self.gui.readout.status.content = status_text(self._status_notes)
            except Exception:  # noqa: BLE001
                log.exception("could not show message %r", text)
        try:
            if isinstance(self.target, viser.ClientHandle):
                note = self.target.add_notification(title=title, body=toast_text(text),
                                                    auto_close_seconds=None if sticky else 6.0,
                                                    color="red" if error else "blue")
                if sticky:  # (one refused upload's note at a time: they do not pile up)
                    if self._sticky_note is not None:
                        self._sticky_note.remove()
                    self._sticky_note = note
        except Exception:  # noqa: BLE001
            log.exception("could not show message %r", text)

    # ------------------------------------------------------------------------------------------
    # Callbacks: every value control only asks for a sync pass
    # ------------------------------------------------------------------------------------------
    def _do(self, func: Callable[..., Any], *args: Any) -> None:
        """Run ``func(*args)`` through :meth:`_guarded` (for callbacks, which return nothing)."""
        self._guarded(func, *args)

    def _on(self, func: Callable[..., Any], *args: Any) -> Callable[[Any], None]:
        """A GUI callback running ``func(*args)`` through :meth:`_guarded`."""
        return lambda _event: self._do(func, *args)

    def _wire_uploads(self) -> None:
        """The upload button's callback and the bounds on what viser buffers for it; without the bounds (viser's
        internals not the ones they hook) the button is off and says why, rather than take files unbounded."""
        app, target, g = self.app, self.target, self.gui
        bounded = limit_uploads(target.gui, g.files.upload, max_bytes=app.max_upload_bytes, budget=app.upload_budget,
                      client_id=target.client_id if isinstance(target, viser.ClientHandle) else None,
                      refuse=lambda name, size: self.show_message(
                          up.oversize_message(up.safe_name(name), size, max_bytes=app.max_upload_bytes), error=True,
                          title=UPLOAD_TOO_LARGE_TITLE, sticky=True),
                      refuse_busy=lambda name, n: self.show_message(
                          f"{up.safe_name(name)}: not uploaded: {n} uploads from this tab are still arriving; upload "
                          "it again when they are done (what is shown is unchanged)", error=True,
                          title=UPLOAD_BUSY_TITLE),
                      refuse_full=lambda name, held: self.show_message(
                          f"{up.safe_name(name)}: not uploaded: the app is receiving other uploads "
                          f"({held / 2**20:.0f} MiB still arriving, {app.upload_budget.max_bytes // 2**20} MiB in all "
                          "at most); upload it again in a moment (what is shown is unchanged)", error=True,
                          title=UPLOAD_BUSY_TITLE),
                      refuse_idle=lambda name, idle_s: self.show_message(
                          f"{up.safe_name(name)}: upload dropped: nothing of it arrived for {idle_s} s (a connection "
                          "lost?); upload it again (what is shown is unchanged)", error=True,
                          title=UPLOAD_BUSY_TITLE))
        if not bounded:
            g.files.upload.disabled = True
            g.files.upload.hint = UPLOADS_OFF
            return
        g.files.upload.on_upload(self._on(lambda: self.load_upload(g.files.upload.value.name,
                                                                   g.files.upload.value.content)))

    def _wire(self) -> None:
        g = self.gui
        sync = self._on(self._runner.request)
        typed = self._typed_name = {id(h): name for name, h in self._typed_controls().items()}
        for h in {id(h): h for h in [g.sample.source, g.sample.demo, *g.sample.h36m_pickers, g.play.frame,
                                     *g.value_handles()]}.values():
            if id(h) in typed:  # the key's time first, in the same callback: viser runs callbacks on a thread
                # pool, so a separate one could run after the pass (a loaded run clamped a half-typed "6" at once)
                h.on_update(functools.partial(self._typed_then_sync, typed[id(h)]))
            else:
                h.on_update(sync)
        g.lift.gt.on_update(self._on(self._request_redraw))
        g.play.trail.on_update(self._on(self._request_redraw))
        g.lift.focal_reset.on_click(self._on(self.reset_focal))
        g.lift.focal_steps.on_click(lambda event: self._do(self.scale_focal, 0.5 if event.target.value == FOCAL_STEPS[0]
                                                           else 2.0))
        g.noise.resample.on_click(self._on(self.resample))
        g.joints.joint.on_update(self._on(self._on_joint_selected))
        g.joints.uv.on_update(self._on_uv_event)
        g.joints.reset.on_click(self._on(self.reset_joints))
        g.joints.undo.on_click(self._on(self.undo_drag))
        g.joints.head_on.on_click(self._on(self.head_on_view))
        g.lift.overview.on_click(self._on(self.overview))
        g.lift.auto_frame.on_update(self._on(self._auto_frame))
        g.play.play.on_click(self._on(self.toggle_play))
        g.play.speed.on_update(self._on(self._on_speed))
        g.files.download_json.on_click(self._on(self.download, "json"))
        g.files.download_glb.on_click(self._on(self.download, "glb"))

    def _speed(self) -> float:
        """Playback speed (× real time): the speed box's, within the slider's range."""
        return clamp_speed(self.gui.play.speed.value, low=SPEED_MIN, high=SPEED_MAX)

    def _on_speed(self) -> None:
        with self._flags:
            seq = next(self._typed_seq)
            self._speed_typed = seq
        self._later(TYPING_SETTLE_S, self._settle_speed, seq)

    def _settle_speed(self, seq: int) -> None:
        """Once the speed box's typing settles: a value outside the slider's range is put in range, in the box too,
        and said (a browser trial's box kept "10" beside a slider at 4×, and "0" beside 0.1×, with no word)."""
        with self._flags:
            if seq != self._speed_typed:
                return  # (a newer key: its own timer settles it)
        h = self.gui.play.speed
        typed = h.value
        speed = self._speed()
        if speed != typed:
            h.value = speed
            self.show_message(f"speed {typed:g}× is outside [{SPEED_MIN:g}×, {SPEED_MAX:g}×]; set to {speed:g}×")

    def _typed_controls(self) -> dict[str, Any]:
        """The controls whose typed values wait for more keys (:data:`TYPING_SETTLE_S`), by state name."""
        g = self.gui
        return {"focal_px": g.lift.focal, "noise_level": g.noise.level, "cloud_samples": g.noise.cloud,
                "frame": g.play.frame}

    def _note_key(self, name: str) -> None:
        self._typed_at[name] = time.time()

    def _note_typed(self, name: str, event: Any) -> None:
        # (viser_hooks.note_typed_values notes the key before the value reaches the control; this callback, after
        # it, keeps the time right where that hook could not be installed)
        if getattr(event, "client", None) is not None:  # from a browser tab, not a value set here
            self._note_key(name)

    def _typed_then_sync(self, name: str, event: Any) -> None:
        self._note_typed(name, event)
        self._do(self._runner.request)

    def _later(self, delay: float, func: Callable[..., Any], *args: Any) -> None:
        """Run ``func(*args)`` through :meth:`_do` after ``delay`` s, on a daemon timer thread."""
        timer = threading.Timer(delay, self._do, args=(func, *args))
        timer.daemon = True
        timer.start()

    def _later_once(self, kind: str, delay: float, func: Callable[..., Any], *args: Any) -> None:
        """:meth:`_later`, unless a timer of the same ``kind`` already waiting fires no later: that one does instead,
        and what it runs asks again for what still waits. A playing sequence runs a pass every frame, and each
        would otherwise start a timer of its own (a test counted 51 after 1 s)."""
        now = time.time()
        due = now + delay
        with self._flags:
            waiting = [t for t in self._due.get(kind, ()) if t > now]
            self._due[kind] = waiting
            if any(t <= due + 0.04 for t in waiting):  # (the passes of one typed value ask for the same time)
                return
            waiting.append(due)
        self._later(delay, func, *args)

    def _settle_later(self, delay: float) -> None:
        """A sync pass after ``delay`` s: a clamped value still in its box is applied then (:data:`TYPING_SETTLE_S`);
        one timer at a time (:meth:`_later_once`)."""
        self._later_once("settle", delay, self._runner.request)

    def _since_typed(self, name: str) -> float:
        """Seconds since the tab last sent a value for control ``name`` (inf: never)."""
        return time.time() - self._typed_at.get(name, -math.inf)

    def _request_redraw(self) -> None:
        with self._flags:
            self._redraw_request = True
        self._runner.request()

    # ------------------------------------------------------------------------------------------
    # The sync pass
    # ------------------------------------------------------------------------------------------
    def _sync(self) -> None:
        """Make the state, scene and readout match what the GUI holds now (see the module docstring)."""
        with self.lock:
            self._pass_t0 = time.time()  # (before reading any control)
            n = self._message_count
            try:
                self._sync_pass()
                self._applied_t = self._pass_t0  # (a pick stamped during the pass is read by the next one)
            finally:
                self._pass_t0 = math.inf
            if self._frame_box_stale and not self.playing:  # (playback stopped: the box shows the frame shown)
                self._frame_box_stale = False
                send_value(self.gui.play.frame)
            if self._uv_box_stale and not self.playing:  # (and the (u, v) box the selected joint's: _draw_2d)
                self._uv_box_stale = False
                send_value(self.gui.joints.uv)
            if self._info_playing != self.playing:  # (started or stopped with no new frame: a trial's paused
                self._show_play_info()  # upload still said "playing")
            with self._status_lock:
                if self._message_count == n and self.gui.readout.status.content and self._status_notes:
                    self._clear_stale_status()

    def _clear_stale_status(self) -> None:
        """Drop the status line's messages that no longer hold (under :attr:`_status_lock`): about a sample no longer
        shown, a focal since changed, another frame, or a frame without a detection left for one with it (a browser
        trial read "no 2D detection ... frame 3" under frame 5's detection); the others stay."""
        st = self.state
        fell_back = None
        fresh = []
        for q in self._status_notes:
            if q.fallback and fell_back is None:
                fell_back = ss.fell_back(st, input_pref=self._input_pref)
            if not ((q.about is not None and sequence_of(st.sample.key) != q.about)
                    or (q.focal is not None and abs(st.focal_px - q.focal) > 1e-6)
                    or (q.frame_key is not None and st.sample.key != q.frame_key)
                    or (q.fallback and not fell_back)):
                fresh.append(q)
        if len(fresh) != len(self._status_notes):
            self._status_notes = fresh
            self.gui.readout.status.content = status_text(fresh)

    def _put(self, handle: Any, value: Any, *, quiet: bool = False) -> None:
        """Show ``value`` in a control, unless the tab sent it a newer value during this pass: that one wins (the
        pass its callback asked for applies it). The player's frames are not the tab's: a frame of the sequence
        being left, written during the pass that leaves it, is replaced (a browser trial's photo pick during
        playback opened its sequence at the old one's frame number). ``quiet``: on the server only
        (:meth:`_write`)."""
        frame_box = handle is self.gui.play.frame
        name = self._typed_name.get(id(handle))
        if name is not None and self._typed_at.get(name, -math.inf) > self._pass_t0:
            return  # (the tab sent a value during this pass: viser puts the value in before its time, so a pass
            # between the two read the new value with the old time, and put its own back: a trial's "1071" typed,
            # paused, became 107 with no word; note_typed_values notes the key before either)
        if (handle.value != value or (frame_box and self._frame_box_stale and not quiet)) and (
                handle.update_timestamp <= self._pass_t0 or (frame_box and self._player_wrote(handle))):
            self._write(handle, value, quiet=quiet)

    def _sync_pass(self) -> None:
        """One pass of :meth:`_sync` (under :attr:`lock`)."""
        try:
            req = self._requested_sample()
        except PoseLifterError as exc:
            self._show_sample_controls(self.state)  # the pickers show the sample in use again
            self.show_message(str(exc), error=True)
            req = None
        if req is not None and req.key != self.state.sample.key:
            try:
                self._show_sample(req, reframe=False)
            except PoseLifterError as exc:
                self._show_sample_controls(self.state)
                self.show_message(str(exc), error=True)
        old = self.state
        values, input_notes = self._input_choice(old, self._control_values())
        st, rejected = ss.apply_controls(old, values, known_model=self.app.pool.get)
        picked = None
        if st.person != old.person:
            self._drop_typed_uv()
            if source_of(st.sample.key) == "video" and st.sample.person_tag(st.person):  # followed from frame to frame
                picked = (sequence_of(st.sample.key), st.sample.person_tag(st.person))  # (once it is shown)
        typing = [r for r in rejected if not r.refused and self._since_typed(r.control) < self._settle_s(r, values)]
        if typing:  # out of range while being typed: not yet (the value in use stays; the box is left alone)
            st = st.evolve(**{r.control: getattr(old, r.control) for r in typing})
            rejected = [r for r in rejected if r not in typing]
            self._settle_later(max(self._settle_s(r, values) - self._since_typed(r.control) for r in typing) + 0.05)
        # a value that more digits could still bring into range: clamped in the lift, but the box keeps the keys
        # until TYPING_IDLE_S (said once per value typed)
        held = [r for r in rejected if self._grows(r, values) and self._since_typed(r.control) < TYPING_IDLE_S]
        said_before = {r for r in held if (r.control, getattr(values, r.control)) in self._held}
        if held:  # (one timer at a time however many passes ask: _later_once)
            self._settle_later(max(TYPING_IDLE_S - self._since_typed(r.control) for r in held) + 0.05)
        self._held = {(r.control, getattr(values, r.control)) for r in held}
        with self._flags:
            drags, self._drags = self._drags, {}
            by_mouse, self._drags_by_mouse = self._drags_by_mouse, False
            reset, self._reset_request = self._reset_request, False
            gesture = self._drags_gesture
            redraw, self._redraw_request = self._redraw_request, False
        # (refused values are errors; clamped ones notes, which stay a while: a user trial saw "focal length 9000 px
        # is outside ...; clamped" vanish within a second, when the settle timer's pass cleared it as an error)
        # (text, error, the focal a clamp set: that note goes once another focal is in use; a user trial saw
        # "99999 px ... clamped to 6000" stay beside a focal of 1144.5 typed since, through a model change)
        notes: list[tuple[str, bool, float | None]] = [
            (r.message + ("; the box keeps what you typed for now" if r in held else ""), r.refused,
             float(r.value) if r.control == "focal_px" and not r.refused  # type: ignore[arg-type]
             and isinstance(r.value, (int, float)) else None) for r in rejected if r not in said_before]
        notes += [(text, False, None) for text in input_notes]  # (last: the status line then says it, and goes
        # once a frame with a detection is shown, as when a frame without one is opened: _show_sample)
        before = st
        if reset:
            st = ss.reset_joints(st)
        refused_drag = False
        for j, uv in drags.items():
            try:
                st = ss.with_joint(st, j, uv)
            except PoseLifterError as exc:
                if not (by_mouse and self._drag_refusal_said):  # (once per mouse drag)
                    notes.append((str(exc), True, None))
                self._drag_refusal_said = by_mouse
                refused_drag = True
        # one undo step per gesture (a mouse drag's 20 moves a second are one; a reset and a drag in one pass are
        # one), kept once the pass's state is applied
        undoable = bool(drags or reset) and not (np.array_equal(st.keypoints, before.keypoints)
                                                 and st.dragged == before.dragged)
        for r in rejected:
            if r not in held:
                self._set_control(r.control, r.value)
        if st.input_kind != old.input_kind and st.sample.has_gt_2d:
            self._input_pref = st.input_kind
            if st.sample.key == old.sample.key:  # (where the dragged joints went, and came back from)
                notes += [(text, False, None) for text in ss.input_drag_notes(old, st)]
        if ss.same_lift(st, old) and not redraw and not reset:
            if refused_drag:  # the sphere and the (u, v) box go back to the joint's position
                self._last_plane = None
                self._draw_2d(old.keypoints, self.frame.noisy_2d if self.frame is not None else None)
            self._say_pass_notes(notes, fallback=input_notes)
            return
        try:
            self._apply(st)
            if undoable:
                self._push_undo(before, gesture=gesture if drags and not reset else -1)
            if picked is not None:
                self._followed = picked
            if st.person != old.person and self._close_up:  # the head-on view follows to the person now draggable
                self.head_on_view()  # (a trial's stayed on the one before, its spheres gone, the new ones off screen)
        except PoseLifterError as exc:  # e.g. a degenerate pose: everything back to the previous state
            notes.append((str(exc), True, None))
            self._show_controls(old)
            self._draw_2d(old.keypoints, self.frame.noisy_2d if self.frame is not None else None)
        self._say_pass_notes(notes, fallback=input_notes)

    def _say_pass_notes(self, notes: list[tuple[str, bool, float | None]], *, fallback: list[str]) -> None:
        """Say a pass's notes ``(text, error, focal set)`` in turn. When the last one said is in ``fallback``
        (:func:`ss.no_detection_note`), the status line keeps it while frames without a detection are shown."""
        for text, error, focal in notes:
            self.show_message(text, error=error, focal=focal, fallback=text in fallback)

    def _settle_s(self, r: ss.Rejection, values: ss.ControlValues) -> float:
        """How long a clamped value typed into ``r.control`` waits for more keys (:data:`TYPING_GROW_S` for a
        positive focal length below the minimum, else :data:`TYPING_SETTLE_S`)."""
        return TYPING_GROW_S if self._grows(r, values) else TYPING_SETTLE_S

    def _grows(self, r: ss.Rejection, values: ss.ControlValues) -> bool:
        """Whether ``r`` is a clamp of a positive focal length below the minimum, typed into its box: more digits
        can still bring it into range."""
        if r.refused or r.control != "focal_px":
            return False
        try:
            typed = float(values.focal_px)
        except (TypeError, ValueError):
            return False
        return 0 < typed < focal_min(self.state.sample)

    def _input_choice(self, old: SessionState, values: ss.ControlValues) -> tuple[ss.ControlValues, list[str]]:
        """The 2D input a pass lifts, and what to say: a choice the dropdown holds (:meth:`_shown_input`) for a
        Human3.6M frame without a detection is kept for the frames that have one (:attr:`_input_pref`), and this frame
        goes on with ground truth (:func:`ss.no_detection_note`, said); choosing ground truth there is a choice too
        (the dropdown showed the detection chosen before)."""
        picked = values.input_kind
        if picked not in ss.INPUT_KINDS or picked not in ss.input_choices(old.sample):
            return values, []  # (a choice the sample does not offer is refused as before: with_input says why)
        if picked == self._shown_input(old) and picked == old.input_kind:
            return values, []
        said: list[str] = []
        if picked != self._input_pref:
            self._input_pref = picked
            if picked not in ss.input_options(old.sample):  # (chosen here: said, whether or not said before)
                self._fallback_said.add(sequence_of(old.sample.key))
                said.append(ss.no_detection_note(old.sample))
        if picked not in ss.input_options(old.sample):
            values = dataclasses.replace(values, input_kind=old.input_kind)
        return values, said

    def _control_values(self) -> ss.ControlValues:
        g = self.gui
        return ss.ControlValues(model=g.lift.model.value,
                                input_kind=ss.INPUT_OF_LABEL.get(g.sample.input.value, g.sample.input.value),
                                focal_px=g.lift.focal.value, noise_level=g.noise.level.value, seed=g.noise.seed.value,
                                cloud_samples=g.noise.cloud.value, analytic=g.lift.analytic.value,
                                person=g.joints.person.value)

    def _value_handle(self, name: str) -> Any:
        """The GUI control of a :class:`ss.ControlValues` field."""
        g = self.gui
        return {"model": g.lift.model, "input_kind": g.sample.input, "focal_px": g.lift.focal,
                "noise_level": g.noise.level, "seed": g.noise.seed, "cloud_samples": g.noise.cloud,
                "analytic": g.lift.analytic, "person": g.joints.person}[name]

    def _set_control(self, name: str, value: Any) -> None:
        handle = self._value_handle(name)
        if name == "focal_px":
            value = float(round(value, 1))  # (the box's precision)
        if name == "person":
            value = self.state.sample.person_name(int(value))
        if name == "input_kind":
            value = ss.input_label(self.state.sample, value)
        self._put(handle, value)

    def _show_controls(self, st: SessionState) -> None:
        """Every value control shows ``st``."""
        for name in ("model", "input_kind", "focal_px", "noise_level", "seed", "cloud_samples", "analytic", "person"):
            self._set_control(name, self._shown_input(st) if name == "input_kind" else getattr(st, name))

    def _shown_input(self, st: SessionState) -> str:
        """The 2D input the dropdown shows for ``st``: the one chosen (:attr:`_input_pref`) on a Human3.6M frame that
        has no detection and so falls back to ground truth (:func:`ss.fell_back`) where the dropdown offers it
        (:func:`ss.input_choices`), else the one lifted."""
        keep = ss.fell_back(st, input_pref=self._input_pref) and self._input_pref in ss.input_choices(st.sample)
        return self._input_pref if keep else st.input_kind

    def _apply(self, st: SessionState, *, new_sample: bool = False) -> None:
        """Lift ``st`` and, if that works, make it the tab's state and draw it (raises, changing nothing, if not:
        a drawing that fails part way is taken back, the previous state drawn again)."""
        t0 = time.perf_counter()
        frame = compute_frame(st, self.app.pool.get(st.model), self.app.error_model)
        t1 = time.perf_counter()
        focal_changed = st.focal_px != self.state.focal_px  # (not each new frame of a playing sequence: _push)
        old_state, old_frame = self.state, self.frame
        self.state = st
        self.frame = frame
        try:
            self._push(frame, new_sample=new_sample, focal_changed=focal_changed)
        except Exception:
            # (a browser trial: an upload that failed while drawn left the new frustum under the old readout, and
            # the focal typed next was not applied)
            self.state, self.frame = old_state, old_frame
            if old_frame is not None:
                try:
                    self._push(old_frame, new_sample=True, focal_changed=True)
                except Exception:  # noqa: BLE001 - the first error is the one said
                    log.error("drawing the previous state again failed:\n%s", traceback.format_exc())
            raise
        t2 = time.perf_counter()
        if st.sample.key != old_state.sample.key:  # (drags of the sample left are dropped, or kept as they are:
            # undoing to a snapshot of an earlier visit brought back half of them, a review)
            self._undo = [u for u in self._undo if u.key[0] == st.sample.key]
        self.timing = Timing(compute_ms=1e3 * (t1 - t0), scene_ms=1e3 * (t2 - t1), total_ms=1e3 * (t2 - t0))
        self.update_count += 1

    # ------------------------------------------------------------------------------------------
    # Samples and sequences
    # ------------------------------------------------------------------------------------------
    def _gui_subject(self) -> str:
        assert self.gui.sample.subject is not None
        return self.gui.sample.subject.value

    def _gui_sequence(self) -> str:
        assert self.gui.sample.sequence is not None
        return self.gui.sample.sequence.value

    def _frame_pick_t(self) -> float:
        """When the frame was last chosen: the frame box's timestamp; when the player wrote it last, and a pick the
        tab made has not been applied by a pass yet (:meth:`_pick_pending`), the box's last timestamp before
        playback's. A pick made during playback wins over the frames written meanwhile (a browser trial's photo
        entry lost to them, and a subject picked then opened at the playing frame number instead of 0), and
        playback wins over picks already applied (a later trial's playback stayed on the photo frame it started
        on, or came to, while the frame box counted on)."""
        h = self.gui.play.frame
        return self._frame_user_t if self._player_wrote(h) and self._pick_pending() else h.update_timestamp

    def _pickers(self) -> list[Any]:
        g = self.gui.sample
        return [q for q in (g.source, g.demo, g.subject, g.sequence, g.camera, g.photo) if q is not None]

    def _pick_pending(self) -> bool:
        """Whether a sample picker holds a value the tab picked that no finished pass has read yet (not one this
        view wrote itself: :meth:`_put` and the other writes record theirs in :attr:`_own_t`)."""
        return any(q.update_timestamp > self._applied_t and self._own_t.get(id(q)) != q.update_timestamp
                   for q in self._pickers())

    def _write(self, handle: Any, value: Any, *, quiet: bool = False) -> None:
        """This view's own write of ``value`` to a control (not the tab's pick: :meth:`_pick_pending`). ``quiet``
        (the frame box during playback): on the server, not sent to the tab, whose box stays empty (cleared as
        playback starts) until a write that is not quiet, or the pass after playback stops, sends the box's value
        (:attr:`_frame_box_stale`).
        Playback's frames sent to the tab landed in the box between the keys of a frame typed there: in
        Chromium "200" became 146, then 0146."""
        frame_box = handle is self.gui.play.frame
        if quiet:
            set_value_here(handle, value)
            self._frame_box_stale = self._frame_box_stale or frame_box
        else:
            resend = frame_box and self._frame_box_stale and handle.value == value  # (viser sends a changed value only)
            handle.value = value
            if resend:
                send_value(handle)
            if frame_box:
                self._frame_box_stale = False
        self._own_t[id(handle)] = handle.update_timestamp

    def _player_wrote(self, h: Any) -> bool:
        """Whether the frame box ``h`` holds the player's last write (its value, written since it began)."""
        w = self._player_write
        return w is not None and h.value == w[0] and h.update_timestamp >= w[1]

    def _picks(self) -> ss.Picks:
        g = self.gui.sample

        def pick(h: Any) -> ss.Pick | None:
            return None if h is None else ss.Pick(h.value, h.update_timestamp)

        src = g.source.value
        return ss.Picks(source=ss.Pick(LABEL_SOURCES.get(src, src), g.source.update_timestamp),
                        demo=ss.Pick(g.demo.value, g.demo.update_timestamp),
                        frame=ss.Pick(self.gui.play.frame.value, self._frame_pick_t()),
                        subject=pick(g.subject), sequence=pick(g.sequence), camera=pick(g.camera), photo=pick(g.photo))

    def _requested_sample(self) -> Sample | None:
        """The sample the pickers ask for (:func:`poselifter_app.session.requested_key`); None: the one shown."""
        shown = self.state.sample.key
        video = self._video
        key = ss.requested_key(self._picks(), shown=shown, last_h36m=self._last_h36m,
                               last_upload=self._last_upload.key if self._last_upload is not None else None,
                               sources=self.app.sources, h36m=self.app.h36m, motion_frames=self.app.motion.num_frames,
                               upload_frames=video.num_frames if video is not None else None)
        self._note_frame_past_end(key, video)
        if key == shown:
            return None
        self._note_sequence_of_subject(key)
        if self._last_upload is not None and key == self._last_upload.key:
            return self._last_upload
        if video is not None and (i := video.index_of(key)) is not None:
            return video.sample(i)
        return self.app.sample(key)

    def _note_sequence_of_subject(self, key: str) -> None:
        """Say so when the subject picked has no sequence of the sequence picker's name, and ``key`` opens another
        (:func:`poselifter_app.session.sequence_of_subject`: a browser trial's S11 opened 'Directions', not a
        word said, from S9 'Phoning')."""
        want, g, h = parse_h36m(key), self.gui.sample, self.app.h36m
        if want is None or h is None or g.sequence is None:
            return
        picked = str(g.sequence.value)
        seqs = h.sequences(want.subject)
        if g.photo is not None and g.photo.value == want.photo_entry:
            return  # (a photo entry picked: that frame itself, no sequence replaced)
        if picked not in seqs and want.sequence == ss.sequence_of_subject(seqs, picked):
            self.show_message(f"{want.subject_name} has no {picked!r}: showing its {want.sequence!r}",
                              about=sequence_of(key))

    def _note_frame_past_end(self, key: str, video: Any) -> None:
        """Say so when the frame asked for (typed in the slider's box) is past the sequence's end or before its start
        and the last or first frame is shown instead (:func:`poselifter_app.session.requested_key` clamps it). While
        the box is being typed in ("9999" on the way to "99999") the value is remembered and said once the typing
        settles (:data:`TYPING_SETTLE_S`), even if the slider has been set to the last frame meanwhile."""
        try:
            wanted = int(self.gui.play.frame.value)
        except (TypeError, ValueError):
            return
        h36m_frame = parse_h36m(key)
        if h36m_frame is not None and self.app.h36m is not None:
            f, last = h36m_frame.frame, self.app.h36m.num_frames(h36m_frame.subject, h36m_frame.sequence) - 1
        elif video is not None and (at := video.index_of(key)) is not None:
            f, last = at, video.num_frames - 1
        elif source_of(key) == "motion" and (at := frame_of(key)) is not None:
            f, last = at, self.app.motion.num_frames - 1
        else:
            self._frame_note = None
            typed = self._typed_at.get("frame")
            if (typed is not None and typed != self._still_frame_typed and self.gui.play.frame.disabled
                    and source_of(key) != "motion"):  # (a disabled slider's box still sends what is typed in it)
                since = self._since_typed("frame")
                if since < TYPING_SETTLE_S:  # (each keystroke arrives: "1", "10", "100"; answer the value left)
                    self._settle_later(TYPING_SETTLE_S - since + 0.05)
                    return
                self._still_frame_typed = typed
                self.show_message(f"frame {wanted}: this is a still sample, with no frames to go to (play switches "
                                  "to the demo motion; a Human3.6M picker, or the source, shows Human3.6M's frames)")
            return
        about = sequence_of(key)
        if f == last and wanted > last:
            self._frame_note = (wanted, last, about)
        elif f == 0 and wanted < 0:
            self._frame_note = (wanted, 0, about)
        elif not (self._frame_note is not None and f == wanted == self._frame_note[1]
                  and self._frame_note[2] == about):
            self._frame_note = None  # another frame or sequence asked for since (the slider set to the end keeps it)
        if self._frame_note is None:
            return
        since = self._since_typed("frame")
        if since < TYPING_SETTLE_S:
            self._settle_later(TYPING_SETTLE_S - since + 0.05)
            return
        wanted, at, about = self._frame_note
        self._frame_note = None
        where = "past the end" if wanted > at else "before the start"
        self.show_message(f"frame {wanted} is {where} of this sequence (frames 0–{last}); showing frame {at}",
                          about=about, frame_key=key if f == at else None)
        self._put(self.gui.play.frame, at)  # (said once: the slider shows the frame in use)

    def sequence(self) -> SequenceSource | None:
        """The sequence the shown sample belongs to (Human3.6M or the demo motion), else None."""
        key = self.state.sample.key
        if source_of(key) == "motion":
            return self.app.motion
        if self._video is not None and self._video.index_of(key) is not None:
            return self._video
        h36m_frame = parse_h36m(key)
        if h36m_frame is not None and self.app.h36m is not None:
            return self.app.h36m_sequence(h36m_frame.subject, h36m_frame.sequence, h36m_frame.camera)
        return None

    def _frame_index(self) -> int | None:
        return frame_of(self.state.sample.key)

    def _show_play_info(self) -> None:
        """The line under the play controls: the frame shown, and while playing, where to jump (the frame box is left
        to the user then: :meth:`_write`); a still sample says what play does."""
        seq, idx = self.sequence(), self._frame_index()
        self._info_playing = self.playing
        if seq is not None and idx is not None:
            own = None  # (a video's or keypoint sequence's own frame number, where frames with nobody were left out)
            if isinstance(seq, vid.VideoSequence) and 0 <= idx < seq.num_frames and seq.frames[idx].index != idx:
                own = seq.frames[idx]
            text = (f"<small>{seq.label}: frame {idx} of 0–{seq.num_frames - 1} ({seq.fps:g} fps)"
                    + ("" if own is None else f" · the file's frame {own.index} ({own.time_s:.2f} s)")
                    + (" · playing: the bar shows where; type or drag a frame above to jump there"
                       if self._info_playing else "") + "</small>")
        elif source_of(self.state.sample.key) == "demo":
            text = "<small>a still sample: <b>play</b> switches to the demo motion</small>"
        else:
            text = "<small>a still upload (upload a video or a keypoint sequence to play it)</small>"
        if self.gui.play.info.content != text:
            self.gui.play.info.content = text

    def _show_sample(self, sample: Sample, *, reframe: bool) -> None:
        """Show ``sample`` now (drags reset; focal to its camera's unless the camera is the same one; model, noise,
        toggles kept). Raises, changing nothing, when it cannot be lifted."""
        old = self.state
        st, note = ss.for_sample(old, sample, input_pref=self._input_pref)
        st, followed, follow_note = self._follow(st, sample)
        with self._flags:
            typed_uv = self._typed_uv
        upload_left, typed_focal_at, gen = self._upload_left, self._typed_at.get("focal_px"), self._sample_gen
        if source_of(old.sample.key) == "upload" and old.sample.key != sample.key:
            # an upload's corrected joints wait for it (a user trial lost them going to a demo sample and back)
            self._upload_left = old if (old.dragged or any(old.others_dragged.values())) else None
        left = (self._upload_left if self._upload_left is not None and self._upload_left.sample.key == sample.key
                else None)
        if left is not None:
            st = st.evolve(keypoints=left.keypoints, dragged=left.dragged, person=left.person, others=left.others,
                           others_dragged=left.others_dragged, input_kind=left.input_kind)
            self._upload_left = None
        src = source_of(sample.key)
        frames_left = dict(self._frames_left)  # (taken back with the rest when the sample cannot be shown)
        if source_of(old.sample.key) == "video" and old.sample.key != sample.key:
            if old.dragged or any(old.others_dragged.values()):  # (without the frame's image: a review counted
                # about 1 MB a frame of a real video)
                self._frames_left[old.sample.key] = old.evolve(sample=replace(old.sample, image=None))
            else:
                self._frames_left.pop(old.sample.key, None)
        gone_frames = 0
        if src in UPLOADED_SOURCES:  # (another upload: the corrections of the one before go, and are said to)
            gone_frames = sum(sequence_of(k) != sequence_of(sample.key) for k in self._frames_left)
            self._frames_left = {k: v for k, v in self._frames_left.items()
                                 if sequence_of(k) == sequence_of(sample.key)}
        back = None
        if src == "video":
            back = self._frames_left.pop(sample.key, None)
            if back is not None:  # (that frame's corrections, with the person followed now selected)
                st = ss.with_person(st.evolve(keypoints=back.keypoints, dragged=back.dragged, person=back.person,
                                              others=back.others, others_dragged=back.others_dragged,
                                              input_kind=back.input_kind), st.person)
        same = _same_camera(sample.camera, old.sample.camera, src=src, old_src=source_of(old.sample.key))
        kept = same and src in SEQUENCE_SOURCES  # (a still sample opens at its camera's own focal)
        if kept:
            st = st.evolve(focal_px=old.focal_px)
        else:  # the new camera's focal replaces one being typed: the box shows it now (and the pass reads it back)
            self._typed_at.pop("focal_px", None)
        # a focal length the user chose, replaced by the new camera's: said, not silent
        chosen = abs(old.focal_px - old.sample.camera.alpha) > 0.5 and abs(st.focal_px - old.focal_px) > 0.5
        self._sample_gen += 1
        self._drop_typed_uv()
        try:
            self._apply(st, new_sample=True)
        except Exception:
            # not shown: the tab's own bookkeeping is taken back too (a review: joints corrected on an upload, waiting
            # for it, were forgotten when going back to it failed to draw)
            self._upload_left = upload_left
            self._frames_left = frames_left
            if typed_focal_at is not None:
                self._typed_at.setdefault("focal_px", typed_focal_at)
            # (the generation stays new: a key typed meanwhile was stamped with it; the (u, v) being typed for the
            # sample still shown is stamped again, and its timer, which may have fired meanwhile, set again)
            if typed_uv is not None:
                with self._flags:
                    restore = self._typed_uv is None
                    if restore:
                        self._typed_uv = (typed_uv[0], typed_uv[1], self._sample_gen, *typed_uv[3:])
                if restore:
                    self._later(TYPING_SETTLE_S, self._settle_typed_uv, typed_uv[0])
            if self._drag_gen == gen:  # (a drag begun on the sample still shown goes on)
                self._drag_gen = self._sample_gen
            raise
        self._followed = followed  # (only once shown: a refused sample changes nothing)
        if source_of(sample.key) == "h36m":
            self._last_h36m = sample.key
        if source_of(sample.key) == "video":
            self._last_upload = sample  # (coming back to the upload returns to this frame)
        self._show_sample_controls(st)
        if self.gui.play.frame.disabled:  # a still: only a frame typed from now on is answered (not one typed before)
            self._still_frame_typed = self._typed_at.get("frame")
        # (h36m/S1/Walking 1/c3: said once per sequence, not per frame; a still sample is its own sequence)
        seq_key = sequence_of(sample.key)
        if left is not None or (back is not None and not self.playing):  # (not a note per frame while playing)
            self.show_message(f"{sample.label}: the joints you corrected are back")
        if gone_frames:  # (a review: the corrections of a sequence's frames went with a new upload without a word)
            self.show_message(f"the joints you corrected on {gone_frames} frame{'s' if gone_frames != 1 else ''} of "
                              "the sequence shown before are dropped, as another upload is shown (download it first "
                              "to keep them)")
        # (an app trial typed 35 and read "track 3 is not found in ... frame 3": each key loads a frame, and the note,
        # said once, named the first key's; said once the typing settles, for the frame then shown)
        if follow_note is not None and not self._held_while_typing("follow", self._say_follow_note):
            self._gaps_said.add(follow_note[0])
            self.show_message(follow_note[1])
        moved = len(old.dragged) + sum(len(v) for k, v in old.others_dragged.items() if k != old.person)
        if moved and source_of(old.sample.key) not in UPLOADED_SOURCES and old.sample.key != sample.key:
            # (an upload's wait for it, above; a trial lost a demo's and a frame's drags on a switch, unsaid)
            self.show_message(f"{moved} dragged joint{'s' if moved != 1 else ''} on {old.sample.label} dropped, "
                              "as another sample shows its own 2D (download the result first to keep them)")
        if note and seq_key not in self._fallback_said:
            if self._since_typed("frame") < TYPING_SETTLE_S:  # said for the frame the typing ends on (a browser
                # trial typed 101 and read "no 2D detection for ... frame 1", the first key's frame)
                self._later_once("fallback", TYPING_SETTLE_S + 0.05, self._say_no_detection)
            else:
                self._fallback_said.add(seq_key)
                self.show_message(note, fallback=True)
        if not kept and chosen:
            uploaded = src in UPLOADED_SOURCES  # (a photo, keypoint file or video)
            self.show_message(f"focal length set to {'this input' if uploaded else 'this camera'}'s "
                              f"{focal_text(st.focal_px)} px (it was {focal_text(old.focal_px)} px: "
                              f"{'a new input' if uploaded else 'a new sample' if same else 'another camera'})",
                              focal=st.focal_px)
        cam = sample.camera
        view_key = (src, np.asarray(cam.R).tobytes(), np.asarray(cam.t, np.float64).tobytes())
        if reframe or view_key != self._view_key:  # a new camera (not a new frame of the same one)
            self._view_key = view_key
            self._reframe()

    def _follow(self, st: SessionState, sample: Sample
                ) -> tuple[SessionState, tuple[str, str] | None, tuple[tuple[str, str], str] | None]:
        """The person a video frame shows: the followed one (:attr:`_followed`) when the frame has them, else the
        frame's first (a new video: its first person, followed from then on). Returns the state, what to follow once
        it is shown, and a note to say (with its :attr:`_gaps_said` key) when the followed person is not in this
        frame: once per video and person while they come back later, and once when their track has ended (the
        one shown is followed from then on)."""
        if source_of(sample.key) != "video":
            return st, self._followed, None
        seq = sequence_of(sample.key)
        if self._followed is None or self._followed[0] != seq:
            return st, (seq, sample.person_tag(st.person)), None
        tag = self._followed[1]
        shown, found = ss.follow_person(st, tag)
        if found:
            return shown, self._followed, None
        video, index = self._video, None
        if video is not None:
            index = video.index_of(sample.key)
        name = st.sample.person_name(st.person)
        if video is not None and index is not None and not video.seen_after(tag, index):
            return st, (seq, st.sample.person_tag(st.person)), (
                (seq, f"{tag} ended"), f"{tag} is not seen after this point of the video ({sample.label}): showing "
                f"{name}, followed from now on")
        if (seq, tag) in self._gaps_said:
            return st, self._followed, None
        return st, self._followed, ((seq, tag), f"{tag} is not found in {sample.label}: showing {name}; {tag} is "
                                    "selected again in each frame that has them (said once; the download's warnings "
                                    "list the frames it is missing from)")

    def _held_while_typing(self, kind: str, say: Callable[[], None]) -> bool:
        """Whether the frame box is being typed (a key within :data:`TYPING_SETTLE_S`): then ``say`` runs once it
        settles (:meth:`_later_once` of ``kind``), for the frame then shown, and a note is not said now."""
        left = TYPING_SETTLE_S - self._since_typed("frame")
        if left > 0:
            self._later_once(kind, left + 0.05, say)
        return left > 0

    def _say_follow_note(self) -> None:
        """The note of :meth:`_follow` on the frame shown, held while the frame box was typed, said now if the followed
        person is still not in it (once per video and person, as when not typed)."""
        with self.lock:
            if self._held_while_typing("follow", self._say_follow_note):
                return
            _, _, note = self._follow(self.state, self.state.sample)
            if note is not None and note[0] not in self._gaps_said:
                self._gaps_said.add(note[0])
                self.show_message(note[1])

    def _say_no_detection(self) -> None:
        """:func:`poselifter_app.session.no_detection_note`, held while the frame box was typed, said now if the
        frame shown still has no detection of its own (once per sequence)."""
        with self.lock:
            if self._held_while_typing("fallback", self._say_no_detection):
                return
            st = self.state
            key = st.sample.key
            seq_key = sequence_of(key)
            if ss.fell_back(st, input_pref=self._input_pref) and seq_key not in self._fallback_said:
                self._fallback_said.add(seq_key)
                self.show_message(ss.no_detection_note(st.sample), fallback=True)

    def _show_sample_controls(self, st: SessionState) -> None:
        """Pickers, 2D-input options, focal range and frame slider for ``st`` (the source dropdown last)."""
        g, p = self.gui.sample, self.gui.play
        sample = st.sample
        src = source_of(sample.key)
        opts = [ss.input_label(sample, kind) for kind in ss.input_choices(sample)]
        shown = ss.input_label(sample, self._shown_input(st))
        if list(g.input.options) != opts:
            g.input.options = opts
            g.input.value = shown  # (new options can reset it to the first one)
        self._put(g.input, shown)
        people = [sample.person_name(k) for k in range(sample.num_people)]
        pick = self.gui.joints.person
        if list(pick.options) != people:
            pick.options = people
            pick.value = people[st.person]  # (new options reset the value, as if the tab had picked person 1)
        pick.disabled = len(people) == 1
        self._set_control("person", st.person)
        lo, hi = focal_min(sample), focal_max(sample)
        if self.gui.lift.focal.min != lo:
            self.gui.lift.focal.min = lo
        if self.gui.lift.focal.max != hi:
            self.gui.lift.focal.max = hi
        # (each frame of a playing sequence: not over a focal being typed, nor before the pass that settles it at
        # TYPING_GROW_S has clamped it and shown it: a frame first would put the old value back, silently)
        if self._since_typed("focal_px") >= TYPING_GROW_S + 1.0:
            self._set_control("focal_px", st.focal_px)
        if src == "demo":
            self._put(g.demo, demo_name(sample.key))
        seq = self.sequence()
        idx = self._frame_index()
        if seq is not None and idx is not None:
            new_range = p.frame.max != seq.num_frames - 1
            if new_range:
                p.frame.max = seq.num_frames - 1
            typed = p.frame.value
            if not (self._since_typed("frame") < TYPING_SETTLE_S and typed != idx
                    and ss.clamp_frame(typed, seq.num_frames) == idx):  # (a frame typed past an end is left in
                # the box until the typing settles, and the pass that says so puts the end frame there: a browser
                # trial's "99999", typed slowly, read 1967 after its fourth key, then 19679)
                self._put(p.frame, idx, quiet=self.playing)  # (playback's frames: on the server, and the bar)
                if self.playing and new_range:
                    self._clear_frame_box()  # (another sequence while playing: no frame number past its end, nor
                    # one that the box would not take typed again)
            at = round(100.0 * idx / max(seq.num_frames - 1, 1), 1)
            if p.position.value != at:
                p.position.value = at
        self._show_play_info()
        p.frame.disabled = seq is None
        if p.position.visible != (seq is not None):
            p.position.visible = seq is not None
        still_upload = seq is None and src != "demo"
        if p.play.disabled != still_upload:  # (a trial pressed play on a photo after a video, and got an error)
            p.play.disabled = still_upload
        h36m_frame = parse_h36m(sample.key)
        if h36m_frame is not None and self.app.h36m is not None and g.subject is not None and g.sequence is not None \
                and g.camera is not None and g.photo is not None:
            subj, sequence, camera = h36m_frame.subject_name, h36m_frame.sequence, h36m_frame.camera
            seqs = self.app.h36m.sequences(int(subj[1:]))
            if list(g.sequence.options) != seqs:
                g.sequence.options = seqs
                self._write(g.sequence, sequence)  # (new options reset it to the first one, stamped as if the tab had
                # picked it: a trial's photo pick then opened that sequence's frame 0)
            self._put(g.subject, subj)
            self._put(g.sequence, sequence)
            self._put(g.camera, camera)
            entry = h36m_frame.photo_entry
            self._put(g.photo, entry if entry in g.photo.options else NO_PHOTO)
        label = SOURCE_LABELS["upload" if src == "video" else src]
        if label == SOURCE_LABELS["upload"] and label not in g.source.options:
            g.source.options = [*g.source.options, label]
        self._put(g.source, label)

    # ------------------------------------------------------------------------------------------
    # Drawing
    # ------------------------------------------------------------------------------------------
    def _draw_2d(self, kp: np.ndarray, noisy: np.ndarray | None = None) -> None:
        """The 2D inset, the joints on the image plane and the (u, v) box of the selected joint."""
        st = self.state
        s = st.sample
        uv = (float(round(kp[self.selected, 0], 1)), float(round(kp[self.selected, 1], 1)))
        with self._flags:
            typing = self._typed_uv is not None  # (a position being typed is left in its box until applied)
        if not typing and tuple(float(v) for v in self.gui.joints.uv.value) != uv:
            if self.playing:  # (on the server only: a researcher trial's u typed while playing was overwritten by
                set_value_here(self.gui.joints.uv, uv)  # the frames within 0.5 s, and never reached the app, so
                self._uv_box_stale = True  # the "pause first" note never came; sent once playback stops)
            else:
                self.gui.joints.uv.value = uv
                self._uv_box_stale = False
        noisy = noisy if st.noise_level > 0 else None  # (what is lifted at a noise level above 0)
        poses = {"gt": s.keypoints_2d if (self.gui.lift.gt.value and s.has_gt_2d) else None,
                 "detected": s.detected_2d, "noisy": noisy, "current": kp}
        base_key = (id(s.image) if s.image is not None else None, st.image_size)  # (sequence frames share a canvas)
        if self._base_key != base_key:
            self._base = scaled_base(s.image, size=st.image_size)
            self._base_key = base_key
        others = [(k, st.others[k]) for k in sorted(st.others)]
        self.gui.sample.image.image = overlay(s.image, size=st.image_size, poses=poses, selected=self.selected,
                                              prescaled=self._base, others=others, zoom=True)
        self._last_plane = draw_2d(self.scene.pose, st, kp, self._last_plane)
        draw_noisy_2d(self.scene.pose, st, noisy)
        draw_others_2d(self.scene.pose, st, [o for _, o in others])

    def _push(self, fr: Frame, *, new_sample: bool, focal_changed: bool) -> None:
        st = self.state
        with self.target.atomic():
            if new_sample or focal_changed:
                s = st.sample
                image_key = (id(s.image) if s.image is not None else None, st.image_size, s.camera.name,
                             s.upload is None)
                draw_camera(self.scene.camera, st, new_sample=new_sample, new_image=image_key != self._image_key)
                self._image_key = image_key
                self._last_plane = None  # the plane moved: every joint sphere
            self._draw_2d(fr.current_2d, fr.noisy_2d)
            draw_pose(self.scene.pose, self.scene.camera, fr, show_gt=bool(self.gui.lift.gt.value),
                      name=st.sample.person_name(st.person), labels=not self._close_up)
            self._update_trail(fr)
            # (in the same batch as the scene: a researcher trial's readout, applied apart from it, said Z 10959 mm
            # beside the scene's "root Z 11.10 m" in every screenshot taken while playing)
            ro = self.gui.readout
            ro.readout.content = readout_markdown(fr, st)
            ro.spread.content = spread_details(fr.spread) if fr.spread is not None else ""
            ro.response.image = response_image(fr.lifted, root=fr.root,
                                               gt=fr.gt_3d if self.gui.lift.gt.value else None, cloud=fr.cloud)
        if self.gui.lift.auto_frame.value:  # (the head-on view keeps to the joints: _keep_in_view)
            since = self._since_typed("focal_px")
            if since < TYPING_SETTLE_S:  # a focal being typed ("1", "11", "114", "1144"): reframe once it settles,
                self._auto_frame_later(TYPING_SETTLE_S - since + 0.05)  # not to each half-typed value
            else:
                self._keep_in_view(zoom_in=focal_changed)

    def _update_trail(self, fr: Frame) -> None:
        st = self.state
        seq, idx = self.sequence(), self._frame_index()
        if isinstance(seq, VideoSequence):  # every track's smoothed path, for the model and focal length in use
            self.trail, self._trail_key = {}, None
            tracks = seq.trajectories(self.app.pool.get(st.model), st.focal)
            draw_tracks(self.scene.camera, tracks, visible=bool(self.gui.play.trail.value))
            return
        if seq is None or idx is None:
            self.trail = {}
            self._trail_key = None
        else:
            # (the input chosen, not the one a frame without a detection fell back to: a review saw the trail
            # restart on every such frame)
            key = (seq.key, st.model, st.focal_px, self._input_pref, st.noise_level, st.seed, st.analytic)
            if key != self._trail_key:
                self.trail, self._trail_key = {}, key
            if not st.dragged:
                self.trail[idx] = np.asarray(fr.root, np.float64).copy()
        draw_trail(self.scene.camera, self.trail, visible=bool(self.gui.play.trail.value))

    # ------------------------------------------------------------------------------------------
    # Viewpoints
    # ------------------------------------------------------------------------------------------
    def framing_points(self) -> np.ndarray:
        """World points (m) the overview keeps in view (:func:`poselifter_app.scene.framing_points`)."""
        return framing_points(self.state, self.frame)

    def viewer(self) -> tuple[framing.Viewpoint, float, float]:
        return self.camera.get()

    @control
    def overview(self) -> None:
        """The default view: camera, frustum and person in view, from behind, above and beside the camera."""
        with self.lock:
            self._close_up = False
            set_joint_radius(self.scene.pose, JOINT_RADIUS_M)
            self.scene.camera.ray.visible = self.scene.camera.root_label.visible = True
            if self.frame is not None:
                draw_others(self.scene.pose, self.frame)  # (their labels back)
            _, fov, aspect = self.camera.get()
            self.camera.set(scene_overview(self.state, self.frame, fov_y=fov, aspect=aspect))

    def _reframe(self) -> None:
        try:
            self.overview()
        except Exception:  # noqa: BLE001 - a viewpoint is cosmetic
            log.exception("could not frame the 3D view")

    def _keep_in_view(self, *, zoom_in: bool = False) -> None:
        """Auto reframing: when the lifted skeleton (or the camera) leaves the view, fit them again, keeping the
        viewing direction; ``zoom_in`` (after a focal change) also when they shrank within :data:`SHRUNK_VIEW` of
        it (a user trial: the view stayed far out after the focal came back down from 6000 px)."""
        vp, fov, aspect = self.camera.get()
        if self._close_up:  # the head-on view keeps to the 2D joints on the image plane (a trial: a focal change
            # zoomed out of it, to everything): looked at again after a focal change, or when the joints left it
            joints = head_on_points(self.state)
            if zoom_in or not framing.in_view(joints, vp, fov_y=fov, aspect=aspect, margin=0.98):
                self.head_on_view()
            return
        pts = self.framing_points()
        inside = framing.in_view(pts, vp, fov_y=fov, aspect=aspect, margin=0.98)
        on_screen = framing.screen_coords(pts, vp, fov_y=fov, aspect=aspect)[:, :2]
        # (their extent, wherever they are in the view: a trial's view, turned by a slider's arrow keys, kept them
        # small and to one side, so they reached past SHRUNK_VIEW from its centre and it never zoomed back in)
        shrunk = zoom_in and inside and float((on_screen.max(0) - on_screen.min(0)).max()) / 2 < SHRUNK_VIEW
        if not inside or shrunk:
            up_ = vp.up if np.linalg.norm(vp.up) > 0 else np.array([0.0, 0.0, 1.0])
            self.camera.set(framing.fit(pts, direction=vp.look_at - vp.eye, up=up_, fov_y=fov, aspect=aspect))

    def _auto_frame(self) -> None:
        if self.gui.lift.auto_frame.value and self.frame is not None:
            with self.lock:
                self._keep_in_view(zoom_in=True)

    def _auto_frame_later(self, delay: float) -> None:
        """:meth:`_auto_frame` once the focal length's box has had no key for :data:`TYPING_SETTLE_S` (one timer at a
        time, :meth:`_later_once`; one that fires while keys still come waits again)."""
        self._later_once("auto_frame", delay, self._auto_frame_settled)

    def _auto_frame_settled(self) -> None:
        since = self._since_typed("focal_px")
        if since < TYPING_SETTLE_S:
            self._auto_frame_later(TYPING_SETTLE_S - since + 0.05)
        else:
            self._auto_frame()

    @control
    def head_on_view(self) -> None:
        """Look straight at the image plane from the camera's side, centred on the current 2D joints, which fill
        most of the view, image up = up: the joints can be dragged precisely (the readout's side / top views show
        the 3D response). Joint spheres shrink with the joints' extent; "reset 3D view" goes back."""
        with self.lock:
            _, fov, aspect = self.camera.get()
            vp, radius = scene_head_on(self.state, fov_y=fov, aspect=aspect)
            self._close_up = True
            set_joint_radius(self.scene.pose, radius)
            self.scene.camera.ray.visible = False  # it would pass next to the eye and cover the joints
            self.scene.camera.root_label.visible = False  # (drawn on top of everything)
            for h in self.scene.pose.others_labels:  # (as the root's: they float over the nearer person's image)
                h.visible = False
            self.camera.set(vp)

    # ------------------------------------------------------------------------------------------
    # Controls in code form (the GUI does the same; each ends in a sync pass)
    # ------------------------------------------------------------------------------------------
    @control
    def set_source(self, source: str) -> None:
        """``"demo"``, ``"motion"``, ``"h36m"`` or ``"upload"``."""
        if source not in self.app.sources:
            raise PoseLifterError(f"unknown sample source {source!r}; available: {self.app.sources}")
        label = SOURCE_LABELS[source]
        if source == "upload" and label not in self.gui.sample.source.options:
            raise PoseLifterError("nothing uploaded yet: use the 'upload photo, video or keypoint JSON' button (File "
                                  "tab)")
        self._set_and_check(self.gui.sample.source, label, lambda: source_of(self.state.sample.key) == source)

    @control
    def select_demo(self, name: str) -> None:
        """Show the embedded demo sample ``name``."""
        self.app.demo.get(name)  # raises for unknown names
        with self._runner.holding():
            self.gui.sample.demo.value = name
            self.gui.sample.source.value = SOURCE_LABELS["demo"]
        self._runner.request()
        if self.state.sample.key != demo_key(name):
            raise PoseLifterError(self.messages[-1] if self.messages else f"could not show demo sample {name!r}")

    @control
    def select_h36m(self, *, subject: int, sequence: str, camera: str, frame: int) -> None:
        """Show a Human3.6M view (``camera`` is the camera id, ``frame`` the 0-based 50-fps row)."""
        if self.app.h36m is None:
            raise PoseLifterError("no Human3.6M folder was given (--h36m)")
        sample = self.app.h36m.get(subject, sequence, camera, frame)  # raises for unknown ones
        with self._runner.holding(), self.lock:
            if sample.key != self.state.sample.key:
                self._show_sample(sample, reframe=False)

    def _set_and_check(self, handle: Any, value: Any, done: Callable[[], bool]) -> None:
        if handle.value != value:
            handle.value = value
        self._runner.request()
        if not done():
            raise PoseLifterError(self.messages[-1] if self.messages else f"could not set {value!r}")

    @control
    def set_input_kind(self, kind: str) -> None:
        """2D input ``"gt"`` or ``"detected"``; the choice is kept for the next samples that have it."""
        self._set_value("input_kind", kind)

    @control
    def set_model(self, name: str) -> None:
        self._set_value("model", name)

    @control
    def set_focal(self, value: float) -> None:
        """Focal length ``alpha`` (px): the root slides along its viewing ray (``Z ∝ f`` exactly for a pixel-space
        model; the default reads the rays too, so its Z/f moves with it)."""
        self._set_value("focal_px", value)

    @control
    def set_noise(self, level: float) -> None:
        self._set_value("noise_level", level)

    @control
    def set_seed(self, seed: Any) -> None:
        self._set_value("seed", seed)

    @control
    def set_cloud_samples(self, n: Any) -> None:
        self._set_value("cloud_samples", n)

    @control
    def set_analytic(self, on: bool) -> None:
        self._set_value("analytic", bool(on))

    def _set_value(self, name: str, value: Any) -> None:
        """Put ``value`` in its control as the browser would (values viser cannot hold are refused here) and sync;
        raises with the message when the value was refused."""
        n = self._message_count
        handle = self._value_handle(name)
        if name == "input_kind":  # ("gt" / "detected": the dropdown shows their labels)
            value = ss.input_label(self.state.sample, value) if isinstance(value, str) else value
        try:
            typed = type(handle.value)(value)
        except (TypeError, ValueError, OverflowError):
            raise PoseLifterError(f"{name.replace('_', ' ')}: {value!r} is not a valid value") from None
        if name in ("seed", "cloud_samples") and isinstance(value, float) and value != int(value):
            raise PoseLifterError(f"{name.replace('_', ' ')} must be an integer, got {value!r}")
        handle.value = typed
        self._runner.request()
        if self._message_count != n and self._last_was_error:  # (a clamped value is a note: applied)
            raise PoseLifterError(self.messages[-1])

    @control
    def reset_focal(self) -> None:
        self.set_focal(self.state.sample.camera.alpha)

    @control
    def scale_focal(self, factor: float) -> None:
        """The focal length times ``factor`` (the focal buttons: 0.5, 2), kept within the slider's range."""
        f = self.gui.lift.focal
        now, exact = float(self.state.focal_px), float(self.state.focal_px) * float(factor)
        target = min(max(exact, float(f.min)), float(f.max))
        end = "end" if factor > 1 else "start"
        if abs(target - now) < 0.05:
            self.show_message(f"the focal length is at the slider's {end} already ({focal_text(target)} px)")
            return
        self.set_focal(target)
        if f"{target / now:.3g}" != f"{float(factor):.3g}":  # (a teacher trial: 4000 x 2 gave 6000, Z x 1.5, unsaid;
            # a review: 3001 x 2 -> 6000 px read "2 times what it was, not 2")
            self.show_message(f"{FOCAL_STEPS[0 if factor < 1 else 1]} would be {focal_text(exact)} px, past the "
                              f"slider's {end}: the focal length is {focal_text(target)} px, {target / now:.3g} times "
                              f"what it was, not {float(factor):g}", focal=target)

    @control
    def resample(self) -> None:
        """New noise draws (seed + 1; after the largest seed, 0)."""
        with self.lock:
            self.gui.noise.seed.value = (int(self.state.seed) + 1) % (MAX_SEED + 1)

    @staticmethod
    def _undo_key(st: SessionState) -> tuple[Any, ...]:
        """Which pose an undo snapshot belongs to: the sample, person and 2D input."""
        return (st.sample.key, st.person, st.input_kind)

    def _push_undo(self, st: SessionState, *, gesture: int) -> None:
        """Keep ``st``'s joints to undo to, unless the gesture on top already kept its start (-1: always)."""
        key = self._undo_key(st)
        if gesture >= 0 and self._undo and self._undo[-1].gesture == gesture and self._undo[-1].key == key:
            return
        self._undo.append(_UndoStep(key, st.keypoints.copy(), frozenset(st.dragged), gesture))
        del self._undo[:-UNDO_DEPTH]

    @control
    def undo_drag(self) -> None:
        """The joints of the pose shown as they were before its last drag (a mouse drag from press to release, a
        typed position, :meth:`move_joint`) or reset; said when there is none."""
        with self._runner.holding(), self.lock:
            key = self._undo_key(self.state)
            k = next((i for i in range(len(self._undo) - 1, -1, -1) if self._undo[i].key == key), None)
            if k is None:
                self.show_message("no drag of this pose to undo")
                return
            step = self._undo.pop(k)
            self._apply(self.state.evolve(keypoints=step.keypoints.copy(), dragged=set(step.dragged)))

    @control
    def reset_joints(self) -> None:
        """Undo all joint drags."""
        with self._flags:
            self._reset_request = True
            self._drags.clear()
        self._runner.request()

    @control
    def move_joint(self, joint: Any, uv: Any) -> None:
        """Put 2D joint ``joint`` (index or name) at pixel ``uv`` and lift; refused far outside the image. The
        joint becomes the selected one."""
        j = ss.joint_index(joint)
        n = self._message_count
        self._queue_drag(j, uv)
        if self._message_count != n:
            raise PoseLifterError(self.messages[-1])

    @control
    def set_keypoints(self, keypoints: Any) -> None:
        """Replace the whole current 2D pose ``(17, 2)`` px. Invalid poses are refused; the previous pose stays."""
        with self._runner.holding(), self.lock:
            st = ss.with_keypoints(self.state, keypoints)
            self._apply(st)

    def _queue_drag(self, joint: int, uv: Any, *, mouse: bool = False) -> None:
        with self._flags:
            self._drags[joint] = np.asarray(uv, dtype=np.float64).reshape(2) if _is_numeric_pair(uv) else uv
            self._drags_by_mouse = mouse
            if not mouse:  # (a mouse drag's gesture begins at its "start" event: on_joint_drag)
                self._gesture += 1
            self._drags_gesture = self._gesture
        if self.selected != joint:
            self.selected = joint
            if self.gui.joints.joint.value != JOINT_NAMES[joint]:
                self.gui.joints.joint.value = JOINT_NAMES[joint]
        self._runner.request()

    def _on_joint_selected(self) -> None:
        name = self.gui.joints.joint.value
        try:
            j = ss.joint_index(name)
        except PoseLifterError:
            self.gui.joints.joint.value = JOINT_NAMES[self.selected]
            raise
        with self.lock:
            if j != self.selected:
                self.selected = j
                self._drop_typed_uv()
                self._draw_2d(self.state.keypoints, self.frame.noisy_2d if self.frame is not None else None)
                if self._uv_box_stale:  # (while playing: the box shows the joint just picked, where it is now)
                    send_value(self.gui.joints.uv)

    def _on_uv_event(self, event: Any) -> None:
        """The (u, v) boxes. A browser sends every keystroke ("9", "99", "999", "9999"): applying each would move the
        joint to half-typed positions and leave it at the last one in range when the whole value is refused. So a
        typed position is applied once the typing settles (:data:`TYPING_SETTLE_S`), to the joint, person and sample
        it was typed for (dropped if any of them changed meanwhile: :meth:`_drop_typed_uv`); a value set here (not
        from a tab) at once."""
        if getattr(event, "client", None) is None:
            self._do(self._on_joint_uv)
        else:
            self._do(self._note_typed_uv)

    def _note_typed_uv(self) -> None:
        if self.playing:  # each frame brings its own 2D (a user trial: the typed value was dropped with no word)
            now = time.monotonic()
            if now - self._typed_while_playing_at > TYPING_SETTLE_S:  # (once per burst of keys, not per keystroke)
                self.show_message(TYPED_WHILE_PLAYING)
            self._typed_while_playing_at = now
            return
        uv = np.asarray(self.gui.joints.uv.value, np.float64).reshape(2)
        with self._flags:
            seq = next(self._typed_seq)
            self._typed_uv = (seq, self.selected, self._sample_gen, self.state.person, uv.copy())
        self._later(TYPING_SETTLE_S, self._settle_typed_uv, seq)

    def _settle_typed_uv(self, seq: int) -> None:
        """Apply the typed position if keystroke ``seq`` was the last one and it is still for what is shown."""
        with self._flags:
            typed = self._typed_uv
            if typed is None or typed[0] != seq:
                return  # a newer keystroke (its own timer applies it), or dropped
            self._typed_uv = None
        _, joint, gen, person, uv = typed
        with self.lock:
            if (gen, person, joint) == (self._sample_gen, self.state.person, self.selected):
                self._move_if_changed(joint, uv)

    def _move_if_changed(self, joint: int, uv: np.ndarray) -> None:
        """Move ``joint`` to the (u, v) box's ``uv`` px unless it is there (the box's own echo, to 0.1 px). Not
        :meth:`move_joint`: the pass says a refusal, and move_joint would raise it again (a second toast)."""
        if not np.allclose(uv, np.round(self.state.keypoints[joint], 1), atol=0.05):
            self._queue_drag(joint, uv)

    def _drop_typed_uv(self) -> None:
        """Forget a position being typed: another sample, person or joint is shown (the box then shows that)."""
        with self._flags:
            self._typed_uv = None

    def _on_joint_uv(self) -> None:
        with self.lock:
            self._move_if_changed(self.selected, np.asarray(self.gui.joints.uv.value, np.float64))

    def drag_to_pixel(self, event: Any) -> np.ndarray:
        """Pixel under the pointer of a drag event: the viewer's ray through ``event.end_position`` (world, m)
        intersected with the image plane; without the viewer's camera, the central projection of
        ``end_position`` through the sample camera."""
        R, C = camera_world(self.state)
        end_c = R @ (np.asarray(event.end_position, np.float64) - C)
        d = image_plane_depth(self.state)
        p = None
        client = getattr(event, "client", None)
        if client is not None:
            o_c = R @ (np.asarray(client.camera.position, np.float64) - C)
            ray = end_c - o_c
            if abs(ray[2]) > 1e-9:
                s = (d - o_c[2]) / ray[2]
                if s > 0:
                    p = o_c + s * ray
        if p is None:
            if end_c[2] <= 1e-6:
                raise PoseLifterError("joint dragged behind the camera; ignored")
            p = end_c * (d / end_c[2])
        return project_generic(p[None], np.asarray(self.state.focal, np.float64),
                               np.asarray(self.state.sample.camera.principal_point, np.float64))[0]

    def on_joint_drag(self, joint: int, event: Any) -> None:
        """Drag callback of 2D joint ``joint`` (a :class:`viser.SceneNodeDragEvent`). Events of a drag that began
        on another sample (late events after the sample changed mid-drag) are ignored."""
        phase = getattr(event, "phase", "update")
        with self.lock:
            if phase == "start":
                self._drag_gen = self._sample_gen
                self._drag_refusal_said = False  # (one refusal per drag, not one per pointer move: a trial's 10)
                with self._flags:
                    self._gesture += 1  # (one undo step per drag)
            elif self._drag_gen is not None and self._drag_gen != self._sample_gen:
                return
            if self.playing:  # each frame brings its own 2D: said once per drag, nothing moved
                if phase == "start":
                    self.show_message(DRAGGED_WHILE_PLAYING)
                return
            uv = self.drag_to_pixel(event)
        self._queue_drag(int(joint), uv, mouse=True)

    # ------------------------------------------------------------------------------------------
    # Playback
    # ------------------------------------------------------------------------------------------
    @property
    def playing(self) -> bool:
        return self.player.playing

    def _play_position(self) -> tuple[SequenceSource, int] | None:
        seq = self.sequence()
        if seq is None:
            return None
        if self._frame_box_waits(seq) and self._play_shown is not None:
            return seq, self._play_shown  # (playing on meanwhile; the frame typed is taken once the typing settles)
        return seq, int(self.gui.play.frame.value)

    def _frame_box_waits(self, seq: SequenceSource) -> bool:
        """The frame box is being typed in, or holds a frame typed past an end of ``seq`` that no pass has answered
        yet (:meth:`_note_frame_past_end` says so and puts the end frame there): playback neither takes it nor
        writes over it. A browser trial's "99999" typed during playback went to frame 1601, 99999 modulo the
        sequence's length, without a word; or the next frame replaced it before the note was said."""
        if self._since_typed("frame") < TYPING_SETTLE_S:
            return True
        try:
            typed = int(self.gui.play.frame.value)
        except (TypeError, ValueError):
            return True
        return ss.clamp_frame(typed, seq.num_frames) != typed

    def _show_frame(self, index: int) -> None:
        """The player's next frame: into the frame box on the server, for a sync pass to show (here, or in the pass
        running now), and not sent to the tab (:meth:`_write`); not while the box is being typed in (a browser
        trial's playback wrote its frames between the keys, and "1500" typed became 1920, or 670), nor over a frame
        typed past an end that no pass has answered yet (:meth:`_frame_box_waits`)."""
        seq = self.sequence()
        if seq is None or seq.key != self.player.playing_key:
            return  # (a frame of the sequence left meanwhile: a browser trial's photo pick opened at its number)
        self._play_shown = index
        if self._frame_box_waits(seq):
            return
        h = self.gui.play.frame
        if not self._player_wrote(h):
            self._frame_user_t = h.update_timestamp  # (set by the user, a picker or a pass since: theirs)
        self._player_write = (int(index), time.time())  # (before the write: it may run a pass at once)
        self._write(h, index, quiet=True)  # (the tab is sent it once playback stops: :meth:`_write`)

    def _clear_frame_box(self) -> None:
        """Empty the tab's frame box while playing (:func:`~poselifter_app.viser_hooks.clear_box`): any frame typed
        there jumps, even the one it showed (a Chromium check: "0" typed over a stale "0" sent nothing). The pass
        after playback stops sends the frame shown (:attr:`_frame_box_stale`)."""
        clear_box(self.gui.play.frame)
        self._frame_box_stale = True

    def _player_stopped(self) -> None:
        try:
            self.gui.play.play.label, self.gui.play.play.icon = "play", viser.Icon.PLAYER_PLAY
        except Exception:  # noqa: BLE001 - the tab may be gone
            pass
        if self._frame_box_stale or self._uv_box_stale or self._info_playing:  # (that pass sends the tab the boxes'
            self._do(self._runner.request)  # values and drops "playing" from the line; through the error wrapper:
            # this runs on the player's thread too)

    @control
    def toggle_play(self) -> None:
        """Play / pause the shown sequence (Human3.6M, the demo motion, an uploaded video or keypoint sequence); on a
        demo still, play the demo motion. An uploaded photo or keypoint file is a still: nothing to play."""
        if self.playing:
            self.stop_playback()
            return
        if self.sequence() is None:
            if self.state.sample.upload is not None:
                raise PoseLifterError("an uploaded photo or keypoint file is a single frame: nothing to play")
            self.gui.sample.source.value = SOURCE_LABELS["motion"]
            self._runner.request()
            end = time.perf_counter() + 5.0
            while self.sequence() is None and time.perf_counter() < end:  # (a pass in another thread shows it)
                time.sleep(0.01)
            if self.sequence() is None:
                raise PoseLifterError("nothing to play")
        self.gui.play.play.label, self.gui.play.play.icon = "pause", viser.Icon.PLAYER_PAUSE
        self.player.start()
        self._clear_frame_box()  # (after the start: a pass ending in between would send the number back)

    def stop_playback(self, *, wait: bool = True) -> None:
        self.player.stop(wait=wait)
        self._player_stopped()

    # ------------------------------------------------------------------------------------------
    # Upload / download
    # ------------------------------------------------------------------------------------------
    @control
    def load_upload(self, name: str, content: bytes) -> None:
        """An uploaded file: a photo (2D joints of everyone by the app's detector) or a keypoint JSON
        (:mod:`app.upload`), a video or a keypoint sequence JSON with ``frames`` (:mod:`app.video`: lifted,
        tracked and smoothed, then played like a sequence). On any problem a message is shown and the tab's state
        is left as it was."""
        try:
            self._load_upload(name, content)
        except (up.UploadRefused, up.DetectorMissing):  # (no detector: this install's problem, not the file's)
            raise
        except PoseLifterError as exc:
            raise up.UploadRefused(str(exc)) from None

    def _superseded(self, mine: int, since: float) -> str | None:
        """Why an upload begun at ``since`` (time.time()) as this tab's ``mine``-th is not to be shown once its file
        is read and lifted: another upload begun after it and shown (not one refused), or a sample picked since (a
        browser trial: a video finishing late replaced the keypoint file uploaded, or the subject picked, while it
        was lifted). None: show it, the last thing the user did. Call it holding :attr:`lock`."""
        if self._upload_shown > mine:
            return "another file was uploaded"
        if any(q.update_timestamp > since and self._own_t.get(id(q)) != q.update_timestamp for q in self._pickers()):
            return "another sample was picked"
        return None

    def _close_refusal(self) -> None:
        """Close the notification of an upload refused before (it stays until closed), and clear an error the status
        line still shows (a refusal stays there a minute: :meth:`show_message`), once an upload is shown."""
        with self._status_lock:
            if self._status_notes and any(q.error for q in self._status_notes):
                self._status_notes = [q for q in self._status_notes if not q.error]
                self._note_until = 0.0
                self.gui.readout.status.content = status_text(self._status_notes)
        note, self._sticky_note = self._sticky_note, None
        if note is not None:
            try:
                note.remove()
            except Exception:  # noqa: BLE001 - the tab may have closed it, or gone
                log.debug("could not close the refusal's notification", exc_info=True)

    @contextlib.contextmanager
    def _showing_upload(self, mine: int, since: float, said: str) -> Iterator[bool]:
        """Whether the upload ``mine`` begun at ``since`` is still to be shown (:meth:`_superseded`; if not, ``said``
        is shown with the reason in its ``{}``), asked before playback is stopped for it and again, holding
        :attr:`lock`, for the body that shows it; a body that returns normally marks it the latest shown."""
        with self._runner.holding(), self.lock:
            why = self._superseded(mine, since)
        if why is None and self.playing:
            self.stop_playback()
        with self._runner.holding(), self.lock:
            why = why or self._superseded(mine, since)  # (again: the player stopped outside the lock)
            if why is not None:
                self.show_message(said.format(why))
            yield why is None
            if why is None:
                self._upload_shown = max(self._upload_shown, mine)
                self._close_refusal()  # (a browser trial: "Upload refused" stayed up beside the same file shown)

    def _min_score(self) -> float:
        """The File tab's "min person score" (:data:`lifter.detect.MIN_PERSON_SCORE` by default), the score floor of
        the next upload; a value the slider should not hold is refused by name
        (:func:`lifter.detect.check_min_score`)."""
        return check_min_score(self.gui.files.min_score.value)

    def _load_upload(self, name: str, content: bytes) -> None:
        content = bytes(content or b"")
        with self.lock:
            self._uploads_begun += 1
            mine, since = self._uploads_begun, time.time()
        if vid.is_video_upload(name, content) or (up.is_json_upload(name, content) and vid.is_sequence_json(content)):
            self._load_video(name, content, mine=mine, since=since)
            return
        try:
            sample, photo = up.upload_sample(
                name, content, key=upload_key(self.app.next_upload_id(), up.safe_name(name)), photo=self._photo,
                max_bytes=self.app.max_upload_bytes, estimator=self.app.estimator,
                lifter=self.app.pool.get(self.state.model), detect_lock=self.app.detect_lock,
                min_score=self._min_score(), on_wait=self._waiting_note(up.safe_name(name)))
        except up.UploadFailed as exc:
            with self.lock:
                kept = self._uploads_begun == mine  # (the photo a later keypoint file is drawn on: not a stale one's)
                if kept:
                    self._photo = exc.photo
            if kept and exc.photo is not None and not isinstance(exc, up.DetectorMissing):  # (that one says it)
                raise up.UploadFailed(f"{exc}. {up.kept_photo_note(exc.photo)}", photo=exc.photo) from None
            raise
        said = f"{up.safe_name(name)}: read, but not shown: {{}} meanwhile (upload it again to see it)"
        with self._showing_upload(mine, since, said) as wanted:
            if not wanted:
                return
            try:
                self._show_sample(sample, reframe=True)  # (a new photo: a new person to look at)
            except PoseLifterError as exc:
                raise PoseLifterError(f"{up.safe_name(name)}: {exc}") from None
            self._photo = photo  # (only once shown: a later keypoint file is drawn on it)
            self._last_upload = sample
        self.show_message(up.upload_message(sample), keep=True)

    def _show_progress(self, text: str) -> None:
        """``⏳ text`` in the status line: progress, not a message (no rule of theirs clears it; the upload shown keeps
        its own, a review), cleared by the next success."""
        with self._status_lock:
            self.gui.readout.status.content = "⏳ " + text
            self._status_notes = [q for q in self._status_notes if q.keep]
            self._note_until = 0.0

    def _waiting_note(self, name: str) -> Callable[[], None]:
        """What an upload that waits for the detector (another upload's, maybe another tab's) shows meanwhile."""
        return lambda: self._show_progress(f"{name}: waiting for the detector: another upload (of this tab or "
                                           "another) is being lifted")

    def _load_video(self, name: str, content: bytes, *, mine: int, since: float) -> None:
        """A video or keypoint sequence: lifted with a progress note (one notification, updated), then shown."""
        nm = up.safe_name(name)
        note: Any = None
        if isinstance(self.target, viser.ClientHandle):
            note = self.target.add_notification(title="poselifter", body=f"{nm}: detecting and lifting ...",
                                                loading=True, with_close_button=False)
        last = [0.0]

        def progress(done: int, total: int | None) -> None:
            if self.gone:  # (a security review: a closed tab's video held the shared detector to its end)
                raise up.UploadRefused(f"{nm}: the tab was closed; lifting stopped")
            now = time.perf_counter()
            if now - last[0] < 0.5:
                return
            last[0] = now
            text = f"{nm}: lifting frame {done}" + (f" of {total}" if total else "")
            self._show_progress(text)
            if note is not None:
                note.body = text

        try:
            seq = vid.video_sequence(name, content, key=video_key(self.app.next_upload_id(), nm),
                                     lifter=self.app.pool.get(self.state.model), estimator=self.app.estimator,
                                     max_bytes=self.app.max_upload_bytes, detect_lock=self.app.detect_lock,
                                     progress=progress, photo=self._photo, min_score=self._min_score(),
                                     on_wait=self._waiting_note(nm))
        finally:
            if note is not None:
                note.remove()
        said = f"{nm}: lifted ({seq.num_frames} frames), but not shown: {{}} while it was lifted (upload it again to " \
               "see it)"
        with self._showing_upload(mine, since, said) as wanted:
            if not wanted:
                return
            old = self._video
            self._video = seq
            try:
                self._show_sample(seq.sample(0), reframe=True)
            except BaseException as exc:  # (refused, or a drawing that failed: the previous sequence is kept)
                self._video = old
                if isinstance(exc, PoseLifterError):
                    raise PoseLifterError(f"{up.safe_name(name)}: {exc}") from None
                raise
        self.show_message(vid.video_message(seq), keep=True)

    def download_payload(self, fmt: str = "json") -> tuple[str, bytes]:
        """``(file name, bytes)`` of the current result: ``"json"`` (the fields of ``poselifter lift``: the current
        clean 2D of everyone, dragged joints included, lifted at the current focal length) or ``"glb"``. For an
        uploaded video or keypoint sequence: the whole sequence as ``poselifter lift clip.mp4`` writes it (JSON with
        ``frames``; GLB animated), tracked and smoothed, at the tab's model and focal length (lifted again when they
        are not the upload's)."""
        if fmt not in ("json", "glb"):
            raise PoseLifterError(f"unknown download format {fmt!r}; expected 'json' or 'glb'")
        seq = self.sequence()
        if isinstance(seq, VideoSequence):  # the whole video, as `poselifter lift clip.mp4 [--glb]` writes it
            with self.lock:
                st = self.state
                stem, model, focal = up.download_stem(st.sample), st.model, st.focal
                at = frame_of(st.sample.key)
                corrected = {} if at is None else seq.corrections(at, st.people_2d(), st.people_dragged())
                for key, was in self._frames_left.items():  # (the other frames' corrections, kept for them)
                    i = frame_of(key)
                    if i is not None and sequence_of(key) == seq.key and key != st.sample.key:
                        corrected.update(seq.corrections(i, was.people_2d(), was.people_dragged()))
            lifter = self.app.pool.get(model)  # (at the tab's model and focal length, as it shows them)
            if fmt == "json":
                return f"{stem}.json", vid.sequence_json_bytes(seq, lifter=lifter, focal=focal, corrected=corrected)
            return f"{stem}.glb", vid.sequence_glb_bytes(seq, lifter=lifter, focal=focal, corrected=corrected)
        with self.lock:
            st = self.state
            rec = up.result_record(st.sample, st.keypoints, lifter=self.app.pool.get(st.model), focal=st.focal,
                                   focal_changed=abs(st.focal_px - st.sample.camera.alpha) > 0.5,
                                   people=st.people_2d(), people_dragged=st.people_dragged(),
                                   source=lift_source(st.evolve(noise_level=0.0)))  # (clean 2D: no noise on it)
            stem = up.download_stem(st.sample)
        if fmt == "json":
            return f"{stem}.json", up.json_bytes(rec)
        return f"{stem}.glb", up.glb_bytes(rec)

    @control
    def download(self, fmt: str = "json") -> None:
        """Send the current result to this tab as a file download (:meth:`download_payload`)."""
        name, data = self.download_payload(fmt)
        self.last_download = (name, data)
        if isinstance(self.target, viser.ClientHandle):
            self.target.send_file_download(name, data, save_immediately=True)


def _is_numeric_pair(uv: Any) -> bool:
    try:
        a = np.asarray(uv, dtype=np.float64)
    except (TypeError, ValueError):
        return False
    return a.size == 2


def _default_estimator() -> Any:
    from lifter.detect import get_estimator

    return get_estimator(up.DEFAULT_DETECTOR)


class PoseLifterApp:
    """The exploration app on a viser server: one :class:`SessionView` per connected browser tab.

    Build it on any :class:`viser.ViserServer` (tests: ``ViserServer(host="127.0.0.1", port=0)``);
    :meth:`headless_view` builds a view on the server itself for in-process tests without a browser.
    """

    def __init__(self, server: viser.ViserServer, *, h36m_root: Path | None = None, models: list[str] | None = None,
                 default_model: str | None = None, error_model: ErrorModelLike | None = None,
                 demo_dir: Path | None = None, estimator_factory: Callable[[], Any] | None = None,
                 max_upload_bytes: int = up.MAX_UPLOAD_BYTES) -> None:
        self.server = server
        self.max_upload_bytes = int(max_upload_bytes)
        self.upload_budget = UploadBudget(max_bytes=UPLOADS_HELD_FACTOR * self.max_upload_bytes)
        """What every tab's unfinished uploads may hold together (:func:`poselifter_app.viser_hooks.limit_uploads`)."""
        self._estimator_factory = estimator_factory or _default_estimator
        self._estimator: Any = None
        self._estimator_error: Exception | None = None
        self.detect_lock = threading.Lock()
        """Serialises 2D detection (one shared MediaPipe graph)."""
        self._upload_ids = 0
        self._gone_early: set[int] = set()
        """Clients that disconnected while their view was being built (:meth:`_on_connect` drops it)."""
        self.demo = DemoCatalog(demo_dir) if demo_dir is not None else DemoCatalog()
        self.motion = DemoMotion(self.demo)
        self.h36m: H36MCatalog | None = open_h36m(str(h36m_root)) if h36m_root is not None else None
        self.sources: list[str] = ["demo", "motion"] + (["h36m"] if self.h36m is not None else []) + ["upload"]
        self._sequences: dict[tuple[int, str, str], H36MSequence] = {}
        self.pool = LifterPool(models)
        if self.pool.error:
            log.error("no models: %s", self.pool.error)
        if default_model is None:
            from lifter.resources import default_model_name

            try:
                default_model = default_model_name()
            except PoseLifterError:
                default_model = self.pool.names[0] if self.pool.names else ""
        elif self.pool.names and default_model not in self.pool.names:  # (else every tab's session fails to build)
            raise PoseLifterError(f"unknown model {default_model!r} (--model): expected one of {self.pool.names}")
        self.default_model = default_model
        self.error_model = error_model if error_model is not None else default_error_model()
        self.views: dict[int, SessionView] = {}
        self._lock = threading.Lock()
        server.gui.configure_theme(control_width="large", dark_mode=False)
        server.on_client_connect(self._on_connect)
        server.on_client_disconnect(self._on_disconnect)

    def sample(self, key: str) -> Sample:
        """The demo, demo-motion or Human3.6M sample of ``key`` (see :func:`poselifter_app.session.requested_key`);
        raises :class:`PoseLifterError` for keys that name nothing."""
        name = demo_name(key)
        if name is not None:
            return self.demo.get(name)
        if source_of(key) == "motion" and (i := frame_of(key)) is not None:
            return self.motion.frame(i).people[0]
        h36m_frame = parse_h36m(key)
        if h36m_frame is not None and self.h36m is not None:
            return self.h36m.get(h36m_frame.subject, h36m_frame.sequence, h36m_frame.camera, h36m_frame.frame)
        raise PoseLifterError(f"no sample {key[:80]!r}")

    def h36m_sequence(self, subject: int, sequence: str, camera: str) -> H36MSequence:
        assert self.h36m is not None
        k = (subject, sequence, camera)
        with self._lock:
            if k not in self._sequences:
                self._sequences[k] = H36MSequence(self.h36m, subject, sequence, camera)
            return self._sequences[k]

    def _on_connect(self, client: viser.ClientHandle) -> None:
        try:
            view = SessionView(self, client)
        except Exception:  # noqa: BLE001
            log.error("could not build a session for client %s:\n%s", client.client_id, traceback.format_exc())
            with self._lock:
                self._gone_early.discard(client.client_id)
            return
        with self._lock:
            gone = client.client_id in self._gone_early
            self._gone_early.discard(client.client_id)
            if not gone:
                self.views[client.client_id] = view
        if gone:  # (the tab went while its view was being built: a review found such views kept for good)
            view.gone = True
            view.stop_playback(wait=False)

    def _on_disconnect(self, client: viser.ClientHandle) -> None:
        with self._lock:
            view = self.views.pop(client.client_id, None)
            if view is None:  # (its view is still being built: dropped once built)
                self._gone_early.add(client.client_id)
        if view is not None:
            view.gone = True
            view.stop_playback(wait=False)

    def estimator(self) -> Any:
        """The shared 2D estimator for photo uploads (built on first use); raises
        :class:`lifter.detect.MissingDependencyError` when its extra is not installed."""
        with self.detect_lock:
            if self._estimator is None and self._estimator_error is None:
                try:
                    self._estimator = self._estimator_factory()
                except PoseLifterError as exc:
                    self._estimator_error = exc
            if self._estimator_error is not None:
                if isinstance(self._estimator_error, up.MissingDependencyError):
                    raise self._estimator_error
                raise PoseLifterError(f"the 2D detector could not be started: {self._estimator_error}")
            return self._estimator

    def next_upload_id(self) -> int:
        with self._lock:
            self._upload_ids += 1
            return self._upload_ids

    def headless_view(self) -> SessionView:
        """A view on the server's shared GUI/scene (no browser needed): for tests and benchmarks."""
        return SessionView(self, self.server)

    @property
    def url(self) -> str:
        return f"http://{self.server.get_host()}:{self.server.get_port()}"
