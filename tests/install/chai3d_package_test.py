#!/usr/bin/env python3
"""The installed package as a new user consumes it, with the CHAI3D it ships or refers to.

  chai3d_package_test.py [--cmake CMAKE] [--ninja NINJA] --build DIR --work DIR --consumer DIR --chai3d-source DIR
                         --forbid PATH... [--cmake-arg ARG...] [--run PROGRAM=DEVICE...]

1. cmake --install <build> --prefix <work>/prefix.
2. The installation holds no symbolic link that leads nowhere or out of the prefix (system libraries
   are the consumer's to find, not copies).
3. A separate CMake project (<consumer>/CMakeLists.txt) with CHAI3D's GLFW example 01-mydevice and
   CHAI3D's GLFW application template, both copied unchanged from CHAI3D's source tree, is configured
   with CMAKE_PREFIX_PATH=<prefix> as its only hint and built.
4. Nothing the consumer's build recorded (build.ninja, compile_commands.json, the compiler's header
   dependencies as `ninja -t deps` lists them, CMakeCache.txt) names a path under a --forbid folder
   (this build tree, the uhaptics sources, the CHAI3D that uhaptics built) outside the work folder.
   So the consumer compiles against the installed headers and links the installed libraries and the
   system's (and a CHAI3D the user gave, where it is).
5. Each program runs for a few seconds under a private Xvfb with a simulated uhaptics device
   (UHAPTICS_DEVICE, UHAPTICS_BACKEND=sim), and the device's statistics file must show that
   device served the program's haptic loop.
Exit status 0 when every step holds, 1 otherwise.
"""
import argparse
import json
import os
import shutil
import signal
import subprocess
import sys
import time

# The drop-in runner's private Xvfb server: one place knows how to start and stop it.
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "examples", "chai3d-unchanged"))
from run_examples import Display  # noqa: E402

SECONDS = 3.0  # [s] each program runs
# The consumer's sources: (file name in the consumer, path in CHAI3D's source tree).
SOURCES = [("01-mydevice.cpp", "examples/GLFW/01-mydevice/01-mydevice.cpp"),
           ("application-GLFW.cpp", "templates/GLFW/application-GLFW/application-GLFW.cpp")]


def fail(message):
    print(f"FAIL: {message}")
    sys.exit(1)


def run(command, **kwargs):
    start = time.monotonic()
    result = subprocess.run(command, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, **kwargs)
    print(f"$ {' '.join(command)}  ({time.monotonic() - start:.1f} s)")
    if result.returncode != 0:
        fail(f"exit status {result.returncode}:\n{result.stdout[-6000:]}")
    return result.stdout


def install(args, prefix):
    shutil.rmtree(args.work, ignore_errors=True)
    os.makedirs(args.work)
    run([args.cmake, "--install", args.build, "--prefix", prefix])
    problems = []
    for folder, dirs, files in os.walk(prefix):
        for name in dirs + files:
            path = os.path.join(folder, name)
            if not os.path.islink(path):
                continue
            target = os.path.realpath(path)
            if not os.path.exists(target):
                problems.append(f"{path} -> {os.readlink(path)} leads nowhere")
            elif os.path.commonpath([target, prefix]) != prefix:
                problems.append(f"{path} -> {target} leads out of the installation")
    if problems:
        fail("the installation holds links it cannot keep:\n  " + "\n  ".join(problems))


def consumer_environment():
    """The environment without anything that could point CMake at another uhaptics or CHAI3D."""
    env = dict(os.environ)
    for name in ("CMAKE_PREFIX_PATH", "CHAI3D_DIR", "CHAI3D_SOURCE", "uhaptics_DIR", "chai3d_DIR",
                 "CMAKE_INCLUDE_PATH", "CMAKE_LIBRARY_PATH", "CPATH", "CPLUS_INCLUDE_PATH", "LIBRARY_PATH"):
        env.pop(name, None)
    return env


def build_consumer(args, prefix, source, binary):
    os.makedirs(source)
    shutil.copy(os.path.join(args.consumer, "CMakeLists.txt"), source)
    for name, relative in SOURCES:
        shutil.copy(os.path.join(args.chai3d_source, relative), os.path.join(source, name))
    env = consumer_environment()
    run([args.cmake, "-S", source, "-B", binary, "-G", "Ninja", "-DCMAKE_BUILD_TYPE=Release",
         f"-DCMAKE_PREFIX_PATH={prefix}", "-DCMAKE_FIND_USE_PACKAGE_REGISTRY=OFF",
         "-DCMAKE_EXPORT_COMPILE_COMMANDS=ON"] + (args.cmake_arg or []), env=env)
    run([args.cmake, "--build", binary, "-j", "2"], env=env)
    with open(os.path.join(binary, "CMakeCache.txt")) as f:
        found = [line.split("=", 1)[1].strip() for line in f if line.startswith("uhaptics_DIR:")]
    expected = os.path.join(prefix, "lib", "cmake", "uhaptics")
    if not found or os.path.realpath(found[0]) != os.path.realpath(expected):
        fail(f"the consumer found uhaptics in {found} instead of {expected}")


