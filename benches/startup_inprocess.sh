#!/usr/bin/env bash
# Start-up to OP in-process: `ecdrive run` against DRIVES emulated drives (MR-J4-TM and BDHDE
# alternating) in the same process, no network; the `startup` figures of its --json (phase
# times and the frames each phase sent), medians over ROUNDS runs.
#
#   benches/startup_inprocess.sh [DRIVES] [ROUNDS]      (default 2 drives, 5 rounds)
#
# CYCLE_MS (default 1) sets the cycle. The emulated drives' own supervision of the cyclic data
# is off (`loss_detection = false`, as `--no-loss-detection` in the veth bench): at 128 drives
# the emulated segment runs on the cycle thread and now and then misses a 1 ms cycle.
#
# Needs a release build (`cargo build --release`); no root. In-process, a frame's round trip is
# the emulated segment's processing time, so the figures show what start-up costs in frames
# and in the master's own work, without a network's latency.
set -euo pipefail
cd "$(dirname "$0")/.."
n="${1:-2}"
rounds="${2:-5}"
cycle_ms="${CYCLE_MS:-1}"
e=target/release/ecdrive
[ -x "$e" ] || { echo "build first: cargo build --release" >&2; exit 1; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
{
  echo 'interface = "sim"'
  echo "cycle = \"${cycle_ms}ms\""
  echo 'duration = "0.1s"'
  printf '[sim]\ndevices = ['
  for i in $(seq 0 $((n - 1))); do
    [ "$i" -gt 0 ] && printf ', '
    if [ $((i % 2)) -eq 0 ]; then printf '"mr-j4-tm"'; else printf '"bdhde"'; fi
  done
  printf ']\nloss_detection = false\n'
  for i in $(seq 0 $((n - 1))); do printf '[[drive]]\nposition = %d\nmode = "csp"\n' "$i"; done
} >"$work/run.toml"
for r in $(seq "$rounds"); do
  "$e" run -c "$work/run.toml" --json 2>"$work/err" >"$work/r$r.json" ||
    { echo "ecdrive run failed: $(tail -1 "$work/err")" >&2; exit 1; }
done
python3 - "$work" "$n" "$rounds" "$cycle_ms" <<'PY'
import json, statistics, subprocess, sys
work, n, rounds = sys.argv[1], sys.argv[2], int(sys.argv[3])
runs = [json.load(open(f"{work}/r{r}.json"))["startup"] for r in range(1, rounds + 1)]
med = lambda k: statistics.median(r[k] for r in runs)
medf = lambda k: statistics.median(r["frames"][k] for r in runs)
commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True).stdout.strip()
print(f"start-up to OP in-process, {n} emulated drives, cycle {sys.argv[4]} ms, median of {rounds} runs (commit {commit})")
frames = sum(medf(k) for k in ["discovery", "coe", "image", "dc_settle", "safe_op"])
print(f"  ecdrive                {med('total_ms'):8.1f} ms to OP; {frames:.0f} frames before the cycle")
for k in ["discovery", "sii", "coe", "image", "dc_settle", "safe_op", "op"]:
    f = f"   {medf(k):6.0f} frames" if k in runs[0]["frames"] else ""
    a = "answered_" + k
    if a in runs[0]["frames"] and medf(a) > 0:
        f += f" (+{medf(a):.0f} of ethercrab's answered, not sent)"
    print(f"    {k:20} {med(k + '_ms'):8.1f} ms{f}")
PY
