#!/usr/bin/python3
"""Trains dynahand's learned keypoint detector (docs/detector.md) and exports it to ONNX.

Reproducible from seeds: the data comes from `dynahand detector data` (synthetic, sample i a
function of (seed, i)); torch is seeded; one run on Debian's python3-torch (CPU).

  /usr/bin/python3 train/train_detector.py --dynahand build/release/apps/dynahand \
      --out models/detector            # the shipped weights (about 85 min on 2 cores)
  /usr/bin/python3 train/train_detector.py --dynahand build/release/apps/dynahand \
      --out /tmp/f --init models/detector/detector.onnx --epochs 7 --lr 4e-4   # fine-tuning
  /usr/bin/python3 train/train_detector.py --dynahand ... --out /tmp/d --quick   # a few steps

Writes OUT/detector.onnx and OUT/detector.json (the model card's figures, measured by
`dynahand detector eval` on held-back motions and hand shapes).
"""
import argparse
import json
import os
import subprocess
import sys
import time

import numpy as np

try:
    import torch
    from torch import nn
except ImportError:  # reported in main(): CTest skips the quick run without torch
    torch = None
    nn = None

CROP = 64
KEYPOINTS = 21
HEAT = 16  # heat map cells per side
HALF_CROP_MM = 150.0  # one normalised crop unit (kCropSizeM / 2), mm
CONFIDENCE_SCALE_MM = 20.0  # confidence target exp(-error / this)
# One sample of the data file: the crop's bytes, 21 x (u, v, d), sensor profile and pose source.
RECORD = [("pixels", "u1", (CROP * CROP,)), ("uvd", "<f4", (KEYPOINTS * 3,)), ("meta", "<i4", (2,))]


def read_data(path):
    """The detector data file (docs/formats/detector-data.md) as numpy arrays."""
    with open(path, "rb") as f:
        head = f.read(20)
    if len(head) < 20 or head[:4] != b"DHKD":
        raise ValueError(f"{path}: not a detector data file")
    version, count, crop, keypoints = np.frombuffer(head[4:], dtype="<u4")
    if version != 1 or crop != CROP or keypoints != KEYPOINTS:
        raise ValueError(f"{path}: version {version}, crop {crop}, keypoints {keypoints} not supported")
    record = np.dtype(RECORD)
    if os.path.getsize(path) != 20 + int(count) * record.itemsize:
        raise ValueError(f"{path}: {os.path.getsize(path)} bytes, not the 20 + {count} x "
                         f"{record.itemsize} its header promises (truncated or not this format)")
    data = np.memmap(path, dtype=record, mode="r", offset=20, shape=(int(count),))
    return np.ascontiguousarray(data["pixels"]), np.ascontiguousarray(data["uvd"])


