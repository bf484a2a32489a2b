"""The report's data layer: DIR/results.json rows, DIR/findings.json, and the small formatting helpers
every section uses (num, label, fmt, the frame-time-with-interval cells).

Rows may come from any version of the runner: every column added since (the interval, session,
control_of, tree_hash, epo, ray_cost, ...) is read with .get() and a missing value is None.
"""
import base64
import html
import io
import json
import math
import os
import sys

try:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.image as mpimg
    import matplotlib.pyplot as plt
    import numpy as np
except ImportError as e:  # pragma: no cover - depends on the machine
    sys.stderr.write(
        "report.py: %s; install Debian's python3-matplotlib and run /usr/bin/python3 "
        "(a pyenv/venv python3 usually lacks it)\n" % e
    )
    sys.exit(3)

AXES = ["scene", "builder", "layout", "triangle_format", "kernel", "leaf_size", "depth", "storage", "aa", "robust", "branching", "view",
        "uber", "smaa_edges", "texture_lod", "workload", "update"]
NUMERIC_AXES = {"leaf_size", "depth"}
# The axes that choose a tree and how it is walked: a builder's "best configuration" ranges over these,
# the others (depth, aa, robust, ...) are held at one setting shared by every builder.
TREE_AXES = ("builder", "layout", "triangle_format", "kernel", "leaf_size", "bins")
# Deterministic per-run cost measures, in the order the report shows them (row column, short label).
COUNTS = [("sah_cost", "SAH"), ("epo", "EPO"), ("node_visits_per_ray", "visits/ray"),
          ("triangle_tests_per_ray", "tests/ray"), ("ray_cost", "ray cost")]
MAX_SERIES_LABEL = 60


# ---------------------------------------------------------------- scalar helpers
def num(v):
    """A finite float, or None (NaN never decides anything here)."""
    if isinstance(v, bool) or v is None:
        return None
    try:
        f = float(v)
    except (TypeError, ValueError):
        return None
    return f if math.isfinite(f) else None


def label(row, axis):
    v = row.get(axis)
    if v is None:
        return None
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, float) and v.is_integer():
        return str(int(v))
    return str(v)


def fmt(v, digits=3):
    f = num(v)
    if f is None:
        return "–" if v is None else html.escape(str(v))
    if f.is_integer() and abs(f) < 1e15:
        return "{:,}".format(int(f)) if abs(f) >= 10000 else str(int(f))
    if abs(f) >= 1000:
        return "{:,.0f}".format(f)
    return "{:.{p}g}".format(f, p=digits)


def ratio(a, b):
    return a / b if a is not None and b not in (None, 0) else None


def plural(n, word):
    return "%d %s%s" % (n, word, "" if n == 1 else "s")


def group(rows, key):
    out = {}
    for r in rows:
        out.setdefault(key(r), []).append(r)
    return out


def describe(row, axes):
    parts = []
    for a in axes:
        v = label(row, a)
        if v is None:
            continue
        parts.append(v if a in ("scene", "builder") else "%s=%s" % (a, v))
    return " ".join(parts)


# ---------------------------------------------------------------- intervals
def frame_ci(row):
    """(low, high) of the run's 95% interval of the median frame time, or None."""
    lo, hi = num(row.get("frame_ms_ci_low")), num(row.get("frame_ms_ci_high"))
    return (lo, hi) if lo is not None and hi is not None else None


def _decimals(v):
    """Decimals that give a frame time about three significant digits."""
    return max(0, 2 - int(math.floor(math.log10(abs(v))))) if v else 2


def fmt_ms(row, key="frame_ms"):
    """The median frame time with its interval, "40.4 [39.8, 41.0]"; just the median without one."""
    ms = num(row.get(key))
    if ms is None:
        return "–"
    ci = frame_ci(row) if key == "frame_ms" else None
    if ci is None:
        return fmt(ms)
    d = _decimals(ms)
    return '%.*f <span class="ci">[%.*f, %.*f]</span>' % (d, ms, d, ci[0], d, ci[1])


