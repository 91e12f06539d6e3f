#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Real-data benchmark: the three Ouster OS-1-128 frames of ../shared/data/real/ (0.1 s apart,
# a static scene) meshed, then the change step untiled on 1 and 2 threads and a whole run on
# 2 threads. Their empty spaces are long (returns up to 60 m), unlike the simulated streets',
# and the sensor stands where four 50 m tiles meet, so each of those tiles holds every
# triangle (owned, halo or empty-space copy). Prints the change step's stages and the run's.
# Skips (exit 0) when the data is absent. Usage: tools/bench/ouster.sh [work folder (default
# /tmp/citymesh-ouster)] [data folder (default ../shared/data/real/ouster_os1_128_walk3)]
set -euo pipefail
cd "$(dirname "$0")/../.."
dir="${1:-/tmp/citymesh-ouster}"
data="${2:-$PWD/../shared/data/real/ouster_os1_128_walk3}"
bin="$PWD/build/release/citymesh"
if [ ! -f "$data/ouster_os1_128_frame1795.ply" ]; then
  echo "no Ouster frames in $data: skipped"
  exit 0
fi
mkdir -p "$dir"
for f in 1795 1796 1797; do
  [ -f "$dir/f$f.ply" ] || "$bin" mesh "$data/ouster_os1_128_frame$f.ply" --out "$dir/f$f.ply" >/dev/null
done
cat >"$dir/ouster.toml" <<'TOML'
# Three frames of a walk, 0.1 s apart: written by tools/bench/ouster.sh.
[project]
crs = "ENU:48.8566,2.3522,35"
vertical_datum = "ellipsoidal"
output = "out"
work = "work"

[change]
sustainability = "0.15s"

[[acquisition]]
path = "f1795.ply"
time = "2026-01-01T00:00:00.0Z"

[[acquisition]]
path = "f1796.ply"
time = "2026-01-01T00:00:00.1Z"

[[acquisition]]
path = "f1797.ply"
time = "2026-01-01T00:00:00.2Z"
TOML
for threads in 1 2; do
  echo "== detect, untiled, $threads thread(s)"
  "$bin" detect "$dir/ouster.toml" --no-pictures --threads "$threads" --set project.output=out-untiled 2>/dev/null |
    tail -2
done
echo "== run, 2 threads"
rm -rf "$dir/work" "$dir/out"
"$bin" run "$dir/ouster.toml" --no-pictures --threads 2 2>/dev/null | tail -1
python3 - "$dir/out/run.json" "$dir/out/detect/summary.json" "$dir/out-untiled/detect/summary.json" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
print("  stages (s): " + ", ".join(f"{k} {v:.2f}" for k, v in r["seconds"].items()))
for t in r["per_tile"]:
    if t["triangles"] > 1000:
        s = t["seconds"]
        print(f"  tile {t['tile']}: {t['owned']} owned of {t['triangles']}, detect {s['detect']:.2f} s, mosaic {s['mosaic']:.2f} s")
# Tiled against untiled labels: the counts per acquisition (they differ by the tile frame's
# rounding only, a few triangles).
tiled, untiled = (json.load(open(p))["acquisitions"] for p in sys.argv[2:4])
for a, b in zip(tiled, untiled):
    print(f"  {a['name']}: tiled - untiled: " +
          ", ".join(f"{k} {a['counts'][k] - b['counts'][k]:+d}" for k in ("consistent", "conflicting", "kept", "refutes")))
PY
