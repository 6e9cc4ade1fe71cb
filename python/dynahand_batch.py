"""Tracking and synthetic data at dataset scale on Dask: one task per sequence or shard.

`track_batch` tracks many recorded sequences, `synth_batch` writes many synthetic ones, each as
one Dask task on an embedded `distributed.LocalCluster` (default) or on a running scheduler
(`scheduler="tcp://HOST:PORT"`). `dynahand batch track|synth ...` runs `main()` (docs/python.md).

Outputs: `OUT/NAME.jsonl` per sequence, the lines `dynahand track SEQ --out NAME.jsonl` writes
(tracked in the task with the `dynahand` module: the same library calls, so the same bytes but
for each line's `"time_ms"`, the frame's own wall time, which differs between any two runs of
`dynahand track` too). A file is written as `NAME.jsonl.part` and renamed when complete, so an
existing `NAME.jsonl` is a finished sequence and a later run skips it (resume). A sequence that
fails (unreadable, a corrupt frame) is reported with its error; the others go on.
"""

import argparse
import glob
import os
import shutil
import subprocess
import sys
import time
import uuid

__all__ = ["track_batch", "synth_batch", "track_sequence", "synth_shard", "main"]

PART = ".part"  # suffix of an output being written


# ---------------------------------------------------------------------------------------------
# The tasks (run on the workers; plain functions of picklable arguments, results are dicts)


def track_sequence(path, out_path, init="auto", detector=True, hands=1, hand_size=None):
    """Tracks one sequence as `dynahand track PATH --out OUT_PATH [--init gt] [--no-detector]`
    does; writes OUT_PATH (via OUT_PATH.part). Returns a summary dict; raises on failure."""
    import numpy as np

    import dynahand

    started, cpu = time.perf_counter(), time.process_time()
    seq = dynahand.open_sequence(path)
    tracker = dynahand.Tracker(seq, hands=hands, hand_size=hand_size, detector=detector)
    if init == "gt":
        if not seq.has_ground_truth or seq.ground_truth(0) is None:
            raise ValueError(f"--init gt: {path} has no ground truth for frame 0")
        tracker.initialize(seq.ground_truth(0))
    elif init != "auto":
        raise ValueError(f"init must be 'auto' or 'gt', not {init!r}")
    part = out_path + PART
    n = len(seq)
    pred = np.full((n, 21, 3), np.nan, dtype=np.float32)
    tracked = 0
    track_seconds = 0.0
    try:
        with open(part, "w", encoding="utf-8", newline="\n") as out:
            for i in range(n):
                depth, scale, _ = seq[i]  # a corrupt frame raises OSError here
                t0 = time.perf_counter()
                hand = tracker.track(depth, scale)[0]
                track_seconds += time.perf_counter() - t0
                out.write(tracker.result_json())
                out.write("\n")
                if hand.tracked:
                    tracked += 1
                    pred[i] = hand.keypoints21
        os.replace(part, out_path)
    except BaseException:
        if os.path.exists(part):
            os.remove(part)
        raise
    mean_mm = None
    if seq.has_ground_truth and n > 0:
        mean_mm = float(dynahand.evaluate(seq.ground_truth_array(), pred, fps=seq.fps).mean_mm)
    return {
        "frames": n,
        "tracked": tracked,
        "seconds": time.perf_counter() - started,
        "cpu_seconds": time.process_time() - cpu,  # the worker process's, this task's share
        "fps": n / track_seconds if track_seconds > 0 else float("nan"),
        "mean_mm": mean_mm,
    }


def _dynahand_exe(exe=None):
    exe = exe or os.environ.get("DYNAHAND_EXE") or shutil.which("dynahand")
    if not exe:
        raise FileNotFoundError("the dynahand command is not found (set DYNAHAND_EXE or PATH)")
    return exe


