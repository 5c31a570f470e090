#!/usr/bin/env python3
"""Generated bad-input suite for the command-line tools (issue 20).

Each tool lists its options with --list-options (tools/common: uhaptics/tools/cli.hpp). For every
numeric option the suite tries NaN, +-inf, negative, zero, huge, non-integral, non-numbers and the
empty string (skipping those the option accepts); for every path option a missing path, a folder
where a file is expected and a file where a folder is, a path that cannot be written and the empty
string; then a few hand-picked cases whose values pass the per-option rule but not the tool's own
checks (a pose outside the workspace, malformed reproduction tables). Every case must end with a
non-zero exit below 128 (no signal, no abort), a message naming the option (or the file and row),
within the timeout, and with nothing written into the scratch folder it ran in.

Usage: bad_input_test.py TOOL...   (paths of the uhaptics-* programs)
"""
import concurrent.futures
import json
import math
import os
import subprocess
import sys
import tempfile

TIMEOUT_S = 20.0
NUMBERS = ["nan", "NaN", "inf", "-inf", "-1", "-5", "0", "1e308", "-1e308", "100000", "1.5",
           "99999999999999999999", "abc", "1,5", "0x", " 1", ""]


def accepted(kind, text, lo, hi):
    """Whether the option's own rule takes `text` (then the case is not a bad input)."""
    lo = -math.inf if lo is None else lo
    hi = math.inf if hi is None else hi
    if text != text.strip() or not text:
        return False
    try:
        v = int(text, 10) if kind == "integer" else float(text)
    except ValueError:
        return False
    return math.isfinite(v) and lo <= v <= hi


def good_value(option):
    lo, hi = option.get("min"), option.get("max")
    if option["kind"] == "integer":
        return str(int(lo if lo is not None else 0))
    return repr(float(lo)) if lo is not None else "0"


def cases_for(tool, scratch_file, scratch_dir):
    listing = subprocess.run([tool, "--list-options"], capture_output=True, text=True, timeout=TIMEOUT_S)
    if listing.returncode != 0:
        raise SystemExit(f"{tool} --list-options: exit {listing.returncode}: {listing.stderr}")
    options = json.loads(listing.stdout)["options"]
    cases, problems = [], []
    for o in options:
        name, kind = o["name"], o["kind"]
        if kind == "unchecked":
            problems.append(f"{os.path.basename(tool)}: {name} takes a value outside the shared rule "
                            "(add it through tools::CommandLine)")
            continue
        rest = []
        if o.get("count", 1) > 1:
            rest = [good_value(o)] * (o["count"] - 1)
        if kind in ("real", "integer"):
            for text in NUMBERS:
                if not accepted(kind, text, o.get("min"), o.get("max")):
                    cases.append(([name, text] + rest, name))
        missing = os.path.join(scratch_dir, "does-not-exist", "x")
        under_file = os.path.join(scratch_file, "sub")  # a file's child: cannot be created, even by root
        if kind == "input-file":
            for p in (missing, scratch_dir, ""):
                cases.append(([name, p], name))
        elif kind == "input-folder":
            for p in (missing, scratch_file, ""):
                cases.append(([name, p], name))
        elif kind == "output-folder":
            for p in (scratch_file, under_file, ""):
                cases.append(([name, p], name))
        elif kind == "output-file":
            for p in (scratch_dir, under_file, ""):
                cases.append(([name, p], name))
    return [(tool, args, expect) for args, expect in cases], problems


def run_case(tool, args, expect, files=None):
    """Runs one case in a fresh folder; returns a problem description or None."""
    with tempfile.TemporaryDirectory(prefix="uh-bad-input-") as cwd:
        for rel, content in (files or {}).items():
            path = os.path.join(cwd, rel)
            os.makedirs(os.path.dirname(path), exist_ok=True)
            if content is None:
                os.makedirs(path, exist_ok=True)
            else:
                with open(path, "w") as f:
                    f.write(content)
        before = sorted(os.walk(cwd))
        label = f"{os.path.basename(tool)} {' '.join(repr(a) for a in args)}"
        try:
            r = subprocess.run([tool] + [a.replace("{cwd}", cwd) for a in args], cwd=cwd, capture_output=True,
                               text=True, timeout=TIMEOUT_S, stdin=subprocess.DEVNULL)
        except subprocess.TimeoutExpired:
            return f"{label}: no answer within {TIMEOUT_S:.0f} s (hang)"
        if r.returncode < 0:
            return f"{label}: killed by signal {-r.returncode}\n{r.stderr}"
        if r.returncode == 0 or r.returncode >= 128:
            return f"{label}: exit {r.returncode} (want 1..127)\n{r.stderr}"
        if expect.replace("{cwd}", cwd) not in r.stderr:
            return f"{label}: message does not name {expect!r}: {r.stderr.strip()!r}"
        if sorted(os.walk(cwd)) != before:
            return f"{label}: wrote into its folder although it refused the input"
    return None


