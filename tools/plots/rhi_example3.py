#!/usr/bin/env python3
"""Paper 003, Fig. 3-4: the 3-DoF example. Top: joint torques and output force at the initial,
free-optimized and stiff-optimized configurations. Bottom: the arm and its FME in each, with the
desired ellipsoids. Usage: rhi_example3.py torques.csv configurations.csv out.png"""
import numpy as np

from plot_common import label, plt, read, run, save


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
        label(ax, xlabel="t [s]", ylabel="N m", title=f"{title}: joint torques")
        ax = axes[1, col]
        ax.plot(t, [float(r["demanded_fx"]) for r in ts], "k--", label="F_e desired")
        ax.plot(t, [float(r[f"{key}_fx"]) for r in ts], label="F output")
        label(ax, xlabel="t [s]", ylabel="N", title=f"{title}: output force along x")
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
    label(ax, title="configurations and FMEs (scaled)")
    for k in (1, 2):
        axes[2, k].axis("off")
    lines = [f"{c['config']}: peak force {float(c['peak_force']):.2f} N, min alpha {float(c['min_alpha']):.2f}, "
             f"nu {float(c['nu']):.3f}" for c in cs]
    axes[2, 1].text(0.0, 0.5, "\n".join(lines), fontsize=10, va="center")
    fig.suptitle("Paper 003 3-DoF example: F_e = [3.5 sin(pi t / 2), 0] N, |tau_i| <= 0.5 N m")
    save(fig, out)


if __name__ == "__main__":
    run(main, 3, __doc__)
