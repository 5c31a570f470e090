#!/usr/bin/env python3
"""Summarize a Google Benchmark JSON file: CSV of every benchmark with its counters, a Markdown table
with the headroom against a 1 kHz servo period, and the run-time-vs-error curves of every benchmark
that reports an `error` counter: time_vs_error.csv and time_vs_error.png (one panel per numerical
knob, one curve per family and fixed arguments, the shipped default starred)."""
import csv
import json
import os
import sys

from plot_common import plt, save

UNIT_NS = {"ns": 1.0, "us": 1e3, "ms": 1e6, "s": 1e9}
STANDARD = {"name", "family_index", "per_family_instance_index", "run_name", "run_type", "repetitions",
            "repetition_index", "threads", "iterations", "real_time", "cpu_time", "time_unit",
            "aggregate_name", "aggregate_unit", "label", "error_occurred", "error_message"}


# Panel of each family (benchmark name up to its first '/'), by name prefix.
PANELS = [("BM_ExoSubspace", "exoskeleton: subspace proxy (error: |x_p - f(q*)| rad)"),
          ("BM_TauFk", "TAU forward kinematics tolerance (error: pose, m / rad)"),
          ("BM_Dare", "DARE doubling tolerance (error: |P - P_ref| / |P_ref|)"),
          ("BM_ZohExp", "ZOH matrix exponential (error: relative, Frobenius)"),
          ("BM_RhiGradient", "RHI FME gradient alone (error: relative to Richardson FD)"),
          ("BM_RhiTick", "RHI controller tick, analytic vs FD gradient (error: as above)")]


def curve_of(b):
    """(panel, curve, swept value): the first argument is swept, the others name the curve."""
    parts = b["name"].split("/")
    family, args = parts[0], parts[1:]
    panel = next((title for prefix, title in PANELS if family.startswith(prefix)), family)
    curve = " ".join([family.replace("BM_", "")] + args[1:] + ([b["label"]] if b.get("label") else []))
    return panel, curve, args[0] if args else ""


def write_curves(rows, out_dir):
    points = [b for b in rows if isinstance(b.get("error"), (int, float))]
    if not points:
        return
    curves = {}
    with open(os.path.join(out_dir, "time_vs_error.csv"), "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["panel", "curve", "swept", "time_ns", "error", "default"])
        for b in points:
            panel, curve, swept = curve_of(b)
            is_default = bool(b.get("default", 0))
            w.writerow([panel, curve, swept, f"{b['time_ns']:.6g}", f"{b['error']:.6g}", int(is_default)])
            curves.setdefault(panel, {}).setdefault(curve, []).append((b["time_ns"] / 1e3, b["error"], is_default))
    fig, axes = plt.subplots(len(curves), 1, figsize=(8, 3.6 * len(curves)), squeeze=False)
    for ax, (panel, by_curve) in zip(axes[:, 0], sorted(curves.items())):
        for curve, pts in sorted(by_curve.items()):
            xs = [p[0] for p in pts]
            ys = [max(p[1], 1e-17) for p in pts]  # an exact zero still shows, at the bottom
            line, = ax.loglog(xs, ys, "o-", ms=4, label=curve)
            for x, y, d in zip(xs, ys, [p[2] for p in pts]):
                if d:
                    ax.loglog([x], [y], "*", ms=14, color=line.get_color(), markeredgecolor="k")
        ax.set_title(panel + "  (star: default)", fontsize=9)
        ax.set_xlabel("run time per call [us]")
        ax.set_ylabel("error")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7)
    save(fig, os.path.join(out_dir, "time_vs_error.png"))


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
    write_curves(rows, out_dir)
    print(open(os.path.join(out_dir, "bench.md")).read())


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit("usage: bench_summary.py bench.json out_dir")
    main(sys.argv[1], sys.argv[2])