def synth_shard(out_path, motion="wave", frames=300, profile="tof", seed=1, fmt="sequence",
                options=(), exe=None):
    """Writes one synthetic shard: fmt "sequence": `dynahand synth --motion M --frames F
    --profile P --seed S [OPTIONS] --out OUT_PATH` (a folder `dynahand track` reads); fmt "npz":
    OUT_PATH (.npz) with `depth` (N, H, W) uint16, `depth_scale`, `ground_truth` (N, 21, 3) m,
    `camera` (width height fx fy cx cy) and `fps` from `dynahand.synth` (training data).
    Written under OUT_PATH.part, renamed when complete. Returns a summary dict."""
    started = time.perf_counter()
    part = out_path + PART
    if os.path.isdir(part):
        shutil.rmtree(part)
    elif os.path.exists(part):
        os.remove(part)
    try:
        if fmt == "sequence":
            args = [_dynahand_exe(exe), "synth", "--motion", motion, "--frames", str(frames),
                    "--profile", profile, "--seed", str(seed), *options, "--out", part]
            done = subprocess.run(args, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                                  text=True)
            if done.returncode != 0:
                raise RuntimeError(done.stderr.strip() or f"dynahand synth exit {done.returncode}")
        elif fmt == "npz":
            import numpy as np

            import dynahand

            clip = dynahand.synth(motion, frames=frames, profile=profile, seed=seed)
            depth, truth = clip.arrays()
            scale = clip[0][1] if len(clip) else 0.001
            cam = clip.camera
            with open(part, "wb") as f:
                np.savez_compressed(
                    f, depth=depth, depth_scale=np.float32(scale), ground_truth=truth,
                    camera=np.array([cam.width, cam.height, cam.fx, cam.fy, cam.cx, cam.cy],
                                    dtype=np.float64),
                    fps=np.float64(clip.fps))
        else:
            raise ValueError(f"format must be 'sequence' or 'npz', not {fmt!r}")
        os.replace(part, out_path)
    except BaseException:
        if os.path.isdir(part):
            shutil.rmtree(part, ignore_errors=True)
        elif os.path.exists(part):
            os.remove(part)
        raise
    seconds = time.perf_counter() - started
    return {"frames": frames, "tracked": None, "seconds": seconds,
            "fps": frames / seconds if seconds > 0 else float("nan"), "mean_mm": None}


# ---------------------------------------------------------------------------------------------
# The client side


def _client(scheduler, workers):
    """A distributed.Client: on the scheduler at `scheduler`, or on a new LocalCluster of
    `workers` single-threaded worker processes. Returns (client, cluster or None)."""
    from distributed import Client, LocalCluster

    if scheduler:
        return Client(scheduler), None
    cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                           dashboard_address=None, silence_logs=40)
    return Client(cluster), cluster


def expand_inputs(inputs):
    """Paths and glob patterns to a sorted, de-duplicated list of paths (a pattern that matches
    nothing is an error; a plain path is kept as given, so a missing one fails as its task)."""
    if isinstance(inputs, (str, os.PathLike)):
        inputs = [inputs]
    paths = []
    for item in inputs:
        item = os.fspath(item)
        if glob.has_magic(item):
            matches = sorted(glob.glob(item))
            if not matches:
                raise ValueError(f"no sequence matches {item!r}")
            paths.extend(matches)
        else:
            paths.append(item)
    seen, unique = set(), []
    for p in paths:
        key = os.path.abspath(p)
        if key not in seen:
            seen.add(key)
            unique.append(p)
    return unique


def output_name(path):
    """A sequence's output name: its folder's or file's name without the extension."""
    base = os.path.basename(os.path.normpath(path))
    stem, ext = os.path.splitext(base)
    return stem if ext and os.path.isfile(path) else base


def _fmt(v, spec):
    return "-" if v is None or v != v else format(v, spec)


def summary_table(rows):
    """The summary as aligned text: sequence, frames, tracked, fps, mean error, status."""
    head = ["sequence", "frames", "tracked", "fps", "mean err mm", "status"]
    body = [[r["name"], _fmt(r.get("frames"), "d"), _fmt(r.get("tracked"), "d"),
             _fmt(r.get("fps"), ".1f"), _fmt(r.get("mean_mm"), ".2f"),
             r["status"] + (": " + r["error"] if r.get("error") else "")] for r in rows]
    widths = [max(len(x[i]) for x in [head] + body) for i in range(5)]
    lines = []
    for x in [head] + body:
        cells = [x[0].ljust(widths[0])] + [x[i].rjust(widths[i]) for i in range(1, 5)] + [x[5]]
        lines.append("  ".join(cells))
    return "\n".join(lines)


