"""`dynahand batch` and dynahand_batch (Dask): a LocalCluster of 2 workers over 4 synthetic
sequences, one corrupt; outputs as `dynahand track` writes them (wall time aside); resume."""

import os
import re
import subprocess

import numpy as np
import pytest

from conftest import run

pytest.importorskip("distributed")
import dynahand_batch  # noqa: E402

FRAMES = 20
# distributed 2022.12 with Debian's tornado: "make_current is deprecated"
pytestmark = pytest.mark.filterwarnings("ignore::DeprecationWarning")


def without_time(text):
    """JSON lines without their wall times (the only field that differs between runs)."""
    return re.sub(r'"time_ms":[-0-9.e]+,', "", text)


def batch(*args, env=None):
    """Runs `dynahand batch ARGS`; returns the CompletedProcess."""
    exe = os.environ.get("DYNAHAND_EXE")
    if not exe:
        pytest.skip("DYNAHAND_EXE (the dynahand command) is not set")
    return subprocess.run([exe, "batch", *map(str, args)], capture_output=True, text=True,
                          env=env)


@pytest.fixture(scope="module")
def sequences(tmp_path_factory):
    """seqs/a, b, c: `dynahand synth --frames 20 --seed 1..3`; seqs/d_corrupt: frame 5's PNG
    truncated."""
    root = tmp_path_factory.mktemp("seqs")
    for seed, name in enumerate(["a", "b", "c", "d_corrupt"], 1):
        run("synth", "--frames", FRAMES, "--seed", seed, "--out", root / name)
    png = root / "d_corrupt" / "depth" / "000005.png"
    png.write_bytes(png.read_bytes()[:100])
    return root


@pytest.fixture(scope="module")
def reference(sequences, tmp_path_factory):
    """`dynahand track SEQ --out NAME.jsonl` of the three good sequences."""
    out = tmp_path_factory.mktemp("ref")
    for name in "abc":
        run("track", sequences / name, "--out", out / f"{name}.jsonl")
    return out


def test_command_two_workers_corrupt_sequence_and_resume(sequences, reference, tmp_path):
    out = tmp_path / "out"
    done = batch("track", sequences / "*", "--out", out, "--workers", 2)
    assert done.returncode == 1, done.stderr  # a task failed
    assert re.search(r"d_corrupt: failed \(OSError: .*000005\.png", done.stdout), done.stdout
    for name in "abc":
        assert re.search(rf"\] {name}: ok \({FRAMES} frames", done.stdout), done.stdout
    assert "3 done (60 frames" in done.stdout and "1 failed" in done.stdout
    assert sorted(os.listdir(out)) == ["a.jsonl", "b.jsonl", "c.jsonl"]  # no .part left
    for name in "abc":
        got = (out / f"{name}.jsonl").read_text()
        want = (reference / f"{name}.jsonl").read_text()
        assert len(got.splitlines()) == FRAMES
        assert without_time(got) == without_time(want)
    # the table: mean errors of the good ones (as `dynahand track` prints them)
    assert re.search(r"^a\s+20\s+20\s+[0-9.]+\s+[0-9]\.[0-9]{2}\s+ok$", done.stdout, re.M)

    # Resume: finished sequences are skipped (untouched), the corrupt one is tried again.
    mtimes = {n: (out / f"{n}.jsonl").stat().st_mtime_ns for n in "abc"}
    again = batch("track", sequences / "*", "--out", out, "--workers", 2)
    assert again.returncode == 1
    for name in "abc":
        assert f"skip {name}:" in again.stdout
    assert "[1/1] d_corrupt: failed" in again.stdout and "3 skipped" in again.stdout
    assert {n: (out / f"{n}.jsonl").stat().st_mtime_ns for n in "abc"} == mtimes

    # A deleted output (an interrupted run leaves none: only NAME.jsonl.part) is redone alone.
    (out / "b.jsonl").unlink()
    (out / "c.jsonl.part").write_text("partial")  # a crash's leftover is overwritten
    third = batch("track", sequences / "[abc]", "--out", out, "--workers", 2)
    assert third.returncode == 0, third.stdout + third.stderr
    assert "[1/1] b: ok" in third.stdout and "skip a:" in third.stdout
    assert without_time((out / "b.jsonl").read_text()) == without_time(
        (reference / "b.jsonl").read_text())
    assert (out / "a.jsonl").stat().st_mtime_ns == mtimes["a"]


