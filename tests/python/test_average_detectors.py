"""train/average_detectors.py: the mean of detector networks' weights (docs/detector.md,
"Reproducing the weights"), refused for networks of another graph, measured and carded."""

import json
import os
import pathlib
import subprocess
import sys

import numpy as np
import pytest

onnx = pytest.importorskip("onnx")
from onnx import numpy_helper  # noqa: E402

ROOT = pathlib.Path(__file__).resolve().parents[2]
TRAIN = ROOT / "train"
SHIPPED = ROOT / "models" / "detector" / "detector.onnx"


@pytest.fixture()
def average_detectors(monkeypatch):
    monkeypatch.syspath_prepend(str(TRAIN))
    import average_detectors as module
    return module


def initializers(model):
    return {t.name: numpy_helper.to_array(t) for t in model.graph.initializer}


def scaled_copy(path, factor, out):
    """The network at path with every weight times factor, written to out."""
    model = onnx.load(str(path))
    scaled = [numpy_helper.from_array((numpy_helper.to_array(t) * factor).astype(
        numpy_helper.to_array(t).dtype), t.name) for t in model.graph.initializer]
    del model.graph.initializer[:]
    model.graph.initializer.extend(scaled)
    onnx.save(model, str(out))
    return out


def test_the_average_is_the_mean_of_every_weight(average_detectors, tmp_path):
    tripled = scaled_copy(SHIPPED, 3.0, tmp_path / "tripled.onnx")
    averaged = average_detectors.average([str(SHIPPED), str(tripled)])
    shipped = onnx.load(str(SHIPPED))
    assert average_detectors.graph_signature(averaged) == \
        average_detectors.graph_signature(shipped)
    expected = initializers(shipped)
    got = initializers(averaged)
    assert got.keys() == expected.keys()
    for name, value in expected.items():
        np.testing.assert_allclose(got[name], 2.0 * value, rtol=1e-6, atol=1e-7, err_msg=name)
    # Two copies of one network average to that network, bit for bit.
    same = initializers(average_detectors.average([str(SHIPPED), str(SHIPPED)]))
    for name, value in expected.items():
        assert np.array_equal(same[name], value), name


def test_a_network_of_another_graph_is_refused(average_detectors, tmp_path):
    model = onnx.load(str(SHIPPED))
    first = model.graph.initializer[0]
    shrunk = numpy_helper.to_array(first).reshape(-1)[:1].copy()
    model.graph.initializer[0].CopyFrom(numpy_helper.from_array(shrunk, first.name))
    other = tmp_path / "other.onnx"
    onnx.save(model, str(other))
    with pytest.raises(ValueError, match="other.onnx"):
        average_detectors.average([str(SHIPPED), str(other)])


def test_the_script_writes_the_average_and_its_card(tmp_path):
    exe = os.environ.get("DYNAHAND_EXE")
    if not exe:
        pytest.skip("DYNAHAND_EXE (the dynahand command) is not set")
    out = tmp_path / "soup"
    done = subprocess.run([sys.executable, str(TRAIN / "average_detectors.py"), "--dynahand", exe,
                           "--out", str(out), "--quick", str(SHIPPED), str(SHIPPED)],
                          capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    card = json.loads((out / "detector.json").read_text())
    assert card["format"] == "dynahand-detector-card"
    assert [m["weights"] for m in card["training"]["average_of"]] == [str(SHIPPED)] * 2
    shipped_card = json.loads((SHIPPED.parent / "detector.json").read_text())
    assert card["training"]["average_of"][0]["figures"] == shipped_card["figures"]
    # The C++ side loads the average and measures it as it measures the shipped weights (the
    # average of two copies is the same network).
    measured = json.loads(subprocess.run(
        [exe, "detector", "eval", "--weights", str(SHIPPED)] + card["figures"]["eval_args"],
        capture_output=True, text=True, check=True).stdout)
    assert card["figures"]["mean_mm"] == measured["mean_mm"]
    assert card["figures"]["p95_mm"] == measured["p95_mm"]
    refused = subprocess.run([sys.executable, str(TRAIN / "average_detectors.py"), "--dynahand",
                              exe, "--out", str(tmp_path / "one"), str(SHIPPED)],
                             capture_output=True, text=True)
    assert refused.returncode != 0 and "two or more" in refused.stderr
