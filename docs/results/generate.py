#!/usr/bin/env python3
"""Writes the result tables of README.md and docs/*.md from the committed result directories.

Every table in the documentation that holds a measured figure is generated here from a directory under
docs/results/ and carries, below it, the command, commit, machine and GL renderer that produced its
data. A table lives in a Markdown file between two markers:

    <!-- generated:NAME -->
    ... (written by this script) ...
    <!-- end generated -->

Usage (Python 3's standard library only):
    python3 docs/results/generate.py            # rewrite every table in place
    python3 docs/results/generate.py --check    # exit 1 naming each table that is stale

A result directory holds what its run wrote (results.csv, findings.json, JSON lines of `bvhlab build`)
and a source.json with the command that made it and a note on the machine's state; the commit, machine
and renderer are read from the rows themselves where the rows record them (results.csv's git_commit,
hostname, cpu, cores and gl_renderer columns), and from source.json otherwise.
"""

import argparse
import os
import re
import sys
import textwrap

sys.dont_write_bytecode = True  # the table modules beside this script: leave no __pycache__ in the checkout
import tables_cpu  # noqa: E402
import tables_gpu  # noqa: E402
from tables_io import ROOT, DataError  # noqa: E402

BEGIN = re.compile(r"^<!-- generated:([a-z0-9-]+) -->$")
END = "<!-- end generated -->"

TABLES = {
    "gpu-render": tables_gpu.gpu_render,
    "gpu-sample-length": tables_gpu.gpu_sample_length,
    "gpu-builders-trace": tables_gpu.gpu_builders_trace,
    "gpu-builders-frames": tables_gpu.gpu_builders_frames,
    "gpu-kernels": tables_gpu.gpu_kernels,
    "gpu-layouts": tables_gpu.gpu_layouts,
    "cpu-build-quality": tables_cpu.cpu_build_quality,
    "cpu-layout-bytes": tables_cpu.cpu_layout_bytes,
    "cpu-layout-kernels": tables_cpu.cpu_layout_kernels,
    "cpu-build-time": tables_cpu.cpu_build_time,
    "cpu-hard-cases": tables_cpu.cpu_hard_cases,
    "cpu-robust-cost": tables_cpu.cpu_robust_cost,
    "cpu-sbvh-knobs": tables_cpu.cpu_sbvh_knobs,
    "cpu-texture-lod": tables_cpu.cpu_texture_lod,
    "cpu-dynamic": tables_cpu.cpu_dynamic,
}


# ---- the Markdown files ------------------------------------------------------------------------

def wrap(lines):
    """Prose lines wrapped at 110 characters; table rows kept whole."""
    out = []
    for line in lines:
        if line.startswith("|") or len(line) <= 110:
            out.append(line)
        else:
            out += textwrap.wrap(line, 110, break_long_words=False, break_on_hyphens=False)
    return out


def markdown_files(root):
    files = [os.path.join(root, "README.md")]
    for dirpath, _, names in os.walk(os.path.join(root, "docs")):
        files += [os.path.join(dirpath, n) for n in sorted(names) if n.endswith(".md")]
    return [f for f in files if os.path.isfile(f)]


def render_file(path, cache, root=ROOT):
    """The file's text with every generated block rewritten, and the names of its blocks.
    Raises DataError naming the file and line on an unknown name or an unclosed block."""
    shown = os.path.relpath(path, root)  # the file as the reader names it
    with open(path) as f:
        lines = f.read().split("\n")
    out, names, i = [], [], 0
    while i < len(lines):
        m = BEGIN.match(lines[i].strip())
        out.append(lines[i])
        if not m:
            i += 1
            continue
        name, start = m.group(1), i + 1
        if name not in TABLES:
            raise DataError(f"{shown}:{start}: unknown table '{name}' (known: {', '.join(TABLES)})")
        j = i + 1
        while j < len(lines) and lines[j].strip() != END:
            if BEGIN.match(lines[j].strip()):
                raise DataError(f"{shown}:{j + 1}: table '{name}' opened on line {start} is not closed")
            j += 1
        if j == len(lines):
            raise DataError(f"{shown}:{start}: table '{name}' has no '{END}'")
        if name not in cache:
            cache[name] = wrap(TABLES[name]())
        out += cache[name]
        out.append(END)
        names.append((name, lines[i + 1:j] != cache[name]))
        i = j + 1
    return "\n".join(out), names


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--check", action="store_true", help="exit 1 if any table differs from its data")
    ap.add_argument("--root", default=ROOT,
                    help="the tree whose README.md and docs/**/*.md hold the tables (default: this checkout); "
                         "the data always comes from the result directories beside this script")
    args = ap.parse_args(argv)
    cache, stale, count = {}, [], 0
    try:
        for path in markdown_files(args.root):
            text, names = render_file(path, cache, args.root)
            count += len(names)
            for name, differs in names:
                if differs:
                    stale.append(f"{os.path.relpath(path, args.root)}: table '{name}'")
            if names and not args.check:
                with open(path) as f:
                    old = f.read()
                if text != old:
                    with open(path, "w") as f:
                        f.write(text)
    except DataError as e:
        print(f"generate.py: error: {e}", file=sys.stderr)
        return 2
    if args.check:
        for s in stale:
            print(f"generate.py: stale: {s} (run python3 docs/results/generate.py)", file=sys.stderr)
        print(f"generate.py: {count} tables checked, {len(stale)} stale")
        return 1 if stale else 0
    print(f"generate.py: {count} tables written ({len(stale)} changed)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
