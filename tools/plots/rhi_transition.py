#!/usr/bin/env python3
"""Paper 003, Fig. 11: null-space torque without (a) and with (b) the smooth transition between the
desired ellipsoids, and (c) the saturation observer V and the activation Omega.
Usage: rhi_transition.py transition_smooth.csv transition_abrupt.csv out.png"""
import csv
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def read(path):
    with open(path) as f:
        return list(csv.DictReader(f))


def main(smooth_path, abrupt_path, out):
    smooth, abrupt = read(smooth_path), read(abrupt_path)
    fig, axes = plt.subplots(4, 1, figsize=(9, 11), sharex=True)
    for ax, rows, title in ((axes[0], abrupt, "(a) without transition"), (axes[1], smooth, "(b) with transition")):
        t = [float(r["t"]) for r in rows]
        for i in range(1, 5):
            ax.plot(t, [float(r[f"cmd{i}"]) for r in rows], label=f"tau_N{i}")
        ax.set_ylabel("null-space torque [N m]")
        ax.set_title(title)
        ax.legend(fontsize=7, ncol=4)
    for rows, style, name in ((smooth, "-", "with"), (abrupt, ":", "without")):
        t = [float(r["t"]) for r in rows]
        axes[2].plot(t, [float(r["observer"]) for r in rows], "k" + style, label=f"V ({name})")
        axes[2].plot(t, [float(r["omega"]) for r in rows], "b" + style, label=f"Omega ({name})")
        axes[3].plot(t, [float(r["demanded"]) for r in rows], "k" + style, lw=0.8, label=f"desired |F| ({name})")
        axes[3].plot(t, [abs(float(r["force_y"])) for r in rows], "r" + style, label=f"rendered |F| ({name})")
    axes[2].axhline(0.7, color="gray", lw=0.6)
    axes[2].axhline(0.95, color="gray", lw=0.6)
    axes[2].set_ylabel("V, Omega")
    axes[2].set_title("(c) saturation observer and activation (thresholds 0.7 / 0.95)")
    axes[2].legend(fontsize=7)
    axes[3].set_ylabel("force along u [N]")
    axes[3].set_xlabel("t [s]")
    axes[3].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(out, dpi=110)


if __name__ == "__main__":
    if len(sys.argv) != 4:
        sys.exit(__doc__)
    main(*sys.argv[1:])
