#!/usr/bin/env python3
"""Each device's paper method beside its baseline in CHAI3D's unchanged stiff scenes, judged by the
referee (the simulated plant's truth: docs/chai3d.md, "The referee").

For every backend asked for, run_examples.py runs each scene twice with each device, the same
scripted hand both times (the scene's, from the device's dropin.json): once as the device ships and
once with its dropin.json "method_off" options (its paper's baseline). The two runs' referee figures
are set side by side, and the scene's "versus_baseline" claims in the device's dropin.json (an entry
under the backend's name overrides them there) are checked on them: {"referee.<figure>": [op,
factor]} holds when method op factor x baseline (e.g. the TAU's true depth <= 0.5 x the spring's);
"versus_baseline_why" says why, or why a scene has none.

  method_vs_baseline.py --bin DIR --out DIR [--example NAME ...] [--device NAME ...]
                        [--backend sim|emulated ...] [--seconds S] [--hand-recordings DIR]

With --hand-recordings (e.g. tests/recordings) a scene and device with a recording there
(<example>.<device>.csv, docs/recording.md) replays it in both runs instead of re-scripting the hand.

Writes to --out: method_vs_baseline.csv (one row per device, scene, backend and figure),
summary.txt (the table), reproduction.csv (one row per claim, for uhaptics-report) and
method_vs_baseline_<device>.png (the figures, method against baseline). Exit status: 0 when every
claim holds, 1 when one does not, 2 when a run could not be made.
"""
import argparse
import csv
import math
import os
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
RUNNER = os.path.join(HERE, "run_examples.py")
sys.path.insert(0, HERE)
import run_examples  # noqa: E402  (the device tables and the referee's columns, defined once there)

# The referee's figures compared, with their units (run_examples.REFEREE_COLUMNS, in this order).
FIGURES = [("max_true_penetration_mm", "true depth [mm]"), ("rendered_stiffness_N_per_m", "rendered stiffness [N/m]"),
           ("force_error_rms_N", "force error RMS [N]"), ("generated_energy_mJ", "energy to the user [mJ]"),
           ("chatter_N", "chatter above 30 Hz [N]"), ("saturated_share", "saturated share")]
DEFAULT_SCENES = ["23-tooth", "14-textures"]
OPS = {"<=": lambda a, b: a <= b, "<": lambda a, b: a < b, ">=": lambda a, b: a >= b, ">": lambda a, b: a > b}


def number(value):
    try:
        return float(value)
    except (TypeError, ValueError):
        return math.nan


