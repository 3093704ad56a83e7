#!/usr/bin/env bash
# Side by side with the Embree-based renderer of ../shared/embree-bench (a measuring instrument,
# not part of penumbra): builds penumbra in release mode, then runs both renderers alternately
# on the instrument's three scenes and prints one JSON line per scene with the median process
# wall times, their ratio (ratio_other_over_embree: penumbra / Embree), Embree's own
# load/build/render split and the PSNR between the two images.
#
#   ../shared/embree-bench/setup.sh          # once per machine: apt packages, build, 1M mesh
#   tools/bench_vs_embree.sh                 # all three scenes, 2 threads, 3 runs each
#   THREADS=1 REPEATS=5 tools/bench_vs_embree.sh cornell
#
# The machines are shared: read the loadavg_max field, and compare ratios from one run, not
# times from different runs.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
bench="${EMBREE_BENCH:-$root/../shared/embree-bench}"
if [ ! -x "$bench/embree_render" ]; then
  echo "error: $bench/embree_render not found; run $bench/setup.sh first (see its README)" >&2
  exit 1
fi
(cd "$root" && cargo build --release --quiet)
scenes=("$@")
[ ${#scenes[@]} -gt 0 ] || scenes=(cornell cornell_bunny cornell_blob1m)
cd "$bench"
for scene in "${scenes[@]}"; do
  python3 tools/side_by_side.py "scenes/$scene.toml" --threads "${THREADS:-2}" \
    --repeats "${REPEATS:-3}" \
    --other "$root/target/release/penumbra render {scene} -o {out} --threads {threads} --quiet {args}"
done
