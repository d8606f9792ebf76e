#!/usr/bin/env python3
"""The jitter tables of docs/guide/jitter.md from `ecdrive jitter --json` files (benches/jitter_tables.sh).

Usage: jitter_tables.py DIR  ->  Markdown on stdout. Reads DIR/{veth,inprocess,stress}-C.json
and DIR/commit.txt. Every figure is "median [min–max]" of the repetitions' values, as the
harness summarised them (`summary` in the JSON); nothing is computed here but formatting.
"""
import json
import os
import sys

CYCLES = [1000, 500, 250, 125]
RUNS = ["sleep", "ethercrab", "soem", "ecdrive"]
VARIANTS = [
    ("veth", "Over veth (the headline)"),
    ("inprocess", "In-process"),
    ("stress", "Over veth with `--stress`"),
]


def spread(s, scale=1e-3, digits=1):
    if not s:
        return "–"
    f = lambda v: f"{v * scale:.{digits}f}"
    if len(s["values"]) == 1:
        return f(s["median"])
    return f"{f(s['median'])} [{f(s['min'])}–{f(s['max'])}]"


def table(reports):
    out = [
        "| cycle | run | wake-up latency p50 (µs) | p99 (µs) | max (µs) | frame round trip p50 (µs) | CPU per cycle (µs) | missed cycles |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for c, r in reports:
        runs = r["summary"]["runs"]
        for name in RUNS:
            f = runs.get(name)
            if f is None:
                if name == "soem" and r["settings"]["transport"] != "in-process":
                    out.append(f"| {c} µs | soem | not run: {r.get('soem_absent') or '?'} | | | | | |")
                continue
            out.append(
                f"| {c} µs | {name} | {spread(f.get('wake_latency_p50'))} | {spread(f.get('wake_latency_p99'))} "
                f"| {spread(f.get('wake_latency_max'))} | {spread(f.get('exchange_p50'))} "
                f"| {spread(f.get('cpu_master_ns'))} | {spread(f.get('missed'), 1, 0)} |"
            )
        for key, label in [("ecdrive_to_ethercrab", "ecdrive ÷ ethercrab"), ("ecdrive_to_soem", "ecdrive ÷ soem")]:
            q = r["summary"]["ratios"].get(key)
            if q is None:
                continue
            out.append(
                f"| | *{label}* | {spread(q.get('wake_latency_p50'), 1, 2)} | {spread(q.get('wake_latency_p99'), 1, 2)} "
                f"| {spread(q.get('wake_latency_max'), 1, 2)} | {spread(q.get('exchange_p50'), 1, 2)} "
                f"| {spread(q.get('cpu_master'), 1, 2)} | |"
            )
    return "\n".join(out)


def drives_table(reports):
    """At the drives: per cycle time and master, each emulated ESC's frame arrival after SYNC0
    (p50) and its largest DC system-time difference (0x092C), median [min–max] over the
    repetitions, from the repetitions' own summaries."""
    out = [
        "| cycle | run | drive | frame arrival after SYNC0 p50 (µs) | DC difference max (ns) |",
        "|---|---|---|---|---|",
    ]
    for c, r in reports:
        for name in RUNS:
            per_drive = {}
            for rep in r["repetitions"]:
                run = rep.get(name)
                if not run:
                    continue
                for d in run.get("drives") or []:
                    e = per_drive.setdefault(d["position"], ([], []))
                    if d.get("arrival_after_sync0"):
                        e[0].append(d["arrival_after_sync0"]["p50"])
                    if d.get("dc_difference"):
                        e[1].append(d["dc_difference"]["max"])
            for pos, (arr, dc) in sorted(per_drive.items()):
                sp = lambda v, scale, digits: spread(
                    {"values": v, "median": sorted(v)[len(v) // 2], "min": min(v), "max": max(v)}
                    if v else None, scale, digits)
                out.append(f"| {c} µs | {name} | {pos} | {sp(arr, 1e-3, 1)} | {sp(dc, 1, 0)} |")
    return "\n".join(out)


PARTS = [
    ("part_receive_ns", "receive"),
    ("part_receive_link_ns", "of which the link"),
    ("part_engine_ns", "engine"),
    ("part_supervision_ns", "supervision"),
    ("part_telemetry_ns", "telemetry"),
    ("part_send_ns", "send"),
    ("part_send_link_ns", "of which the link"),
    ("part_sleep_and_wake_ns", "sleep and wake-up"),
]


def parts_table(reports):
    """ecdrive's cycle thread by part, µs per cycle, median [min–max] over the repetitions
    (the harness's `part_*` figures), with the thread's whole CPU figure and SOEM's loop."""
    out = [
        "| cycle | " + " | ".join(label for _, label in PARTS) + " | cycle thread | SOEM's loop |",
        "|---|" + "---|" * (len(PARTS) + 2),
    ]
    for c, r in reports:
        runs = r["summary"]["runs"]
        e = runs.get("ecdrive") or {}
        if not any(e.get(k) for k, _ in PARTS):
            continue
        thread = [
            rep["ecdrive"]["cpu"].get("cycle_thread_ns")
            for rep in r["repetitions"]
            if rep.get("ecdrive") and rep["ecdrive"]["cpu"].get("cycle_thread_ns") is not None
        ]
        th = None
        if thread:
            v = sorted(thread)
            th = {"values": thread, "median": v[len(v) // 2] if len(v) % 2 else (v[len(v) // 2 - 1] + v[len(v) // 2]) / 2, "min": v[0], "max": v[-1]}
        soem = (runs.get("soem") or {}).get("cpu_master_ns")
        out.append(
            f"| {c} µs | " + " | ".join(spread(e.get(k)) for k, _ in PARTS)
            + f" | {spread(th)} | {spread(soem)} |"
        )
    return "\n".join(out)


def main():
    d = sys.argv[1]
    commit_file = os.path.join(d, "commit.txt")
    commit = open(commit_file).read().strip() if os.path.exists(commit_file) else "?"
    for key, title in VARIANTS:
        reports = []
        for c in CYCLES:
            p = os.path.join(d, f"{key}-{c}.json")
            if os.path.exists(p):
                reports.append((c, json.load(open(p))))
        if not reports:
            continue
        r0 = reports[0][1]
        # The JSON names the commit its binary was built from (older files do not).
        commits = sorted({r.get("commit", commit) for _, r in reports})
        commit_text = ", ".join(commits)
        h = r0["host"]
        st = r0["settings"]
        cmd = r0.get("command", "?").replace(f"--cycle-us {reports[0][0]}", "--cycle-us C")
        cmd = cmd.replace(f"{key}-{reports[0][0]}", f"{key}-C")
        la = lambda l: "n/a" if not l else f"{l[0]:.2f}"
        loads = ", ".join(
            f"{c} µs: {la(r['load']['loadavg_before'])} → {la(r['load']['loadavg_after'])}" for c, r in reports
        )
        print(f"#### {title}\n")
        print(
            f"`{cmd}` at C = {', '.join(str(c) for c, _ in reports)}; commit {commit_text}; "
            f"{st['repeat']} repetitions of {st['cycles']} cycles at 1000 µs "
            f"(the same number of seconds at each cycle time), drives {', '.join(st['drives'])}, "
            f"SCHED_FIFO {st['priority']}{' granted' if r0['priority_granted'] else ' NOT granted'}, "
            f"CPU {st['cpu'] if st['cpu'] is not None else 'not pinned'}, memory "
            f"{'locked' if st['lock_memory'] else 'not locked'}. Host: {h['kernel'].split()[0]}, "
            f"PREEMPT_RT {'yes' if h['preempt_rt'] else 'no'}, {h['cpu_model']} ({h['cpus']} CPUs), "
            f"isolated CPUs {h['isolated_cpus'] or 'none'}. Load: "
            f"{r0['load']['stress'] or 'nothing added'}; 1-minute load average before → after: {loads}.\n"
        )
        print(table(reports))
        print()
        if key == "veth":
            print("ecdrive's cycle thread by part (µs per cycle; see above):\n")
            print(parts_table(reports))
            print()
            print("At the drives (the emulated slave controllers' own records):\n")
            print(drives_table(reports))
            print()


main()