def _run(jobs, scheduler, workers, progress, out=sys.stdout):
    """Runs jobs [(name, output, function, args, kwargs)] (existing outputs skipped) and returns
    the rows in job order plus the wall time."""
    rows = {name: {"name": name, "output": output} for name, output, *_ in jobs}
    todo = []
    for name, output, fn, args, kwargs in jobs:
        if os.path.exists(output):
            rows[name].update(status="skipped", error=None)
            if output.endswith(".jsonl"):
                with open(output, "rb") as f:
                    rows[name]["frames"] = sum(1 for _ in f)
            if progress:
                print(f"skip {name}: {output} exists (finished earlier)", file=out, flush=True)
        else:
            todo.append((name, fn, args, kwargs))
    started = time.perf_counter()
    if todo:
        from distributed import as_completed

        client, cluster = _client(scheduler, workers)
        startup = time.perf_counter() - started
        started += startup  # the rate counts from the cluster's start, its start-up aside
        if progress:
            print(f"cluster: {len(client.scheduler_info()['workers'])} workers, started in "
                  f"{startup:.1f} s", file=out, flush=True)
        try:
            futures = {}
            run_id = uuid.uuid4().hex[:8]  # task keys unique on a shared scheduler
            for name, fn, args, kwargs in todo:
                fut = client.submit(fn, *args, **kwargs, key=f"dynahand-{name}-{run_id}",
                                    pure=False, retries=0)
                futures[fut] = name
            for done, fut in enumerate(as_completed(list(futures)), 1):
                name = futures[fut]
                row = rows[name]
                try:
                    row.update(fut.result(), status="ok", error=None)
                except Exception as e:  # the task's exception, re-raised here
                    msg = str(e).strip().splitlines()[0] if str(e).strip() else ""
                    row.update(status="failed", error=f"{type(e).__name__}: {msg}")
                if progress:
                    if row["status"] == "ok":
                        extra = f"{row['frames']} frames, {row['fps']:.1f} frames/s"
                        if row.get("mean_mm") is not None:
                            extra += f", mean error {row['mean_mm']:.2f} mm"
                        extra += f", {row['seconds']:.1f} s"
                    else:
                        extra = row["error"]
                    print(f"[{done}/{len(todo)}] {name}: {row['status']} ({extra})", file=out,
                          flush=True)
        finally:
            client.close()
            if cluster is not None:
                cluster.close()
    return [rows[name] for name, *_ in jobs], time.perf_counter() - started


def track_batch(inputs, out_dir, scheduler=None, workers=2, init="auto", detector=True, hands=1,
                hand_size=None, progress=True, summary=True, out=sys.stdout):
    """Tracks every sequence of `inputs` (paths and glob patterns), one Dask task each, into
    OUT_DIR/NAME.jsonl as `dynahand track SEQ --out NAME.jsonl` writes it (but `time_ms`).
    `scheduler`: None (a LocalCluster of `workers` processes, one thread each) or
    "tcp://HOST:PORT" (its workers must import dynahand and see the paths and OUT_DIR).
    Sequences whose output exists are skipped. Returns a list of dicts (name, output, status
    "ok" / "skipped" / "failed", error, frames, tracked, fps, mean_mm, seconds)."""
    if init not in ("auto", "gt"):
        raise ValueError(f"init must be 'auto' or 'gt', not {init!r}")
    paths = expand_inputs(inputs)
    if not paths:
        raise ValueError("no input sequence")
    out_dir = os.fspath(out_dir)
    os.makedirs(out_dir, exist_ok=True)
    jobs, names = [], {}
    for p in paths:
        name = output_name(p)
        if name in names:
            raise ValueError(f"{p} and {names[name]} would both write {name}.jsonl")
        names[name] = p
        output = os.path.abspath(os.path.join(out_dir, name + ".jsonl"))
        jobs.append((name, output, track_sequence, (os.path.abspath(p), output),
                     {"init": init, "detector": detector, "hands": hands,
                      "hand_size": hand_size}))
    rows, wall = _run(jobs, scheduler, workers, progress, out)
    if summary:
        _print_summary(rows, wall, out)
    return rows


def synth_batch(n, out_dir, motion="wave", frames=300, profile="tof", seed=1, format="sequence",
                options=(), scheduler=None, workers=2, exe=None, progress=True, summary=True,
                out=sys.stdout):
    """Writes `n` synthetic shards OUT_DIR/shard_0000 ... (format "sequence": `dynahand synth`
    folders; "npz": shard_0000.npz arrays for training), one Dask task each. Shard i uses
    motion[i % len(motion)] (a name or a list) and sensor noise seed `seed + i`; `options`:
    more `dynahand synth` flags (format "sequence"). Existing shards are skipped. Returns rows
    as track_batch does."""
    if n < 1:
        raise ValueError("n must be at least 1")
    if format not in ("sequence", "npz"):
        raise ValueError(f"format must be 'sequence' or 'npz', not {format!r}")
    motions = [motion] if isinstance(motion, str) else list(motion)
    try:
        import dynahand
    except ImportError:  # the shards' own dynahand synth says so
        dynahand = None
    if dynahand is not None:
        unknown = [m for m in motions if m not in dynahand.clips()]
        if unknown:
            raise ValueError(f"unknown clip {unknown[0]!r} (known: {', '.join(dynahand.clips())})")
    out_dir = os.fspath(out_dir)
    os.makedirs(out_dir, exist_ok=True)
    jobs = []
    for i in range(n):
        name = f"shard_{i:04d}"
        output = os.path.abspath(os.path.join(out_dir, name + (".npz" if format == "npz" else "")))
        kwargs = {"motion": motions[i % len(motions)], "frames": frames, "profile": profile,
                  "seed": seed + i, "fmt": format, "options": tuple(options), "exe": exe}
        jobs.append((name, output, synth_shard, (output,), kwargs))
    rows, wall = _run(jobs, scheduler, workers, progress, out)
    if summary:
        _print_summary(rows, wall, out)
    return rows


