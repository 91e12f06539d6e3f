#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Out-of-core benchmark (issue 6): a simulated city of ~27 M triangles over 6 epochs (6 streets
# of 500 m), run end to end with a 2 GiB memory budget on 1 and 2 threads. Prints the tiler
# against plain reading (tile_bench), then per thread count: wall time, input triangles/s and
# peak RSS (/usr/bin/time -v). Labelled PLYs and pictures are off (they are as large as the
# input). Usage: tools/bench/out_of_core.sh [folder (default /tmp/citymesh-city)] [streets]
set -euo pipefail
cd "$(dirname "$0")/../.."
dir="${1:-/tmp/citymesh-city}"
streets="${2:-6}"
bin=build/release/citymesh
[ -f "$dir/config.toml" ] || "$bin" simulate --out "$dir" --streets "$streets" --length 500 >/dev/null
build/release/bench/tile_bench "$dir/config.toml" 50 "$dir/tile-bench" 3
for threads in 1 2; do
  rm -rf "$dir/work-$threads" "$dir/out-$threads"
  /usr/bin/time -v "$bin" run "$dir/config.toml" --no-pictures --threads "$threads" --memory 2GiB \
    --set output.labels=false --set project.work="work-$threads" --set project.output="out-$threads" \
    2>"$dir/time-$threads.log" | tail -1
  grep -E "Elapsed|Maximum resident" "$dir/time-$threads.log" | sed 's/^\s*/  /'
done
if cmp -s "$dir/out-1/mosaic/mosaic.ply" "$dir/out-2/mosaic/mosaic.ply"; then
  echo "1 and 2 threads: identical mosaic.ply"
else
  echo "1 and 2 threads: mosaic.ply DIFFERS"
fi
