#!/usr/bin/env bash
# Side by side with the Embree-based renderer of ../shared/embree-bench (a measuring instrument,
# not part of penumbra): builds penumbra in release mode, then runs both renderers alternately
# on the instrument's three scenes and prints one JSON line per scene with the median process
# wall times, their ratio (ratio_other_over_embree: penumbra / Embree), Embree's own
# load/build/render split and the PSNR between the two images.
#
#   ../shared/embree-bench/setup.sh          # once per machine: apt packages, build, 1M mesh
#   tools/bench_vs_embree.sh                 # the instrument's three rooms, 2 threads, 3 runs each
#   tools/bench_vs_embree.sh suite           # the suite: every scene of scenes/bench/
#   THREADS=1 REPEATS=5 tools/bench_vs_embree.sh cornell scenes/bench/jittered.toml
#
# An argument is one of the instrument's scene names (cornell, cornell_bunny, cornell_blob1m),
# `suite`, or a scene file. With more than one scene, a last line gives the geometric mean of
# the ratios (geomean_ratio). The suite's scenes use only the project's assets and shapes that
# both renderers build alike (no spheres, whose tessellation is each renderer's own): the images
# agree to 77-101 dB, except jittered.toml (each renderer draws its own jitter: about 52 dB).
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
scenes=()
for arg in "${@:-cornell cornell_bunny cornell_blob1m}"; do
  for a in $arg; do
    case "$a" in
      suite) scenes+=("$root"/scenes/bench/*.toml) ;;
      *.toml) scenes+=("$(cd "$(dirname "$a")" && pwd)/$(basename "$a")") ;;
      *) scenes+=("$bench/scenes/$a.toml") ;;
    esac
  done
done
cd "$bench"
results=$(mktemp)
trap 'rm -f "$results"' EXIT
for scene in "${scenes[@]}"; do
  python3 tools/side_by_side.py "$scene" --threads "${THREADS:-2}" \
    --repeats "${REPEATS:-3}" \
    --other "$root/target/release/penumbra render {scene} -o {out} --threads {threads} --quiet --allow-path $root/assets --allow-path $(dirname "$bench") {args}" |
    tee -a "$results"
done
if [ ${#scenes[@]} -gt 1 ]; then
  python3 -c 'import json, math, sys
ratios = [json.loads(l)["ratio_other_over_embree"] for l in open(sys.argv[1]) if l.strip()]
print(json.dumps({"scenes": len(ratios), "geomean_ratio": round(math.exp(sum(map(math.log, ratios)) / len(ratios)), 3)}))' "$results"
fi
