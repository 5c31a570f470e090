#!/usr/bin/env python3
"""Runs CHAI3D's own examples, unchanged and relinked with the uhaptics slot, headless under Xvfb
with each uhaptics device, and checks from the device's session statistics that the device's own
rendering method did its work in that scene (examples.json gives the scenes and the hand's paths;
each device's devices/<folder>/chai3d/dropin.json what it must show in each scene).

  run_examples.py --bin DIR [--example NAME ...] [--device NAME ...] [--backend sim|emulated]
                  [--option DEVICE/NAME=VALUE ...] [--out DIR] [--screenshots] [--report]
  run_examples.py --bin DIR --example NAME --reject     (an invalid selection must be refused)
  run_examples.py ... --method-off                      (the device's dropin.json "method_off" options
                                                         switch its paper's method off: the scene's rule
                                                         must fail, the run otherwise hold)
  run_examples.py ... --record DIR                      (each run writes its scripted hand's side to
                                                         DIR/<example>.<device>.csv: docs/recording.md)
  run_examples.py ... --hand-recordings DIR             (a run whose DIR/<example>.<device>.csv exists
                                                         replays that hand instead of the scene's path)

Each run: the example starts with UHAPTICS_DEVICE, UHAPTICS_STATS and UHAPTICS_CONFIG (the
scripted hand's path for that scene) in its environment and is ended after its time (the examples
run until a key is pressed). With --screenshots the X display is captured once while the device
reports contact. With --report the folder gets dropin.csv, dropin.md, reproduction.csv (for
uhaptics-report) and summary.txt. Exit status: 0 when every run shows what its device's
dropin.json expects, 1 otherwise, 2 on a usage error or a missing program.
"""
import argparse
import csv
import json
import math
import os
import shutil
import signal
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
TABLE = os.path.join(HERE, "examples.json")
STARTUP_GRACE = 30.0  # [s] beyond an example's time before a run counts as hung


def load_json(path):
    with open(path) as f:
        data = json.load(f)
    if data.get("format_version") != 1:
        raise SystemExit(f"{path}: format_version 1 expected")
    return data


def load_table(path, bin_dir):
    """The examples (examples.json) and, per registered device, what it must show in them: the build
    writes uhaptics-devices.json (device name -> its devices/<folder>/chai3d/dropin.json)."""
    table = load_json(path)
    registry = os.path.join(bin_dir, "uhaptics-devices.json")
    with open(registry) as f:
        files = json.load(f)
    table["devices"] = {name: load_json(rules) for name, rules in files.items()}
    return table