def build_ms_cell(row):
    """A CPU builder's wall-clock build_ms; a GPU builder's GL-timed median with its interval where the run
    timed its builds (`gpu_builds` in [render]: render/gpu_build_timing.hpp), marked GPU."""
    gpu = num(row.get("gpu_build_ms"))
    if gpu is None:
        return fmt(row.get("build_ms"))
    lo, hi = num(row.get("gpu_build_ms_ci_low")), num(row.get("gpu_build_ms_ci_high"))
    interval = ' <span class="ci">[%s, %s]</span>' % (fmt(lo), fmt(hi)) if lo is not None and hi is not None else ""
    packed = row.get("gpu_pack") or ""
    return "%s%s on the GPU%s" % (fmt(gpu), interval, " (pack into %s included)" % html.escape(packed) if packed else "")


def fps(row):
    return ratio(1000.0, num(row.get("frame_ms")))


def fmt_fps(row):
    f = fps(row)
    if f is None:
        return "–"
    ci = frame_ci(row)
    if ci is None or not ci[0] or not ci[1]:
        return fmt(f)
    d = _decimals(f)
    return '%.*f <span class="ci">[%.*f, %.*f]</span>' % (d, f, d, 1000.0 / ci[1], d, 1000.0 / ci[0])


def fmt_ratio(r, lo=None, hi=None):
    """A time ratio with its interval, "1.120× [1.100, 1.140]"; "1.12×" without one."""
    r = num(r)
    if r is None:
        return "–"
    lo, hi = num(lo), num(hi)
    if lo is None or hi is None:
        return "%s×" % fmt(r)
    return '%.3f× <span class="ci">[%.3f, %.3f]</span>' % (r, lo, hi)


def band_of(lo, hi):
    """The noise band an A/A interval gives (max |ln ci|, as in the spec), or None without one."""
    lo, hi = num(lo), num(hi)
    if lo is None or hi is None or lo <= 0 or hi <= 0:
        return None
    return max(abs(math.log(lo)), abs(math.log(hi)))


def fmt_band(band):
    b = num(band)
    return "–" if b is None else "±%.1f%%" % (100.0 * (math.exp(b) - 1.0))


