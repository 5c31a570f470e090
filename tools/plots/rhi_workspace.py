#!/usr/bin/env python3
"""Paper 003, Fig. 10: ratio of the maximum force along u = [0, 1] with the stiff vs the free
desired ellipsoid over the RHI's workspace. Usage: rhi_workspace.py workspace_ratio.csv out.png"""
import math

from plot_common import plt, read, run, save


def main(path, out):
    rows = read(path)
    pts = [(float(r["x"]), float(r["y"]), float(r["ratio"])) for r in rows]
    ok = [p for p in pts if math.isfinite(p[2])]
    fig, ax = plt.subplots(figsize=(7, 6))
    sc = ax.scatter([p[0] for p in ok], [p[1] for p in ok], c=[p[2] for p in ok], cmap="viridis", s=12, marker="s")
    below = [p for p in ok if p[2] <= 1.0]
    if below:
        ax.scatter([p[0] for p in below], [p[1] for p in below], facecolors="none", edgecolors="r", s=30,
                   label=f"ratio <= 1 ({len(below)} of {len(ok)})")
        ax.legend(fontsize=8)
    ax.plot([0.5], [0.1], "w*", ms=12)
    fig.colorbar(sc, ax=ax, label="F_max(stiff) / F_max(free) along u")
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_title("Force-capability ratio over the workspace (star: X0)")
    save(fig, out)


if __name__ == "__main__":
    run(main, 2, __doc__)