class Display:
    """A private Xvfb server (a free display number chosen by Xvfb itself)."""

    def __init__(self):
        xvfb = shutil.which("Xvfb")
        if xvfb is None:
            raise SystemExit("run_examples.py: Xvfb not found (apt-get install xvfb)")
        read_fd, write_fd = os.pipe()
        self.proc = subprocess.Popen(
            [xvfb, "-displayfd", str(write_fd), "-screen", "0", "1280x960x24", "-nolisten", "tcp"],
            pass_fds=(write_fd,), stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        os.close(write_fd)
        number = b""
        deadline = time.monotonic() + 20
        while not number.endswith(b"\n") and time.monotonic() < deadline:
            chunk = os.read(read_fd, 16)
            if not chunk:
                break
            number += chunk
        os.close(read_fd)
        if not number.strip():
            self.close()
            raise SystemExit("run_examples.py: Xvfb did not start")
        self.name = ":" + number.decode().strip()

    def screenshot(self, path):
        grabber = shutil.which("import")  # ImageMagick
        if grabber is None:
            return False
        result = subprocess.run([grabber, "-display", self.name, "-window", "root", path],
                                stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, timeout=30)
        return result.returncode == 0 and os.path.exists(path)

    def close(self):
        if self.proc.poll() is None:
            self.proc.terminate()
            try:
                self.proc.wait(5)
            except subprocess.TimeoutExpired:
                self.proc.kill()


def read_stats(path):
    try:
        with open(path) as f:
            return json.load(f)
    except (OSError, ValueError):
        return None


def scene_rules(table, example, device):
    """The device's entry for this example (expect, why, hand), empty for a device without rules; an
    entry under the backend's name (e.g. "emulated") overrides it on that backend."""
    rules = dict(table["devices"].get(device, {}).get("scenes", {}).get(example["name"], {}))
    rules.update(rules.pop(ARGS.backend, {}) if "ARGS" in globals() else {})
    for backend in ("sim", "emulated", "usb"):
        rules.pop(backend, None)
    return rules


def parse_options(items):
    """--option DEVICE/NAME=VALUE -> {device: {name: value}} (the config's "options")."""
    options = {}
    for item in items or []:
        key, sep, value = item.partition("=")
        device, slash, name = key.partition("/")
        if not sep or not slash or not device or not name:
            raise SystemExit(f"run_examples.py: --option {item!r}: expected DEVICE/NAME=VALUE")
        options.setdefault(device, {})[name] = float(value)
    return options


def hand_config(table, example, device):
    """The UHAPTICS_CONFIG file content: the scripted hand's path for this scene and device, and
    the device options given with --option."""
    hand = dict(example.get("hand", {}))
    hand.update(scene_rules(table, example, device).get("hand", {}))
    waypoints = hand.pop("waypoints", None)
    config = {"device": "chai3d-selection", "format_version": 1, "hand": hand}
    options = parse_options(ARGS.option)
    if ARGS.method_off:
        off = table["devices"][device].get("method_off")
        if not off:
            raise SystemExit(f"run_examples.py: {device}'s dropin.json has no \"method_off\" options")
        options.setdefault(device, {}).update(off)
    if options:
        config["options"] = options
    if waypoints is not None:
        config["hand"]["waypoint_count"] = len(waypoints)
        config["hand"]["waypoints"] = [c for point in waypoints for c in point]
    recording = hand_recording(example, device)
    if recording:
        config["hand"]["recording"] = recording
    if ARGS.record:
        config["record"] = os.path.join(ARGS.record, recording_name(example, device))
    return config


def recording_name(example, device):
    """The file a scene's hand recording with a device has (docs/recording.md)."""
    return f"{example['name']}.{device}.csv"


def hand_recording(example, device):
    """The recording this run replays (--hand-recordings), None for the scene's scripted path."""
    if not ARGS.hand_recordings:
        return None
    path = os.path.join(ARGS.hand_recordings, recording_name(example, device))
    return path if os.path.exists(path) else None


def figure(stats, name):
    """A renderer figure or a session statistic by name, "referee.NAME" one of the referee's figures
    (the plant's truth: docs/chai3d.md, "The referee"); "a/b" is their ratio (e.g. the share of
    the contact ticks the LQR wall held: lqr_held_ticks/contact_ticks)."""
    if "/" in name:
        top, bottom = (figure(stats, part) for part in name.split("/", 1))
        return top / bottom if bottom > 0 else math.nan
    if name.startswith("referee."):
        value = (stats.get("referee") or {}).get(name[len("referee."):])
        return float(value) if isinstance(value, (int, float)) else math.nan
    value = stats.get("renderer_figures", {}).get(name, stats.get(name))
    return float(value) if isinstance(value, (int, float)) else math.nan


def check(table, example, device, stats, backend):
    """What failed (empty list: the run shows what it must), and the expectation applied."""
    expectation = scene_rules(table, example, device).get("expect", "engaged")
    if stats is None:
        return ["the device wrote no statistics: the application did not open it"], expectation
    problems = []
    if stats.get("device") != device or stats.get("backend") != backend:
        problems.append(f"statistics are from {stats.get('device')} on {stats.get('backend')}")
    rules = table["rules"]
    # The device opens after the window and GL context exist (about 1 s under Xvfb); the haptic
    # thread shares 2 cores with Xvfb's software GL, so half the nominal rate is the floor.
    if stats["ticks"] < rules["min_ticks"] or stats["rate_hz"] < rules["min_rate_hz"]:
        problems.append(f"only {stats['ticks']} servo ticks ({stats['rate_hz']:.0f} Hz)")
    if stats["faults"] > 0:
        problems.append(f"{stats['faults']} faulted ticks")
    cannot_engage = expectation.startswith("none:")
    needs_force = example.get("forces", example.get("contact", True)) and not cannot_engage
    if needs_force and (stats["peak_force_N"] < rules["min_peak_force_N"] or stats["peak_output"] == 0):
        problems.append(f"no force rendered (peak {stats['peak_force_N']} N)")
    if cannot_engage or not example.get("contact", True):
        return problems, expectation  # nothing the device's method can engage in: ticks, no faults
    if stats["contacts"] < 1:
        problems.append("the scripted hand never touched the scene (0 contacts)")
    # "a|b": the run must satisfy one of the rules (a scene at a rule's boundary); the statistics
    # say which one it did.
    misses = []
    for rule in expectation.split("|"):
        missed = []
        for name, (op, bound) in table["devices"][device]["engagement"][rule].items():
            value = figure(stats, name)
            ok = (value >= bound) if op == ">=" else (value <= bound) if op == "<=" else (value == bound)
            if not ok or math.isnan(value):
                missed.append(f"{name} = {value} (expected {op} {bound} for '{rule}')")
        if not missed:
            return problems, rule
        misses += missed
    return problems + misses, expectation


def run_one(table, example, device, backend, display, out, screenshots, reject=False):
    name = example["name"]
    tag = f"{name}-{device}" + ("" if backend == "sim" else f"-{backend}") + ("-method-off" if ARGS.method_off else "")
    stats_path = os.path.join(out, tag + ".json")
    config_path = os.path.join(out, tag + ".config.json")
    shot_path = os.path.join(out, tag + ".png")
    for path in (stats_path, shot_path):
        if os.path.exists(path):
            os.remove(path)
    with open(config_path, "w") as f:
        json.dump(hand_config(table, example, device), f, indent=1)
    # Under Xvfb (no vsync) an example draws as fast as it can, and Mesa's software renderer spreads
    # each frame over every core: one rendering thread leaves the other core to the device's haptic
    # and servo threads and to whatever runs beside the scene (the caller may set another count).
    env_base = dict(os.environ)
    env_base.setdefault("LP_NUM_THREADS", "1")
    env = dict(env_base, DISPLAY=display.name, UHAPTICS_DEVICE=device, UHAPTICS_BACKEND=backend,
               UHAPTICS_STATS=stats_path, UHAPTICS_CONFIG=config_path)
    seconds = ARGS.seconds if ARGS.seconds else float(example["seconds"])
    exe = os.path.join(ARGS.bin, "uhaptics-chai3d-" + name)
    log_path = os.path.join(out, tag + ".log")
    with open(log_path, "w") as log:
        proc = subprocess.Popen([exe], env=env, stdout=log, stderr=subprocess.STDOUT, cwd=out)
        start = time.monotonic()
        shot = {"taken": False, "in_contact": False}
        ended_early = None
        rejection = f"uhaptics: invalid device selection: UHAPTICS_DEVICE = '{device}'"
        # A run that must be refused lasts its time and until the refusal is printed (stderr, not
        # buffered), which a slow start (a sanitizer build on a loaded machine) can delay past it.
        deadline = seconds + (STARTUP_GRACE if reject else 0.0)
        while time.monotonic() - start < deadline:
            if proc.poll() is not None:
                ended_early = proc.returncode
                break
            if reject and time.monotonic() - start >= seconds:
                with open(log_path) as f:
                    if rejection in f.read():
                        break
            if screenshots and not shot["taken"] and time.monotonic() - start > 1.0:
                stats = read_stats(stats_path)
                if stats and stats.get("in_contact"):
                    shot["taken"] = display.screenshot(shot_path)
                    after = read_stats(stats_path)
                    shot["in_contact"] = bool(after and after.get("in_contact"))
            time.sleep(0.1)
        if screenshots and not shot["taken"] and ended_early is None:
            shot["taken"] = display.screenshot(shot_path)  # no contact seen: the scene as it ended
        if ended_early is None:
            proc.send_signal(signal.SIGTERM)  # SIGTERM skips atexit: the stats are the periodic file
            try:
                proc.wait(timeout=STARTUP_GRACE)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait()
    with open(log_path) as f:
        output = f.read()
    if reject:
        problems = []
        if rejection not in output:
            problems.append("the uhaptics slot did not report the invalid selection (is CHAI3D's stub linked?)")
        if os.path.exists(stats_path):
            problems.append("a device ran although the selection was invalid")
        if ended_early is not None:
            problems.append(f"the example ended with {ended_early} instead of running without a device")
        return {"example": name, "device": device, "backend": backend, "expect": "rejected",
                "problems": problems, "stats": None, "shot": None, "log": output}
    stats = read_stats(stats_path)
    problems, expectation = check(table, example, device, stats, backend)
    if ARGS.method_off:
        # The method is off: the run must still be a valid session that touched the scene, and its
        # rule must fail (otherwise the rule does not measure the method); a rule that reads the
        # referee must fail on the referee's figures, what the user felt, not only on the method's
        # own account of itself.
        rule_misses = [p for p in problems if "expected" in p]
        others = [p for p in problems if "expected" not in p]
        engagement = table["devices"][device]["engagement"]
        reads_referee = any(name.startswith("referee.") for rule in expectation.split("|") if rule in engagement
                            for name in engagement[rule])
        felt = [p for p in rule_misses if p.startswith("referee.")] if reads_referee else rule_misses
        problems = others if others else ([] if felt else
                                           [f"the rule '{expectation}' held with the method off"
                                            + (" on the referee's figures" if reads_referee else "")
                                            + ": it does not measure the method"])
        expectation = "counterfactual: " + expectation + (" fails (" + "; ".join(rule_misses) + ")" if rule_misses else "")
    if ended_early is not None:
        problems.insert(0, f"the example ended with {ended_early} before its {seconds:.0f} s")
    return {"example": name, "device": device, "backend": backend, "expect": expectation,
            "problems": problems, "stats": stats,
            "shot": shot_path if screenshots and shot["taken"] else None,
            "shot_in_contact": shot["in_contact"], "log": output}


def run_isolated(table, example, device):
    """One run on its own X server. GLFW's initialization under Xvfb fails now and then (seen about
    once in 30 runs, at once, "failed initialization"): such a start is tried once more on a new
    server, and said so, instead of failing the scene."""
    for attempt in (1, 2):
        display = Display()
        try:
            result = run_one(table, example, device, ARGS.backend, display, ARGS.out, ARGS.screenshots,
                             reject=ARGS.reject)
        finally:
            display.close()
        if attempt == 1 and "failed initialization" in result["log"]:
            print(f"{example['name']} with {device}: GLFW could not initialize on the X server; trying once more")
            continue
        return result
    return result


# The referee's figures dropin.csv carries beside the method's own.
REFEREE_COLUMNS = ("max_true_penetration_mm", "rendered_stiffness_N_per_m", "rate_hardness_N_per_m",
                   "force_error_rms_N", "generated_energy_mJ", "chatter_N", "saturated_share", "peak_user_force_N")


def describe(result):
    stats = result["stats"] or {}
    figures = stats.get("renderer_figures", {})
    parts = [f"{k}={v:g}" if isinstance(v, float) else f"{k}={v}" for k, v in figures.items()]
    return ", ".join(parts)


def write_report(results, out, table):
    rows = []
    for r in results:
        s = r["stats"] or {}
        rows.append({
            "example": r["example"], "device": r["device"], "backend": r["backend"], "expect": r["expect"],
            "ticks": s.get("ticks", ""), "rate_hz": round(s.get("rate_hz", 0.0), 1) if s else "",
            "contacts": s.get("contacts", ""), "contact_ticks": s.get("contact_ticks", ""),
            "peak_force_N": s.get("peak_force_N", ""), "peak_output": s.get("peak_output", ""),
            "max_entry_depth_mm": s.get("renderer_figures", {}).get("max_entry_depth_mm", ""),
            "max_penetration_mm": s.get("renderer_figures", {}).get("max_penetration_mm", ""),
            **{f"referee_{k}": (s.get("referee") or {}).get(k, "") for k in REFEREE_COLUMNS},
            "renderer": s.get("renderer", ""), "figures": describe(r),
            "screenshot": os.path.basename(r["shot"]) if r.get("shot") else "",
            "screenshot_in_contact": r.get("shot_in_contact", ""),
            "result": "pass" if not r["problems"] else "FAIL: " + "; ".join(r["problems"]),
        })
    with open(os.path.join(out, "dropin.csv"), "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0].keys()), lineterminator="\n")
        writer.writeheader()
        writer.writerows(rows)
    lines = ["| example | device | ticks | rate [Hz] | contacts | renderer engagement | max force [N] | "
             "max penetration [mm] | result |", "|---|---|---:|---:|---:|---|---:|---:|---|"]
    for row in rows:
        pen = row["max_penetration_mm"]
        lines.append(f"| {row['example']} | {row['device']} | {row['ticks']} | {row['rate_hz']} | {row['contacts']} | "
                     f"{row['figures']} | {float(row['peak_force_N'] or 0):.2f} | "
                     f"{'' if pen == '' else f'{float(pen):.3f}'} | {row['result']} |")
    entries = [(e["name"], d, scene_rules(table, e, d)) for e in table["examples"] for d in table["devices"]]
    reasons = [f"- {name} with {d}: {r['expect'][5:].strip()}" for name, d, r in entries
               if r.get("expect", "").startswith("none:")]
    if reasons:
        lines += ["", "Runs in which the device's method cannot engage, and why:"] + reasons
    whys = [f"- {name} with {d}: {r['why']}" for name, d, r in entries if "why" in r]
    if whys:
        lines += ["", "Why a run expects another rule than the device's engaged one (e.g. TAU's spring, RHI's free ellipsoid):"] + whys
    reasons += whys
    with open(os.path.join(out, "dropin.md"), "w") as f:
        f.write("\n".join(lines) + "\n")
    with open(os.path.join(out, "summary.txt"), "w") as f:
        for row in rows:
            f.write(f"{row['example']:>14} {row['device']:>4}: {row['ticks']} ticks at {row['rate_hz']} Hz, "
                    f"{row['contacts']} contacts, peak {float(row['peak_force_N'] or 0):.2f} N; {row['figures']}; "
                    f"{row['result']}\n")
        for line in reasons:
            f.write(line + "\n")
    # One reproduction row per run, for uhaptics-report (paper column "chai3d").
    with open(os.path.join(out, "reproduction.csv"), "w", newline="") as f:
        writer = csv.writer(f, lineterminator="\n")
        writer.writerow(["paper", "quantity", "published", "measured", "criterion", "pass", "unit", "needs_data"])
        for r, row in zip(results, rows):
            writer.writerow(["chai3d", f"{row['example']} with {row['device']}: {r['expect']}", "nan",
                             row["contact_ticks"] or "nan", "dropin.json: " + r["expect"].split(":")[0],
                             "pass" if not r["problems"] else "FAIL", "contact ticks", ""])


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--bin", required=True, help="folder of the relinked examples (uhaptics-chai3d-*)")
    parser.add_argument("--table", default=TABLE)
    parser.add_argument("--example", action="append", help="run only these (default: all in the table)")
    parser.add_argument("--device", action="append",
                        help="run only these devices (default: every device the table has rules for)")
    parser.add_argument("--backend", default="sim")
    parser.add_argument("--out", default=".")
    parser.add_argument("--screenshots", action="store_true")
    parser.add_argument("--report", action="store_true")
    parser.add_argument("--reject", action="store_true", help="expect the selection to be refused")
    parser.add_argument("--seconds", type=float, help="run time of each example (default: the table's)")
    parser.add_argument("--option", action="append", help="a device option DEVICE/NAME=VALUE (repeatable)")
    parser.add_argument("--record", help="folder: each run records its hand there (<example>.<device>.csv)")
    parser.add_argument("--hand-recordings",
                        help="folder of hand recordings (<example>.<device>.csv): a run with one replays it")
    parser.add_argument("--method-off", action="store_true",
                        help="the device's method switched off (its dropin.json \"method_off\" options): "
                             "its scene rule must fail")
    global ARGS
    ARGS = parser.parse_args()
    ARGS.bin = os.path.abspath(ARGS.bin)
    for folder in ("record", "hand_recordings"):
        if getattr(ARGS, folder):
            setattr(ARGS, folder, os.path.abspath(getattr(ARGS, folder)))
    if ARGS.record:
        os.makedirs(ARGS.record, exist_ok=True)
    table = load_table(ARGS.table, ARGS.bin)
    examples = {e["name"]: e for e in table["examples"]}
    chosen = ARGS.example or list(examples)
    unknown = [e for e in chosen if e not in examples]
    if unknown:
        print(f"run_examples.py: {unknown} not in {ARGS.table} (choose from {list(examples)})", file=sys.stderr)
        return 2
    devices = ARGS.device or list(table["devices"])
    os.makedirs(ARGS.out, exist_ok=True)
    results = []
    for name in chosen:
        for device in devices:
            result = run_isolated(table, examples[name], device)
            results.append(result)
            verdict = "ok" if not result["problems"] else "FAIL: " + "; ".join(result["problems"])
            stats = result["stats"] or {}
            replayed = hand_recording(examples[name], device)
            print(f"{name} with {device} ({ARGS.backend}, expect {result['expect']}"
                  f"{', replaying ' + replayed if replayed else ''}): {verdict}")
            if stats:
                print(f"  {stats['ticks']} ticks at {stats['rate_hz']:.0f} Hz, {stats['contacts']} contacts, "
                      f"peak {stats['peak_force_N']:.2f} N, renderer {stats['renderer']}; {describe(result)}; "
                      f"visited {stats.get('visited_min_radii')} .. {stats.get('visited_max_radii')} radii")
                if stats.get("referee"):
                    print("  referee: " + ", ".join(f"{k}={stats['referee'].get(k)}" for k in REFEREE_COLUMNS))
            if result["problems"]:
                print("  example output (last lines):\n    " +
                      "\n    ".join(result["log"].strip().splitlines()[-15:]))
            sys.stdout.flush()
    if ARGS.report and results and not ARGS.reject:
        write_report(results, ARGS.out, table)
    failed = sum(1 for r in results if r["problems"])
    print(f"{len(results) - failed} passed, {failed} failed")
    return 0 if failed == 0 else 1


if __name__ == "__main__":
    sys.exit(main())
