"""Shared fixtures of the dynahand module's tests: the dynahand command and short synthetic
clips it writes (run through CTest: PYTHONPATH holds the module, DYNAHAND_EXE the command)."""

import os
import subprocess

import pytest

FRAMES = 30  # one second of the wave clip: a few seconds for every test together


def run(*args):
    """Runs the dynahand command; returns its stdout."""
    exe = os.environ.get("DYNAHAND_EXE")
    if not exe:
        pytest.skip("DYNAHAND_EXE (the dynahand command) is not set")
    done = subprocess.run([exe, *map(str, args)], capture_output=True, text=True)
    assert done.returncode == 0, f"dynahand {' '.join(map(str, args))}: {done.stderr}"
    return done.stdout


@pytest.fixture(scope="session")
def clip(tmp_path_factory):
    """`dynahand synth --motion wave --frames 30 --out DIR` (defaults: tof, desk, seed 1)."""
    path = tmp_path_factory.mktemp("synth") / "wave"
    run("synth", "--motion", "wave", "--frames", FRAMES, "--out", path)
    return path


@pytest.fixture(scope="session")
def tracked(clip, tmp_path_factory):
    """`dynahand track CLIP --out poses.jsonl`: the command's JSON lines."""
    out = tmp_path_factory.mktemp("track") / "poses.jsonl"
    run("track", clip, "--out", out)
    return out
