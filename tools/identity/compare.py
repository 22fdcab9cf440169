#!/usr/bin/env python3
"""compare.py REF NEW [HASHES]: compare two output folders of run.sh file by file, bytes
except timing: JSON keys t_* and timings_s (and the Pareto front, which ranks by time), CSV
time columns, the stability table's time rows and column, "N.NN s" in logs, log lines' time
stamps and module paths, the sweep page's time column and Pareto marks, and the
accuracy_vs_time chart. NEW's absolute path is read as REF's. HASHES: write the sha256 of
every compared file of REF (as compared) there. Exit status 1 when anything differs."""
import sys, os, json, csv, io, hashlib
ref, new = sys.argv[1], sys.argv[2]
TIMING_KEYS = {"timings_s", "pareto", "pareto_front", "wall_s", "elapsed_s", "seconds"}
def strip(v):
    if isinstance(v, dict):
        return {k: strip(x) for k, x in v.items() if k not in TIMING_KEYS and not k.startswith("t_")}
    if isinstance(v, list):
        return [strip(x) for x in v]
    return v
import re
def norm(path):
    b = open(path, 'rb').read()
    if path.startswith(new):
        b = b.replace(os.path.abspath(new).encode(), os.path.abspath(ref).encode())
    if path.endswith(('.stdout', '.stderr', '.md')):
        b = re.sub(rb'\d+\.\d+ s\b', b'T s', b)
    if path.endswith('.stderr'):
        # Log lines: their time stamps, and the module path of their origin (which crate
        # holds a file is a refactor's business, not the output's).
        b = re.sub(rb'^\d{4}-\d\d-\d\dT[0-9:.]+Z +', b'', b, flags=re.M)
        b = re.sub(rb'^(WARN|INFO|ERROR|DEBUG) [a-z_:]+: ', rb'\1 ', b, flags=re.M)
    n = os.path.basename(path)
    if n == 'log':
        return None
    if 'accuracy_vs_time' in n:
        return None
    if n == 'index.html' and os.path.exists(os.path.join(os.path.dirname(path), 'results.csv')):
        # The sweep's page: its time column and the Pareto front (ranked by time).
        b = re.sub(rb'<td>[0-9.]+ (ms|s)</td>', b'<td>T</td>', b)
        b = b.replace(b'<td>Pareto front</td>', b'<td></td>')
    if n.endswith('.json'):
        try:
            return json.dumps(strip(json.loads(b)), sort_keys=True).encode()
        except Exception:
            return b
    if n == 'stability.csv':
        rows = list(csv.reader(io.StringIO(b.decode())))
        q = rows[0].index('quantity')
        return '\n'.join(','.join(r) for r in rows if not r[q].startswith('t_')).encode()
    if n == 'stability.md':
        # the last column of the table is the build time in seconds
        out = []
        for line in b.decode().split('\n'):
            if line.startswith('|'):
                cells = line.split('|')
                line = '|'.join(cells[:-2])
            out.append(line)
        return '\n'.join(out).encode()
    if n.endswith('.csv'):
        rows = list(csv.reader(io.StringIO(b.decode())))
        if rows:
            keep = [i for i, h in enumerate(rows[0]) if not (h.startswith('t_') or h.endswith('_s') or 'time' in h)]
            return '\n'.join(','.join(r[i] for i in keep if i < len(r)) for r in rows).encode()
    return b
def files(d):
    out = {}
    for dp, dn, fn in os.walk(d):
        for f in fn:
            p = os.path.join(dp, f); out[os.path.relpath(p, d)] = p
    return out
a, b = files(ref), files(new)
bad = 0; same = 0
for k in sorted(set(a) | set(b)):
    if k not in a or k not in b:
        print("ONLY IN", "ref" if k in a else "new", k); bad += 1; continue
    x, y = norm(a[k]), norm(b[k])
    if x is None: continue
    if x != y:
        print("DIFF", k); bad += 1
    else:
        same += 1
print(f"{same} files identical, {bad} differ")
if len(sys.argv) > 3:
    with open(sys.argv[3], 'w') as h:
        for k in sorted(a):
            x = norm(a[k])
            if x is not None:
                h.write(f"{hashlib.sha256(x).hexdigest()}  {k}\n")
sys.exit(1 if bad else 0)
