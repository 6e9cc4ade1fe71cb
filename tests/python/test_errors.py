"""Every bad input is a Python exception carrying the library's message, never a crash."""

import json

import numpy as np
import pytest

import dynahand

CAMERA = dynahand.Camera(320, 240, 224.0, 224.0, 159.5, 119.5)


@pytest.fixture(scope="module")
def tracker():
    return dynahand.Tracker(CAMERA, detector=False)


def test_depth_dtype(tracker):
    with pytest.raises(ValueError, match="dtype uint16"):
        tracker.track(np.zeros((240, 320), np.float32))
    with pytest.raises(ValueError, match="dtype uint16"):
        tracker.track(np.zeros((240, 320), ">u2"))  # uint16, but not the machine's byte order


def test_depth_shape(tracker):
    with pytest.raises(ValueError, match="2-D"):
        tracker.track(np.zeros((240, 320, 1), np.uint16))
    with pytest.raises(ValueError, match="camera is 240 x 320"):
        tracker.track(np.zeros((320, 240), np.uint16))
    with pytest.raises(ValueError, match="numpy uint16 array"):
        tracker.track([[0] * 320] * 240)


def test_depth_scale_and_timestamp(tracker):
    depth = np.zeros((240, 320), np.uint16)
    for scale in (0.0, -1.0, float("nan")):
        with pytest.raises(ValueError, match="depth_scale"):
            tracker.track(depth, scale)
    with pytest.raises(ValueError, match="timestamp"):
        tracker.track(depth, 0.001, float("inf"))
    assert not tracker.track(depth)[0].tracked  # an empty frame: no hand, no error


def test_camera():
    with pytest.raises(ValueError, match="image size 0 x 240"):
        dynahand.Camera(0, 240, 224.0, 224.0, 159.5, 119.5)
    with pytest.raises(ValueError, match="fx"):
        dynahand.Camera(320, 240, -1.0, 224.0, 159.5, 119.5)
    with pytest.raises(ValueError, match="lacks 'fy'"):
        dynahand.Tracker({"width": 320, "height": 240, "fx": 224.0, "cx": 1.0, "cy": 1.0})
    with pytest.raises(ValueError, match="camera must be"):
        dynahand.Tracker("camera:0")
    with pytest.raises(ValueError, match="fps"):
        dynahand.Tracker(CAMERA, fps=0.0)


def test_tracker_options(tmp_path):
    with pytest.raises(ValueError, match="hands must be 1 or 2"):
        dynahand.Tracker(CAMERA, hands=3)
    with pytest.raises(ValueError, match="length must be"):
        dynahand.Tracker(CAMERA, hand_size=(0.5, 0.08))
    with pytest.raises(ValueError, match="needs the frames"):  # more: test_hand_size.py
        dynahand.Tracker(CAMERA, hand_size="auto")
    with pytest.raises(ValueError, match="hand_size must be"):
        dynahand.Tracker(CAMERA, hand_size=(0.19,))
    with pytest.raises(FileNotFoundError, match="missing.onnx"):
        dynahand.Tracker(CAMERA, detector=str(tmp_path / "missing.onnx"))
    garbage = tmp_path / "garbage.onnx"
    garbage.write_bytes(b"not a network")
    with pytest.raises(OSError, match="garbage.onnx"):
        dynahand.Tracker(CAMERA, detector=garbage)
    with pytest.raises(FileNotFoundError):
        dynahand.Tracker(CAMERA, model_file=tmp_path / "hand.json")
    bad_model = tmp_path / "bad.json"
    bad_model.write_text("{")
    with pytest.raises(OSError, match="bad.json"):
        dynahand.Tracker(CAMERA, model_file=bad_model)


def test_initialize_and_json():
    tracker = dynahand.Tracker(CAMERA, detector=False)
    with pytest.raises(ValueError, match="no frame tracked yet"):
        tracker.result_json()
    with pytest.raises(ValueError, match=r"shape \(21, 3\)"):
        tracker.initialize(np.zeros((20, 3)))
    with pytest.raises(ValueError, match="one \\(right\\) hand"):
        tracker.initialize(np.zeros((21, 3)), side="left")
    with pytest.raises(ValueError, match="side must be"):
        tracker.initialize(np.zeros((21, 3)), side="up")


