#!/usr/bin/env python3
"""Runs the shell blocks of the README and the task guides as a reader would (issue 31).

Every ```sh block of README.md, docs/guide-*.md and docs/development.md either runs, as
written, on the simulator, or is marked in the markdown by a comment on the line before it,
    <!-- norun: why this block cannot run here -->
which this check lists with its reason. Blocks of one file run in order in one scratch folder
(what a block writes, the next one reads, as for a reader following the page), with `calstand`
and `calstandd` of the build on PATH and the repository's scripts/, sim/, procedures/ and
schemas/ beside them. A comment
    <!-- given: COMMAND -->
runs COMMAND there first: what the page says the reader already has (a recorded run, say).

Usage: check-doc-commands.py --build BUILD_DIR [--source SOURCE_DIR] [--list] [FILE...]
Exit 0 when every block ran or is marked, 1 otherwise (each failure with the block's output).
"""
import argparse
import os
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

NORUN = re.compile(r"^<!--\s*norun:\s*(.*?)\s*-->\s*$")
GIVEN = re.compile(r"^<!--\s*given:\s*(.*?)\s*-->\s*$")
FENCE = re.compile(r"^```(\w*)\s*$")
SHELLS = {"sh", "bash", "shell"}
LINKED = ("scripts", "sim", "procedures", "schemas")
BLOCK_TIMEOUT_S = 300


def blocks(path):
    """Yields (kind, line, text) in file order: kind 'given', 'run' or 'norun:<reason>'."""
    lines = Path(path).read_text().split("\n")
    i = 0
    while i < len(lines):
        given = GIVEN.match(lines[i])
        if given:
            yield "given", i + 1, given.group(1)
        fence = FENCE.match(lines[i])
        if not fence:
            i += 1
            continue
        start = i
        i += 1
        while i < len(lines) and not lines[i].startswith("```"):
            i += 1
        if fence.group(1) in SHELLS:
            text = "\n".join(lines[start + 1 : i]) + "\n"
            before = start - 1
            while before >= 0 and not lines[before].strip():
                before -= 1
            norun = NORUN.match(lines[before]) if before >= 0 else None
            if norun:
                yield "norun:" + norun.group(1), start + 1, text
            else:
                yield "run", start + 1, text
        i += 1


def run_block(text, cwd, env):
    script = "set -euo pipefail\n" + text
    started = time.monotonic()
    try:
        done = subprocess.run(["bash", "-c", script], cwd=cwd, env=env, capture_output=True,
                              text=True, timeout=BLOCK_TIMEOUT_S)
        return done.returncode, done.stdout + done.stderr, time.monotonic() - started
    except subprocess.TimeoutExpired as e:
        out = (e.stdout or b"").decode(errors="replace") if isinstance(e.stdout, bytes) else (e.stdout or "")
        return 124, out + f"\n(timed out after {BLOCK_TIMEOUT_S} s)", time.monotonic() - started


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--build", required=True, help="build folder holding cli/calstand")
    parser.add_argument("--source", default=str(Path(__file__).resolve().parent.parent))
    parser.add_argument("--list", action="store_true", help="list the blocks, run nothing")
    parser.add_argument("files", nargs="*")
    args = parser.parse_args()
    source = Path(args.source).resolve()
    build = Path(args.build).resolve()
    files = [Path(f) for f in args.files] or (
        [source / "README.md"] + sorted((source / "docs").glob("guide-*.md")) +
        [source / "docs" / "development.md"])

    bin_dir = Path(tempfile.mkdtemp(prefix="calstand-doc-bin-"))
    for program in (build / "cli" / "calstand", build / "daemon" / "calstandd"):
        if not program.exists():
            print(f"check-doc-commands: {program} is not built", file=sys.stderr)
            return 1
        (bin_dir / program.name).symlink_to(program)
    env = dict(os.environ, PATH=f"{bin_dir}:{os.environ.get('PATH', '')}",
               CALSTAND_BUILD_DIR=str(build))

    ran = marked = failed = 0
    for path in files:
        rel = path.resolve().relative_to(source)
        with tempfile.TemporaryDirectory(prefix="calstand-doc-") as scratch:
            for name in LINKED:
                os.symlink(source / name, Path(scratch) / name)
            for kind, line, text in blocks(path):
                where = f"{rel}:{line}"
                if kind.startswith("norun:"):
                    reason = kind[len("norun:"):]
                    if not reason:
                        print(f"FAIL  {where}: a norun mark must say why")
                        failed += 1
                        continue
                    print(f"norun {where}: {reason}")
                    marked += 1
                    continue
                if args.list:
                    print(f"run   {where}")
                    continue
                code, out, seconds = run_block(text, scratch, env)
                if code == 0:
                    print(f"ok    {where} ({seconds:.1f} s)" + (" [given]" if kind == "given" else ""))
                    ran += kind == "run"
                else:
                    print(f"FAIL  {where}: exit {code} after {seconds:.1f} s\n{text}--- output:\n{out}")
                    failed += 1
    print(f"{ran} blocks ran, {marked} marked as not runnable here, {failed} failed")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
