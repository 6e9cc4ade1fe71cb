#!/usr/bin/python3
"""Averages the weights of detector networks fine-tuned from a common network (docs/detector.md,
"Reproducing the weights"), then measures the average and writes its model card.

Networks fine-tuned from the same start stay in one basin of the loss, where the mean of their
weights is a network at least as accurate as its members (a "model soup", Wortsman et al.
2022) at the cost of one: the members' errors are partly independent and average out.

  /usr/bin/python3 train/average_detectors.py --dynahand build/release/apps/dynahand \
      --out models/detector /tmp/curl/detector.onnx /tmp/fresh/detector.onnx \
      /tmp/head/detector.onnx

Every member must be an export of train/train_detector.py with the same graph. Writes
OUT/detector.onnx and OUT/detector.json (the members' cards and the average's figures,
measured by `dynahand detector eval` as train_detector.py does).
"""
import argparse
import os
import sys

import numpy as np

import train_detector  # the card's figures, as the training script measures them (torch optional)

try:
    import onnx
    from onnx import numpy_helper
except ImportError:  # reported in main(): CTest skips the quick run without python3-onnx
    onnx = None


def graph_signature(model):
    """What two networks must share for their weights to be averaged: the nodes in order and
    every initializer's name, type and shape."""
    nodes = [(n.op_type, tuple(n.input), tuple(n.output)) for n in model.graph.node]
    weights = [(t.name, t.data_type, tuple(t.dims)) for t in model.graph.initializer]
    return nodes, weights


def average(paths):
    """The first network with every initializer replaced by the mean over all networks."""
    models = [onnx.load(p) for p in paths]
    signature = graph_signature(models[0])
    for path, model in zip(paths[1:], models[1:]):
        if graph_signature(model) != signature:
            raise ValueError(f"{path}: not the same network as {paths[0]} (nodes or weights "
                             "differ); only exports of one architecture can be averaged")
    tables = [{t.name: numpy_helper.to_array(t) for t in m.graph.initializer} for m in models]
    averaged = []
    for tensor in models[0].graph.initializer:
        values = [table[tensor.name] for table in tables]
        mean = np.mean(np.stack([v.astype(np.float64) for v in values]), axis=0)
        averaged.append(numpy_helper.from_array(mean.astype(values[0].dtype), tensor.name))
    result = models[0]
    del result.graph.initializer[:]
    result.graph.initializer.extend(averaged)
    return result


def main():
    p = argparse.ArgumentParser(description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--dynahand", required=True, help="the dynahand command (measures the average)")
    p.add_argument("--out", required=True, help="output folder for detector.onnx and detector.json")
    p.add_argument("--quick", action="store_true", help="measure on a few samples (CI)")
    p.add_argument("--skip-if-no-onnx", action="store_true",
                   help="exit 77 (CTest's skip) when python3-onnx is not installed")
    p.add_argument("members", nargs="+", help="detector.onnx files to average (two or more)")
    a = p.parse_args()
    if onnx is None:
        print("average_detectors: python3-onnx is not installed (scripts/install-deps.sh)",
              file=sys.stderr)
        sys.exit(77 if a.skip_if_no_onnx else 1)
    if len(a.members) < 2:
        sys.exit("average_detectors: give two or more networks to average")
    try:
        model = average(a.members)
    except ValueError as e:
        sys.exit(f"average_detectors: {e}")
    os.makedirs(a.out, exist_ok=True)
    onnx_path = os.path.join(a.out, "detector.onnx")
    onnx.save(model, onnx_path)
    cards = [train_detector.card_beside(m) for m in a.members]
    first = next((c for c in cards if c is not None), {})
    card = {
        "format": "dynahand-detector-card", "version": 1,
        "input": first.get("input"), "output": first.get("output"),
        "parameters": first.get("parameters"),
        "training": {
            "command": " ".join(["train/average_detectors.py"] + sys.argv[1:]),
            "average_of": [{"weights": m,
                            "training": c.get("training") if c else None,
                            "figures": c.get("figures") if c else None}
                           for m, c in zip(a.members, cards)],
        },
        "figures": train_detector.card_figures(a.dynahand, onnx_path, a.quick),
    }
    train_detector.write_card(a.out, card)


if __name__ == "__main__":
    main()
