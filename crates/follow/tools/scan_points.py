"""A scenario's real scan in its world frame (the follow tools' shared reader):
the scenario's binary_compressed PCD (pure Python LZF), placed by the
scenario's pose (rpy as Rz·Ry·Rx; the table then lies at z = 0). Standard
library only.
"""
import math, os, re, struct


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


def load(scenario_path):
    """The scan's points (x, y, z tuples, world frame), NaNs left out."""
    scen = open(scenario_path).read()
    pcd = os.path.normpath(os.path.join(os.path.dirname(scenario_path), re.search(r'file = "([^"]+)"', scen)[1]))
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
    return pts


def grid(points, cell):
    """The points hashed into cubic cells `cell` wide."""
    g = {}
    for q in points:
        g.setdefault((int(math.floor(q[0]/cell)), int(math.floor(q[1]/cell)), int(math.floor(q[2]/cell))), []).append(q)
    return g


def nearest(g, cell, v):
    """Distance from v to the nearest point of grid g within one cell (1.0 beyond)."""
    key = tuple(int(math.floor(v[i]/cell)) for i in range(3)); best = 1.0
    for dx in (-1, 0, 1):
        for dy in (-1, 0, 1):
            for dz in (-1, 0, 1):
                for q in g.get((key[0]+dx, key[1]+dy, key[2]+dz), ()):
                    d = (q[0]-v[0])**2 + (q[1]-v[1])**2 + (q[2]-v[2])**2
                    if d < best: best = d
    return math.sqrt(best)
