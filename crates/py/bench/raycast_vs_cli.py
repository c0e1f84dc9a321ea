"""Time ``Scene.raycast`` on the 1 M-ray fixture against ``surveyor raycast``."""
import argparse, re, statistics, subprocess, sys, tempfile, time
from pathlib import Path
import numpy as np
import surveyor

p = argparse.ArgumentParser(description=__doc__)
p.add_argument("--surveyor", default="target/release/surveyor")
p.add_argument("--rounds", type=int, default=5)
a = p.parse_args()
with tempfile.TemporaryDirectory() as tmp:
    fx = Path(tmp)
    subprocess.run([a.surveyor, "raycast-fixture", "--out", str(fx)], check=True, capture_output=True)
    rays = np.fromfile(fx / "rays.bin", dtype="<f4").reshape(-1, 6).astype(np.float64)
    origins, directions = np.ascontiguousarray(rays[:, :3]), np.ascontiguousarray(rays[:, 3:])
    scene = surveyor.Scene.from_file(fx / "structure.ply")
    ratios = []
    for r in range(a.rounds):
        times = []
        for _ in range(5):
            t = time.perf_counter()
            distances, faces = scene.raycast(origins, directions)
            times.append(time.perf_counter() - t)
        py = statistics.median(times)
        out = subprocess.run([a.surveyor, "raycast", "--scene", str(fx / "structure.ply"), "--rays", str(fx / "rays.bin"), "--out", str(fx / "d.bin")], check=True, capture_output=True, text=True).stdout
        mrays = float(re.search(r"([0-9.]+) Mrays/s", out).group(1))
        cli = len(rays) / (mrays * 1e6)
        ratios.append(py / cli)
        print(f"round {r}: Python {py * 1e3:.1f} ms, CLI {cli * 1e3:.1f} ms, ratio {py / cli:.2f}")
    same = np.array_equal(np.fromfile(fx / "d.bin", dtype="<f4").astype(np.float64), distances)
    print(f"median ratio {statistics.median(ratios):.2f} over {a.rounds} rounds; distances identical: {same}")
