#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Appending a pass over one district to a run (a monthly update): the run of every
# acquisition but the last, then the last one's triangles within a box appended to the same
# work folder, against a fresh run of the same config; then that pass withdrawn again
# (session 65), against the first run's outputs. Prints the wall times, the tiles reused and
# whether the outputs are the same bytes; before appending, what `run --plan` expects
# (session 77).
# Usage: tools/bench/append.sh FOLDER XMIN YMIN XMAX YMAX [threads (default 2)]
#   (FOLDER holds a config.toml, e.g. from tools/bench/out_of_core.sh; the box in the files' CRS)
# LATE=1: the district's pass is dated one day after the first acquisition (a pass delivered
#   late, listed last): the run processes it second by time, so the later passes are
#   renumbered; the tiles it does not reach keep their results, renumbered (session 75).
set -euo pipefail
cd "$(dirname "$0")/../.."
if [ $# -lt 5 ] || [ ! -f "$1/config.toml" ]; then
  echo "usage: tools/bench/append.sh FOLDER XMIN YMIN XMAX YMAX [threads] (FOLDER/config.toml must exist)" >&2
  exit 1
fi
dir="$1"
threads="${6:-2}"
bin="$PWD/build/release/citymesh"
last=$(grep -n '^\[\[acquisition\]\]' "$dir/config.toml" | tail -1 | cut -d: -f1)
last_path=$(tail -n +"$last" "$dir/config.toml" | sed -n 's/^path = "\(.*\)"/\1/p' | head -1)
head -n $((last - 1)) "$dir/config.toml" >"$dir/append-before.toml"
cp "$dir/append-before.toml" "$dir/append-after.toml"
late_time='&'  # sed: the time line as it is
if [ "${LATE:-0}" = 1 ]; then
  first_time=$(sed -n 's/^time = "\(.*\)"/\1/p' "$dir/config.toml" | head -1)
  late_time=$(python3 -c "import datetime, sys; t = datetime.datetime.fromisoformat(sys.argv[1].replace('Z', '+00:00'))
print('time = \"' + (t + datetime.timedelta(days=1)).strftime('%Y-%m-%dT%H:%M:%SZ') + '\"')" "$first_time")
  echo "the district's pass dated one day after the first acquisition: $late_time"
fi
tail -n +"$last" "$dir/config.toml" | sed -e "s|^path = \".*\"|path = \"append-part.ply\"|" -e "s|^time = .*|$late_time|" \
  >>"$dir/append-after.toml"
build/release/bench/partial_pass "$dir/$last_path" "$dir/append-part.ply" "$2" "$3" "$4" "$5"
run() {  # config, work/output name
  /usr/bin/time -f "%e s, peak RSS %M kB" "$bin" run "$dir/$1" --no-pictures --threads "$threads" --memory 2GiB \
    --set output.labels=false --set project.work="work-$2" --set project.output="out-$2" 2>"$dir/append-$2.log" |
    tail -1
  tail -1 "$dir/append-$2.log"
}
same_as() {  # output folder against another: mosaic.ply and 3D Tiles
  cmp -s "$dir/$1/mosaic/mosaic.ply" "$dir/$2/mosaic/mosaic.ply" && diff -rq "$dir/$1/tiles" "$dir/$2/tiles" >/dev/null
}
reused() {  # what the last run into out-append reused, and its stages' times
  python3 -c "import json; r = json.load(open('$dir/out-append/run.json')); s = r['seconds']
print(f\"  tiles reused: {r['reused_tiles']} of {r['tiles']} ({r.get('kept_tiles', 0)} of them kept: a neighbour redone, or their passes renumbered)\")
print(f\"  tiling {s['tiling']:.1f} s, tiles {s['tiles']:.1f} s, final pass {s['total'] - s['tiling'] - s['tiles']:.1f} s\")"
}
rm -rf "$dir/work-append" "$dir/out-append" "$dir/work-fresh" "$dir/out-fresh" "$dir/out-before"
echo "every acquisition but the last:"
run append-before.toml append
cp -r "$dir/out-append" "$dir/out-before"
echo "the plan of appending it (run --plan: tiles the district's pass, processes nothing):"
/usr/bin/time -f "  plan: %e s" "$bin" run "$dir/append-after.toml" --plan --threads "$threads" \
  --set output.labels=false --set project.work=work-append --set project.output=out-append 2>"$dir/append-plan.log" |
  grep -v "to process:" | sed 's/^/  /'
tail -1 "$dir/append-plan.log"
echo "the district appended to that work folder:"
run append-after.toml append
reused
echo "a fresh run of the same config:"
run append-after.toml fresh
if same_as out-append out-fresh; then
  echo "appended and fresh: identical mosaic.ply and 3D Tiles"
else
  echo "appended and fresh: outputs DIFFER"
fi
echo "the district withdrawn again from the appended work folder:"
run append-before.toml append
reused
if same_as out-append out-before; then
  echo "withdrawn and the first run: identical mosaic.ply and 3D Tiles"
else
  echo "withdrawn and the first run: outputs DIFFER"
fi
