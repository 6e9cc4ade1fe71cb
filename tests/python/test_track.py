"""The binding tracks exactly as `dynahand track` does, frame by frame."""

import json
import re

import numpy as np

import dynahand
from conftest import FRAMES, run


def without_time(line):
    """A JSON line without its wall time (the only field that differs between runs)."""
    return re.sub(r'"time_ms":[-0-9.e]+,', "", line)


def g6(value):
    """A number as the JSON lines print it ({:.6g} of the float)."""
    return format(float(value), ".6g")


def check_same(hands, tracker, line):
    """One frame: the binding's arrays and JSON line against the command's JSON line."""
    assert without_time(tracker.result_json()) == without_time(line)
    expected = json.loads(line)["hands"]
    assert len(hands) == len(expected) == 1
    hand, cmd = hands[0], expected[0]
    assert hand.tracked == cmd["tracked"]
    assert hand.simulation == cmd["simulation"]
    assert hand.acquired == cmd["acquired"]
    assert g6(hand.error) == g6(cmd["error"])
    assert hand.keypoints21.dtype == np.float32 and hand.keypoints21.shape == (21, 3)
    if hand.tracked:
        got = [[g6(v) for v in row] for row in hand.keypoints21]
        want = [[g6(v) for v in row] for row in cmd["keypoints21"]]
        assert got == want
        # The report is blended toward the detector's keypoints: at most 0.8 x (1 - d / 10 cm)
        # x d, so no keypoint moves more than 2 cm from the skeleton's.
        assert hand.skeleton_keypoints21.shape == (21, 3)
        assert np.linalg.norm(hand.skeleton_keypoints21 - hand.keypoints21, axis=1).max() < 0.0201
        assert [[g6(v) for v in row[:3]] for row in hand.openxr26] == [
            [g6(v) for v in j["p"]] for j in cmd["openxr26"]
        ]
        assert [[g6(v) for v in row[:3]] for row in hand.bodies] == [
            [g6(v) for v in b["p"]] for b in cmd["bodies"]
        ]
    else:
        assert np.isnan(hand.keypoints21).all()
        assert np.isnan(hand.skeleton_keypoints21).all()


def test_binding_matches_command(clip, tracked):
    lines = tracked.read_text().splitlines()
    seq = dynahand.open_sequence(clip)
    tracker = dynahand.Tracker(seq)  # the sequence's camera and fps
    assert tracker.detector  # the shipped weights, as the command uses them
    assert len(seq) == len(lines) == FRAMES
    tracked_frames = 0
    for i, (depth, scale, _) in enumerate(seq):
        hands = tracker.track(depth, scale)
        check_same(hands, tracker, lines[i])
        tracked_frames += hands[0].tracked
    assert tracked_frames >= FRAMES - 2


def test_in_memory_clip_matches_files_and_tracks_the_same(clip, tracked):
    files = dynahand.open_sequence(clip)
    memory = dynahand.synth("wave", frames=FRAMES)  # `dynahand synth`'s defaults
    assert len(memory) == FRAMES and memory.camera == files.camera and memory.fps == files.fps
    lines = tracked.read_text().splitlines()
    tracker = dynahand.Tracker(memory.camera)
    for i, (depth, scale, truth) in enumerate(memory):
        file_depth, file_scale, file_truth = files[i]
        assert np.array_equal(depth, file_depth) and scale == file_scale
        # groundtruth.jsonl holds micrometres ({:.6f})
        f6 = lambda a: [[format(float(v), ".6f") for v in row] for row in a]
        assert f6(truth) == f6(file_truth)
        check_same(tracker.track(depth, scale), tracker, lines[i])


def test_init_from_ground_truth_matches_command(clip, tmp_path):
    out = tmp_path / "gt.jsonl"
    run("track", clip, "--init", "gt", "--no-detector", "--out", out)
    lines = out.read_text().splitlines()
    seq = dynahand.open_sequence(clip)
    tracker = dynahand.Tracker(seq, detector=False)
    assert not tracker.detector
    tracker.initialize(seq.ground_truth(0))
    for i in range(10):
        depth, scale, _ = seq[i]
        check_same(tracker.track(depth, scale), tracker, lines[i])


def test_non_contiguous_depth_tracks_the_same():
    clip = dynahand.synth("wave", frames=3, profile="ideal")
    a = dynahand.Tracker(clip, detector=False)
    b = dynahand.Tracker(clip, detector=False)
    for depth, scale, _ in clip:
        strided = np.asfortranarray(depth)  # a copy inside; contiguous input is not copied twice
        ha, hb = a.track(depth, scale)[0], b.track(strided, scale)[0]
        assert np.array_equal(ha.keypoints21, hb.keypoints21, equal_nan=True)


def test_two_hands_and_results():
    clip = dynahand.synth("two-hands", frames=2, profile="ideal")
    assert clip.hand_count == 2
    tracker = dynahand.Tracker(clip, hands=2, detector=False)
    for depth, scale, truth in clip:
        hands = tracker.track(depth, scale)
    assert [h.side for h in hands] == ["right", "left"]
    assert truth.shape == (21, 3) and clip.ground_truth(1, hand=1).shape == (21, 3)
    h = hands[0]
    assert h.openxr26.shape == (26, 8) and h.bodies.shape == (17, 7)
    assert h.body_error.shape == (17,) and len(tracker.body_names) == 17
    assert len(dynahand.Tracker.openxr_joint_names) == 26
    assert tracker.frames == 2 and tracker.hand_size[0] == np.float32(0.19)


def test_two_hands_seen_from_the_head():
    """behind_user: the user's left hand is on the image's left (a head-mounted camera)."""
    clip = dynahand.synth("two-hands", frames=12, placement="head")
    tracker = dynahand.Tracker(clip, hands=2, behind_user=True)
    for depth, scale, _ in clip:
        hands = tracker.track(depth, scale)
    for h, side in ((0, "right"), (1, "left")):
        assert hands[h].side == side and hands[h].tracked
        error = np.linalg.norm(hands[h].keypoints21 - clip.ground_truth(11, hand=h), axis=1)
        assert error.mean() < 0.05, (side, error.mean())


def test_settings_by_name_track_as_the_command_sets_them(clip, tmp_path):
    # Tracker(settings=...) takes the names `dynahand track --set` takes, with the same effect.
    out = tmp_path / "set.jsonl"
    run("track", clip, "--init", "gt", "--no-detector", "--set", "substeps=1",
        "--set", "detector.reportBlend=0", "--out", out)
    lines = out.read_text().splitlines()
    seq = dynahand.open_sequence(clip)
    tracker = dynahand.Tracker(seq, detector=False,
                               settings={"substeps": 1, "detector.reportBlend": 0.0})
    tracker.initialize(seq.ground_truth(0))
    for i in range(10):
        depth, scale, _ = seq[i]
        check_same(tracker.track(depth, scale), tracker, lines[i])
    # The setting acts: one physics step a frame tracks otherwise than the default two.
    default = tmp_path / "default.jsonl"
    run("track", clip, "--init", "gt", "--no-detector", "--out", default)
    assert without_time(default.read_text()) != without_time(out.read_text())
    for bad, message in [({"detector.noSuchThing": 1}, "unknown tracker setting"),
                         ({"substeps": 1.5}, "not a whole number"),
                         ({"perFrame": "yes"}, "a number or a bool")]:
        try:
            dynahand.Tracker(seq, detector=False, settings=bad)
        except (ValueError, TypeError) as e:
            assert message in str(e)
        else:
            raise AssertionError(f"settings={bad} accepted")