def test_open_sequence(tmp_path):
    with pytest.raises(FileNotFoundError, match="no such file or folder"):
        dynahand.open_sequence(tmp_path / "nothing")
    with pytest.raises(ValueError, match="path-like"):
        dynahand.open_sequence(42)
    empty = tmp_path / "empty"
    empty.mkdir()
    with pytest.raises(OSError) as raised:
        dynahand.open_sequence(empty)
    assert not isinstance(raised.value, FileNotFoundError) and str(raised.value)


def test_corrupt_frame(tmp_path):
    folder = tmp_path / "corrupt"
    (folder / "depth").mkdir(parents=True)
    camera = {"version": 1, "width": 4, "height": 3, "fx": 5.0, "fy": 5.0, "cx": 1.5, "cy": 1.0}
    (folder / "camera.json").write_text(json.dumps({**camera, "depth_scale": 0.001}))
    (folder / "depth" / "000000.png").write_bytes(b"\x89PNG truncated")
    seq = dynahand.open_sequence(folder)
    assert len(seq) == 1
    with pytest.raises(OSError, match="000000.png"):
        seq[0]
    with pytest.raises(OSError):
        list(seq)


def test_synth():
    with pytest.raises(ValueError, match="no-such-clip") as raised:
        dynahand.synth("no-such-clip", frames=2)
    assert "wave" in str(raised.value)  # the library's message lists the known clips
    with pytest.raises(ValueError, match="profile"):
        dynahand.synth("wave", frames=2, profile="lidar")
    with pytest.raises(ValueError, match="frame count"):
        dynahand.synth("wave", frames=0)
    with pytest.raises(ValueError, match="placement"):
        dynahand.synth("wave", frames=2, placement="ceiling")
    with pytest.raises(ValueError, match="background"):
        dynahand.synth("wave", frames=2, background="sky")
    with pytest.raises(ValueError, match="hand length"):
        dynahand.synth("wave", frames=2, hand_size=(0.5, 0.08))
    clip = dynahand.synth("wave", frames=2)
    with pytest.raises(IndexError):
        clip[2]
    with pytest.raises(ValueError, match="hand 1 out of range"):
        clip.ground_truth(0, hand=1)


def test_evaluate():
    gt = np.zeros((3, 21, 3), np.float32)
    with pytest.raises(ValueError, match=r"\(N, 21, 3\)"):
        dynahand.evaluate(gt, np.zeros((3, 20, 3)))
    with pytest.raises(ValueError, match="not an \\(N, 21, 3\\) array"):
        dynahand.evaluate(gt, "poses.jsonl")
    partly = gt.copy()
    partly[1, 4, 0] = np.nan
    with pytest.raises(ValueError, match="pred frame 1: keypoints partly NaN"):
        dynahand.evaluate(gt, partly)
    with pytest.raises(ValueError, match="gt frame 1: keypoints must have shape"):
        dynahand.evaluate([gt[0], np.zeros(3)], gt)
    with pytest.raises(ValueError, match="fps"):
        dynahand.evaluate(gt, gt, fps=0.0)


def test_set_keypoints_errors():
    tracker = dynahand.Tracker(CAMERA, detector=False)
    with pytest.raises(ValueError, match=r"shape \(21, 3\)"):
        tracker.set_keypoints(np.zeros((20, 3)))
    with pytest.raises(ValueError, match=r"shape \(21,\)"):
        tracker.set_keypoints(np.zeros((21, 3)), confidence=np.ones(20))
    with pytest.raises(ValueError, match=r"in \[0, 1\]"):
        tracker.set_keypoints(np.zeros((21, 3)), confidence=np.full(21, 2.0))
    with pytest.raises(ValueError, match="one \\(right\\) hand"):
        tracker.set_keypoints(np.zeros((21, 3)), side="left")
    with pytest.raises(ValueError, match="all NaN"):
        tracker.set_keypoints(np.full((21, 3), np.nan))
