"""Figures of uhaptics-zwidth: one per device, the K-B plane at each servo rate (delay 0) with the
measured passivity boundary K_max(B) (with and without the passivity controller) and the analytic
bound of Colgate and Brown K = 2 (b - B) / T drawn beside it as a line; a second panel gives K_max
against the command delay at each rate. With the task-space rows (task_boundaries.csv), one figure per
device, zwidth_task_<device>.png: the wall at the tool's K_max against the servo rate per renderer
(the TAU: spring and LQR wall, the LQR's rendered stiffness beside it) with 2 b_n / T drawn as a line.
Usage: zwidth.py <output folder>."""
import math
import os

from plot_common import plt, read, run, save


def number(row, key):
    return float(row[key])


def device_figure(name, rows, b, out):
    rates = sorted({number(r, "rate_hz") for r in rows})
    fig, (plane, delays) = plt.subplots(1, 2, figsize=(11, 4.5))
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for i, rate in enumerate(rates):
        c = colors[i % len(colors)]
        at = [r for r in rows if number(r, "rate_hz") == rate]
        off = sorted((number(r, "wall_damping"), number(r, "k_max")) for r in at
                     if number(r, "delay") == 0 and number(r, "passivity") == 0 and math.isfinite(number(r, "k_max")))
        on = [(number(r, "wall_damping"), number(r, "k_max")) for r in at
              if number(r, "delay") == 0 and number(r, "passivity") == 1 and math.isfinite(number(r, "k_max"))]
        label = f"{rate:g} Hz"
        if off:
            plane.plot([p[0] for p in off], [p[1] for p in off], "o", color=c, label=f"{label}: measured")
        if on:
            plane.plot([p[0] for p in on], [p[1] for p in on], "^", color=c, mfc="none",
                       label=f"{label}: passivity controller")
        # b identified at this rate's contact frequency (the same for every case at the rate).
        b_rate = number(at[0], "b_identified") if "b_identified" in at[0] else b
        if b_rate > 0:
            bs = [b_rate * k / 50.0 for k in range(51)]
            plane.plot(bs, [2.0 * (b_rate - x) * rate for x in bs], "-", color=c, lw=1,
                       label=f"{label}: 2 (b - B) / T, b = {b_rate:.3g}")
        for passivity, marker, style in ((0, "o", "-"), (1, "^", "--")):
            pts = sorted((number(r, "delay"), number(r, "k_max")) for r in at
                         if number(r, "wall_damping") == 0 and number(r, "passivity") == passivity
                         and math.isfinite(number(r, "k_max")))
            if pts:
                delays.plot([p[0] for p in pts], [p[1] for p in pts], marker + style, color=c,
                            mfc="none" if passivity else c,
                            label=f"{label}{', passivity controller' if passivity else ''}")
    plane.set_yscale("log")
    plane.set_xlabel("wall damping B (N m s/rad)")
    plane.set_ylabel("K_max (N m/rad)")
    plane.set_title(f"{name}: passive region, delay 0")
    if plane.get_legend_handles_labels()[0]:
        plane.legend(fontsize=6)
    delays.set_yscale("log")
    delays.set_xlabel("command delay (servo periods)")
    delays.set_ylabel("K_max (N m/rad), B = 0")
    delays.set_title(f"{name}: delay")
    if delays.get_legend_handles_labels()[0]:
        delays.legend(fontsize=6)
    save(fig, os.path.join(out, f"zwidth_{name}.png"))
    plt.close(fig)


def finite(x):
    return math.isfinite(x) and x > 0


def task_figure(name, rows, out):
    fig, ax = plt.subplots(figsize=(6.5, 4.5))
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    at0 = [r for r in rows if number(r, "delay") == 0]
    bound = sorted({(number(r, "rate_hz"), number(r, "bound")) for r in at0 if finite(number(r, "bound"))})
    if bound:
        ax.plot([b[0] for b in bound], [b[1] for b in bound], "-", color="0.4", lw=1,
                label="2 b_n / T (b_n identified)")
    renderers = []
    for r in at0:
        if r["renderer"] not in renderers:
            renderers.append(r["renderer"])
    for i, renderer in enumerate(renderers):
        c = colors[i % len(colors)]
        pts = sorted((number(r, "rate_hz"), number(r, "k_max")) for r in at0 if r["renderer"] == renderer
                     and finite(number(r, "k_max")))
        if pts:
            ax.plot([p[0] for p in pts], [p[1] for p in pts], "o-", color=c, label=f"{renderer}: K_max (passive)")
        if renderer != "spring":
            stable = sorted((number(r, "rate_hz"), number(r, "k_stable")) for r in at0
                            if r["renderer"] == renderer and finite(number(r, "k_stable")))
            rendered = sorted((number(r, "rate_hz"), number(r, "rendered_stable")) for r in at0
                              if r["renderer"] == renderer and finite(number(r, "rendered_stable")))
            if stable:
                ax.plot([p[0] for p in stable], [p[1] for p in stable], "s", color=c, mfc="none",
                        label=f"{renderer}: scene K, no bounce")
            if rendered:
                ax.plot([p[0] for p in rendered], [p[1] for p in rendered], "*", color=c, ms=10,
                        label=f"{renderer}: stiffness it renders there")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("servo rate (Hz)")
    ax.set_ylabel("wall stiffness at the tool (N/m)")
    ax.set_title(f"{name}: task-space Z-width, delay 0")
    if ax.get_legend_handles_labels()[0]:
        ax.legend(fontsize=7, loc="lower right")
    save(fig, os.path.join(out, f"zwidth_task_{name}.png"))
    plt.close(fig)


def main(out):
    joint = os.path.join(out, "boundaries.csv")
    if os.path.exists(joint):
        boundaries = read(joint)
        devices = {r["device"]: r for r in read(os.path.join(out, "devices.csv"))}
        for name, dev in devices.items():
            rows = [r for r in boundaries if r["device"] == name]
            if rows:
                device_figure(name, rows, float(dev["b_identified"]), out)
    task = os.path.join(out, "task_boundaries.csv")
    if os.path.exists(task):
        rows = read(task)
        for name in sorted({r["device"] for r in rows}):
            task_figure(name, [r for r in rows if r["device"] == name], out)


run(main, 1, __doc__)
