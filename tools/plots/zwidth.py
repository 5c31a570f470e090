"""Figures of uhaptics-zwidth: one per device, the K-B plane at each servo rate (delay 0) with the
measured passivity boundary K_max(B) (with and without the passivity controller) and the analytic
bound of Colgate and Brown K = 2 (b - B) / T drawn beside it as a line; a second panel gives K_max
against the command delay at each rate. Usage: zwidth.py <output folder>."""
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


def main(out):
    boundaries = read(os.path.join(out, "boundaries.csv"))
    devices = {r["device"]: r for r in read(os.path.join(out, "devices.csv"))}
    for name, dev in devices.items():
        rows = [r for r in boundaries if r["device"] == name]
        if rows:
            device_figure(name, rows, float(dev["b_identified"]), out)


run(main, 1, __doc__)
