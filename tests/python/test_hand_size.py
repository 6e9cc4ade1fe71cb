"""estimate_hand_size and Tracker(hand_size='auto') give `dynahand track --hand-size auto`'s
size and results, from every kind of frames; every misuse is a ValueError."""

import json
import re

import numpy as np
import pytest

import dynahand
from conftest import FRAMES, run
from test_track import without_time

CAMERA = dynahand.Camera(320, 240, 224.0, 224.0, 159.5, 119.5)


def printed_estimate(stdout):
    """The command's `hand size estimate: length L m  width W m  (N frames, C candidate models,
    fit F, ...)` line as (L, W, N, C, F) strings."""
    m = re.search(r"hand size estimate: length (\S+) m  width (\S+) m  \((\d+) frames, (\d+) "
                  r"candidate models, fit (\S+),", stdout)
    assert m, stdout
    return m.groups()


def as_printed(e):
    return (f"{e.length:.4f}", f"{e.width:.4f}", str(e.frames_used), str(e.candidates),
            f"{e.fit_score:.3f}")


@pytest.fixture(scope="module")
def auto_tracked(clip, tmp_path_factory):
    """`dynahand track CLIP --hand-size auto --out auto.jsonl`: (printed estimate, JSON lines)."""
    out = tmp_path_factory.mktemp("auto") / "auto.jsonl"
    stdout = run("track", clip, "--hand-size", "auto", "--out", out)
    return printed_estimate(stdout), out.read_text().splitlines()


def test_estimate_matches_command(clip, auto_tracked):
    printed, lines = auto_tracked
    estimate = dynahand.estimate_hand_size(dynahand.open_sequence(clip))  # its camera and fps
    assert as_printed(estimate) == printed
    # 13 for the size, 24 for the metacarpals (the palm faces this camera)
    assert estimate.frames_used == FRAMES and estimate.candidates == 13 + 24
    record = json.loads(lines[0])["hand_size"]
    assert record["source"] == "estimated" and record["frames"] == FRAMES
    g6 = lambda v: format(float(v), ".6g")
    assert [g6(estimate.length), g6(estimate.width), g6(estimate.fit_score)] == [
        g6(record["length"]), g6(record["width"]), g6(record["fit"])]
    assert [g6(f) for f in estimate.metacarpals] == [g6(f) for f in record["metacarpals"]]
    assert all(0.85 <= f <= 1.15 for f in estimate.metacarpals)
    d = estimate.to_dict()
    assert d["length"] == estimate.length and d["candidates"] == estimate.candidates
    assert d["metacarpals"] == list(estimate.metacarpals)
    assert repr(estimate).startswith("HandSize(length=0.")


def test_auto_tracker_matches_command(clip, auto_tracked):
    printed, lines = auto_tracked
    seq = dynahand.open_sequence(clip)
    tracker = dynahand.Tracker(seq, hand_size="auto", threads=2)  # frames read ahead from seq
    assert as_printed(tracker.hand_size_estimate) == printed
    assert tracker.hand_size == (tracker.hand_size_estimate.length,
                                 tracker.hand_size_estimate.width)
    assert tracker.frames == 0  # the read-ahead frames are not tracked
    for i, (depth, scale, _) in enumerate(seq):
        tracker.track(depth, scale)
        assert without_time(tracker.result_json()) == without_time(lines[i]), f"frame {i}"


def test_every_kind_of_frames_gives_the_same_estimate(auto_tracked):
    printed, _ = auto_tracked
    clip = dynahand.synth("wave", frames=FRAMES)  # the same frames as the command's files
    assert as_printed(dynahand.Tracker(clip, hand_size="auto").hand_size_estimate) == printed
    depth, _ = clip.arrays()
    by_array = dynahand.estimate_hand_size(depth, clip.camera, fps=clip.fps, threads=2)
    assert as_printed(by_array) == printed
    frames = (d for d, _, _ in clip)  # a generator of bare arrays, at depth_scale 0.001
    assert as_printed(dynahand.estimate_hand_size(frames, clip, threads=2)) == printed
    tracker = dynahand.Tracker(clip.camera, fps=clip.fps, hand_size="auto",
                               frames=[(d, s) for d, s, _ in clip])
    assert as_printed(tracker.hand_size_estimate) == printed


