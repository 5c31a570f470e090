"""What every figure script shares: a headless matplotlib, CSV rows as dicts, saving, and the
command line (usage from the script's docstring when the argument count is wrong)."""
import csv
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402,F401  (re-exported for the scripts)


def read(path):
    """Rows of a CSV file as dicts (header -> string value)."""
    with open(path) as f:
        return list(csv.DictReader(f))


def save(fig, out, dpi=110):
    fig.tight_layout()
    fig.savefig(out, dpi=dpi)


def run(main, nargs, doc):
    """Calls main(*argv[1:]) when there are nargs arguments, else exits with the usage in doc."""
    if len(sys.argv) != nargs + 1:
        sys.exit(doc)
    main(*sys.argv[1:])


def label(ax, xlabel=None, ylabel=None, title=None, legend=7):
    """Axis labels, title and a legend (font size `legend`; None: no legend)."""
    if xlabel:
        ax.set_xlabel(xlabel)
    if ylabel:
        ax.set_ylabel(ylabel)
    if title:
        ax.set_title(title)
    if legend:
        ax.legend(fontsize=legend)
