"""open_sequence on a `dynahand synth` folder: frame count, camera, ground truth."""

import json
import shutil

import numpy as np
import pytest

import dynahand
from conftest import FRAMES


def test_synth_folder(clip):
    seq = dynahand.open_sequence(clip)
    assert len(seq) == FRAMES and seq.format == "canonical" and seq.has_ground_truth
    camera = json.loads((clip / "camera.json").read_text())
    assert seq.camera.width == camera["width"] and seq.camera.height == camera["height"]
    assert seq.camera.fx == np.float32(camera["fx"]) and seq.camera.cy == np.float32(camera["cy"])
    assert seq.depth_scale == np.float32(camera["depth_scale"]) and seq.fps == 30.0
    lines = (clip / "groundtruth.jsonl").read_text().splitlines()
    assert len(lines) == FRAMES
    count = 0
    for i, (depth, scale, truth) in enumerate(seq):
        assert depth.dtype == np.uint16 and depth.shape == (camera["height"], camera["width"])
        assert scale == seq.depth_scale
        want = np.array(json.loads(lines[i])["keypoints21"], dtype=np.float64).astype(np.float32)
        assert truth.dtype == np.float32 and np.array_equal(truth, want)
        count += 1
    assert count == FRAMES
    assert np.array_equal(seq[-1][0], seq[FRAMES - 1][0])
    assert np.array_equal(seq.ground_truth_array()[5], seq.ground_truth(5))
    info = seq.info
    assert info["frames"] == FRAMES and info["format"] == "canonical"
    # the sensor's near range, which the tracker's segmentation is told (docs/cloud.md)
    assert seq.min_range_m == np.float32(camera["min_range_m"]) == info["min_range_m"]
    assert dynahand.synth("wave", frames=1, profile="structured-light").min_range_m == 0.5
    assert dynahand.Tracker(info, detector=False).camera == seq.camera


def test_folder_without_ground_truth(clip, tmp_path):
    copy = tmp_path / "nogt"
    shutil.copytree(clip, copy)
    (copy / "groundtruth.jsonl").unlink()
    seq = dynahand.open_sequence(str(copy))
    assert len(seq) == FRAMES and not seq.has_ground_truth
    assert seq[0][2] is None and seq.ground_truth(3) is None
    assert np.isnan(seq.ground_truth_array()).all()


def test_depth_array_owns_its_buffer(clip):
    seq = dynahand.open_sequence(clip)
    depth = seq[0][0]
    del seq  # the array keeps the frame alive (no copy out)
    assert depth.base is not None and int(depth.max()) > 0


def test_index_out_of_range(clip):
    seq = dynahand.open_sequence(clip)
    with pytest.raises(IndexError, match="out of range"):
        seq[FRAMES]


def test_held_object_changes_the_depth_only_in_front_of_the_palm():
    bare = dynahand.synth("grasp-cylinder", frames=1, profile="ideal")
    held = dynahand.synth("grasp-cylinder", frames=1, profile="ideal", held_object="box")
    a, b = bare[0][0].astype(np.int32), held[0][0].astype(np.int32)
    changed = (a != b) & (b > 0)
    assert changed.sum() > 200
    # the box lies in front of the hand (nearer) wherever both show something
    both = changed & (a > 0)
    assert (b[both] < a[both]).all()
    assert np.array_equal(bare[0][2], held[0][2])  # ground truth: the hand's keypoints only
    with pytest.raises(ValueError, match="held_object must be"):
        dynahand.synth("wave", frames=1, held_object="mug")
    with pytest.raises(ValueError, match="held object size"):
        dynahand.synth("wave", frames=1, held_object="ball", held_object_size=0.5)


def test_view_shift_moves_the_scene_and_keeps_the_ground_truth():
    centred = dynahand.synth("wave", frames=1, profile="ideal")
    shifted = dynahand.synth("wave", frames=1, profile="ideal", view_shift=(0, -100))
    assert shifted.camera.cy == pytest.approx(centred.camera.cy - 100)
    a, b = centred[0][0], shifted[0][0]
    assert np.array_equal(a[100:], b[:-100])  # 100 rows up; the top rows went out of view
    assert (a[:100] > 0).sum() > 500
    assert np.array_equal(centred[0][2], shifted[0][2])
    with pytest.raises(ValueError, match="view shift"):
        dynahand.synth("wave", frames=1, view_shift=(400, 0))
