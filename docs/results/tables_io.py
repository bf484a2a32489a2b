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


# ---- re-deriving paired intervals from per-round times -------------------------------------------
# The same arithmetic as render/frame_stats.cpp (pairedRatio, medianInterval): the median of the
# per-round log ratios with a distribution-free order-statistic interval, so that every ratio and
# interval a table quotes from findings.json is checked against the per-round times in results.json.

CONFIDENCE = 0.95
MIN_VALUES_FOR_INTERVAL = 6  # below this even [min, max] covers less than 95% (render/frame_stats.hpp)


def _binomial_half_cdf(n, j):
    """P(B <= j) for B ~ Binomial(n, 1/2), summed in log space."""
    log_half_n = n * math.log(0.5)
    return sum(math.exp(math.lgamma(n + 1) - math.lgamma(i + 1) - math.lgamma(n - i + 1) + log_half_n)
               for i in range(0, min(j, n) + 1))


def _median(v):
    n = len(v)
    return v[n // 2] if n % 2 else 0.5 * (v[n // 2 - 1] + v[n // 2])


def paired_ratio(a, b):
    """(estimate, low, high) of a/b over paired rounds, or None with fewer than 6 usable pairs."""
    logs = sorted(math.log(x) - math.log(y) for x, y in zip(a, b)
                  if isinstance(x, (int, float)) and isinstance(y, (int, float))
                  and math.isfinite(x) and math.isfinite(y) and x > 0 and y > 0)
    n = len(logs)
    if n < MIN_VALUES_FOR_INTERVAL:
        return None
    k_best = 0
    for k in range(1, (n + 1) // 2 + 1):
        if 1.0 - 2.0 * _binomial_half_cdf(n, k - 1) < CONFIDENCE:
            break
        k_best = k
    if k_best == 0:
        return None
    return math.exp(_median(logs)), math.exp(logs[k_best - 1]), math.exp(logs[n - k_best])


# Relative tolerance when comparing with the C++ result: both sides use IEEE doubles and the C
# library's log/exp, which may differ in the last bit; 1e-9 is far above that and far below the
# three decimals the tables print.
REDERIVE_TOLERANCE = 1e-9


def check_paired(comparison, rows_by_key, fpath, rpath):
    """Raises DataError unless a paired comparison's ratio and interval follow from the rows' rounds."""
    if comparison.get("interval_over") != "rounds" or comparison.get("ci_low") is None:
        raise DataError(f"{rel(fpath)}: comparison {comparison.get('a')} / {comparison.get('b')} is not over paired "
                        f"rounds ('{comparison.get('interval_over')}'): its interval cannot be re-derived here")
    ra, rb = rows_by_key.get(comparison.get("a")), rows_by_key.get(comparison.get("b"))
    if ra is None or rb is None:
        raise DataError(f"{rel(rpath)}: no row for run {comparison.get('a')} or {comparison.get('b')}")
    got = paired_ratio(ra.get("frame_ms_all") or [], rb.get("frame_ms_all") or [])
    want = (num(comparison, "ratio", fpath), num(comparison, "ci_low", fpath), num(comparison, "ci_high", fpath))
    if got is None or any(abs(g - w) > REDERIVE_TOLERANCE * abs(w) for g, w in zip(got, want)):
        raise DataError(f"{rel(fpath)}: comparison {comparison.get('a')} / {comparison.get('b')}: ratio and interval "
                        f"{want} do not follow from frame_ms_all in {rel(rpath)} (re-derived: {got})")
