"""dynahand.detector_data gives the samples `dynahand detector data` writes, byte for byte, and
the detector's training script makes its data file through it (train/train_detector.py)."""

import os
import pathlib
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

import dynahand
from conftest import run

TRAIN = pathlib.Path(__file__).resolve().parents[2] / "train"


def as_file(data):
    """The arrays as the bytes of a detector data file (docs/formats/detector-data.md)."""
    n = len(data["pixels"])
    meta = np.stack([data["profile"], data["source"]], axis=1).astype("<i4")
    return b"DHKD" + np.array([1, n, 64, 21], "<u4").tobytes() + b"".join(
        data["pixels"][i].tobytes() + data["uvd"][i].astype("<f4").tobytes() + meta[i].tobytes()
        for i in range(n))


@pytest.mark.parametrize("split, count, seed, threads, spread, objects", [
    ("train", 40, 5, 1, None, None),
    ("held-back", 24, 9, 2, 0.1, None),
    ("train", 24, 6, 2, None, (0.6, True)),
])
def test_same_bytes_as_command(tmp_path, split, count, seed, threads, spread, objects):
    out = tmp_path / "data.bin"
    args = ["detector", "data", "--split", split, "--count", count, "--seed", seed,
            "--threads", 2, "-o", out]
    kwargs = {}
    if spread is not None:
        args += ["--proportion-spread", spread]
        kwargs["proportion_spread"] = spread
    if objects is not None:
        args += ["--held-object-share", objects[0]] + (["--held-object-boxes"] if objects[1] else [])
        kwargs.update(held_object_share=objects[0], held_object_boxes=objects[1])
    run(*args)
    data = dynahand.detector_data(split=split, count=count, seed=seed, threads=threads, **kwargs)
    assert data["pixels"].dtype == np.uint8 and data["pixels"].shape == (count, 64, 64)
    assert data["uvd"].dtype == np.float32 and data["uvd"].shape == (count, 21, 3)
    assert data["profile"].dtype == np.int32 and data["source"].shape == (count,)
    assert as_file(data) == out.read_bytes()


def test_training_script_makes_the_same_file(tmp_path, monkeypatch):
    exe = os.environ.get("DYNAHAND_EXE")
    if not exe:
        pytest.skip("DYNAHAND_EXE (the dynahand command) is not set")
    monkeypatch.syspath_prepend(str(TRAIN))
    import train_detector  # torch is optional at import

    by_command, by_module = tmp_path / "command.bin", tmp_path / "module.bin"
    train_detector.generate(exe, "held-back", 20, 3, str(by_command), 2)
    train_detector.generate(exe, "held-back", 20, 3, str(by_module), 2, dynahand)
    assert by_module.read_bytes() == by_command.read_bytes()
    assert not (tmp_path / "module.bin.partial").exists()
    pixels, uvd = train_detector.read_data(str(by_module))
    assert pixels.shape == (20, 64 * 64) and uvd.shape == (20, 63)
    # A current cached file is kept (reruns skip the data); one the generator no longer makes
    # (another generator's, or damaged) is made again.
    stamp = by_module.stat().st_mtime_ns
    train_detector.generate(exe, "held-back", 20, 3, str(by_module), 2, dynahand)
    assert by_module.stat().st_mtime_ns == stamp
    damaged = bytearray(by_command.read_bytes())
    damaged[100] ^= 0xFF
    by_module.write_bytes(bytes(damaged))
    train_detector.generate(exe, "held-back", 20, 3, str(by_module), 2, dynahand)
    assert by_module.read_bytes() == by_command.read_bytes()
    by_module.write_bytes(b"cached")
    train_detector.generate(exe, "held-back", 20, 3, str(by_module), 2)
    assert by_module.read_bytes() == by_command.read_bytes()
    assert not list(tmp_path.glob("*.check"))
    # The scene settings (--held-object-share, --held-object-boxes, --shared-curl-share,
    # --head-view-share) reach both generators.
    scenes = {"held_object_share": 0.7, "held_object_boxes": True, "shared_curl_share": 0.9,
              "head_view_share": 0.8}
    objects_command, objects_module = tmp_path / "objects_command.bin", tmp_path / "objects_module.bin"
    train_detector.generate(exe, "train", 12, 4, str(objects_command), 2, None, scenes)
    train_detector.generate(exe, "train", 12, 4, str(objects_module), 2, dynahand, scenes)
    assert objects_module.read_bytes() == objects_command.read_bytes()
    train_detector.generate(exe, "train", 12, 4, str(by_module), 2, dynahand)
    assert objects_module.read_bytes() != by_module.read_bytes()


