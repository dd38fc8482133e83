#!/usr/bin/env python3
"""Runs the examples that README.md and the user guide (book/src) show, as a reader would.

Usage: check-examples.py ASI_LIFT_BINARY [FILE.md ...]   (default: README.md and book/src/*.md)

Two kinds of fenced block are run, each in a fresh temporary directory that holds links to the
repository's scenarios/, examples/ and controllers/ (the paths the examples use), with HOME pointing there too
and the given binary first on PATH as `asi-lift`:

- A transcript: a ```text or ```console block whose first line starts with `$ `. Each `$` line
  is run with bash, its standard output and error together, and must print the lines shown
  under it, in order. A line that is only `…` stands for any number of lines; a `…` inside a
  line stands for any text. Trailing blanks do not count. A command must exit with 0 unless
  the block's next line after it is `? N` (the exit code shown).
- A command listing: a ```sh block. It runs as one bash script (`set -euo pipefail`) and must
  exit with 0. A listing that cannot run here (it starts a server that runs until Ctrl-C, needs
  the network, or is a synopsis) is fenced as ```sh,ignore instead and counted as skipped.

Every command gets at most TIMEOUT seconds. Exit status 1 and a report of each failure, with the
file, the block's line and what differed; 2 for a usage error.
"""

import os
import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

TIMEOUT = 300
ELLIPSIS = "…"


def blocks(path):
    """Yields (line number of the fence, info string, lines) for each fenced block of `path`."""
    fence = None
    for number, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
        stripped = line.strip()
        if fence is None:
            if stripped.startswith("```"):
                fence = (number, stripped[3:].strip(), [])
        elif stripped.startswith("```"):
            yield fence
            fence = None
        else:
            fence[2].append(line)
    if fence is not None:
        raise SystemExit(f"{path}:{fence[0]}: a fenced block is never closed")


def parse_transcript(lines):
    """Splits a transcript into (command, expected exit code, expected output lines)."""
    steps = []
    for line in lines:
        if line.startswith("$ "):
            steps.append([line[2:], 0, []])
        elif not steps:
            continue
        elif not steps[-1][2] and re.fullmatch(r"\? \d+", line.strip()):
            steps[-1][1] = int(line.strip()[2:])
        else:
            steps[-1][2].append(line.rstrip())
    return steps


def line_matches(pattern, actual):
    if ELLIPSIS not in pattern:
        return pattern == actual
    parts = [re.escape(part) for part in pattern.split(ELLIPSIS)]
    return re.fullmatch(".*".join(parts), actual) is not None


def output_matches(expected, actual):
    """Whether `actual` lines match `expected` lines, where a line `…` matches any run of lines."""
    # Trailing blank lines of either side do not count.
    while expected and not expected[-1]:
        expected = expected[:-1]
    while actual and not actual[-1]:
        actual = actual[:-1]
    # Dynamic programming over (pattern line, actual line): small blocks, plain and sure.
    memo = {}

    def match(i, j):
        key = (i, j)
        if key in memo:
            return memo[key]
        if i == len(expected):
            result = j == len(actual)
        elif expected[i].strip() == ELLIPSIS:
            result = match(i + 1, j) or (j < len(actual) and match(i, j + 1))
        else:
            result = j < len(actual) and line_matches(expected[i], actual[j]) and match(i + 1, j + 1)
        memo[key] = result
        return result

    sys.setrecursionlimit(max(10000, 4 * (len(expected) + len(actual)) + 100))
    return match(0, 0)


def sandbox(root, binary):
    work = Path(tempfile.mkdtemp(prefix="asi-lift-examples-"))
    for name in ("scenarios", "examples", "controllers"):
        (work / name).symlink_to(root / name)
    bin_dir = work / ".bin"
    bin_dir.mkdir()
    (bin_dir / "asi-lift").symlink_to(binary)
    env = dict(os.environ)
    env["PATH"] = f"{bin_dir}{os.pathsep}{env.get('PATH', '')}"
    env["HOME"] = str(work)
    env.pop("NO_COLOR", None)
    env["CLICOLOR"] = "0"
    return work, env


def run(script, work, env):
    try:
        done = subprocess.run(
            ["bash", "-c", script],
            cwd=work,
            env=env,
            stdin=subprocess.DEVNULL,
            stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT,
            timeout=TIMEOUT,
        )
    except subprocess.TimeoutExpired:
        return None, f"still running after {TIMEOUT} s"
    return done.returncode, done.stdout.decode("utf-8", errors="replace")


def self_test():
    """The matcher's rules on small cases, run first so that a broken matcher cannot pass."""
    assert output_matches(["a", "b"], ["a", "b"])
    assert not output_matches(["a", "b"], ["a", "b", "c"])
    assert not output_matches(["a"], ["b"])
    assert output_matches(["a", ELLIPSIS, "d"], ["a", "b", "c", "d"])
    assert output_matches(["a", ELLIPSIS, "b"], ["a", "b"])
    assert not output_matches([ELLIPSIS, "d", "e"], ["d", "x", "e"])
    assert output_matches(["x 1" + ELLIPSIS + " z"], ["x 1 y z"])
    assert not output_matches(["x 1" + ELLIPSIS + " z"], ["x 2 y z"])
    assert output_matches(["a", ""], ["a"])
    assert parse_transcript(["$ one", "? 2", "out", "$ two"]) == [["one", 2, ["out"]], ["two", 0, []]]


def main(argv):
    self_test()
    if len(argv) < 2:
        print(__doc__.strip().splitlines()[2], file=sys.stderr)
        return 2
    root = Path(__file__).resolve().parent.parent
    binary = Path(argv[1]).resolve()
    if not os.access(binary, os.X_OK):
        print(f"check-examples: {argv[1]}: not an executable file", file=sys.stderr)
        return 2
    files = [Path(f) for f in argv[2:]] or [root / "README.md", *sorted((root / "book/src").glob("*.md"))]
    failures, ran, skipped = [], 0, 0
    for path in files:
        shown = os.path.relpath(path, root)
        for number, info, lines in blocks(path):
            words = re.split(r"[,\s]+", info)
            language, attributes = words[0], set(words[1:])
            transcript = language in ("text", "console") and lines and lines[0].startswith("$ ")
            if language == "sh" and "ignore" in attributes:
                skipped += 1
                continue
            if language != "sh" and not transcript:
                continue
            work, env = sandbox(root, binary)
            try:
                if language == "sh":
                    ran += 1
                    code, output = run("set -euo pipefail\n" + "\n".join(lines), work, env)
                    if code != 0:
                        failures.append(f"{shown}:{number}: the listing failed (exit {code}):\n{output}")
                    continue
                for command, expected_code, expected in parse_transcript(lines):
                    ran += 1
                    code, output = run(command, work, env)
                    actual = output.splitlines() if code is not None else []
                    if code != expected_code:
                        failures.append(
                            f"{shown}:{number}: `{command}` exited with {code}, the example shows "
                            f"{expected_code}:\n{output}"
                        )
                    elif not output_matches(expected, [a.rstrip() for a in actual]):
                        failures.append(
                            f"{shown}:{number}: `{command}` printed something else.\n"
                            "--- the example shows\n" + "\n".join(expected)
                            + "\n--- it printed\n" + output
                        )
            finally:
                shutil.rmtree(work, ignore_errors=True)
    for failure in failures:
        print(failure, file=sys.stderr)
        print(file=sys.stderr)
    print(f"check-examples: {ran} examples run, {len(failures)} failed, {skipped} listings marked ignore")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
