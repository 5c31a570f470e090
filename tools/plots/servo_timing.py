"""Histogram of the servo loop's measured period and wake-up latency (uhaptics-servo).
Usage: servo_timing.py <timing_histogram.csv> <out.png> <title> <nominal period us>"""
import csv
import sys

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt


def main():
    path, png, title, nominal = sys.argv[1], sys.argv[2], sys.argv[3], float(sys.argv[4])
    bins, period, latency = [], [], []
    with open(path) as f:
        for row in csv.DictReader(f):
            bins.append(float(row["bin_us"]))
            period.append(int(float(row["period_count"])))
            latency.append(int(float(row["wake_latency_count"])))
    fig, axes = plt.subplots(1, 2, figsize=(11, 4))
    for ax, counts, label in ((axes[0], period, "period"), (axes[1], latency, "wake-up latency (jitter)")):
        ax.bar(bins, counts, width=1.0, color="tab:blue")
        ax.set_yscale("log")
        ax.set_xlabel(label + " [us]")
        ax.set_ylabel("cycles")
        ax.set_title(label)
    axes[0].axvline(nominal, color="tab:red", linestyle="--", label="nominal")
    axes[0].legend()
    fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(png, dpi=120)


if __name__ == "__main__":
    main()