# ---------------------------------------------------------------- the sweep
class Data:
    def __init__(self, results, root):
        self.root = root
        self.results = results
        self.experiment = results.get("experiment", {})
        every = results.get("rows", [])
        self.by_key = {r.get("key"): r for r in every}
        # A/A control runs (a second measurement of another run) only feed the noise floor.
        self.controls = [r for r in every if r.get("control_of")]
        self.rows = [r for r in every if not r.get("control_of")]
        self.ok = [r for r in self.rows if r.get("status") == "ok" and num(r.get("frame_ms")) is not None]
        # Runs on the rays axis (`bvhlab trace`) have their own sections (report_rays.py); the frame-time
        # sections are about rendered frames.
        self.traced = [r for r in self.ok if r.get("workload")]
        self.ok = [r for r in self.ok if not r.get("workload")]
        self.sweep = [r for r in self.ok if not r.get("reference_only")]
        self.failed = [r for r in every if r.get("status") != "ok"]
        self.order = self.experiment.get("axes", {})
        self.findings, self.findings_problem = load_findings(root)
        self._records = {}
        self._comparisons = None
        self._swept = {}

    def values(self, rows, axis):
        """Distinct labels of an axis among rows, in config order (numbers ascending)."""
        present = {label(r, axis) for r in rows if label(r, axis) is not None}
        if axis in NUMERIC_AXES:
            return sorted(present, key=lambda s: num(s) if num(s) is not None else math.inf)
        known = [v for v in self.order.get(axis, []) if v in present]
        return known + sorted(present - set(known))

    def varying(self, rows, exclude=()):
        return [a for a in AXES if a not in exclude and len(self.values(rows, a)) > 1]

    def swept(self, exclude=()):
        """The axes that vary over the whole sweep, less `exclude` (cached: descriptions ask it per run)."""
        exclude = tuple(exclude)
        if exclude not in self._swept:
            self._swept[exclude] = self.varying(self.sweep or self.rows, exclude=exclude)
        return self._swept[exclude]

    def baseline(self, axis):
        vals = self.order.get(axis, [])
        return vals[0] if vals else None

    def record(self, key):
        """DIR/runs/KEY.json's renderer result ({} when absent): values older rows lack as columns."""
        if key not in self._records:
            rec = {}
            path = os.path.join(self.root, "runs", "%s.json" % key)
            if key and os.path.isfile(path):
                try:
                    with open(path) as f:
                        rec = json.load(f).get("result") or {}
                except (OSError, ValueError):
                    rec = {}
            self._records[key] = rec if isinstance(rec, dict) else {}
        return self._records[key]

    def value(self, row, column):
        """A row's column, else the same field of its run record (e.g. effective_depth before it was a column)."""
        v = row.get(column)
        return v if v is not None else self.record(row.get("key")).get(column)

    def comparison(self, a_key, b_key, metric="frame_ms"):
        """findings.json's comparison of runs a and b (either way round, turned to a / b):
        dict(ratio, ci_low, ci_high, verdict, band) or None."""
        if self._comparisons is None:
            self._comparisons = {}
            for c in (self.findings or {}).get("comparisons") or []:
                self._comparisons.setdefault((c.get("a"), c.get("b"), c.get("metric", "frame_ms")), c)
        c = self._comparisons.get((a_key, b_key, metric))
        if c is not None:
            return {k: c.get(k) for k in ("ratio", "ci_low", "ci_high", "verdict", "band")}
        c = self._comparisons.get((b_key, a_key, metric))
        if c is not None:
            inv = lambda v: 1.0 / num(v) if num(v) else None  # noqa: E731
            flip = {"faster": "slower", "slower": "faster"}
            return {"ratio": inv(c.get("ratio")), "ci_low": inv(c.get("ci_high")), "ci_high": inv(c.get("ci_low")),
                    "verdict": flip.get(c.get("verdict"), c.get("verdict")), "band": c.get("band")}
        return None

    def _ratio(self, a, b):
        """(a / b of the median frame times, findings.json's comparison of the two with an interval or None)."""
        plain = ratio(num(a.get("frame_ms")), num(b.get("frame_ms")))
        c = self.comparison(a.get("key"), b.get("key"))
        if c is None or num(c.get("ratio")) is None or num(c.get("ci_low")) is None or num(c.get("ci_high")) is None:
            return plain, None
        return plain, c

    def ratio_cell(self, a, b):
        """A table cell: a's frame time over b's, with findings.json's interval and verdict when it compared
        the two runs; the plain ratio of the medians otherwise."""
        if a is None or b is None:
            return "–"
        plain, c = self._ratio(a, b)
        if c is None:
            return fmt(plain)
        return "%s %s" % (fmt_ratio(c["ratio"], c["ci_low"], c["ci_high"]), verdict_tag(c.get("verdict")))

    def ratio_text(self, a, b):
        """The same for a sentence: "1.050× [1.040, 1.060] (slower)" or "1.05×"."""
        plain, c = self._ratio(a, b)
        if c is None:
            return "%s×" % fmt(plain)
        return "%s (%s)" % (fmt_ratio(c["ratio"], c["ci_low"], c["ci_high"]), verdict_tag(c.get("verdict")))

    def image_uri(self, rel, max_width=None):
        """The PNG as a data: URI; wider than max_width -> box-filtered down by an integer factor
        (keeps a report over hundreds of runs small enough to open)."""
        if not rel:
            return None
        path = os.path.join(self.root, rel)
        if not os.path.isfile(path):
            return None
        if max_width:
            img = mpimg.imread(path)
            factor = -(-img.shape[1] // max_width)
            if factor > 1:
                h, w = img.shape[0] // factor * factor, img.shape[1] // factor * factor
                small = img[:h, :w].reshape(h // factor, factor, w // factor, factor, -1).mean(axis=(1, 3))
                if small.shape[-1] == 1:  # grey PNG
                    small = small[..., 0]
                buf = io.BytesIO()
                plt.imsave(buf, np.clip(small, 0.0, 1.0), format="png")
                return "data:image/png;base64," + base64.b64encode(buf.getvalue()).decode("ascii")
        with open(path, "rb") as f:
            return "data:image/png;base64," + base64.b64encode(f.read()).decode("ascii")

    def load_image(self, rel):
        path = os.path.join(self.root, rel) if rel else None
        if not path or not os.path.isfile(path):
            return None
        return mpimg.imread(path)


def load_findings(root):
    """DIR/findings.json as (dict, None), or (None, why not)."""
    path = os.path.join(root, "findings.json")
    if not os.path.isfile(path):
        return None, "missing"
    try:
        with open(path) as f:
            record = json.load(f)
    except (OSError, ValueError) as e:
        return None, "unreadable (%s)" % e
    if not isinstance(record, dict):
        return None, "not a JSON object"
    return record, None


VERDICT_CLASS = {"faster": "v-faster", "slower": "v-slower", "no detectable difference": "v-none",
                 "same tree": "v-same"}


def verdict_tag(verdict):
    if not verdict:
        return ""
    return '<span class="%s">%s</span>' % (VERDICT_CLASS.get(verdict, "v-none"), html.escape(str(verdict)))


# ---------------------------------------------------------------- choosing runs
def typical_values(data, rows):
    """Each axis's most frequent value among rows (config order breaks ties): the setting the
    per-builder images are shown at, so that builders are compared like for like."""
    out = {}
    for a in AXES:
        values = data.values(rows, a)
        if values:
            counts = {v: sum(1 for r in rows if label(r, a) == v) for v in values}
            out[a] = max(values, key=lambda v: (counts[v], -values.index(v)))
    return out


def representative(rows, typical):
    """The run matching the typical values on the most axes, lowest index on ties."""
    return min(rows, key=lambda r: (-sum(1 for a, v in typical.items() if label(r, a) == v), r.get("index", 0)))


def shared_setting(srows):
    """The largest set of runs (of one scene) that agree on every axis other than the tree's (builder, kernel,
    leaf size, bins): runs that differ only in how the tree is built and walked. Ties: the most builders."""
    other = [a for a in AXES if a not in TREE_AXES and a != "scene"]
    settings = group(srows, lambda r: tuple(label(r, a) for a in other))
    return max(settings.values(), key=lambda rs: (len({label(r, "builder") for r in rs}), len(rs))) if srows else []


def builder_bests(data, srows):
    """{builder: its fastest run} on one scene. The builders' choices (kernel, leaf size, bins) range
    freely; the other axes (depth, aa, ...) are held at the setting that most builders share, so a
    builder's depth-1 run never stands for it. findings.json's builder-best runs win when present."""
    builders = data.values(srows, "builder")
    if not builders:
        return {}
    shared = shared_setting(srows)
    out = {}
    for b in builders:
        mine = [r for r in shared if label(r, "builder") == b] or [r for r in srows if label(r, "builder") == b]
        out[b] = min(mine, key=lambda r: num(r["frame_ms"]))
    if data.findings:
        scene = label(srows[0], "scene")
        for c in data.findings.get("comparisons") or []:
            if c.get("kind") == "builder-best" and c.get("scene") == scene:
                for k in (c.get("a"), c.get("b")):
                    r = data.by_key.get(k)
                    if r is not None and r in srows:
                        out[label(r, "builder")] = r
    return out


def in_sweep(rows, name):
    return [r for r in rows if name in str(r.get("sweeps", "")).split(";")]