def script_module(tmp_path, exe, module_dir=None, pythonpath=None):
    """train_detector.import_dynahand(exe, module_dir) in a fresh interpreter: (exit code,
    stdout + stderr)."""
    code = ("import sys; sys.path.insert(0, sys.argv[1]); import train_detector as t; "
            "m = t.import_dynahand(sys.argv[2], sys.argv[3] or None); "
            "print('MODULE', m and m.__file__)")
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    if pythonpath:
        env["PYTHONPATH"] = str(pythonpath)
    done = subprocess.run([sys.executable, "-c", code, str(TRAIN), str(exe), str(module_dir or "")],
                          capture_output=True, text=True, cwd=tmp_path, env=env)
    return done.returncode, done.stdout + done.stderr


def test_training_script_finds_the_module(tmp_path):
    exe = os.environ.get("DYNAHAND_EXE")
    if not exe:
        pytest.skip("DYNAHAND_EXE (the dynahand command) is not set")
    here = pathlib.Path(dynahand.__file__).resolve().parent  # the build tree's python/
    # Beside the command's build tree (build/release/apps/dynahand: build/release/python).
    if pathlib.Path(exe).resolve().parents[1] / "python" == here:
        rc, out = script_module(tmp_path, exe)
        assert rc == 0 and f"MODULE {here}" in out, out
    # An explicit folder.
    rc, out = script_module(tmp_path, tmp_path / "bin" / "dynahand", module_dir=here)
    assert rc == 0 and f"MODULE {here}" in out, out
    # An explicit folder without it: an error, even when another one is importable.
    empty = tmp_path / "empty"
    empty.mkdir()
    rc, out = script_module(tmp_path, exe, module_dir=empty, pythonpath=here)
    assert rc == 1 and "--python-module-dir" in out and "no dynahand module" in out, out
    # A module without detector_data (an older build): the command makes the data.
    old = tmp_path / "old"
    old.mkdir()
    (old / "dynahand.py").write_text("")
    rc, out = script_module(tmp_path, tmp_path / "bin" / "dynahand", pythonpath=old)
    assert rc == 0 and "MODULE None" in out and "no dynahand Python module" in out, out


def test_errors():
    bad = [
        (dict(split="test"), "split must be 'train' or 'held-back' \\(got 'test'\\)"),
        (dict(count=0), "count must be in 1..10000000 \\(got 0\\)"),
        (dict(count=10000001), "count must be in 1..10000000"),
        (dict(threads=0), "threads must be 1..64"),
        (dict(threads=65), "threads must be 1..64"),
        (dict(proportion_spread=-0.1), "proportion_spread must be in \\[0, 0.5\\]"),
        (dict(proportion_spread=float("nan")), "proportion_spread must be in"),
        (dict(held_object_share=1.5), "held_object_share must be in \\[0, 1\\]"),
        (dict(shared_curl_share=-0.1), "shared_curl_share must be in \\[0, 1\\]"),
        (dict(shared_curl_share=float("nan")), "shared_curl_share must be in"),
        (dict(head_view_share=1.1), "head_view_share must be in \\[0, 1\\]"),
        (dict(seed=-1), "seed must be in \\[0, 2\\*\\*64\\) \\(got -1\\)"),
        (dict(seed=2**64), "seed must be in \\[0, 2\\*\\*64\\)"),
        (dict(seed=1.5), "seed must be an integer \\(got float\\)"),
        (dict(seed="1"), "seed must be an integer \\(got str\\)"),
    ]
    for kwargs, message in bad:
        with pytest.raises(ValueError, match=message):
            dynahand.detector_data(count=kwargs.pop("count", 2), **kwargs)
    assert dynahand.detector_data(count=1, seed=2**64 - 1)["pixels"].shape == (1, 64, 64)


def test_interrupt():
    """Ctrl-C while the samples are made: KeyboardInterrupt between blocks, not a hang."""
    code = ("import dynahand, sys; print('go', flush=True)\n"
            "try:\n    dynahand.detector_data(count=100000)\n"
            "except KeyboardInterrupt:\n    print('interrupted'); sys.exit(3)\n")
    proc = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, text=True)
    assert proc.stdout.readline().strip() == "go"
    time.sleep(1.0)  # well into the first blocks
    proc.send_signal(signal.SIGINT)
    out, _ = proc.communicate(timeout=60)
    assert proc.returncode == 3 and "interrupted" in out
