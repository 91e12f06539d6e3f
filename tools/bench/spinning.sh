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
# With REUSE_TILES=1 the work folder's tiles are kept (only the outputs and the stitched parts
# are removed): the final pass alone runs again, 10-14 s on the 30 m street, for throw-away
# switches read from the environment in one build. The same build and config only: a rebuild
# makes the tiles again (the build is in their fingerprint), and `run` refuses a work folder
# done with another config.
set -euo pipefail
cd "$(dirname "$0")/../.."
dir="${1:-/tmp/citymesh-spinning}"
length="${2:-30}"
shift $(( $# < 2 ? $# : 2 ))
bin="$PWD/build/release/citymesh"
[ -f "$dir/config.toml" ] || "$bin" simulate --out "$dir" --scanner spinning --length "$length" >/dev/null
cd "$dir"
if [ "${REUSE_TILES:-0}" = 1 ]; then rm -rf out work/seam-cache; else rm -rf work out; fi
/usr/bin/time -v "$bin" run config.toml --no-pictures "$@" 2>time.log | tail -1
grep -E "Elapsed|Maximum resident" time.log | sed 's/^\s*/  /'
grep -E "^warning: the tiles took" time.log | cut -c1-100 || true
python3 - <<'PY'
import json
run = json.load(open("out/run.json"))
largest = max(run["per_tile"], key=lambda t: t["triangles"])
if largest.get("reused"):
    print(f"  largest tile {largest['tile']}: reused; final pass {run['seconds']['total']:.1f} s")
else:
    s = largest["seconds"]
    print(f"  largest tile {largest['tile']}: {largest['triangles']} triangles with its halo, "
          f"read {s['read']:.1f} s, detect {s['detect']:.1f} s, mosaic {s['mosaic']:.1f} s")
PY
echo "  mosaic.ply md5 $(md5sum out/mosaic/mosaic.ply | cut -c1-8)"
"$bin" eval out --truth . | sed -n '/^mosaic (energy)/,$p'
