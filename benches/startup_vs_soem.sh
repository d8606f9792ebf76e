#!/usr/bin/env bash
# Start-up to OP over veth: ecdrive against SOEM (pysoem), same emulated drives, same segment,
# runs interleaved, medians printed with ecdrive's phase breakdown.
#
#   sudo benches/startup_vs_soem.sh [DRIVES] [ROUNDS]      (default 2 drives, 5 rounds)
#
# CYCLE_MS (default 1) sets the cycle and SYNC0 period of both masters: at 128 drives the
# emulated segment, one thread answering every frame, needs more than 1 ms a cycle over veth.
# ANSWER_REREADS=false runs ecdrive with every one of ethercrab's start-up reads on the wire
# (the run file's `answer_rereads`; by default ecdrive answers ethercrab's re-reads of the SII
# and of the PDO configuration from what it read and wrote, and says how many it answered).
#
# DRIVES emulated drives (MR-J4-TM and BDHDE alternating) are served by `ecdrive sim` in a
# network namespace of this script's own (ecdrive-su) on one end of a veth pair. Each round:
#   SOEM    config_init, config_map, config_dc, SYNC0 1 ms, SAFE-OP, process data, OP, measured
#           inside the Python process (interpreter start-up not counted), to OP and to the
#           moment every drive has had 10 SYNC0 cycles (SOEM starts SYNC0 100 ms out and
#           requests OP before it runs; ecdrive requests OP after 10 SYNC0 cycles), and the
#           frames it sent (the veth's TX counter);
#   ecdrive `ecdrive run` of a file with every drive in csp at 1 ms, the `startup` figures of
#           its --json (discovery with the SII, CoE configuration including the PDO remap, the
#           process image, DC settle, SAFE-OP, OP) and the frames each phase sent, measured
#           inside the process.
# Needs root, the deployment build (`cargo build --profile rt`: fat LTO, one codegen unit) and pysoem (PYTHON names the
# interpreter that has it; `.ci/run` installs one in target/pysoem-venv). Without pysoem the
# SOEM column is skipped with a message.
set -euo pipefail
cd "$(dirname "$0")/.."
n="${1:-2}"
rounds="${2:-5}"
cycle_ms="${CYCLE_MS:-1}"
answer="${ANSWER_REREADS:-true}"
e=target/rt/ecdrive
py="${PYTHON:-python3}"
[ -x "$py" ] || command -v "$py" >/dev/null || py=python3
if [ -x target/pysoem-venv/bin/python3 ] && [ -z "${PYTHON:-}" ]; then py=target/pysoem-venv/bin/python3; fi
soem=1
"$py" -c "import pysoem" 2>/dev/null || { echo "pysoem not found ($py): SOEM skipped" >&2; soem=0; }
[ -x "$e" ] || { echo "build first: cargo build --profile rt" >&2; exit 1; }

work=$(mktemp -d)
ns=ecdrive-su
cleanup() {
  pkill -INT -f "ecdrive sim -i ecsu1" 2>/dev/null || true
  sleep 0.5
  ip netns del "$ns" 2>/dev/null || true
  ip link del ecsu0 2>/dev/null || true
  [ -n "${KEEP:-}" ] && echo "kept $work" >&2 || rm -rf "$work"
}
trap cleanup EXIT

{
  echo 'interface = "ecsu0"'
  echo "cycle = \"${cycle_ms}ms\""
  echo 'duration = "0.1s"'
  echo "answer_rereads = $answer"
  for i in $(seq 0 $((n - 1))); do printf '[[drive]]\nposition = %d\nmode = "csp"\n' "$i"; done
} >"$work/run.toml"

cat >"$work/soem.py" <<'EOF'
import sys, time, struct, pysoem
CYCLE = int(sys.argv[3]) * 1_000_000
t0 = time.monotonic()
m = pysoem.Master()
m.open(sys.argv[1])
n = m.config_init()
m.config_map()
m.config_dc()
for s in m.slaves:
    s.dc_sync(True, CYCLE)
m.state_check(pysoem.SAFEOP_STATE, 2_000_000)
m.send_processdata(); m.receive_processdata(200_000)
m.state = pysoem.OP_STATE
m.write_state()
ok = False
for _ in range(5000):
    m.send_processdata(); m.receive_processdata(200_000)
    if m.state_check(pysoem.OP_STATE, 1_000) == pysoem.OP_STATE:
        ok = True
        break
    time.sleep(0.001)
