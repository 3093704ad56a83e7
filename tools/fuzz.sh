#!/usr/bin/env bash
# Fuzzes penumbra with cargo-fuzz (libFuzzer) for a bounded time; exits non-zero on a crash,
# a hang (one input over 10 s) or a blown memory limit, leaving the input under
# fuzz/artifacts/TARGET/.
#
#   tools/fuzz.sh TARGET SECONDS [libFuzzer options...]   # one target
#   tools/fuzz.sh all SECONDS                             # each target in turn (CI)
#   tools/fuzz.sh list                                    # the targets
#
# Targets: scene_toml, scene_json, scene_override (a TOML scene with a --set override on its
# first line), pack (a scene pack: its overrides, scene text and packed files, see the body):
# parse, build and a 4×4 render; obj, mtl, ply (ASCII and binary), gltf (GLB and JSON),
# texture (PNG and JPEG decoding), hdr (an environment map file, Radiance HDR headers and
# scanlines above all: decoded and sampled). Their
# bodies are in crates/penumbra-fuzz-targets. Needs the nightly toolchain
# (`rustup toolchain install nightly`); installs cargo-fuzz from crates.io when it is missing.
# Runs one fuzzer process. New inputs go to fuzz/target/corpus/TARGET (kept between runs, not
# committed); the committed seeds in fuzz/corpus/TARGET are only read.
#
# A crash: minimise it with `cargo +nightly fuzz tmin TARGET fuzz/artifacts/TARGET/crash-…`,
# commit the result under fuzz/regressions/TARGET/ (the stable test
# `cargo test -p penumbra-fuzz-targets` replays it) and fix the library.
set -euo pipefail
cd "$(dirname "$0")/.."
targets=(scene_toml scene_json scene_override obj mtl ply gltf texture pack hdr)

usage() {
    sed -n '2,10p' "$0" | sed 's/^# \{0,1\}//' >&2
    exit 2
}

case "${1:-}" in
    list)
        printf '%s\n' "${targets[@]}"
        exit 0
        ;;
    all)
        [ $# -eq 2 ] || usage
        for t in "${targets[@]}"; do
            "$0" "$t" "$2"
        done
        exit 0
        ;;
    "" | -h | --help) usage ;;
esac
[ $# -ge 2 ] || usage
target=$1
seconds=$2
shift 2
[[ " ${targets[*]} " == *" $target "* ]] || {
    echo "tools/fuzz.sh: unknown target \`$target\` (known: ${targets[*]})" >&2
    exit 2
}
[[ "$seconds" =~ ^[0-9]+$ ]] || {
    echo "tools/fuzz.sh: SECONDS must be a whole number, not \`$seconds\`" >&2
    exit 2
}

cargo +nightly --version >/dev/null 2>&1 || {
    echo "tools/fuzz.sh: the nightly toolchain is needed (rustup toolchain install nightly)" >&2
    exit 1
}
if ! cargo fuzz --version >/dev/null 2>&1; then
    echo "tools/fuzz.sh: installing cargo-fuzz" >&2
    cargo install cargo-fuzz --locked
fi

root=$PWD
scratch="$root/fuzz/target/corpus/$target"
mkdir -p "$scratch"
echo "tools/fuzz.sh: fuzzing $target for $seconds s" >&2
# Release code with debug assertions, overflow checks and AddressSanitizer; one process. The
# dictionary holds the words of the format (keys, statements, chunk names) for mutations to use.
# LeakSanitizer skips glibc's thread-local destructor records of exiting pool threads
# (fuzz/lsan.supp says why).
export LSAN_OPTIONS="suppressions=$root/fuzz/lsan.supp${LSAN_OPTIONS:+:$LSAN_OPTIONS}"
cargo +nightly fuzz run -O --debug-assertions "$target" "$scratch" "$root/fuzz/corpus/$target" -- \
    -dict="$root/fuzz/dicts/$target.dict" -max_total_time="$seconds" -timeout=10 \
    -rss_limit_mb=2048 -print_final_stats=1 "$@"