ROWS_HEADER = "paper,quantity,published,measured,criterion,pass,unit,needs_data,accepts\n"


def hand_picked(tools):
    by_name = {os.path.basename(t): t for t in tools}
    cases = []
    if "uhaptics-tau-design" in by_name:
        t = by_name["uhaptics-tau-design"]
        cases.append((t, ["--pose", "0.5", "0", "0", "0", "0", "0"], "--pose", None))  # outside the 50 mm cube
        cases.append((t, ["--pose", "0", "0", "0", "1e308", "0", "0"], "--pose", None))
    if "uhaptics-report" in by_name:
        t = by_name["uhaptics-report"]
        good = "000,q,1,1,|m-p| <= 0,pass,,,\"[1, 1]\"\n"
        for what, files, expect in [
            ("empty", {"out/x/reproduction.csv": ""}, "reproduction.csv"),
            ("garbage", {"out/x/reproduction.csv": "\x00\x01garbage\n"}, "reproduction.csv"),
            ("folder", {"out/x/reproduction.csv": None}, "reproduction.csv"),
            ("header only", {"out/x/reproduction.csv": ROWS_HEADER}, "reproduction.csv"),
            ("non-numeric", {"out/x/reproduction.csv": ROWS_HEADER + good.replace(",1,1,", ",1,abc,")}, "row 1"),
            ("short row", {"out/x/reproduction.csv": ROWS_HEADER + "000,q,1\n"}, "row 1"),
            ("wrong verdict", {"out/x/reproduction.csv": ROWS_HEADER + good + good.replace(",1,1,", ",1,2,")},
             "row 2"),
            ("bad interval", {"out/x/reproduction.csv": ROWS_HEADER + good.replace("[1, 1]", "[2, 1]")}, "row 1"),
        ]:
            cases.append((t, ["--out", "{cwd}/out"], expect, files))
    if "uhaptics-replay" in by_name:
        t = by_name["uhaptics-replay"]
        header = ("# uhaptics hand recording\n# format_version: 1\n# workspace_radius_m: 0.025\n"
                  "time_s,anchor_x,anchor_y,anchor_z,anchor_vx,anchor_vy,anchor_vz,grip_stiffness_N_per_m,"
                  "grip_damping_N_s_per_m,grip_max_force_N,scene_fx_N,scene_fy_N,scene_fz_N,scene_x,scene_y,scene_z\n")
        row = "0,0,0,0.5,0,0,-0.75,1500,20,12,0,0,0,0,0,0.5\n"
        good = header + row + row.replace("0,", "0.01,", 1)
        run = ["--program", "{cwd}/program", "--recording", "{cwd}/hand.csv", "--device"]
        tau = ["tau"]
        for what, recording, extra, expect in [
            ("wrong version", header.replace("version: 1", "version: 9"), tau, "hand.csv:2: format_version"),
            ("one row", header + row, tau, "hand.csv:5: rows"),
            ("bad grip", header + row + row.replace("1500", "-1").replace("0,", "0.01,", 1), tau,
             "hand.csv:6: grip_stiffness_N_per_m"),
            ("unknown device", good, ["no-such-device"], "no-such-device"),
            ("bad check", good, tau + ["--expect", "method.max_true_penetration_mm~1"], "--expect"),
            ("baseline check without the baseline", good, tau + ["--expect", "baseline.chatter_N<1"], "--baseline"),
            ("bad device option", good, tau + ["--option", "wall"], "--option"),
        ]:
            cases.append((t, run + extra, expect, {"program": "#!/bin/sh\n", "hand.csv": recording}))
    return cases


def main():
    tools = [os.path.abspath(t) for t in sys.argv[1:]]
    if not tools:
        raise SystemExit(__doc__)
    with tempfile.TemporaryDirectory(prefix="uh-bad-input-fixtures-") as fixtures:
        scratch_file = os.path.join(fixtures, "a-file")
        with open(scratch_file, "w") as f:
            f.write("not a folder\n")
        scratch_dir = os.path.join(fixtures, "a-folder")
        os.makedirs(scratch_dir)
        cases, problems = [], []
        for tool in tools:
            c, p = cases_for(tool, scratch_file, scratch_dir)
            cases += [(t, a, e, None) for t, a, e in c]
            problems += p
        cases += hand_picked(tools)
        workers = max(2, (os.cpu_count() or 2) * 2)
        with concurrent.futures.ThreadPoolExecutor(workers) as pool:
            for problem in pool.map(lambda c: run_case(*c), cases):
                if problem:
                    problems.append(problem)
    print(f"bad-input suite: {len(cases)} cases on {len(tools)} tools, {len(problems)} problems")
    for p in problems:
        print("  " + p)
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