def _print_summary(rows, wall, out):
    print(summary_table(rows), file=out)
    ran = [r for r in rows if r["status"] == "ok"]
    frames = sum(r["frames"] for r in ran)
    failed = sum(r["status"] == "failed" for r in rows)
    skipped = sum(r["status"] == "skipped" for r in rows)
    rate = f", {frames / wall:.1f} frames/s" if ran and wall > 0 else ""
    cpu = sum(r.get("cpu_seconds") or 0.0 for r in ran)
    if cpu > 0:
        rate += f", {frames / cpu:.1f} frames per CPU-second"
    print(f"{len(ran)} done ({frames} frames in {wall:.1f} s{rate}), {skipped} skipped, "
          f"{failed} failed", file=out, flush=True)


# ---------------------------------------------------------------------------------------------
# The command line: `dynahand batch ...` runs main(sys.argv[1:])


def _parser():
    p = argparse.ArgumentParser(
        prog="dynahand batch",
        description="Track sequences or write synthetic shards as one Dask task each.")
    sub = p.add_subparsers(dest="command", required=True)

    def cluster_args(s):
        s.add_argument("--out", required=True, help="output folder")
        s.add_argument("--scheduler", help="a running Dask scheduler, tcp://HOST:PORT "
                       "(default: a local cluster)")
        s.add_argument("--workers", type=int, default=2,
                       help="local worker processes, one thread each (default 2)")
        s.add_argument("--quiet", action="store_true", help="no line per finished task")

    t = sub.add_parser("track", help="track sequences (paths or glob patterns) into OUT/NAME.jsonl",
                       epilog="example: dynahand batch track 'data/*/' --out poses/ --workers 2")
    t.add_argument("inputs", nargs="+", metavar="SEQUENCE_OR_GLOB")
    cluster_args(t)
    t.add_argument("--init", choices=["auto", "gt"], default="auto",
                   help="start: automatic (default) or from the ground truth, as dynahand track")
    t.add_argument("--no-detector", action="store_true", help="track without the detector")
    t.add_argument("--hands", type=int, choices=[1, 2], default=1)

    s = sub.add_parser("synth", help="write N synthetic shards OUT/shard_NNNN",
                       epilog="example: dynahand batch synth --count 8 --frames 150 --out synth/")
    s.add_argument("--count", type=int, required=True, help="number of shards")
    cluster_args(s)
    s.add_argument("--motion", default="wave",
                   help="clip, or clips separated by commas (shard i: clip i mod count)")
    s.add_argument("--frames", type=int, default=300)
    s.add_argument("--profile", default="tof")
    s.add_argument("--seed", type=int, default=1, help="shard i uses seed SEED+i")
    s.add_argument("--format", choices=["sequence", "npz"], default="sequence",
                   help="sequence: dynahand synth folders; npz: arrays for training")
    return p


def main(argv=None):
    """`dynahand batch`: exit 0 when every task succeeded, 1 when one failed, 2 usage."""
    args = _parser().parse_args(argv)
    if args.workers < 1:
        print("dynahand batch: --workers must be at least 1", file=sys.stderr)
        return 2
    try:
        import dask  # noqa: F401
        import distributed  # noqa: F401
    except ImportError as e:
        print(f"dynahand batch: Dask is missing ({e}); apt-get install python3-dask "
              "python3-distributed", file=sys.stderr)
        return 2
    try:
        import dynahand  # noqa: F401
    except ImportError as e:
        print(f"dynahand batch: the dynahand Python module is missing ({e}); build it "
              "(docs/python.md) or put its folder on PYTHONPATH", file=sys.stderr)
        return 2
    progress = not args.quiet
    try:
        if args.command == "track":
            rows = track_batch(args.inputs, args.out, scheduler=args.scheduler,
                               workers=args.workers, init=args.init,
                               detector=not args.no_detector, hands=args.hands,
                               progress=progress)
        else:
            if args.count < 1 or args.frames < 1:
                print("dynahand batch: --count and --frames must be at least 1", file=sys.stderr)
                return 2
            rows = synth_batch(args.count, args.out, motion=args.motion.split(","),
                               frames=args.frames, profile=args.profile, seed=args.seed,
                               format=args.format, scheduler=args.scheduler,
                               workers=args.workers, progress=progress)
    except ValueError as e:
        print(f"dynahand batch: {e}", file=sys.stderr)
        return 2
    return 1 if any(r["status"] == "failed" for r in rows) else 0


if __name__ == "__main__":
    # Run as `python3 -m dynahand_batch`: the tasks must be this module's functions (importable
    # on the workers), not __main__'s.
    import dynahand_batch

    sys.exit(dynahand_batch.main())
