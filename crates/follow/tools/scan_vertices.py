#!/usr/bin/env python3
"""Share of a follow run's model polygon vertices within λ of a real scan (issue 45
acceptance 6; run.json scores polygons by samples, not vertices). Reads the
scenario's binary_compressed PCD (pure Python LZF), places it by the scenario's
pose (rpy as Rz·Ry·Rx; the table then lies at z = 0), and measures each vertex's
distance to the nearest scan point. Standard library only.

Usage: scan_vertices.py data/scenarios/mosd_boxes.toml RUN_DIR
"""
import sys, struct, math, json, re, os
def lzf(data, outlen):
    out = bytearray(); i = 0; n = len(data)
    while i < n:
        c = data[i]; i += 1
        if c < 32:
            l = c + 1; out += data[i:i+l]; i += l
        else:
            l = c >> 5
            if l == 7: l += data[i]; i += 1
            ref = len(out) - ((c & 0x1f) << 8) - data[i] - 1; i += 1
            for k in range(l + 2): out.append(out[ref + k])
    assert len(out) == outlen, (len(out), outlen)
    return bytes(out)
scen = open(sys.argv[1]).read()
pcd = os.path.normpath(os.path.join(os.path.dirname(sys.argv[1]), re.search(r'file = "([^"]+)"', scen)[1]))
tr = [float(x) for x in re.search(r'translation = \[([^\]]+)\]', scen)[1].split(',')]
rpy = [math.radians(float(x)) for x in re.search(r'rpy_deg = \[([^\]]+)\]', scen)[1].split(',')]
raw = open(pcd, 'rb').read()
hdr_end = raw.index(b'DATA binary_compressed\n') + len(b'DATA binary_compressed\n')
hdr = raw[:hdr_end].decode()
npts = int(re.search(r'POINTS (\d+)', hdr)[1])
fields = re.search(r'FIELDS (.*)', hdr)[1].split()
csize, usize = struct.unpack('<II', raw[hdr_end:hdr_end+8])
data = lzf(raw[hdr_end+8:hdr_end+8+csize], usize)
cols = {}
for k, f in enumerate(fields):
    cols[f] = data[k*4*npts:(k+1)*4*npts]
xs = struct.unpack('<%df' % npts, cols['x']); ys = struct.unpack('<%df' % npts, cols['y']); zs = struct.unpack('<%df' % npts, cols['z'])
r, p, y = rpy
cr, sr, cp, sp, cy, sy = math.cos(r), math.sin(r), math.cos(p), math.sin(p), math.cos(y), math.sin(y)
R = [[cy*cp, cy*sp*sr - sy*cr, cy*sp*cr + sy*sr], [sy*cp, sy*sp*sr + cy*cr, sy*sp*cr - cy*sr], [-sp, cp*sr, cp*cr]]
pts = []
for a, b, c in zip(xs, ys, zs):
    if a != a or b != b or c != c: continue
    pts.append(tuple(R[i][0]*a + R[i][1]*b + R[i][2]*c + tr[i] for i in range(3)))
# grid of λ cells
L = 0.05; grid = {}
for q in pts:
    grid.setdefault((int(math.floor(q[0]/L)), int(math.floor(q[1]/L)), int(math.floor(q[2]/L))), []).append(q)
m = json.load(open(sys.argv[2] + '/surface_model.json'))
tot = within = 0; worst = 0; per = []
for s in m['segments']:
    if s['kind'] != 'polygon' or s.get('initial'): continue
    w = 0
    for v in s['vertices']:
        key = tuple(int(math.floor(v[i]/L)) for i in range(3)); best = 1e9
        for dx in (-1,0,1):
            for dy in (-1,0,1):
                for dz in (-1,0,1):
                    for q in grid.get((key[0]+dx, key[1]+dy, key[2]+dz), ()):
                        d = (q[0]-v[0])**2 + (q[1]-v[1])**2 + (q[2]-v[2])**2
                        if d < best: best = d
        best = math.sqrt(best); worst = max(worst, min(best, 1.0))
        tot += 1
        if best < L: within += 1; w += 1
    per.append((s['id'], len(s['vertices']), w))
zt = sorted(q[2] for q in pts)
print('%s: %d scan points (median z %.3f), %d of %d vertices within λ (%.1f %%), worst vertex %.1f mm; per polygon (id, vertices, within): %s' % (os.path.basename(sys.argv[1]), len(pts), zt[len(zt)//2], within, tot, 100*within/tot, 1000*worst, per))
