#!/usr/bin/env python3
"""Reads frond sweep results.csv files and compares methods at matched billboard counts: for
every run of a spectral method, the static and per-bone curves (animated colour metric and
dominating-axis metric against billboards, interpolated linearly in log(billboards) between
their grid points) are read at that run's billboard count. Prints a Markdown table."""
import csv, math, sys

def curve(rows, method, key):
    pts = sorted((float(r['billboards']), float(r[key])) for r in rows
                 if r['method'] == method and r['status'] == 'ok')
    return pts

def at(pts, b):
    if not pts or b < pts[0][0] or b > pts[-1][0]:
        return None
    for (b0, y0), (b1, y1) in zip(pts, pts[1:]):
        if b0 <= b <= b1:
            if b1 == b0:
                return y0
            t = (math.log(b) - math.log(b0)) / (math.log(b1) - math.log(b0))
            return y0 + t * (y1 - y0)
    return pts[-1][1] if b == pts[-1][0] else None

def fmt(v):
    return '–' if v is None else f'{v:.3f}'

print('| tree | method | ε % | billboards | colour | static @ same | per-bone @ same | dom. axis | static @ same | per-bone @ same |')
print('|---|---|---|---|---|---|---|---|---|---|')
for path in sys.argv[1:]:
    rows = list(csv.DictReader(open(path)))
    tree = path.rstrip('/').split('/')[-2].split('_', 1)[-1]
    curves = {(m, k): curve(rows, m, k) for m in ('static', 'per-bone')
              for k in ('coverage_animated', 'dominating_axis')}
    for r in rows:
        if not r['method'].startswith('spectral') or r['status'] != 'ok':
            continue
        b = float(r['billboards'])
        print(f"| {tree} | {r['method'][9:]} | {float(r['epsilon_pct']):.1f} | {int(b)} | "
              f"{float(r['coverage_animated']):.3f} | {fmt(at(curves[('static','coverage_animated')], b))} | "
              f"{fmt(at(curves[('per-bone','coverage_animated')], b))} | {float(r['dominating_axis']):.3f} | "
              f"{fmt(at(curves[('static','dominating_axis')], b))} | {fmt(at(curves[('per-bone','dominating_axis')], b))} |")
