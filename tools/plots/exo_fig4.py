"""Fig. 4 of paper 000 from uhaptics-exo-fig4's CSV: exo_fig4.py <exo_fig4.csv> <out.png>."""
import csv
import math
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

METHODS = [("standard", "standard"), ("nullspace", "null-space"),
           ("subspace_lin", "subspace (linearized)"), ("subspace_nl", "subspace (nonlinear)")]
STYLES = {"standard": dict(color="tab:red"), "nullspace": dict(color="tab:orange"),
          "subspace_lin": dict(color="tab:blue"), "subspace_nl": dict(color="black", linestyle="--")}


def main(path, png):
    with open(path) as f:
        rows = list(csv.DictReader(f))
    col = lambda k: [float(r[k]) for r in rows]
    t = col("t_s")
    fig, ax = plt.subplots(1, 4, figsize=(18, 4.2))
    ax[0].plot(t, [math.degrees(v) for v in col("mcp_rad")], label="MCP")
    ax[0].plot(t, [math.degrees(v) for v in col("pip_rad")], label="PIP")
    ax[0].set_title("joint angles")
    ax[0].set_ylabel("deg")
    for key, name in METHODS:
        ax[1].plot(t, col(key + "_force_N"), label=name, **STYLES[key])
        ax[2].plot(t, col(key + "_theory_N_per_m"), label=name, **STYLES[key])
        fd = col(key + "_fd_N_per_m")
        ax[3].plot(t, fd, ".", markersize=1.5, label=name, **{k: v for k, v in STYLES[key].items() if k == "color"})
    ax[1].set_title("actuator force (Z_q = 1 N/m)")
    ax[1].set_ylabel("N")
    ax[2].set_title("displayed impedance, theory (eq. 2, 5, 9)")
    ax[2].set_ylabel("d tau_a / d l_x  [N/m]")
    ax[3].set_title("displayed impedance, finite differences")
    ax[3].set_ylabel("Delta tau_a / Delta l_x  [N/m]")
    ax[3].set_yscale("symlog", linthresh=1.0)
    for a in ax:
        a.set_xlabel("t [s]")
        a.grid(alpha=0.3)
    for a in ax[2:]:
        a.axhline(0.0, color="grey", linewidth=0.8)
    ax[0].legend(loc="upper right")
    ax[1].legend(loc="lower right", fontsize=8)
    ax[3].legend(loc="upper right", fontsize=8, markerscale=6)
    fig.tight_layout()
    fig.savefig(png, dpi=110)


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
