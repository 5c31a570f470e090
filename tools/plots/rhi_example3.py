#!/usr/bin/env python3
"""Paper 003, Fig. 3-4: the 3-DoF example. Top: joint torques and output force at the initial,
free-optimized and stiff-optimized configurations. Bottom: the arm and its FME in each, with the
desired ellipsoids. Usage: rhi_example3.py torques.csv configurations.csv out.png"""
import csv
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402


def read(path):
    with open(path) as f:
        return list(csv.DictReader(f))


def ellipse(ax, center, xx, xy, yy, scale, **kw):
    w, v = np.linalg.eigh(np.array([[xx, xy], [xy, yy]]))
    t = np.linspace(0, 2 * np.pi, 100)
    pts = v @ np.diag(np.sqrt(w)) @ np.vstack([np.cos(t), np.sin(t)]) * scale
    ax.plot(center[0] + pts[0], center[1] + pts[1], **kw)


def main(torques, configs, out):
    ts = read(torques)
    cs = read(configs)
    t = [float(r["t"]) for r in ts]
    fig, axes = plt.subplots(3, 3, figsize=(13, 10))
    for col, (key, title) in enumerate([("init", "initial"), ("free", "free-optimized"), ("stiff", "stiff-optimized")]):
        ax = axes[0, col]
        for i in range(1, 4):
            ax.plot(t, [float(r[f"{key}_tau{i}"]) for r in ts], label=f"tau{i}")
        ax.axhline(0.5, color="k", ls=":", lw=0.8)
        ax.axhline(-0.5, color="k", ls=":", lw=0.8)
        ax.set_title(f"{title}: joint torques")
        ax.set_xlabel("t [s]")
        ax.set_ylabel("N m")
        ax.legend(fontsize=7)
        ax = axes[1, col]
        ax.plot(t, [float(r["demanded_fx"]) for r in ts], "k--", label="F_e desired")
        ax.plot(t, [float(r[f"{key}_fx"]) for r in ts], label="F output")
        ax.set_title(f"{title}: output force along x")
        ax.set_xlabel("t [s]")
        ax.set_ylabel("N")
        ax.legend(fontsize=7)
    ax = axes[2, 0]
    colors = {"initial": "tab:blue", "free": "tab:red", "stiff": "tab:purple"}
    for c in cs:
        xs = [float(c[f"x{i}"]) for i in range(4)]
        ys = [float(c[f"y{i}"]) for i in range(4)]
        ax.plot(xs, ys, "o-", color=colors[c["config"]], label=c["config"])
        ellipse(ax, (xs[-1], ys[-1]), float(c["fme_xx"]), float(c["fme_xy"]), float(c["fme_yy"]), 0.03,
                color=colors[c["config"]])
    c0 = cs[0]
    xe, ye = float(c0["x3"]), float(c0["y3"])
    ellipse(ax, (xe, ye), float(c0["des_free_xx"]), float(c0["des_free_xy"]), float(c0["des_free_yy"]), 0.03,
            color="g", ls="--", label="desired free")
    ellipse(ax, (xe, ye), float(c0["des_stiff_xx"]), float(c0["des_stiff_xy"]), float(c0["des_stiff_yy"]), 0.03,
            color="g", ls=":", label="desired stiff")
    ax.set_aspect("equal")
    ax.set_title("configurations and FMEs (scaled)")
    ax.legend(fontsize=7)
    for k in (1, 2):
        axes[2, k].axis("off")
    lines = [f"{c['config']}: peak force {float(c['peak_force']):.2f} N, min alpha {float(c['min_alpha']):.2f}, "
             f"nu {float(c['nu']):.3f}" for c in cs]
    axes[2, 1].text(0.0, 0.5, "\n".join(lines), fontsize=10, va="center")
    fig.suptitle("Paper 003 3-DoF example: F_e = [3.5 sin(pi t / 2), 0] N, |tau_i| <= 0.5 N m")
    fig.tight_layout()
    fig.savefig(out, dpi=110)


if __name__ == "__main__":
    if len(sys.argv) != 4:
        sys.exit(__doc__)
    main(*sys.argv[1:])
