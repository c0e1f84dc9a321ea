#!/usr/bin/env bash
# point3 over the three mOSD scans from shifted starts and under range noise
# (issue 45 acceptance 6): for each scan, the scenario's start, the start moved
# 3 cm in +x, -x, +y and 5 cm up, and noise sigma = 5 mm with seeds 1-3. Prints
# each run's sets, end and scan clearance, then how many kept 35 and 20 mm.
#
# Usage: scan_robustness.sh OUT_DIR [CONFIG.toml]
# CONFIG replaces the scenarios' own [follow] table (surveyor follow --config);
# without it each scenario's own parameters are used. SURVEYOR_BIN overrides
# the binary (default target/release/surveyor).
set -euo pipefail
root="$(cd "$(dirname "$0")/../../.." && pwd)"
bin="${SURVEYOR_BIN:-$root/target/release/surveyor}"
out="$1"
config=()
[ $# -ge 2 ] && config=(--config "$2")
mkdir -p "$out"
for f in mosd_boxes mosd_learn5 mosd_learn17; do
  scenario="$root/data/scenarios/$f.toml"
  read -r x y z < <(sed -n 's/^start_joints = \[\(.*\)\]/\1/p' "$scenario" | tr -d ',')
  shifted() { python3 -c "print('%.4f,%.4f,%.4f' % ($x + $1, $y + $2, $z + $3))"; }
  variants=("" "--start $(shifted 0.03 0 0)" "--start $(shifted -0.03 0 0)"
    "--start $(shifted 0 0.03 0)" "--start $(shifted 0 0 0.05)"
    "--noise-m 0.005 --seed 1" "--noise-m 0.005 --seed 2" "--noise-m 0.005 --seed 3")
  for k in "${!variants[@]}"; do
    dir="$out/$f-$k"
    # shellcheck disable=SC2086 # the variant is a list of arguments
    "$bin" follow --scenario "$scenario" --no-timings ${config[@]+"${config[@]}"} ${variants[$k]} --out "$dir" >/dev/null
    python3 -c '
import json, sys
r = json.load(open(sys.argv[1] + "/run.json"))
print("%-14s %-36s %5d sets  %-16s %5.1f mm" % (sys.argv[2], sys.argv[3] or "(scenario start)", r["sets"], r["termination"], 1000 * r["min_scan_clearance_m"]))
' "$dir" "$f" "${variants[$k]}"
  done
done
python3 -c '
import glob, json, statistics, sys
c = [1000 * json.load(open(d))["min_scan_clearance_m"] for d in glob.glob(sys.argv[1] + "/*/run.json")]
print("%d runs: %d keep 35 mm, %d keep 20 mm; least %.1f mm, median %.1f mm" % (len(c), sum(x >= 35 for x in c), sum(x >= 20 for x in c), min(c), statistics.median(c)))
' "$out"