def test_start_keypoints_and_a_given_length_match_command(clip, tmp_path):
    out = tmp_path / "gt.jsonl"
    stdout = run("track", clip, "--init", "gt", "--no-detector", "--hand-size", "auto",
                 "--hand-size-frames", 10, "--hand-length", 0.2, "--out", out)
    seq = dynahand.open_sequence(clip)
    start = seq.ground_truth(0)
    estimate = dynahand.estimate_hand_size(seq, start_keypoints=start, frames_used=10,
                                           length=0.2)
    assert as_printed(estimate) == printed_estimate(stdout)
    assert estimate.length == np.float32(0.2) and estimate.candidates == 7 + 24
    size_only = dynahand.estimate_hand_size(seq, start_keypoints=start, frames_used=10,
                                            length=0.2, metacarpals=False)
    assert size_only.candidates == 7 and size_only.metacarpals == (1.0,) * 5
    assert size_only.width == estimate.width
    # Both given: kept, the metacarpals alone estimated (one scored candidate, then step 4).
    shape = dynahand.estimate_hand_size(seq, start_keypoints=start, frames_used=10, length=0.2,
                                        width=0.09)
    assert (shape.length, shape.width) == (np.float32(0.2), np.float32(0.09))
    assert shape.candidates == 1 + 24 and len(shape.metacarpals) == 5
    tracker = dynahand.Tracker(seq, hand_size=estimate, detector=False)
    assert tracker.hand_size_estimate.width == estimate.width
    tracker.initialize(start)  # as --init gt
    lines = out.read_text().splitlines()
    for i in range(5):
        depth, scale, _ = seq[i]
        tracker.track(depth, scale)
        assert without_time(tracker.result_json()) == without_time(lines[i])


def test_reads_no_further_than_needed():
    taken = []

    def blank():  # an endless stream of empty frames
        while True:
            taken.append(1)
            yield np.zeros((240, 320), np.uint16)

    estimate = dynahand.estimate_hand_size(blank(), CAMERA, frames_used=10)
    assert len(taken) == 10 and estimate.frames_used == 10


def test_given_size_has_no_estimate():
    assert dynahand.Tracker(CAMERA, detector=False).hand_size_estimate is None
    given = dynahand.Tracker(CAMERA, hand_size=(0.2, 0.09), detector=False)
    assert given.hand_size_estimate is None


def test_tracker_misuse(tmp_path):
    with pytest.raises(ValueError, match="needs the frames to estimate from"):
        dynahand.Tracker(CAMERA, hand_size="auto")
    with pytest.raises(ValueError, match="needs the frames"):
        dynahand.Tracker(CAMERA.to_dict(), hand_size="auto")  # a dict is iterable, not frames
    with pytest.raises(ValueError, match="hand_size must be None, \\(length, width\\) in metres, "
                                         "'auto' or a dynahand.HandSize \\(got 'given'\\)"):
        dynahand.Tracker(CAMERA, hand_size="given")
    with pytest.raises(ValueError, match="frames: only with hand_size='auto'"):
        dynahand.Tracker(CAMERA, frames=np.zeros((10, 240, 320), np.uint16))
    with pytest.raises(ValueError, match="hand_size must be None.*got 'Auto'"):
        dynahand.Tracker(CAMERA, hand_size="Auto", frames=np.zeros((10, 240, 320), np.uint16))
    with pytest.raises(ValueError, match="hand_size_frames must be in 10..600"):
        dynahand.Tracker(CAMERA, hand_size="auto", frames=[], hand_size_frames=9)
    with pytest.raises(ValueError, match="hand_size_frames must be in 10..600"):
        dynahand.Tracker(CAMERA, hand_size_frames=601)
    model = tmp_path / "hand.json"
    model.write_text("{}")
    with pytest.raises(ValueError, match="does not go with model_file"):
        dynahand.Tracker(CAMERA, hand_size="auto", model_file=model)
    with pytest.raises(ValueError, match="0 frames; needs more than 6"):
        dynahand.Tracker(CAMERA, hand_size="auto", frames=[])
    with pytest.raises(TypeError):
        dynahand.HandSize()  # made by estimate_hand_size only


