#!/usr/bin/env python3
"""Summarize a Google Benchmark JSON file: CSV of every benchmark with its counters, a Markdown table
with the headroom against a 1 kHz servo period, and a run-time-vs-error plot for every family that
reports an `error` counter (families are the benchmark name up to its first '/')."""
import csv
import json
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

UNIT_NS = {"ns": 1.0, "us": 1e3, "ms": 1e6, "s": 1e9}
STANDARD = {"name", "family_index", "per_family_instance_index", "run_name", "run_type", "repetitions",
            "repetition_index", "threads", "iterations", "real_time", "cpu_time", "time_unit",
            "aggregate_name", "aggregate_unit", "label", "error_occurred", "error_message"}


def main(path, out_dir):
    with open(path) as f:
        data = json.load(f)
    rows = [b for b in data["benchmarks"] if b.get("run_type", "iteration") == "iteration"]
    counters = sorted({k for b in rows for k in b if k not in STANDARD})
    for b in rows:
        b["time_ns"] = b["real_time"] * UNIT_NS[b.get("time_unit", "ns")]
        b["headroom_1khz"] = 1e6 / b["time_ns"] if b["time_ns"] > 0 else float("inf")
    with open(os.path.join(out_dir, "bench.csv"), "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["name", "time_ns", "headroom_1khz"] + counters)
        for b in rows:
            w.writerow([b["name"], f"{b['time_ns']:.6g}", f"{b['headroom_1khz']:.6g}"]
                       + [b.get(c, "") for c in counters])
    with open(os.path.join(out_dir, "bench.md"), "w") as f:
        ctx = data.get("context", {})
        f.write(f"Machine: {ctx.get('num_cpus', '?')} CPUs at {ctx.get('mhz_per_cpu', '?')} MHz, "
                f"{ctx.get('date', '')}\n\n")
        f.write("| benchmark | time | x 1 kHz budget | " + " | ".join(counters) + " |\n")
        f.write("|---|---:|---:|" + "---:|" * len(counters) + "\n")
        for b in rows:
            t = b["time_ns"]
            ts = f"{t:.0f} ns" if t < 1e4 else f"{t / 1e3:.1f} us" if t < 1e7 else f"{t / 1e6:.1f} ms"
            cells = [f"{b[c]:.3g}" if isinstance(b.get(c), (int, float)) else "" for c in counters]
            f.write(f"| {b['name']} | {ts} | {b['headroom_1khz']:.0f} | " + " | ".join(cells) + " |\n")
    families = {}
    for b in rows:
        if isinstance(b.get("error"), (int, float)):
            families.setdefault(b["name"].split("/")[0], []).append(b)
    if families:
        fig, ax = plt.subplots(figsize=(7, 4.5))
        for fam, bs in sorted(families.items()):
            xs = [b["time_ns"] / 1e3 for b in bs]
            ys = [max(b["error"], 1e-17) for b in bs]
            ax.loglog(xs, ys, "o-", label=fam)
        ax.set_xlabel("run time per call [us]")
        ax.set_ylabel("error (each benchmark's `error` counter)")
        ax.set_title("Run time against error")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7)
        fig.tight_layout()
        fig.savefig(os.path.join(out_dir, "time_vs_error.png"), dpi=120)
    print(open(os.path.join(out_dir, "bench.md")).read())


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit("usage: bench_summary.py bench.json out_dir")
    main(sys.argv[1], sys.argv[2])
