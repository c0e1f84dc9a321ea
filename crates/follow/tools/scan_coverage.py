#!/usr/bin/env python3
"""How much of a real scan's seen surface a follow run modelled: the share of
the scan's points above the table (z > 15 mm) within 15 mm and within 30 mm of
a non-initial model polygon (the exact point-to-polygon distance: to the plane
where the point projects inside the polygon, else to its nearest edge). The
other direction of `scan_vertices.py`. Standard library only; reads the scan
with `scan_points.py`.

Usage: scan_coverage.py data/scenarios/mosd_boxes.toml RUN_DIR
"""
import json, math, os, sys
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import scan_points


def sub(a, b): return (a[0]-b[0], a[1]-b[1], a[2]-b[2])
def dot(a, b): return a[0]*b[0] + a[1]*b[1] + a[2]*b[2]
def cross(a, b): return (a[1]*b[2]-a[2]*b[1], a[2]*b[0]-a[0]*b[2], a[0]*b[1]-a[1]*b[0])
def unit(a):
    n = math.sqrt(dot(a, a)); return (a[0]/n, a[1]/n, a[2]/n)


def polygon(vertices):
    """Origin, in-plane axes, normal, the 2-D outline and the bounding sphere."""
    n = [0.0, 0.0, 0.0]
    for i, a in enumerate(vertices):
        b = vertices[(i+1) % len(vertices)]
        n[0] += (a[1]-b[1])*(a[2]+b[2]); n[1] += (a[2]-b[2])*(a[0]+b[0]); n[2] += (a[0]-b[0])*(a[1]+b[1])
    n = unit(n); o = vertices[0]
    e1 = unit(sub(vertices[1], o)); e2 = cross(n, e1)
    outline = [(dot(sub(v, o), e1), dot(sub(v, o), e2)) for v in vertices]
    c = tuple(sum(v[i] for v in vertices)/len(vertices) for i in range(3))
    r = max(math.sqrt(dot(sub(v, c), sub(v, c))) for v in vertices)
    return o, e1, e2, n, outline, c, r


def distance(p, poly):
    o, e1, e2, n, outline, _, _ = poly
    d = sub(p, o); x, y, h = dot(d, e1), dot(d, e2), dot(d, n)
    inside = False; best = float('inf')
    for i, (x1, y1) in enumerate(outline):
        x2, y2 = outline[(i+1) % len(outline)]
        if (y1 > y) != (y2 > y) and x < x1 + (y-y1)*(x2-x1)/(y2-y1):
            inside = not inside
        ex, ey = x2-x1, y2-y1; t = ((x-x1)*ex + (y-y1)*ey) / (ex*ex + ey*ey or 1.0)
        t = min(1.0, max(0.0, t)); best = min(best, (x-x1-t*ex)**2 + (y-y1-t*ey)**2)
    return abs(h) if inside else math.sqrt(best + h*h)


points = [q for q in scan_points.load(sys.argv[1]) if q[2] > 0.015]
m = json.load(open(sys.argv[2] + '/surface_model.json'))
polys = [polygon(s['vertices']) for s in m['segments'] if s['kind'] == 'polygon' and not s.get('initial')]
within = {0.015: 0, 0.03: 0}
for p in points:
    d = float('inf')
    for poly in polys:
        c, r = poly[5], poly[6]
        if math.sqrt(dot(sub(p, c), sub(p, c))) - r < min(d, 0.03):
            d = min(d, distance(p, poly))
    for k in within:
        within[k] += d <= k
print('%s: %d scan points above the table, %.1f %% within 15 mm of the model, %.1f %% within 30 mm (%d polygons)' % (
    os.path.basename(sys.argv[1]), len(points), 100*within[0.015]/len(points), 100*within[0.03]/len(points), len(polys)))
