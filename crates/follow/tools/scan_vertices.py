#!/usr/bin/env python3
"""Share of a follow run's model polygon vertices within λ of a real scan (issue 45
acceptance 6; run.json scores polygons by samples, not vertices). Reads the
scan with `scan_points.py` and measures each vertex's
distance to the nearest scan point. Standard library only.

Usage: scan_vertices.py data/scenarios/mosd_boxes.toml RUN_DIR
"""
import json, math, os, sys
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import scan_points

pts = scan_points.load(sys.argv[1])
L = 0.05
grid = scan_points.grid(pts, L)
m = json.load(open(sys.argv[2] + '/surface_model.json'))
tot = within = 0; worst = 0; per = []
for s in m['segments']:
    if s['kind'] != 'polygon' or s.get('initial'): continue
    w = 0
    for v in s['vertices']:
        best = scan_points.nearest(grid, L, v); worst = max(worst, best)
        tot += 1
        if best < L: within += 1; w += 1
    per.append((s['id'], len(s['vertices']), w))
zt = sorted(q[2] for q in pts)
print('%s: %d scan points (median z %.3f), %d of %d vertices within λ (%.1f %%), worst vertex %.1f mm; per polygon (id, vertices, within): %s' % (os.path.basename(sys.argv[1]), len(pts), zt[len(zt)//2], within, tot, 100*within/tot, 1000*worst, per))