def check_paths(args, binary):
    """Every path the consumer's build recorded under a forbidden folder must lie in the work folder."""
    forbid = [os.path.realpath(p) for p in args.forbid]
    allow = [os.path.realpath(args.work)]
    # The headers each object was compiled from, as the compiler reported them to ninja.
    deps = subprocess.run([args.ninja, "-C", binary, "-t", "deps"], stdout=subprocess.PIPE, check=True).stdout
    files = ["build.ninja", "compile_commands.json", "CMakeCache.txt", "ninja -t deps"]
    problems = []
    for name in files:
        if name == "ninja -t deps":
            text = deps
        else:
            with open(os.path.join(binary, name), "rb") as f:
                text = f.read()
        for folder in forbid:
            key = folder.encode() + b"/"
            at = text.find(key)
            while at >= 0:
                end = at
                while end < len(text) and text[end] > 32 and text[end] not in b"\"';$,":
                    end += 1
                path = text[at:end].decode(errors="replace")
                if not any(path == a or path.startswith(a + "/") for a in allow):
                    problems.append(f"{name}: {path}")
                at = text.find(key, end)
    if problems:
        shown = sorted(set(problems))
        fail(f"the consumer's build reaches into {len(shown)} paths outside the installation:\n  " +
             "\n  ".join(shown[:30]))
    print(f"the consumer's {', '.join(files)} name nothing under {', '.join(forbid)} outside {', '.join(allow)}")


def run_program(exe, device, out):
    """Runs exe for SECONDS with the device; returns (its output, its statistics or None, early exit)."""
    stats_path = os.path.join(out, os.path.basename(exe) + ".stats.json")
    if os.path.exists(stats_path):
        os.remove(stats_path)
    display = Display()
    try:
        env = dict(os.environ, DISPLAY=display.name, UHAPTICS_DEVICE=device, UHAPTICS_BACKEND="sim",
                   UHAPTICS_STATS=stats_path)
        env.pop("UHAPTICS_CONFIG", None)
        proc = subprocess.Popen([exe], env=env, cwd=out, stdout=subprocess.PIPE, stderr=subprocess.STDOUT)
        try:
            proc.wait(timeout=SECONDS)
            early = proc.returncode
        except subprocess.TimeoutExpired:
            early = None
            proc.send_signal(signal.SIGTERM)  # the examples run until a key; the stats file is periodic
            try:
                proc.wait(timeout=30)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait()
        output = proc.stdout.read().decode(errors="replace")
    finally:
        display.close()
    try:
        with open(stats_path) as f:
            stats = json.load(f)
    except (OSError, ValueError):
        stats = None
    return output, stats, early


def run_programs(args, binary):
    for item in args.run:
        name, _, device = item.partition("=")
        exe = os.path.join(binary, name)
        for attempt in (1, 2):
            output, stats, early = run_program(exe, device, args.work)
            # GLFW under Xvfb now and then fails to initialize at once: one more start on a new server.
            if attempt == 1 and "failed initialization" in output:
                print(f"{name}: GLFW could not initialize on the X server; trying once more")
                continue
            break
        problems = []
        if early is not None:
            problems.append(f"it ended with {early} before its {SECONDS:.0f} s")
        if stats is None:
            problems.append("the device wrote no statistics: the program did not open a uhaptics device")
        elif stats.get("device") != device or stats.get("backend") != "sim":
            problems.append(f"statistics are from {stats.get('device')} on {stats.get('backend')}")
        elif stats.get("ticks", 0) <= 0:
            problems.append("the device served no haptic ticks")
        if problems:
            fail(f"{name} with {device}: " + "; ".join(problems) + "\n  output:\n    " +
                 "\n    ".join(output.strip().splitlines()[-15:]))
        print(f"{name} with {device} (sim): {stats['ticks']} ticks at {stats['rate_hz']:.0f} Hz")


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--cmake", default="cmake")
    parser.add_argument("--ninja", default="ninja")
    parser.add_argument("--build", required=True, help="the uhaptics build tree to install")
    parser.add_argument("--work", required=True, help="scratch folder (emptied): prefix, consumer, runs")
    parser.add_argument("--consumer", required=True, help="folder of the consumer's CMakeLists.txt")
    parser.add_argument("--chai3d-source", required=True, help="CHAI3D's source tree")
    parser.add_argument("--forbid", action="append", required=True)
    parser.add_argument("--cmake-arg", action="append", help="passed to the consumer's configure")
    parser.add_argument("--run", action="append", default=[], help="PROGRAM=DEVICE")
    args = parser.parse_args()
    args.work = os.path.abspath(args.work)
    prefix = os.path.join(args.work, "prefix")
    install(args, prefix)
    binary = os.path.join(args.work, "consumer-build")
    build_consumer(args, prefix, os.path.join(args.work, "consumer"), binary)
    check_paths(args, binary)
    run_programs(args, binary)
    print("the installed package builds and runs CHAI3D's unchanged programs")
    return 0


if __name__ == "__main__":
    sys.exit(main())
