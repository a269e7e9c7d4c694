"""The app's sample keys (``poselifter_app.keys``): one writer and one reader for every source."""

from __future__ import annotations

import pytest
from hypothesis import given
from hypothesis import strategies as st
from poselifter_app import keys

names = st.text(st.characters(blacklist_characters="/", blacklist_categories=("Cs",)), min_size=1, max_size=20)


@given(subject=st.integers(1, 11), sequence=names, camera=st.sampled_from(["54138969", "55011271"]),
       frame=st.integers(0, 10**6))
def test_h36m_key_round_trip(subject: int, sequence: str, camera: str, frame: int) -> None:
    key = keys.h36m_key(subject, sequence, camera, frame)
    parsed = keys.parse_h36m(key)
    assert parsed == keys.H36MKey(subject, sequence, camera, frame)
    assert str(parsed) == key
    assert keys.source_of(key) == "h36m"
    assert keys.frame_of(key) == frame
    assert keys.sequence_of(key) == parsed.sequence_key == f"h36m/S{subject}/{sequence}/{camera}"
    assert keys.with_frame(keys.sequence_of(key), frame) == key


@given(number=st.integers(0, 10**4), name=names, frame=st.integers(0, 10**5))
def test_video_key_frames(number: int, name: str, frame: int) -> None:
    seq = keys.video_key(number, name)
    key = keys.with_frame(seq, frame)
    assert keys.source_of(key) == "video"
    assert keys.sequence_of(key) == seq
    assert keys.frame_of(key) == frame
    assert keys.parse_h36m(key) is None


def test_still_samples_are_their_own_sequence() -> None:
    for key in (keys.demo_key("walking"), keys.upload_key(3, "photo.jpg")):
        assert keys.sequence_of(key) == key
        assert keys.frame_of(key) is None
        assert keys.parse_h36m(key) is None
    assert keys.demo_name(keys.demo_key("walking")) == "walking"
    assert keys.demo_name(keys.upload_key(1, "walking")) is None
    assert keys.source_of(keys.upload_key(1, "a.json")) in keys.UPLOADED_SOURCES
    assert keys.source_of(keys.motion_key(7)) in keys.SEQUENCE_SOURCES
    assert keys.frame_of(keys.motion_key(7)) == 7
    assert keys.sequence_of(keys.motion_key(7)) == "motion"


@pytest.mark.parametrize("key", ["h36m/9/Walking/54138969/0", "h36m/S9/Walking/54138969", "h36m/S9/Walking/c/x",
                                 "h36m/Sx/Walking/c/1", "h36m/S9/a/b/c/1", "demo/S9/Walking/c/1", "h36m"])
def test_malformed_h36m_keys_parse_to_none(key: str) -> None:
    assert keys.parse_h36m(key) is None


def test_negative_h36m_frame_parses_for_the_range_message() -> None:
    parsed = keys.parse_h36m("h36m/S9/Walking 1/54138969/-1")
    assert parsed is not None and parsed.frame == -1


def test_catalogue_samples_carry_parseable_keys() -> None:
    """The keys the demo catalogue and the demo motion write are the ones the key functions read."""
    from poselifter_app.playback import DemoMotion
    from poselifter_app.samples import DemoCatalog

    demo = DemoCatalog()
    name = demo.names[0]
    assert keys.demo_name(demo.get(name).key) == name
    motion = DemoMotion(demo)
    frame = motion.frame(5).people[0]
    assert keys.frame_of(frame.key) == 5 and keys.sequence_of(frame.key) == "motion"


@given(subject=st.integers(1, 11), sequence=st.sampled_from(["Posing 1", "Walking", "Discussion 2"]),
       camera=st.sampled_from(["54138969", "55011271"]), frame=st.integers(0, 10**5))
def test_photo_entry_round_trip(subject: int, sequence: str, camera: str, frame: int) -> None:
    """The "frame with photo" picker's entry: one writer (H36MKey.photo_entry) and one reader (parse_photo_entry)."""
    k = keys.H36MKey(subject, sequence, camera, frame)
    assert k.photo_entry == f"S{subject} {sequence} {camera} {frame}"
    assert keys.parse_photo_entry(k.photo_entry) == k


@pytest.mark.parametrize("entry", ["", keys.NO_PHOTO, "S9", "X9 Walking 54138969 3", "S9 Walking 54138969 x"])
def test_photo_entry_refuses_what_names_no_frame(entry: str) -> None:
    assert keys.parse_photo_entry(entry) is None