def build_detector(batch_norm=True):
    """64x64 depth crop -> 21 x (u, v, d) and 21 confidences (84 values).

    Integral regression: a small encoder-decoder gives each keypoint a 16x16 heat map and a
    16x16 depth map; the keypoint is the heat map's soft-argmax (u, v over the crop's cells)
    and its depth the heat-weighted mean of the depth map. Convolutions keep the position of
    what they see, which a fully connected regressor has to learn; the soft-argmax is formed
    from MatMul and Softmax so that OpenCV's DNN runs the whole network (opset 11).

    Without batch_norm each convolution has a bias instead: the exported graph (where the
    exporter folds batch normalisation into the convolutions) as a trainable network, which
    is what a fine-tuning run starts from (load_onnx_weights).
    """
    width = 32  # channels at 16x16

    def conv(cin, cout, stride=1, kernel=3):
        if not batch_norm:
            return nn.Sequential(nn.Conv2d(cin, cout, kernel, stride, kernel // 2, bias=True),
                                 nn.ReLU(inplace=True))
        return nn.Sequential(nn.Conv2d(cin, cout, kernel, stride, kernel // 2, bias=False),
                             nn.BatchNorm2d(cout), nn.ReLU(inplace=True))

    class Detector(nn.Module):
        def __init__(self):
            super().__init__()
            self.down16 = nn.Sequential(conv(1, 16, 2), conv(16, 32, 2), conv(32, width))
            self.down8 = nn.Sequential(conv(width, 64, 2), conv(64, 64))
            self.down4 = nn.Sequential(conv(64, 128, 2), conv(128, 128), conv(128, 128),
                                       conv(128, 128))
            self.lift8 = conv(128, 64, kernel=1)
            self.up8 = conv(64, 64)
            self.lift16 = conv(64, width, kernel=1)
            self.up16 = conv(width, width)
            self.maps = nn.Conv2d(width, 2 * KEYPOINTS, 1)
            self.confidence = nn.Linear(128, KEYPOINTS)
            centres = (torch.arange(HEAT, dtype=torch.float32) + 0.5) / HEAT * 2.0 - 1.0
            # (HEAT * HEAT, 2): each cell's (u, v) in crop units, row-major as the maps.
            self.register_buffer("cells", torch.stack([centres.repeat(HEAT),
                                                       centres.repeat_interleave(HEAT)], 1))
            self.register_buffer("ones", torch.ones(HEAT * HEAT, 1))

        def forward(self, x):
            f16 = self.down16(x)
            f8 = self.down8(f16)
            f4 = self.down4(f8)
            up = nn.functional.interpolate(self.lift8(f4), scale_factor=2.0, mode="nearest")
            g8 = self.up8(up + f8)
            up = nn.functional.interpolate(self.lift16(g8), scale_factor=2.0, mode="nearest")
            g16 = self.up16(up + f16)
            maps = self.maps(g16)
            n = x.shape[0]
            heat = torch.softmax(maps[:, :KEYPOINTS].reshape(n, KEYPOINTS, HEAT * HEAT), dim=2)
            depth = maps[:, KEYPOINTS:].reshape(n, KEYPOINTS, HEAT * HEAT)
            uv = torch.matmul(heat, self.cells)
            d = torch.matmul(heat * depth, self.ones)
            points = torch.cat([uv, d], dim=2).reshape(n, KEYPOINTS * 3)
            confidence = torch.sigmoid(self.confidence(f4.mean(dim=(2, 3))))
            return torch.cat([points, confidence], dim=1)

    return Detector()


def load_onnx_weights(model, path):
    """Copies an exported detector's weights (detector.onnx) into a network built without batch
    normalisation: the graph's convolutions in order are the network's, then the confidence
    layer's Gemm."""
    import onnx
    from onnx import numpy_helper
    graph = onnx.load(path).graph
    values = {t.name: numpy_helper.to_array(t).copy() for t in graph.initializer}
    convs = [m for m in model.modules() if isinstance(m, nn.Conv2d)]
    nodes = [n for n in graph.node if n.op_type == "Conv"]
    gemms = [n for n in graph.node if n.op_type == "Gemm"]
    if len(nodes) != len(convs) or len(gemms) != 1:
        raise ValueError(f"{path}: {len(nodes)} convolutions and {len(gemms)} Gemm, not the "
                         f"detector's {len(convs)} and 1")
    with torch.no_grad():
        for conv, node in zip(convs, nodes):
            weight, bias = values[node.input[1]], values[node.input[2]]
            if tuple(weight.shape) != tuple(conv.weight.shape):
                raise ValueError(f"{path}: convolution {node.input[1]} is {weight.shape}, the "
                                 f"detector's {tuple(conv.weight.shape)}")
            conv.weight.copy_(torch.from_numpy(weight))
            conv.bias.copy_(torch.from_numpy(bias))
        gemm = gemms[0]
        model.confidence.weight.copy_(torch.from_numpy(values[gemm.input[1]]))
        model.confidence.bias.copy_(torch.from_numpy(values[gemm.input[2]]))


def import_dynahand(exe, module_dir=None):
    """The dynahand Python module that makes the data in memory, or None (the command makes
    it): the one in --python-module-dir (which must hold it), else in the python/ folder of the
    command's build tree (build/release/apps/dynahand: build/release/python), else importable."""
    import importlib
    import shutil
    build = os.path.dirname(os.path.dirname(os.path.realpath(shutil.which(exe) or exe)))
    folder = module_dir or os.path.join(build, "python")
    sys.path.insert(0, folder)
    try:
        module = importlib.import_module("dynahand")
    except ImportError:
        module = None
    finally:
        sys.path.remove(folder)
    usable = module is not None and hasattr(module, "detector_data")
    if module_dir and not (usable and os.path.dirname(os.path.realpath(module.__file__))
                           == os.path.realpath(module_dir)):
        sys.exit(f"train_detector: --python-module-dir {module_dir}: no dynahand module with "
                 "detector_data there")
    if not usable:
        print(f"detector data: {exe} detector data (no dynahand Python module)", flush=True)
        return None
    print(f"detector data: dynahand.detector_data ({module.__file__})", flush=True)
    return module


CACHE_CHECK = 64  # samples remade to check a cached file against the generator of today


DEFAULT_SCENES = {"held_object_share": 0.15, "held_object_boxes": False, "shared_curl_share": 0.3,
                  "head_view_share": 0.45}


def make_file(dynahand, split, count, seed, path, threads, module, scenes=None):
    """Writes the data file (docs/formats/detector-data.md): dynahand.detector_data (module) or
    the command, the same bytes either way. scenes: the generator's scene settings
    (DEFAULT_SCENES' keys)."""
    scenes = scenes or DEFAULT_SCENES
    if module is None:
        subprocess.run([dynahand, "detector", "data", "--split", split, "--count", str(count),
                        "--seed", str(seed), "--threads", str(threads),
                        "--held-object-share", str(scenes["held_object_share"])]
                       + (["--held-object-boxes"] if scenes["held_object_boxes"] else [])
                       + ["--shared-curl-share", str(scenes["shared_curl_share"])]
                       + ["--head-view-share", str(scenes["head_view_share"])]
                       + ["-o", path], check=True)
        return
    data = module.detector_data(split=split, count=count, seed=seed, threads=threads, **scenes)
    records = np.empty(count, RECORD)
    records["pixels"] = data["pixels"].reshape(count, -1)
    records["uvd"] = data["uvd"].reshape(count, -1)
    records["meta"] = np.stack([data["profile"], data["source"]], axis=1)
    with open(path + ".partial", "wb") as f:  # renamed when complete, as the command does
        f.write(b"DHKD" + np.array([1, count, CROP, KEYPOINTS], dtype="<u4").tobytes())
        records.tofile(f)
    os.replace(path + ".partial", path)


def cache_is_current(dynahand, split, count, seed, path, threads, module, scenes=None):
    """Whether a cached file holds what the generator makes today. Sample i depends on (seed, i)
    alone, so its first samples are remade and compared: a file from an older generator (another
    crop rule, other scenes) would otherwise train a network on data the tracker never shows it."""
    check = min(CACHE_CHECK, count)
    fresh = path + ".check"
    make_file(dynahand, split, check, seed, fresh, threads, module, scenes)
    try:
        record = np.dtype(RECORD).itemsize
        with open(fresh, "rb") as f:
            expected = f.read()[20:20 + check * record]
        with open(path, "rb") as f:
            head = f.read(20)
            cached = f.read(check * record)
    finally:
        os.remove(fresh)
    stored = np.frombuffer(head[4:20], dtype="<u4") if len(head) == 20 else None
    return stored is not None and int(stored[1]) == count and cached == expected


def generate(dynahand, split, count, seed, path, threads, module=None, scenes=None):
    """The data file at path: kept when it is there and current, else made (again)."""
    if os.path.exists(path):
        if cache_is_current(dynahand, split, count, seed, path, threads, module, scenes):
            return
        print(f"detector data: {path} was made by another generator; making it again", flush=True)
    make_file(dynahand, split, count, seed, path, threads, module, scenes)


def to_input(pixels, rng=None):
    x = torch.from_numpy(pixels.astype(np.float32) / 127.5 - 1.0).view(-1, 1, CROP, CROP)
    if rng is not None:
        # Sensor dropout beyond the simulated one: a few per cent of pixels read "far".
        drop = torch.from_numpy(rng.random(x.shape) < rng.uniform(0.0, 0.05)).to(torch.bool)
        x = torch.where(drop, torch.ones_like(x), x)
    return x


def losses(output, target):
    points = output[:, :KEYPOINTS * 3]
    confidence = output[:, KEYPOINTS * 3:]
    point_loss = (points - target).abs().mean()
    error_mm = (points.detach() - target).view(-1, KEYPOINTS, 3).norm(dim=2) * HALF_CROP_MM
    confidence_loss = ((confidence - torch.exp(-error_mm / CONFIDENCE_SCALE_MM)) ** 2).mean()
    return point_loss, confidence_loss, error_mm.mean().item()


def evaluate(model, pixels, uvd, batch=512):
    model.eval()
    errors = []
    with torch.no_grad():
        for i in range(0, len(pixels), batch):
            out = model(to_input(pixels[i:i + batch]))
            target = torch.from_numpy(uvd[i:i + batch])
            errors.append((out[:, :KEYPOINTS * 3] - target).view(-1, KEYPOINTS, 3).norm(dim=2))
    model.train()
    return float(torch.cat(errors).mean()) * HALF_CROP_MM


def card_figures(dynahand, onnx_path, quick=False):
    """The model card's figures: the C++ side's `detector eval` on a fixed held-back set (what
    KeypointDetector.ShippedWeightsReproduceTheirModelCard reproduces); a few samples when
    quick."""
    eval_args = ["--split", "held-back", "--count", "300" if not quick else "32", "--seed", "7"]
    measured = json.loads(subprocess.run([dynahand, "detector", "eval", "--weights", onnx_path]
                                         + eval_args, check=True, capture_output=True,
                                         text=True).stdout)
    return {"eval_args": eval_args, "mean_mm": measured["mean_mm"],
            "p95_mm": measured["p95_mm"], "mean_confidence": measured["mean_confidence"]}


def card_beside(onnx_path):
    """The model card (detector.json) in the folder of an exported network, or None."""
    path = os.path.join(os.path.dirname(os.path.abspath(onnx_path)), "detector.json")
    if not os.path.exists(path):
        return None
    with open(path) as f:
        return json.load(f)


def write_card(out, card):
    """OUT/detector.json; prints the figures."""
    with open(os.path.join(out, "detector.json"), "w") as f:
        json.dump(card, f, indent=2)
        f.write("\n")
    print(json.dumps(card["figures"]))


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--dynahand", required=True, help="the dynahand command (generates the data)")
    p.add_argument("--python-module-dir", default=None,
                   help="folder of the dynahand Python module that makes the data in memory "
                        "(default: the python/ folder of --dynahand's build tree, else import)")
    p.add_argument("--out", required=True, help="output folder for detector.onnx and detector.json")
    p.add_argument("--work", default=None, help="data cache folder (default: OUT/../work or /tmp)")
    p.add_argument("--train-count", type=int, default=300000)
    p.add_argument("--heldback-count", type=int, default=3000)
    p.add_argument("--epochs", type=float, default=10.0)
    p.add_argument("--batch", type=int, default=128)
    p.add_argument("--lr", type=float, default=2e-3)
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--threads", type=int, default=2)
    p.add_argument("--init", default=None,
                   help="fine-tune: start from this detector.onnx (its folded weights, no batch "
                        "normalisation) instead of random weights")
    p.add_argument("--held-object-share", type=float, default=DEFAULT_SCENES["held_object_share"],
                   help="training scenes: share with an object held at the palm")
    p.add_argument("--held-object-boxes", action="store_true",
                   help="training scenes: held objects may be boxes as well as balls and cylinders")
    p.add_argument("--shared-curl-share", type=float, default=DEFAULT_SCENES["shared_curl_share"],
                   help="training poses: share of the random poses whose fingers curl together")
    p.add_argument("--head-view-share", type=float, default=DEFAULT_SCENES["head_view_share"],
                   help="training views: share of draws seen as from a head-mounted camera")
    p.add_argument("--quick", action="store_true", help="a few steps on a small set (CI)")
    p.add_argument("--skip-if-no-torch", action="store_true",
                   help="exit 77 (CTest's skip) when python3-torch is not installed")
    a = p.parse_args()
    if torch is None:
        print("train_detector: python3-torch is not installed (scripts/install-deps.sh)",
              file=sys.stderr)
        sys.exit(77 if a.skip_if_no_torch else 1)
    if a.quick:
        a.train_count, a.heldback_count, a.epochs = 256, 128, 1.0
    os.makedirs(a.out, exist_ok=True)
    work = a.work or os.path.join(a.out, "work")
    os.makedirs(work, exist_ok=True)
    torch.manual_seed(a.seed)
    torch.set_num_threads(a.threads)
    rng = np.random.default_rng(a.seed)

    scenes = {"held_object_share": a.held_object_share, "held_object_boxes": a.held_object_boxes,
              "shared_curl_share": a.shared_curl_share, "head_view_share": a.head_view_share}
    scene_tag = "" if scenes == DEFAULT_SCENES else \
        f"_o{a.held_object_share:g}{'b' if a.held_object_boxes else ''}" + \
        ("" if a.shared_curl_share == DEFAULT_SCENES["shared_curl_share"]
         else f"_c{a.shared_curl_share:g}") + \
        ("" if a.head_view_share == DEFAULT_SCENES["head_view_share"]
         else f"_h{a.head_view_share:g}")
    train_path = os.path.join(work, f"train_{a.train_count}_s{a.seed}{scene_tag}.bin")
    held_path = os.path.join(work, f"heldback_{a.heldback_count}_s{a.seed + 1000}.bin")
    t0 = time.time()
    module = import_dynahand(a.dynahand, a.python_module_dir)
    generate(a.dynahand, "train", a.train_count, a.seed, train_path, a.threads, module, scenes)
    generate(a.dynahand, "held-back", a.heldback_count, a.seed + 1000, held_path, a.threads, module)
    data_s = time.time() - t0
    pixels, uvd = read_data(train_path)
    held_pixels, held_uvd = read_data(held_path)

    model = build_detector(batch_norm=a.init is None)
    if a.init:
        load_onnx_weights(model, a.init)
        print(f"detector: fine-tuning {a.init}: held-back {evaluate(model, held_pixels, held_uvd):.2f} mm "
              "at the start", flush=True)
    params = sum(p.numel() for p in model.parameters())
    steps = max(1, int(a.epochs * len(pixels) / a.batch))
    optimiser = torch.optim.AdamW(model.parameters(), lr=a.lr, weight_decay=1e-4)
    schedule = torch.optim.lr_scheduler.OneCycleLR(optimiser, max_lr=a.lr, total_steps=steps,
                                                   pct_start=0.05)
    print(f"detector: {params} parameters, {len(pixels)} training samples, {steps} steps "
          f"of {a.batch}, data {data_s:.0f} s", flush=True)
    t0 = time.time()
    order = rng.permutation(len(pixels))
    at = 0
    for step in range(steps):
        if at + a.batch > len(order):
            order, at = rng.permutation(len(pixels)), 0
        index = np.sort(order[at:at + a.batch])
        at += a.batch
        out = model(to_input(pixels[index], rng))
        point_loss, confidence_loss, err = losses(out, torch.from_numpy(uvd[index]))
        optimiser.zero_grad()
        (point_loss + 0.5 * confidence_loss).backward()
        optimiser.step()
        schedule.step()
        if step % 200 == 0 or step == steps - 1:
            held = evaluate(model, held_pixels[:512], held_uvd[:512]) if step % 1000 == 0 or step == steps - 1 else float("nan")
            print(f"step {step}/{steps} train {err:.1f} mm held-back {held:.1f} mm "
                  f"{(step + 1) * a.batch / (time.time() - t0):.0f} samples/s", flush=True)
    train_s = time.time() - t0
    held_mm = evaluate(model, held_pixels, held_uvd)

    torch.save(model.state_dict(), os.path.join(work, "detector.pt"))
    model.eval()
    onnx_path = os.path.join(a.out, "detector.onnx")
    torch.onnx.export(model, torch.ones(1, 1, CROP, CROP), onnx_path, opset_version=11,
                      input_names=["crop"], output_names=["keypoints"])
    card = {
        "format": "dynahand-detector-card", "version": 1,
        "input": [1, 1, CROP, CROP], "output": KEYPOINTS * 4, "parameters": params,
        "training": {"command": " ".join(["train/train_detector.py"] + sys.argv[1:]),
                     "seed": a.seed, "init": a.init, "train_samples": a.train_count,
                     "scenes": scenes, "epochs": a.epochs,
                     "batch": a.batch, "lr": a.lr, "threads": a.threads,
                     "data_seconds": round(data_s), "train_seconds": round(train_s),
                     "torch": torch.__version__},
        "held_back": {"samples": a.heldback_count, "seed": a.seed + 1000,
                      "mean_mm_approx": round(held_mm, 2)},
        "figures": card_figures(a.dynahand, onnx_path, a.quick),
    }
    if a.init:
        # The run this one fine-tuned, from the card beside its weights: a fine-tuned network's
        # whole recipe is then in one card.
        base = card_beside(a.init)
        if base is not None:
            card["training"]["base"] = {"training": base.get("training"),
                                        "figures": base.get("figures")}
    write_card(a.out, card)


if __name__ == "__main__":
    main()
