#!/usr/bin/env bash
# The jitter tables of docs/guide/jitter.md, regenerated: `ecdrive jitter` over veth (the headline, with SOEM
# when benches/soem/build.sh can build its loop), in-process, and over veth with --stress, at
# 1000, 500, 250 and 125 µs. Root, from the repository root, after `cargo build --profile rt`
# (the deployment build: fat LTO, one codegen unit; Cargo.toml).
#
#   benches/jitter_tables.sh [OUT_DIR]          (default target/jitter-tables)
#
# REPEAT/SECS set the headline's repetitions and seconds per run (default 5 and 10, the
# command of docs/guide/jitter.md); VREPEAT/VSECS those of the in-process and --stress variants (default 3
# and 5). Writes OUT_DIR/{veth,inprocess,stress}-C.json (+ .svg) and OUT_DIR/tables.md, the
# Markdown docs/guide/jitter.md shows, made by benches/jitter_tables.py from the JSON alone.
set -euo pipefail
cd "$(dirname "$0")/.."
OUT=${1:-target/jitter-tables}
REPEAT=${REPEAT:-5}
SECS=${SECS:-10}
VREPEAT=${VREPEAT:-3}
VSECS=${VSECS:-5}
ECDRIVE=./target/rt/ecdrive
[ "$(id -u)" = 0 ] || { echo "jitter_tables.sh: needs root (veth, SCHED_FIFO)" >&2; exit 2; }
[ -x "$ECDRIVE" ] || { echo "jitter_tables.sh: build first: cargo build --profile rt" >&2; exit 2; }
mkdir -p "$OUT"
commit="$(git rev-parse --short HEAD)"
if [ -n "$(git status --porcelain --untracked-files=no)" ]; then
    commit="$commit (with uncommitted changes)"
fi
echo "$commit" > "$OUT/commit.txt"
# The SOEM loop, if it can be built here (the harness says why SOEM is absent otherwise).
benches/soem/build.sh || echo "jitter_tables.sh: continuing without the SOEM loop" >&2
for C in 1000 500 250 125; do
    "$ECDRIVE" jitter --veth --repeat "$REPEAT" --seconds "$SECS" --cycle-us "$C" \
        --json "$OUT/veth-$C.json" --svg "$OUT/veth-$C.svg" > "$OUT/veth-$C.txt"
done
for C in 1000 500 250 125; do
    "$ECDRIVE" jitter --repeat "$VREPEAT" --seconds "$VSECS" --cycle-us "$C" \
        --json "$OUT/inprocess-$C.json" > "$OUT/inprocess-$C.txt"
done
for C in 1000 500 250 125; do
    "$ECDRIVE" jitter --veth --stress --repeat "$VREPEAT" --seconds "$VSECS" --cycle-us "$C" \
        --json "$OUT/stress-$C.json" > "$OUT/stress-$C.txt"
done
python3 benches/jitter_tables.py "$OUT" > "$OUT/tables.md"
echo "jitter_tables.sh: $OUT/tables.md"
