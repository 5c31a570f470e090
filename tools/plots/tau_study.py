"""Figures of uhaptics-tau-study (paper 001): heat maps over the wall (Fig. 10, 12, 13 style) and
one trace per scenario (Fig. 8, 9 style). Usage: tau_study.py <output folder>."""
import csv
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def read(path):
    with open(path) as f:
        rows = list(csv.DictReader(f))
    return {k: [float(r[k]) for r in rows] for k in rows[0]}


def heatmap(data, column_lqr, column_spring, title, path):
    xs = sorted(set(data["x_mm"]))
    ys = sorted(set(data["y_mm"]))
    fig, axes = plt.subplots(2, 1, figsize=(5.5, 8))
    for ax, col, name in ((axes[0], column_lqr, "LQR position control"), (axes[1], column_spring, "spring wall 6000 N/m")):
        grid = [[0.0] * len(xs) for _ in ys]
        for x, y, v in zip(data["x_mm"], data["y_mm"], data[col]):
            grid[ys.index(y)][xs.index(x)] = v
        im = ax.imshow(grid, origin="lower", extent=[xs[0], xs[-1], ys[0], ys[-1]], aspect="equal", cmap="viridis")
        fig.colorbar(im, ax=ax, label="N/m")
        ax.set_title(f"{title}: {name}")
        ax.set_xlabel("x (mm)")
        ax.set_ylabel("y (mm)")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main():
    out = sys.argv[1]
    data = read(os.path.join(out, "points.csv"))
    heatmap(data, "lqr_s1_k_z1", "spring_s1_k_z1", "mean K_z1, scenario 1", os.path.join(out, "kz1_s1.png"))
    heatmap(data, "lqr_s1_k_zs", "spring_s1_k_zs", "mean K_zs, scenario 1", os.path.join(out, "kzs_s1.png"))
    heatmap(data, "lqr_s2_k_zs", "spring_s2_k_zs", "mean K_zs, scenario 2", os.path.join(out, "kzs_s2.png"))
    for s in (1, 2):
        t = read(os.path.join(out, f"trace_s{s}.csv"))
        fig, (a, b) = plt.subplots(2, 1, figsize=(7, 6), sharex=True)
        a.plot(t["t"], t["force_n"], lw=0.6)
        a.set_ylabel("push toward wall (N)")
        b.plot(t["t"], t["lqr_z_mm"], label="LQR")
        b.plot(t["t"], t["spring_z_mm"], label="spring 6000 N/m")
        b.set_ylabel("tool z (mm)")
        b.set_xlabel("t (s)")
        b.legend()
        a.set_title(f"scenario {s} at the workspace centre")
        fig.tight_layout()
        fig.savefig(os.path.join(out, f"trace_s{s}.png"), dpi=110)
        plt.close(fig)


if __name__ == "__main__":
    main()
