"""evaluate() gives the figures `dynahand eval` prints."""

import json

import numpy as np
import pytest

import dynahand
from conftest import FRAMES, run


def read_keypoints(path, key="keypoints21"):
    """Keypoint rows of JSON lines: (N, 21, 3) float32, NaN where no hand."""
    rows = []
    for line in path.read_text().splitlines():
        item = json.loads(line)
        k = item["hands"][0][key] if "hands" in item else item[key]
        rows.append(np.full((21, 3), np.nan) if k is None else np.array(k, dtype=np.float64))
    return np.array(rows).astype(np.float32)


@pytest.mark.parametrize("flags", [[], ["--fps", "15", "--lost-mm", "4"]])
def test_evaluate_equals_command(clip, tracked, flags):
    printed = run("eval", "--gt", clip / "groundtruth.jsonl", "--pred", tracked, *flags)
    gt = read_keypoints(clip / "groundtruth.jsonl")
    pred = read_keypoints(tracked)
    options = dict(zip(["fps", "lost_mm"], map(float, flags[1::2])))
    metrics = dynahand.evaluate(gt, pred, **options)
    assert metrics.summary() == printed
    assert metrics.frames == FRAMES and metrics.per_frame_mean_mm.shape == (FRAMES,)
    assert metrics.per_joint_mean_mm.shape == (21,)


def test_lists_with_none_equal_nan_rows(clip):
    seq = dynahand.open_sequence(clip)
    gt = seq.ground_truth_array()
    pred = gt + np.float32(0.003)
    rows = [None if i % 7 == 3 else pred[i] for i in range(len(pred))]
    nan_rows = pred.copy()
    nan_rows[3::7] = np.nan
    a = dynahand.evaluate(list(gt), rows)
    b = dynahand.evaluate(gt, nan_rows)
    assert a.summary() == b.summary()
    assert a.evaluated_frames == FRAMES - len(range(3, FRAMES, 7))
    assert a.mean_mm == pytest.approx(3.0 * np.sqrt(3.0), abs=1e-3)


def test_binding_tracking_evaluated(clip):
    seq = dynahand.open_sequence(clip)
    tracker = dynahand.Tracker(seq)
    pred = [tracker.track(depth, scale)[0].keypoints21 for depth, scale, _ in seq]
    metrics = dynahand.evaluate(seq.ground_truth_array(), pred)
    assert metrics.evaluated_frames >= FRAMES - 2 and metrics.mean_mm < 15.0