def test_python_api_init_gt_without_detector(sequences, tmp_path):
    ref = tmp_path / "ref.jsonl"
    run("track", sequences / "a", "--init", "gt", "--no-detector", "--out", ref)
    log = tmp_path / "log.txt"
    with open(log, "w") as f:
        rows = dynahand_batch.track_batch([sequences / "a", sequences / "b"], tmp_path / "out",
                                          workers=1, init="gt", detector=False, out=f)
    assert [(r["name"], r["status"], r["frames"]) for r in rows] == [("a", "ok", FRAMES),
                                                                     ("b", "ok", FRAMES)]
    assert rows[0]["mean_mm"] < 10 and rows[0]["fps"] > 0
    assert without_time((tmp_path / "out" / "a.jsonl").read_text()) == without_time(
        ref.read_text())
    assert "sequence" in log.read_text()  # the summary table
    with pytest.raises(ValueError):
        dynahand_batch.track_batch([str(sequences / "nothing*")], tmp_path / "x")


def test_synth_shards_match_the_command_and_resume(tmp_path):
    ref = tmp_path / "ref"
    run("synth", "--motion", "pinch", "--frames", 5, "--seed", 8, "--out", ref)
    out = tmp_path / "shards"
    done = batch("synth", "--count", 2, "--frames", 5, "--motion", "wave,pinch", "--seed", 7,
                 "--out", out, "--workers", 2)
    assert done.returncode == 0, done.stdout + done.stderr
    assert sorted(os.listdir(out)) == ["shard_0000", "shard_0001"]
    shard = out / "shard_0001"  # pinch, seed 8
    for rel in ["camera.json", "groundtruth.jsonl", "poses.jsonl", "synth.json",
                "depth/000004.png"]:
        assert (shard / rel).read_bytes() == (ref / rel).read_bytes(), rel
    again = batch("synth", "--count", 3, "--frames", 5, "--motion", "wave,pinch", "--seed", 7,
                  "--out", out, "--workers", 1, "--format", "sequence")
    assert again.returncode == 0 and "skip shard_0000" in again.stdout
    assert "[1/1] shard_0002: ok" in again.stdout

    rows = dynahand_batch.synth_batch(1, tmp_path / "npz", frames=3, format="npz", workers=1,
                                      progress=False, summary=False)
    assert rows[0]["status"] == "ok"
    data = np.load(tmp_path / "npz" / "shard_0000.npz")
    assert data["depth"].shape[0] == 3 and data["depth"].dtype == np.uint16
    assert data["ground_truth"].shape == (3, 21, 3)
    with pytest.raises(ValueError, match="unknown clip"):
        dynahand_batch.synth_batch(1, tmp_path / "x", motion="no-such-clip")


def test_command_errors(tmp_path):
    none = batch()
    assert none.returncode == 2 and "dynahand batch:" in none.stderr
    usage = batch("track", tmp_path)  # no --out
    assert usage.returncode == 2 and "--out" in usage.stderr
    env = dict(os.environ, DYNAHAND_PYTHON=str(tmp_path / "no-python"))
    missing_python = batch("track", tmp_path, "--out", tmp_path / "o", env=env)
    assert missing_python.returncode == 2
    assert missing_python.stderr.count("\n") == 1 and "Python 3 not found" in missing_python.stderr
    env = dict(os.environ, DYNAHAND_PYTHONPATH=str(tmp_path), PYTHONPATH=str(tmp_path))
    missing_module = batch("track", tmp_path, "--out", tmp_path / "o", env=env)
    assert missing_module.returncode == 2 and missing_module.stderr.count("\n") == 1
    assert "dynahand_batch is missing" in missing_module.stderr
    # dask missing: a `distributed` that cannot be imported ahead of the real one
    (tmp_path / "distributed.py").write_text("raise ImportError('no distributed here')\n")
    module_dir = os.path.dirname(dynahand_batch.__file__)
    env = dict(os.environ, DYNAHAND_PYTHONPATH=f"{tmp_path}:{module_dir}")
    no_dask = batch("track", tmp_path, "--out", tmp_path / "o", env=env)
    assert no_dask.returncode == 2 and no_dask.stderr.count("\n") == 1
    assert "Dask is missing" in no_dask.stderr
