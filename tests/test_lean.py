"""The lean note: poses whose legs and torso lean the same way by more than LEAN_NOTE_DEG, with a straight body, as
a rolled camera leans upright people (a developer trial: photos turned 30-60 deg were lifted a metre off without a
word; the sideways note begins near 65 deg). ``python scripts/roll_lean.py`` measures how often it names poses."""

from __future__ import annotations

import re
import warnings

import numpy as np
import pytest
from conftest import tiny_lifter

from lifter import PoseLifterWarning, demo_sample
from lifter._checks import LEAN_NOTE_DEG, body_lean_deg, lean_notes, leaning_people
from lifter.camera import camera_turn, turn_pixels
from lifter.pipeline import detected_lean_notes, plausibility_notes

F, C = 1145.0, (512.0, 515.0)


def _rolled(name: str, deg: float) -> np.ndarray:
    """A demo sample's exact 2D as its camera rolled by ``deg`` sees it (+ clockwise seen from behind the camera)."""
    turn = camera_turn(np.array(0.0), np.array(0.0), np.deg2rad(np.array(deg)))
    return turn_pixels(demo_sample(name).keypoints_2d, turn, F, C)


@pytest.mark.parametrize("deg", [-50.0, -40.0, 40.0, 50.0])
def test_a_rolled_camera_leans_a_standing_body_by_its_roll(deg):
    kp = _rolled("standing", deg)
    assert body_lean_deg(kp[None])[0] == pytest.approx(deg, abs=6.0)
    assert leaning_people(kp[None]).tolist() == [True]
    lean = body_lean_deg(kp[None])[0]
    with pytest.warns(PoseLifterWarning, match=rf"the body leans {abs(lean):.0f} deg from the image's vertical in 1 of "
                                               rf"1 pose\(s\) .*first \(the README's 'Camera roll' recipe\), by a "
                                               rf"roll of about {re.escape(f'{lean:+.0f}')} deg"):
        tiny_lifter(16).lift(kp, focal=F, principal_point=C)


@pytest.mark.parametrize("name", ["walking", "standing", "sitting", "crouching", "reaching"])
def test_upright_cameras_and_small_rolls_get_no_note(name):
    for deg in (0.0, 10.0, -20.0):
        kp = _rolled(name, deg)
        assert not leaning_people(kp[None]).any(), (name, deg, body_lean_deg(kp[None]))
        with warnings.catch_warnings():
            warnings.simplefilter("error", PoseLifterWarning)
            tiny_lifter(16).lift(kp, focal=F, principal_point=C)


def test_a_bent_body_is_not_taken_for_a_rolled_camera():
    """Legs and torso leaning the same way but 40 deg apart (a person bending) are not a rolled camera's."""
    kp = _rolled("standing", 0.0)
    torso = [0, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16]
    legs = _rolled("standing", 40.0)
    bent = kp.copy()
    bent[[1, 2, 3, 4, 5, 6]] = legs[[1, 2, 3, 4, 5, 6]] - legs[0] + kp[0]
    turn = camera_turn(np.array(0.0), np.array(0.0), np.deg2rad(np.array(80.0)))
    top = turn_pixels(kp, turn, F, C)
    bent[torso] = top[torso] - top[0] + kp[0]
    assert abs(body_lean_deg(bent[None])[0]) > LEAN_NOTE_DEG
    assert not leaning_people(bent[None]).any()


def test_a_batch_is_noted_when_most_of_it_leans_and_each_detected_person_is_named():
    up, rolled = _rolled("standing", 0.0), _rolled("standing", 45.0)
    assert lean_notes(np.stack([rolled, rolled, up]))[0].startswith("the body leans 45 deg from the image's vertical "
                                                                    "in 2 of 3 pose(s)")
    assert lean_notes(np.stack([rolled, up])) == []  # (one of two: not most)
    said = detected_lean_notes(np.stack([up, rolled]))
    assert len(said) == 1 and said[0].startswith("person 2 (+45 deg) of the output's people leans from the image's "
                                                 "vertical"), said
    assert detected_lean_notes(rolled[None])[0].startswith("the person found leans +45 deg")
    # (a review) opposite leans name no roll: they named "about -0 deg"
    other = _rolled("standing", -45.0)
    both = detected_lean_notes(np.stack([rolled, other]))[0]
    assert both.startswith("person 1 (+45 deg), person 2 (-45 deg) of the output's people lean") and \
        "by the camera's own roll;" in both and "about" not in both.split("recipe")[1], both
    batch = lean_notes(np.stack([rolled, other, rolled, other]))[0]
    assert batch.startswith("the body leans 45 deg from the image's vertical in 4 of 4") and "-0 deg" not in batch
    assert detected_lean_notes(up[None]) == []
    # a keypoint file's records get the batch note, a photo's (detected) the per-person one only
    notes = plausibility_notes(rolled[None], np.array([F, F]), (1024, 1030))
    assert any(n.startswith("the body leans 45 deg") for n in notes), notes
    assert not any("leans" in n for n in plausibility_notes(rolled[None], np.array([F, F]), (1024, 1030),
                                                            detected=True))


def test_missing_joints_give_no_reading():
    kp = _rolled("standing", 45.0)
    for j in (0, 3, 8):
        bad = kp.copy()
        bad[j] = np.nan
        assert body_lean_deg(bad[None])[0] == 0.0 and not leaning_people(bad[None]).any()
    zero = kp.copy()
    zero[3] = 0.0  # (a detector's placeholder at (0, 0))
    assert body_lean_deg(zero[None])[0] == 0.0


def test_an_all_missing_pose_gives_no_reading_and_no_numpy_warning():
    """(a review) np.nanmax over an all-NaN pose warned "All-NaN slice encountered", an error under -W error."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert body_lean_deg(np.full((1, 17, 2), np.nan)).tolist() == [0.0]
        assert leaning_people(np.full((2, 17, 2), np.nan)).tolist() == [False, False]