def run(args, backend, method_off, out):
    """run_examples.py with --report into out; its dropin.csv rows by (example, device)."""
    command = [sys.executable, RUNNER, "--bin", args.bin, "--out", out, "--backend", backend, "--report"]
    for e in args.example:
        command += ["--example", e]
    for d in args.device:
        command += ["--device", d]
    if args.seconds:
        command += ["--seconds", str(args.seconds)]
    if args.hand_recordings:
        command += ["--hand-recordings", args.hand_recordings]
    if method_off:
        command.append("--method-off")
    print(f"method_vs_baseline.py: {backend}, {'baseline' if method_off else 'method'}: running", flush=True)
    status = subprocess.run(command, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    if status.returncode > 1:
        print(status.stdout, file=sys.stderr)
        raise SystemExit(f"method_vs_baseline.py: run_examples.py failed (exit {status.returncode})")
    path = os.path.join(out, "dropin.csv")
    if not os.path.exists(path):
        print(status.stdout, file=sys.stderr)
        raise SystemExit(f"method_vs_baseline.py: run_examples.py wrote no {path}")
    with open(path) as f:
        return {(r["example"], r["device"]): r for r in csv.DictReader(f)}


def scene_entry(table, example, device, backend):
    """The device's dropin.json entry for the scene, with the backend's own entry over it."""
    entry = dict(table["devices"][device].get("scenes", {}).get(example, {}))
    entry.update(entry.pop(backend, {}))
    return entry


def compare(table, pairs):
    """Rows of the comparison and the claims' verdicts from {(example, device, backend): (method, baseline)}."""
    rows, claims = [], []
    for (example, device, backend), (method, baseline) in sorted(pairs.items()):
        for name, label in FIGURES:
            m, b = number(method.get("referee_" + name)), number(baseline.get("referee_" + name))
            rows.append({"example": example, "device": device, "backend": backend, "figure": name, "label": label,
                         "method": m, "baseline": b})
        for figure, (op, factor) in scene_entry(table, example, device, backend).get("versus_baseline", {}).items():
            name = figure[len("referee."):]
            m, b = number(method.get("referee_" + name)), number(baseline.get("referee_" + name))
            ok = not math.isnan(m) and not math.isnan(b) and OPS[op](m, factor * b)
            claims.append({"example": example, "device": device, "backend": backend, "figure": name, "op": op,
                           "factor": factor, "method": m, "baseline": b, "pass": ok})
    return rows, claims


def fmt(v):
    return "-" if math.isnan(v) else f"{v:.3g}"


def write(out, table, rows, claims):
    with open(os.path.join(out, "method_vs_baseline.csv"), "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=["example", "device", "backend", "figure", "method", "baseline"],
                                extrasaction="ignore", lineterminator="\n")
        writer.writeheader()
        writer.writerows(rows)
    lines = []
    keys = sorted({(r["device"], r["example"], r["backend"]) for r in rows})
    head = " ".join(f"{label.split(' [')[0][:14]:>16}" for _, label in FIGURES)
    lines.append(f"{'device, scene, backend':<32} {head}")
    for device, example, backend in keys:
        cells = {r["figure"]: r for r in rows if (r["device"], r["example"], r["backend"]) == (device, example, backend)}
        pair = " ".join(f"{fmt(cells[n]['method']) + ' / ' + fmt(cells[n]['baseline']):>16}" for n, _ in FIGURES)
        lines.append(f"{device + ', ' + example + ', ' + backend:<32} {pair}")
    lines.append("(each cell: method / baseline, the same hand, scripted or replayed from a recording; "
                 "units: mm, N/m, N, mJ, N, share)")
    for device, example, backend in keys:
        why = scene_entry(table, example, device, backend).get("versus_baseline_why")
        if why:
            lines.append(f"- {device}, {example}, {backend}: {why}")
    with open(os.path.join(out, "summary.txt"), "w") as f:
        f.write("\n".join(lines) + "\n")
    with open(os.path.join(out, "reproduction.csv"), "w", newline="") as f:
        writer = csv.writer(f, lineterminator="\n")
        writer.writerow(["paper", "quantity", "published", "measured", "criterion", "pass", "unit", "needs_data"])
        for c in claims:
            ratio = c["method"] / c["baseline"] if c["baseline"] != 0.0 else math.nan  # NaN stays NaN
            writer.writerow(["chai3d", f"{c['example']} with {c['device']} ({c['backend']}): {c['figure']}, method over "
                             f"baseline ({fmt(c['method'])} / {fmt(c['baseline'])})", "nan", ratio,
                             f"method {c['op']} {c['factor']} x baseline", "pass" if c["pass"] else "FAIL", "ratio", ""])
    print("\n".join(lines))
    return lines


def plot(out, rows):
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("method_vs_baseline.py: no matplotlib; figures skipped", file=sys.stderr)
        return
    for device in sorted({r["device"] for r in rows}):
        mine = [r for r in rows if r["device"] == device]
        groups = sorted({(r["example"], r["backend"]) for r in mine})
        fig, axes = plt.subplots(1, len(FIGURES), figsize=(3.6 * len(FIGURES), 3.6))
        for ax, (name, label) in zip(axes, FIGURES):
            values = {(r["example"], r["backend"]): r for r in mine if r["figure"] == name}
            xs = range(len(groups))
            ax.bar([x - 0.2 for x in xs], [values[g]["method"] if g in values else math.nan for g in groups], 0.4,
                   label="method")
            ax.bar([x + 0.2 for x in xs], [values[g]["baseline"] if g in values else math.nan for g in groups], 0.4,
                   label="baseline")
            ax.set_xticks(list(xs))
            ax.set_xticklabels([f"{e}\n{b}" for e, b in groups], fontsize=6)
            ax.set_title(label, fontsize=8)
            ax.axhline(0.0, color="black", linewidth=0.5)
        axes[0].legend(fontsize=7)
        fig.suptitle(f"{device}: its paper's method against its baseline, the same hand, judged from the plant's truth",
                     fontsize=9)
        fig.tight_layout()
        fig.savefig(os.path.join(out, f"method_vs_baseline_{device}.png"), dpi=110)
        plt.close(fig)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--bin", required=True, help="folder of the relinked examples (uhaptics-chai3d-*)")
    parser.add_argument("--out", required=True)
    parser.add_argument("--example", action="append", help=f"scenes (default: {', '.join(DEFAULT_SCENES)})")
    parser.add_argument("--device", action="append", help="devices (default: every device with a method_off)")
    parser.add_argument("--backend", action="append", help="sim and/or emulated (default: both)")
    parser.add_argument("--seconds", type=float, help="run time of each example (default: the table's)")
    parser.add_argument("--hand-recordings", help="folder of hand recordings to replay (<example>.<device>.csv)")
    args = parser.parse_args()
    table = run_examples.load_table(run_examples.TABLE, args.bin)
    args.example = args.example or DEFAULT_SCENES
    args.device = args.device or [d for d, t in table["devices"].items() if t.get("method_off")]
    backends = args.backend or ["sim", "emulated"]
    os.makedirs(args.out, exist_ok=True)
    pairs = {}
    for backend in backends:
        method = run(args, backend, False, os.path.join(args.out, backend, "method"))
        baseline = run(args, backend, True, os.path.join(args.out, backend, "baseline"))
        for key in sorted(set(method) & set(baseline)):
            example, device = key
            if method[key]["expect"].startswith("none:"):
                continue  # a scene the device's method cannot engage in: nothing to compare
            pairs[(example, device, backend)] = (method[key], baseline[key])
    if not pairs:
        raise SystemExit("method_vs_baseline.py: no run to compare")
    rows, claims = compare(table, pairs)
    write(args.out, table, rows, claims)
    plot(args.out, rows)
    failed = [c for c in claims if not c["pass"]]
    for c in failed:
        print(f"claim missed: {c['example']} with {c['device']} ({c['backend']}): {c['figure']} {fmt(c['method'])} "
              f"not {c['op']} {c['factor']} x {fmt(c['baseline'])}")
    print(f"{len(claims) - len(failed)} passed, {len(failed)} failed")
    return 0 if not failed else 1


if __name__ == "__main__":
    sys.exit(main())
