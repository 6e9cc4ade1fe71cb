#!/usr/bin/env python3
"""The hand-size estimate's figures in docs/tracker.md ("Hand size"), through the command:
for the bench's small / medium / large hands and three clips (tof), the size
`dynahand track --hand-size auto` estimates against the truth, and the mean 21-keypoint error
tracked with the default model and with the estimated one.

With --shapes: medium hands shaped unlike the model (`dynahand synth --proportion-spread 0.15
--proportion-seed S`, clips at 2.5x as in the motion suite), the metacarpal factors
`--hand-size auto` estimates against the truth (root mean square over the five digits; the
default shape's alongside), and the keypoint error with the size alone (`--hand-size-only`)
and with the metacarpals.

usage: scripts/hand_size_figures.py [--init gt|auto] [--placement desk|head] [--frames 90]
                                    [--shapes [--seeds 3,4,5,6] [--clips wave,open-close,...]]
                                    [--dynahand PATH] [--work DIR]
"""
import argparse
import json
import math
import os
import re
import subprocess

SIZES = [('small', 0.165, 0.075), ('medium', 0.19, 0.085), ('large', 0.215, 0.095)]
CLIPS = ['wave', 'open-close', 'pinch']


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    p = argparse.ArgumentParser()
    p.add_argument('--init', default='gt', choices=['gt', 'auto'])
    p.add_argument('--placement', default='desk', choices=['desk', 'head'],
                   help='camera facing the user, or worn on the head (forearm toward it)')
    p.add_argument('--frames', type=int, default=90)
    p.add_argument('--dynahand', default=os.path.join(here, '..', 'build', 'release', 'apps', 'dynahand'))
    p.add_argument('--work', default='/tmp/dynahand-hand-size')
    p.add_argument('--shapes', action='store_true',
                   help='hands shaped unlike the model: the metacarpal estimate')
    p.add_argument('--seeds', default='3,4,5,6', help='--shapes: proportion seeds')
    p.add_argument('--clips', default='open-close,count,pinch,wave', help='--shapes: clips')
    a = p.parse_args()
    os.makedirs(a.work, exist_ok=True)

    def run(args):
        r = subprocess.run([a.dynahand] + args, capture_output=True, text=True)
        if r.returncode != 0:
            raise SystemExit(f'dynahand {" ".join(args)}: exit {r.returncode}: {r.stderr.strip()}')
        return r.stdout

    def keypoint_error(out):
        m = re.search(r'21-keypoint error vs ground truth  mean ([\d.]+) mm', out)
        return float(m.group(1)) if m else float('nan')

    if a.shapes:
        shapes(a, run, keypoint_error)
        return
    print('| hand | clip | estimated length (error) | estimated width (error) | fit | estimate s '
          '| keypoints, default model (mm) | keypoints, estimated (mm) |')
    print('| --- | --- | ---: | ---: | ---: | ---: | ---: | ---: |')
    for name, length, width in SIZES:
        for clip in CLIPS:
            clip_dir = os.path.join(a.work, f'{name}-{clip}-{a.placement}-{a.frames}')
            if not os.path.isdir(clip_dir):
                run(['synth', '--motion', clip, '--profile', 'tof', '--frames', str(a.frames),
                     '--placement', a.placement, '--hand-length', str(length),
                     '--hand-width', str(width), '--out', clip_dir])
            default = keypoint_error(run(['track', clip_dir, '--init', a.init]))
            out = run(['track', clip_dir, '--init', a.init, '--hand-size', 'auto'])
            m = re.search(r'hand size estimate: length ([\d.]+) m  width ([\d.]+) m .*fit ([\d.]+), '
                          r'([\d.]+) s', out)
            el, ew, fit, seconds = map(float, m.groups())
            print(f'| {name} {length:.3f} x {width:.3f} | {clip} | {el:.4f} ({100 * (el / length - 1):+.1f} %) '
                  f'| {ew:.4f} ({100 * (ew / width - 1):+.1f} %) | {fit:.3f} | {seconds:.1f} '
                  f'| {default:.2f} | {keypoint_error(out):.2f} |', flush=True)


def shapes(a, run, keypoint_error):
    def rms(values):
        return math.sqrt(sum(v * v for v in values) / len(values))

    print('| clip | seed | true metacarpals | estimated | factor rms error (default shape) '
          '| keypoints, size alone (mm) | keypoints, with metacarpals (mm) |')
    print('| --- | --- | --- | --- | ---: | ---: | ---: |')
    rows = []
    for seed in a.seeds.split(','):
        for clip in a.clips.split(','):
            clip_dir = os.path.join(a.work, f'shape-{clip}-{seed}-{a.placement}-{a.frames}')
            if not os.path.isdir(clip_dir):
                run(['synth', '--motion', clip, '--profile', 'tof', '--frames', str(a.frames),
                     '--speed', '2.5', '--placement', a.placement, '--proportion-spread', '0.15',
                     '--proportion-seed', seed, '--out', clip_dir])
            with open(os.path.join(clip_dir, 'synth.json')) as f:
                truth = [b[0] for b in json.load(f)['proportions']['bone_length']]
            track = ['track', clip_dir, '--init', a.init, '--hand-size', 'auto']
            size_only = keypoint_error(run(track + ['--hand-size-only']))
            out = run(track)
            m = re.search(r'hand shape estimate: metacarpals \(thumb..pinky\) ([\d. ]+)', out)
            estimated = [float(v) for v in m.group(1).split()] if m else [1.0] * 5
            error = rms([e - t for e, t in zip(estimated, truth)])
            default = rms([1 - t for t in truth])
            shaped = keypoint_error(out)
            rows.append((error, default, size_only, shaped))
            print(f'| {clip} | {seed} | {" ".join(f"{t:.2f}" for t in truth)} '
                  f'| {" ".join(f"{e:.2f}" for e in estimated)} | {error:.3f} ({default:.3f}) '
                  f'| {size_only:.2f} | {shaped:.2f} |', flush=True)
    mean = [sum(r[i] for r in rows) / len(rows) for i in range(4)]
    worse = sum(1 for r in rows if r[3] > r[2] + 0.05)
    print(f'| mean of {len(rows)} | | | | {mean[0]:.3f} ({mean[1]:.3f}) | {mean[2]:.2f} '
          f'| {mean[3]:.2f} ({worse} worse by more than 0.05) |')


if __name__ == '__main__':
    main()
