#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Spinning-scanner benchmark: a simulated street driven by a multi-beam sensor whose turns are
# meshed one by one (each pass holds several overlapping layers, 12 overlap terms per mosaic
# candidate against ~3 on a profiler street), run end to end on 2 threads with the default
# 2 GiB budget, then scored. Prints the run's time and peak RSS, the largest tile's split
# (read, detect, mosaic), the mosaic's md5 (the same bytes on any thread count and across
# speed-only changes) and `citymesh eval`'s mosaic scores (the layered ratio among them).
# Usage: tools/bench/spinning.sh [work folder (default /tmp/citymesh-spinning)] [length in
# metres (default 30, at least 30)] [more `citymesh run` arguments, e.g.
# --set mosaic.stitch_own_pieces=true]
set -euo pipefail
cd "$(dirname "$0")/../.."
dir="${1:-/tmp/citymesh-spinning}"
length="${2:-30}"
shift $(( $# < 2 ? $# : 2 ))
bin="$PWD/build/release/citymesh"
[ -f "$dir/config.toml" ] || "$bin" simulate --out "$dir" --scanner spinning --length "$length" >/dev/null
cd "$dir"
rm -rf work out
/usr/bin/time -v "$bin" run config.toml --no-pictures "$@" 2>time.log | tail -1
grep -E "Elapsed|Maximum resident" time.log | sed 's/^\s*/  /'
grep -E "^warning: the tiles took" time.log | cut -c1-100 || true
python3 - <<'PY'
import json
run = json.load(open("out/run.json"))
largest = max(run["per_tile"], key=lambda t: t["triangles"])
s = largest["seconds"]
print(f"  largest tile {largest['tile']}: {largest['triangles']} triangles with its halo, "
      f"read {s['read']:.1f} s, detect {s['detect']:.1f} s, mosaic {s['mosaic']:.1f} s")
PY
echo "  mosaic.ply md5 $(md5sum out/mosaic/mosaic.ply | cut -c1-8)"
"$bin" eval out --truth . | sed -n '/^mosaic (energy)/,$p'