t_op = (time.monotonic() - t0) * 1e3
# ecdrive's criterion for requesting OP: every drive has had 10 SYNC0 cycles with valid
# outputs (its first SYNC0 is in 0x0990; SOEM starts SYNC0 100 ms out).
start = max(struct.unpack("<Q", bytes(s._fprd(0x0990, 8)))[0] for s in m.slaves)
for _ in range(5000):
    if m.dc_time >= start + 10 * CYCLE:
        break
    time.sleep(0.001)
    m.send_processdata(); m.receive_processdata(200_000)
t_sync = (time.monotonic() - t0) * 1e3
m.state = pysoem.INIT_STATE; m.write_state(); m.close()
print(f"{t_op:.1f} {t_sync:.1f}" if ok and n == int(sys.argv[2]) else "fail")
EOF

devices=()
for i in $(seq 0 $((n - 1))); do
  if [ $((i % 2)) -eq 0 ]; then devices+=(-d mr-j4-tm); else devices+=(-d bdhde); fi
done
ip netns add "$ns"
ip link add ecsu0 type veth peer name ecsu1
ip link set ecsu1 netns "$ns"
ip link set ecsu0 up
ip netns exec "$ns" ip link set ecsu1 up
ip netns exec "$ns" "$e" sim -i ecsu1 "${devices[@]}" --no-loss-detection >"$work/sim.log" 2>&1 &
sleep 1

fields="total_ms discovery_ms sii_ms coe_ms image_ms dc_settle_ms safe_op_ms op_ms"
frames="discovery sii coe image dc_settle safe_op answered_discovery answered_image"
tx() { cat /sys/class/net/ecsu0/statistics/tx_packets; }
for r in $(seq "$rounds"); do
  if [ "$soem" = 1 ]; then
    a=$(tx)
    out=$("$py" "$work/soem.py" ecsu0 "$n" "$cycle_ms" 2>>"$work/soem.err" || echo fail)
    echo "$out $(($(tx) - a))" >>"$work/soem.txt"
  fi
  if ! "$e" run -c "$work/run.toml" --json >"$work/one.json" 2>"$work/one.err"; then
    echo "ecdrive run failed (round $r): $(tail -1 "$work/one.err")" >&2
    continue
  fi
  python3 -c "
import json, sys
s = json.load(open('$work/one.json'))['startup']
print(' '.join([str(s[k]) for k in '$fields'.split()] + [str(s['frames'][k]) for k in '$frames'.split()] + [str(s['sync0_rearmed'])]))" >>"$work/ecdrive.txt"
done

python3 - "$work" "$n" "$rounds" "$fields" "$soem" "$frames" "$cycle_ms" "$answer" <<'EOF'
import statistics, sys, subprocess
work, n, rounds, fields, soem, frames, cycle_ms, answer = sys.argv[1:]
med = lambda xs: statistics.median(xs) if xs else float("nan")
names = fields.split() + ["frames_" + f for f in frames.split()] + ["rearmed"]
rows = [list(map(float, l.split())) for l in open(f"{work}/ecdrive.txt")]
cols = dict(zip(names, zip(*rows)))
commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True).stdout.strip()
print(f"start-up to OP over veth, {n} emulated drives, cycle {cycle_ms} ms, median of {rounds} interleaved runs (commit {commit}, answer_rereads = {answer})")
if soem == "1":
    s = [l.split() for l in open(f"{work}/soem.txt")]
    ok = [list(map(float, x)) for x in s if x[0] != "fail"]
    print(f"  SOEM (pysoem 1.1.13)   {med([x[0] for x in ok]):8.1f} ms to OP, "
          f"{med([x[1] for x in ok]):.1f} ms to 10 SYNC0 cycles; "
          f"{med([x[2] for x in ok]):.0f} frames in all ({len(s) - len(ok)} failed)")
total = sum(med(cols["frames_" + f]) for f in frames.split() if f in ("discovery", "coe", "image", "dc_settle", "safe_op"))
print(f"  ecdrive                {med(cols['total_ms']):8.1f} ms to OP (after 10 SYNC0 cycles); "
      f"{total:.0f} frames before the cycle")
for k in fields.split()[1:]:
    f = "frames_" + k[:-3]
    extra = f"   {med(cols[f]):6.0f} frames" if f in cols else ""
    a = "frames_answered_" + k[:-3]
    if a in cols and med(cols[a]) > 0:
        extra += f" (+{med(cols[a]):.0f} of ethercrab's answered, not sent)"
    if k == "safe_op_ms":
        late = [x for x in cols["rearmed"] if x > 0]
        extra += f" (SYNC0 armed again on {sum(late):.0f} drives in {len(late)} of {len(rows)} runs)"
    print(f"    {k[:-3]:20} {med(cols[k]):8.1f} ms{extra}")
EOF
