#!/usr/bin/env python3
"""Checks that the comments of the public headers (plugin/ and devices/, *.hpp and *.h) say what a
member is, its units, preconditions and what it throws, not how it was tuned: no measured timings,
no before/after figures, no run counts of one experiment, no history. Such figures belong in docs/
(in present tense, as what is true now and why) or in commit messages. Design constants with their
physical meaning ("default 0.06 s: longer than the kernel's 50 ms RT throttling window") are fine.

Only comment text is searched (after // and inside /* */), a run of comment lines at a time, so a
phrase wrapped over two lines is found too. Usage:
check_header_comments.py <source root>; exits 1 listing each hit as path:line: [pattern] text."""
import os
import re
import sys

# Each pattern names a kind of figure that only a particular run or an earlier version produced.
PATTERNS = [
    ("before/after", re.compile(r"\bwas [~<>]?[0-9]")),
    ("before/after", re.compile(r"\binstead of [~<>]?[0-9][0-9.]*\s?(mm|um|us|ms|s|N|N m|rad|mrad|%|kg)\b")),
    ("before/after", re.compile(r"\b(before|after) (this|the) (change|fix|commit)\b", re.I)),
    ("history", re.compile(r"\b(previously|no longer|used to be)\b", re.I)),
    ("history", re.compile(r"\b(it|that|this) took\b|\btook (about |~)?[0-9]", re.I)),
    ("timing", re.compile(r"\b[0-9][0-9.]*\s?(us|ms|µs)\b[^.;]{0,20}\b(on this|CPU|wall time|of the time)")),
    ("timing", re.compile(r"\b[0-9][0-9.]*\s?s of (GCC|compile|compiler|CPU|build) time", re.I)),
    ("timing", re.compile(r"\bon this (machine|VM|computer|host)\b", re.I)),
    ("measured", re.compile(r"\bMeasured\b|\bmeasured:|\(measured\b")),
    ("improvement", re.compile(r"\b[0-9][0-9.]*\s?% (faster|slower|less|more|fewer|lower|higher|cheaper|of the "
                               r"(time|CPU|run time|tick))", re.I)),
    ("improvement", re.compile(r"\b[0-9][0-9.]*\s?(x|times) (faster|slower|too (large|small))", re.I)),
    ("timing", re.compile(r"~[0-9][0-9.]*\s?(s|ms|us)\b")),
    ("run count", re.compile(r"\b([0-9]+|one|two|three|four|five|six|seven|eight|nine|ten) (of|out of) "
                             r"([0-9]+|two|three|four|five|six|seven|eight|nine|ten) (runs|scenes|trials|seeds)\b", re.I)),
    ("run count", re.compile(r"\b(in|over|across) [0-9]+ runs\b", re.I)),
    ("test figure", re.compile(r"\b(tests|tools)/[\w/.]*\.cpp: ?[~<>]? ?[0-9]")),
    # A past-tense outcome with its figure: what one run did ("stepped the torque by 6.4 N m").
    ("history", re.compile(r"\b(stepped|kicked|rang|swung|reached|commanded|sank|diverged)\b[^.;]{0,60}?"
                           r"\b[0-9][0-9.]*\s?(N m|N|mm|rad|mrad)\b")),
    ("before/after", re.compile(r"\bwith it\b[^.;]{0,40}\bwithout it\b", re.I)),
    # A measured worst case ("turns the torque by up to 0.3 N m per tick").
    ("measured", re.compile(r"\bby up to [0-9][0-9.]*\s?(N m|N|mm|mrad|rad|%)")),
    # A drift over a run's duration ("0.38 rad in 3 s").
    ("history", re.compile(r"\b[0-9][0-9.]*\s?(rad|mrad|mm|N m)\b in [0-9][0-9.]*\s?s\b")),
]


def comments(text):
    """Yields (line number, comment text) for every // comment and every line of a /* */ comment."""
    in_block = False
    for number, line in enumerate(text.splitlines(), 1):
        rest, found = line, []
        while rest:
            if in_block:
                end = rest.find("*/")
                found.append(rest if end < 0 else rest[:end])
                if end < 0:
                    break
                rest, in_block = rest[end + 2:], False
                continue
            slash, block = rest.find("//"), rest.find("/*")
            if slash >= 0 and (block < 0 or slash < block):
                found.append(rest[slash + 2:])
                break
            if block < 0:
                break
            rest, in_block = rest[block + 2:], True
        if found:
            yield number, " ".join(text.lstrip("/!<") for text in found)


def paragraphs(numbered):
    """Groups (line number, text) pairs of consecutive lines: yields (first line number, [texts])."""
    first, lines, previous = None, [], None
    for number, text in numbered:
        if previous is not None and number != previous + 1:
            yield first, lines
            first, lines = None, []
        if first is None:
            first = number
        lines.append(text)
        previous = number
    if lines:
        yield first, lines


def main():
    root = sys.argv[1] if len(sys.argv) > 1 else "."
    hits, files = [], 0
    for top in ("plugin", "devices"):
        for folder, _, names in os.walk(os.path.join(root, top)):
            for name in sorted(names):
                if not name.endswith((".hpp", ".h")):
                    continue
                path = os.path.join(folder, name)
                files += 1
                with open(path, encoding="utf-8") as f:
                    text = f.read()
                for first, lines in paragraphs(comments(text)):
                    joined = " ".join(line.strip() for line in lines)
                    starts, offset = [], 0
                    for line in lines:
                        starts.append(offset)
                        offset += len(line.strip()) + 1
                    for kind, pattern in PATTERNS:
                        for match in pattern.finditer(joined):
                            index = max(i for i, start in enumerate(starts) if start <= match.start())
                            hits.append(f"{os.path.relpath(path, root)}:{first + index}: [{kind}] "
                                        f"{lines[index].strip()}")
    if files == 0:
        print(f"no headers under {root}/plugin or {root}/devices")
        return 1
    for hit in hits:
        print(hit)
    print(f"{files} headers, {len(hits)} comment(s) with measured history or before/after figures")
    return 1 if hits else 0


if __name__ == "__main__":
    sys.exit(main())
