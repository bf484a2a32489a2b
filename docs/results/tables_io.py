"""Reading committed result directories (docs/results/NAME/) and writing Markdown tables with their
provenance, for docs/results/generate.py. Python 3's standard library only."""

import csv
import json
import math
import os

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))


class DataError(Exception):
    """A result file is missing or does not hold what a table needs."""


# ---- reading result directories -------------------------------------------------------------------

def result_path(*parts):
    return os.path.join(HERE, *parts)


def rel(path):
    return os.path.relpath(path, ROOT)


def read_csv(dirname, filename):
    path = result_path(dirname, filename)
    try:
        with open(path, newline="") as f:
            rows = list(csv.DictReader(f))
    except OSError as e:
        raise DataError(f"{rel(path)}: {e.strerror}") from None
    if not rows:
        raise DataError(f"{rel(path)}: no rows")
    return path, rows


def read_json(dirname, filename):
    path = result_path(dirname, filename)
    try:
        with open(path) as f:
            return path, json.load(f)
    except OSError as e:
        raise DataError(f"{rel(path)}: {e.strerror}") from None
    except json.JSONDecodeError as e:
        raise DataError(f"{rel(path)}: line {e.lineno}: {e.msg}") from None


def read_json_lines(dirname, filename):
    path = result_path(dirname, filename)
    out = []
    try:
        with open(path) as f:
            for n, line in enumerate(f, 1):
                if line.strip():
                    try:
                        out.append(json.loads(line))
                    except json.JSONDecodeError as e:
                        raise DataError(f"{rel(path)}: line {n}: {e.msg}") from None
    except OSError as e:
        raise DataError(f"{rel(path)}: {e.strerror}") from None
    return path, out


def source(dirname):
    """source.json of a result directory: {"commands": {file: command}, "note": ..., and, for data
    that does not record them itself, "git_commit", "machine", "gl_renderer"}."""
    return read_json(dirname, "source.json")[1]


def num(row, key, path=""):
    """A finite number from a row, or a DataError naming the file and the key."""
    value = row.get(key)
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise DataError(f"{rel(path)}: key '{key}' is {value!r}, not a number") from None
    if not math.isfinite(x):
        raise DataError(f"{rel(path)}: key '{key}' is not finite")
    return x


def pick(rows, path, **match):
    """The one row whose columns equal `match`."""
    found = [r for r in rows if all(r.get(k) == v for k, v in match.items())]
    if len(found) != 1:
        raise DataError(f"{rel(path)}: {len(found)} rows match {match}, expected 1")
    return found[0]


# ---- formatting ----------------------------------------------------------------------------------

def f3(x):
    return f"{x:.3f}"


def sig(x, digits=3):
    """x to `digits` significant figures, without exponent notation."""
    if x == 0:
        return "0"
    decimals = max(0, digits - 1 - int(math.floor(math.log10(abs(x)))))
    return f"{x:.{decimals}f}"


def with_ci(x, lo, hi, fmt=sig):
    return f"{fmt(x)} [{fmt(lo)}, {fmt(hi)}]"


def table(header, rows):
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(r) + " |" for r in rows]
    return lines


def provenance(paths_rows, src, command_of):
    """The lines below a table: data files, command, commit, machine, renderer, note."""
    commits, machines, renderers = set(), set(), set()
    for _, rows in paths_rows:
        for r in rows:
            c = r.get("git_commit")
            if c:
                commits.add(c[:12])
            if r.get("hostname"):
                machines.add(f"{r['hostname']}, {r.get('cpu', '?')}, {r.get('cores', '?')} cores")
            g = r.get("gl_renderer") or r.get("renderer")
            if g:
                renderers.add(g)
    commits = commits or {src.get("git_commit", "not recorded")[:12]}
    machines = machines or {src.get("machine", "not recorded")}
    renderers = renderers or {src.get("gl_renderer", "not recorded")}
    files = ", ".join(f"`{rel(p)}`" for p, _ in paths_rows)
    cmds = "; ".join(f"`{c}`" for c in dict.fromkeys(command_of(p) for p, _ in paths_rows))
    lines = ["", f"Data: {files}. Command: {cmds}. Commit: {', '.join(sorted(commits))}. "
                 f"Machine: {'; '.join(sorted(machines))}. GL renderer: {'; '.join(sorted(renderers))}."]
    if src.get("note"):
        lines.append(f"{src['note']}")
    return lines


def commands(dirname, src):
    cmds = src.get("commands", {})

    def command_of(path):
        name = os.path.basename(path)
        if name not in cmds:
            raise DataError(f"{rel(result_path(dirname, 'source.json'))}: no command for '{name}'")
        return cmds[name]
    return command_of


# ---- quoting findings.json -------------------------------------------------------------------------
# Tables quote ratios, intervals, bands and verdicts from a result directory's findings.json verbatim.
# That they follow from the per-round times in its results.json with the current rules is checked by
# the C++ that computes them (`bvhlab findings DIR --check`, test_findings), never re-implemented here.


def band_cell(comparison):
    """A comparison's noise band as "±x.x%", or "none" when its runs had no band (docs/measurement.md)."""
    band = comparison.get("band")
    if band is None:
        return "none"
    return f"±{100 * (math.exp(float(band)) - 1):.1f}%"
