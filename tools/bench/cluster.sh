#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Cluster benchmark (issue 8): the simulated city run end to end under mpirun with 1 and then
# 2 ranks of 1 thread each (on this 2-core machine: one core per rank), from an empty work
# folder each time (tiling included), 2 GiB memory budget per rank. Prints per rank count: wall
# time, input triangles/s, the stages' seconds from run.json, then whether both runs wrote
# the same bytes. Per-core throughput (1 rank) feeds the estimate in docs/cluster.md.
# Usage: tools/bench/cluster.sh [folder (default /tmp/citymesh-city)] [streets (default 6)]
set -euo pipefail
cd "$(dirname "$0")/../.."
dir="${1:-/tmp/citymesh-city}"
streets="${2:-6}"
bin="$PWD/build/release/citymesh"
[ -f "$dir/config.toml" ] || "$bin" simulate --out "$dir" --streets "$streets" --length 500 >/dev/null
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1  # CI containers run as root
for ranks in 1 2; do
  rm -rf "$dir/work-r$ranks" "$dir/out-r$ranks"
  echo "== $ranks rank(s), 1 thread each"
  /usr/bin/time -f "  wall %e s, mpirun peak RSS %M KiB" \
    mpirun --oversubscribe --bind-to none -n "$ranks" "$bin" run "$dir/config.toml" --no-pictures --threads 1 \
    --memory 2GiB --set output.labels=false --set project.work="work-r$ranks" --set project.output="out-r$ranks" \
    2>"$dir/cluster-r$ranks.log" | tail -1
  tail -1 "$dir/cluster-r$ranks.log"
  python3 - "$dir/out-r$ranks/run.json" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
s = r["seconds"]
print("  stages (s): " + ", ".join(f"{k} {v:.1f}" for k, v in s.items()))
print(f"  {r['input_triangles']/1e6:.2f} M input triangles, {r['triangles_per_second']/1e6:.3f} M triangles/s, "
      f"rank 0 peak RSS {r['peak_rss_bytes']/2**30:.2f} GiB")
PY
done
if cmp -s "$dir/out-r1/mosaic/mosaic.ply" "$dir/out-r2/mosaic/mosaic.ply" &&
   diff -rq "$dir/out-r1/tiles" "$dir/out-r2/tiles" >/dev/null; then
  echo "1 and 2 ranks: identical mosaic.ply and tiles"
else
  echo "1 and 2 ranks: outputs DIFFER"
fi
