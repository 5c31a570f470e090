#!/usr/bin/env python3
"""Paper 003, Fig. 11: null-space torque without (a) and with (b) the smooth transition between the
desired ellipsoids, and (c) the saturation observer V and the activation Omega.
Usage: rhi_transition.py transition_smooth.csv transition_abrupt.csv out.png"""
from plot_common import label, plt, read, run, save


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
    label(axes[2], ylabel="V, Omega", title="(c) saturation observer and activation (thresholds 0.7 / 0.95)")
    label(axes[3], xlabel="t [s]", ylabel="force along u [N]")
    save(fig, out)


if __name__ == "__main__":
    run(main, 3, __doc__)
