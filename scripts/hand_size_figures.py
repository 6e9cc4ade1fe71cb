#!/usr/bin/env python3
"""The hand-size estimate's figures in docs/tracker.md ("Hand size"), through the command:
for the bench's small / medium / large hands and three clips (tof), the size
`dynahand track --hand-size auto` estimates against the truth, and the mean 21-keypoint error
tracked with the default model and with the estimated one.

usage: scripts/hand_size_figures.py [--init gt|auto] [--placement desk|head] [--frames 90]
                                    [--dynahand PATH] [--work DIR]
"""
import argparse
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


if __name__ == '__main__':
    main()