def test_estimate_misuse():
    frames = np.zeros((12, 240, 320), np.uint16)
    with pytest.raises(ValueError, match="camera: needed unless frames is a Sequence"):
        dynahand.estimate_hand_size(frames)
    with pytest.raises(ValueError, match="camera must be"):
        dynahand.estimate_hand_size(frames, "camera:0")
    bad = [
        (dict(frames_used=9), "frames_used must be in 10..600 \\(got 9\\)"),
        (dict(frames_used=601), "frames_used must be in 10..600"),
        (dict(threads=0), "threads must be 1..64"),
        (dict(hands=3), "hands must be 1 or 2"),
        (dict(depth_scale=0.0), "depth_scale must be a positive number"),
        (dict(fps=0.0), "fps must be > 0"),
        (dict(length=0.5), "length must be in \\[0.10, 0.30\\] m"),
        (dict(width=0.01), "width must be in \\[0.05, 0.15\\] m"),
        (dict(length=0.19, width=0.085, metacarpals=False),
         "length and width both given and metacarpals=False: nothing to estimate"),
        (dict(start_keypoints=np.zeros((20, 3))), "start_keypoints: keypoints must have shape"),
    ]
    for kwargs, message in bad:
        with pytest.raises(ValueError, match=message):
            dynahand.estimate_hand_size(frames, CAMERA, **kwargs)
    with pytest.raises(ValueError, match="3 frames; needs more than 6 \\(the frames a candidate"):
        dynahand.estimate_hand_size(frames[:3], CAMERA)


@pytest.mark.parametrize("frames, message", [
    (42, "frames must be a Sequence, a SyntheticClip, an \\(N, H, W\\) uint16 array .*got int"),
    ("clip/", "frames must be a Sequence.*got str"),
    (np.zeros((240, 320), np.uint16), "frames: an array of frames must have shape \\(N, H, W\\)"),
    (np.zeros((12, 240, 320), np.float32), "frames: frame 0: depth must have dtype uint16"),
    (np.zeros((12, 120, 160), np.uint16), "frames: frame 0: depth is 120 x 160 \\(H x W\\)"),
    ([[0] * 320] * 240, "frames: frame 0: depth must be a numpy uint16 array"),
    ([(np.zeros((240, 320), np.uint16),)], "frame 0: a tuple must be \\(depth, depth_scale"),
    ([(np.zeros((240, 320), np.uint16), "mm")], "frame 0: depth_scale must be a number"),
    ([(np.zeros((240, 320), np.uint16), -1.0)], "frame 0: depth_scale must be a positive"),
])
def test_bad_frames(frames, message):
    with pytest.raises(ValueError, match=message):
        dynahand.estimate_hand_size(frames, CAMERA)


def test_frame_errors_pass_through(tmp_path):
    def failing():
        yield np.zeros((240, 320), np.uint16)
        raise RuntimeError("camera unplugged")

    with pytest.raises(RuntimeError, match="camera unplugged"):
        dynahand.estimate_hand_size(failing(), CAMERA)
    folder = tmp_path / "corrupt"  # a recording whose first frame cannot be decoded: OSError
    (folder / "depth").mkdir(parents=True)
    camera = {"version": 1, "width": 4, "height": 3, "fx": 5.0, "fy": 5.0, "cx": 1.5, "cy": 1.0}
    (folder / "camera.json").write_text(json.dumps({**camera, "depth_scale": 0.001}))
    (folder / "depth" / "000000.png").write_bytes(b"\x89PNG truncated")
    seq = dynahand.open_sequence(folder)
    with pytest.raises(OSError, match="000000.png"):
        dynahand.estimate_hand_size(seq)
    with pytest.raises(OSError, match="000000.png"):
        dynahand.Tracker(seq, hand_size="auto")


def test_given_keypoints_stand_in_for_the_detector(clip):
    """Tracker.set_keypoints: with detector=False, the given keypoints are used (and reported)
    for the next frame only."""
    seq = dynahand.open_sequence(clip)
    tracker = dynahand.Tracker(seq, detector=False)
    tracker.initialize(seq.ground_truth(0))
    for i in range(3):
        depth, scale, _ = seq[i]
        truth = seq.ground_truth(i)
        given = i != 1
        if given:
            tracker.set_keypoints(truth, confidence=np.full(21, 0.8))
        hand = tracker.track(depth, scale)[0]
        assert hand.detected == given
        if given:
            np.testing.assert_allclose(hand.detector_keypoints21, truth, atol=1e-6)
            np.testing.assert_allclose(hand.detector_confidence, 0.8, atol=1e-6)
        assert np.linalg.norm(hand.keypoints21 - truth, axis=1).mean() < 0.01
