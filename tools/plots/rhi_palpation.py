#!/usr/bin/env python3
"""Paper 003, Fig. 9 / Table I: palpation with the free vs the stiff ellipsoid (rendered force vs
demanded force over the push), and the identification data (force balance fit).
Usage: rhi_palpation.py out_dir out.png"""
import os

from plot_common import label, plt, read, run, save


def main(folder, out):
    fig, axes = plt.subplots(1, 3, figsize=(15, 4.5))
    table = {r["ellipsoid"]: r for r in read(os.path.join(folder, "palpation_table.csv"))}
    for name, color in (("free", "tab:red"), ("stiff", "tab:purple")):
        rows = read(os.path.join(folder, f"palpation_{name}.csv"))
        t = [float(r["t"]) for r in rows]
        t0 = t[0]
        t = [x - t0 for x in t]
        axes[0].plot(t, [float(r["demanded"]) for r in rows], "--", color=color, lw=0.8, label=f"{name}: desired K_e dX")
        axes[0].plot(t, [abs(float(r["force_y"])) for r in rows], color=color, label=f"{name}: rendered")
        for i in range(1, 5):
            axes[1].plot(t, [float(r[f"tau{i}"]) for r in rows], color=color, lw=0.8, alpha=0.4 + 0.15 * i)
    label(axes[0], xlabel="t [s]", ylabel="|F| along u [N]", title="palpation force")
    label(axes[1], xlabel="t [s]", ylabel="joint torque [N m]", title="joint torques (red free, purple stiff)",
          legend=None)
    ident = read(os.path.join(folder, "identification.csv"))
    for name, color in (("free", "tab:red"), ("stiff", "tab:purple")):
        r = table[name]
        m, phi = float(r["inertia_identified_kg"]), float(r["friction_identified_Ns_per_m"])
        pts = [x for x in ident if x["ellipsoid"] == name]
        meas = [float(x["force_u"]) for x in pts]
        fit = [float(x["fitted_force_u"]) for x in pts]
        axes[2].plot(meas, fit, ".", color=color, ms=2,
                     label=f"{name}: M_x {m:.3f} kg (model {float(r['inertia_model_kg']):.3f}), "
                           f"Phi {phi:.2f} N s/m, F_max {float(r['peak_force_N']):.2f} N")
    lo = min([float(x["force_u"]) for x in ident] + [-1.0])
    hi = max([float(x["force_u"]) for x in ident] + [1.0])
    axes[2].plot([lo, hi], [lo, hi], "k:", lw=0.8)
    label(axes[2], xlabel="measured force along u [N]", ylabel="M_x a + Phi v + F_c sign(v) [N]",
          title="identification fit")
    save(fig, out)


if __name__ == "__main__":
    run(main, 2, __doc__)
