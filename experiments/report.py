#!/usr/bin/python3
"""bvhlab experiment report: DIR/results.json (+ DIR/images) -> DIR/report.html.

The page is self-contained and works offline: plots are matplotlib PNGs and rendered images are
embedded as base64. Every sentence in "Findings" is computed from the rows; nothing is hand-written.
A plot with no data for this config is replaced by a note saying so.

Run with Debian's interpreter, which has python3-matplotlib:
    /usr/bin/python3 experiments/report.py DIR
(`bvhlab run`, `bvhlab merge` and `bvhlab report DIR` call it.)
"""
import base64
import datetime
import html
import io
import json
import math
import os
import platform
import statistics
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from report_robust import section_robustness  # noqa: E402  (experiments/report_robust.py, next to this file)

try:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.image as mpimg
    import matplotlib.patches
    import matplotlib.ticker
    import matplotlib.pyplot as plt
    import numpy as np
except ImportError as e:  # pragma: no cover - depends on the machine
    sys.stderr.write(
        "report.py: %s; install Debian's python3-matplotlib and run /usr/bin/python3 "
        "(a pyenv/venv python3 usually lacks it)\n" % e
    )
    sys.exit(3)

AXES = ["scene", "builder", "kernel", "leaf_size", "depth", "storage", "aa", "robust", "branching", "view", "uber", "smaa_edges"]
NUMERIC_AXES = {"leaf_size", "depth"}
# Axes whose cost the findings report as a time ratio against the first value in the config.
KNOBS = ["aa", "robust", "depth", "storage", "branching", "uber", "kernel", "view"]
# Two frame times closer than this are "the same" in the findings. Measured llvmpipe run-to-run
# noise is ~0.5% (shared/NOTES.md); 5% leaves a margin for busier machines. The report prints the
# spread measured in this sweep next to it.
SAME_TIME = 0.05
MAX_SERIES_LABEL = 60
THUMBNAIL_WIDTH = 400  # per-builder images wider than this are shown downscaled (full size in DIR/images)


# ---------------------------------------------------------------- data helpers
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


def geomean(values):
    values = [v for v in values if v is not None and v > 0]
    return math.exp(sum(math.log(v) for v in values) / len(values)) if values else None


class Data:
    def __init__(self, results, root):
        self.root = root
        self.results = results
        self.experiment = results.get("experiment", {})
        self.rows = results.get("rows", [])
        self.ok = [r for r in self.rows if r.get("status") == "ok" and num(r.get("frame_ms")) is not None]
        self.sweep = [r for r in self.ok if not r.get("reference_only")]
        self.failed = [r for r in self.rows if r.get("status") != "ok"]
        self.order = self.experiment.get("axes", {})

    def values(self, rows, axis):
        """Distinct labels of an axis among rows, in config order (numbers ascending)."""
        present = {label(r, axis) for r in rows if label(r, axis) is not None}
        if axis in NUMERIC_AXES:
            return sorted(present, key=lambda s: num(s) if num(s) is not None else math.inf)
        known = [v for v in self.order.get(axis, []) if v in present]
        return known + sorted(present - set(known))

    def varying(self, rows, exclude=()):
        return [a for a in AXES if a not in exclude and len(self.values(rows, a)) > 1]

    def baseline(self, axis):
        vals = self.order.get(axis, [])
        return vals[0] if vals else None

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


def describe(row, axes):
    parts = []
    for a in axes:
        v = label(row, a)
        if v is None:
            continue
        parts.append(v if a in ("scene", "builder") else "%s=%s" % (a, v))
    return " ".join(parts)


def plural(n, word):
    return "%d %s%s" % (n, word, "" if n == 1 else "s")


def group(rows, key):
    out = {}
    for r in rows:
        out.setdefault(key(r), []).append(r)
    return out


# ---------------------------------------------------------------- html helpers
class Page:
    def __init__(self):
        self.parts = []
        self.toc = []

    def add(self, s):
        self.parts.append(s)

    def section(self, sid, title, level=2):
        if level == 2:
            self.toc.append((sid, title))
        self.add('<h%d id="%s">%s</h%d>' % (level, sid, html.escape(title), level))

    def p(self, text):
        self.add("<p>%s</p>" % text)

    def note(self, text):
        self.add('<p class="note">%s</p>' % text)

    def figure(self, fig, caption=""):
        buf = io.BytesIO()
        fig.savefig(buf, format="png", dpi=96, bbox_inches="tight")
        plt.close(fig)
        uri = "data:image/png;base64," + base64.b64encode(buf.getvalue()).decode("ascii")
        self.add('<figure><img src="%s" alt="%s"><figcaption>%s</figcaption></figure>'
                 % (uri, html.escape(caption), caption))

    def table(self, tid, header, rows, cls=""):
        out = ['<div class="scroll"><table id="%s" class="%s"><thead><tr>' % (tid, cls)]
        out += ["<th>%s</th>" % html.escape(h) for h in header]
        out.append("</tr></thead><tbody>")
        for r in rows:
            out.append("<tr>" + "".join("<td>%s</td>" % c for c in r) + "</tr>")
        out.append("</tbody></table></div>")
        self.add("".join(out))


CSS = """
body{font:14px/1.45 sans-serif;margin:2em auto;max-width:1200px;color:#222;padding:0 1em}
h1{margin-bottom:0}h2{border-bottom:1px solid #ccc;margin-top:2em}
table{border-collapse:collapse;font-size:12px}td,th{border:1px solid #ddd;padding:2px 6px;text-align:right}
th{background:#f3f3f3;position:sticky;top:0}td:first-child,th:first-child{text-align:left}
.scroll{overflow:auto;max-height:600px;margin:1em 0}.note{color:#777;font-style:italic}
figure{margin:1em 0}figure img{max-width:100%}figcaption{color:#555;font-size:12px}
img.render{image-rendering:pixelated;max-width:480px}pre{background:#f7f7f7;padding:.5em;overflow:auto;max-height:300px}
ul.findings li{margin:.3em 0}.pair{display:flex;gap:1em;flex-wrap:wrap;align-items:flex-start}
.pair div{text-align:center;font-size:12px}
"""


# ---------------------------------------------------------------- plots
def facet_axes(n, width=7.5, height=3.4):
    """One panel per scene, stacked, with room on the right for the legend."""
    fig, axs = plt.subplots(n, 1, figsize=(width, height * n), squeeze=False)
    return fig, [row[0] for row in axs]


def outside_legend(ax, n):
    if n:
        ax.legend(fontsize=7 if n <= 12 else 6, ncol=1 if n <= 16 else 2, loc="upper left",
                  bbox_to_anchor=(1.01, 1.0), borderaxespad=0)


def log2_ticks(ax, values):
    ax.set_xscale("log", base=2)
    ax.set_xticks(sorted(values))
    ax.get_xaxis().set_major_formatter(matplotlib.ticker.ScalarFormatter())
    ax.get_xaxis().set_minor_locator(matplotlib.ticker.NullLocator())


def line_plot(data, rows, x, y, ylabel, title, logx=False):
    """y vs x, one panel per scene, one line per combination of the other varying axes.
    Returns (figure, None) or (None, reason)."""
    rows = [r for r in rows if num(r.get(x)) is not None and num(r.get(y)) is not None]
    if len(data.values(rows, x)) < 2:
        return None, "fewer than two values of %s" % x
    scenes = data.values(rows, "scene")
    series_axes = data.varying(rows, exclude=(x, "scene"))
    panels = []
    for scene in scenes:
        srows = [r for r in rows if label(r, "scene") == scene]
        lines = group(srows, lambda r: tuple(label(r, a) for a in series_axes))
        lines = {k: v for k, v in lines.items() if len({label(r, x) for r in v}) >= 2}
        if lines:
            panels.append((scene, lines))
    if not panels:
        return None, "no series with two or more values of %s" % x
    fig, axs = facet_axes(len(panels))
    for ax, (scene, lines) in zip(axs, panels):
        palette = plt.cm.tab10.colors if len(lines) <= 10 else plt.cm.tab20.colors
        for i, (k, members) in enumerate(sorted(lines.items(), key=lambda kv: [str(v) for v in kv[0]])):
            by_x = group(members, lambda r: num(r.get(x)))
            xs = sorted(by_x)
            ys = [statistics.median(num(r.get(y)) for r in by_x[v]) for v in xs]
            name = " ".join(describe(members[0], series_axes).split()) or "runs"
            line, = ax.plot(xs, ys, marker="o", markersize=3, linewidth=1.2, label=name[:MAX_SERIES_LABEL],
                            color=palette[i % len(palette)], linestyle=("-", "--", ":")[(i // len(palette)) % 3])
            if y == "frame_ms":  # the fastest and slowest timed frame of each run, as a band
                lo = [min(num(r.get("frame_ms_min")) or num(r[y]) for r in by_x[v]) for v in xs]
                hi = [max(num(r.get("frame_ms_max")) or num(r[y]) for r in by_x[v]) for v in xs]
                ax.fill_between(xs, lo, hi, color=line.get_color(), alpha=0.12, linewidth=0)
        if logx:
            log2_ticks(ax, {num(r.get(x)) for r in rows})
        ax.set_title("%s — %s" % (title, scene), fontsize=10)
        ax.set_xlabel(x)
        ax.set_ylabel(ylabel)
        ax.set_ylim(bottom=0)  # ratios read true from a zero baseline
        ax.grid(alpha=0.3)
        outside_legend(ax, len(lines))
    fig.tight_layout()
    return fig, None


def scatter_visits_vs_sah(data, rows):
    rows = [r for r in rows if num(r.get("sah_cost")) is not None and num(r.get("node_visits_per_ray")) is not None]
    if len(rows) < 2:
        return None, "no runs report both SAH cost and node visits per ray"
    scenes = data.values(rows, "scene")
    fig, axs = facet_axes(len(scenes))
    for ax, scene in zip(axs, scenes):
        srows = [r for r in rows if label(r, "scene") == scene]
        kernels = data.values(srows, "kernel")
        markers = dict(zip(kernels, "o^sDv<>pH*")) if len(kernels) > 1 else {}
        for i, b in enumerate(data.values(srows, "builder")):
            br = [r for r in srows if label(r, "builder") == b]
            for k in kernels or [None]:
                kr = [r for r in br if label(r, "kernel") == k] if markers else br
                if kr:
                    ax.scatter([num(r["sah_cost"]) for r in kr], [num(r["node_visits_per_ray"]) for r in kr], s=16,
                               color="C%d" % (i % 10), marker=markers.get(k, "o"),
                               label=b + (" / " + k if markers else ""))
                if not markers:
                    break
            for r in br:
                if label(r, "leaf_size") is not None:
                    ax.annotate(label(r, "leaf_size"), (num(r["sah_cost"]), num(r["node_visits_per_ray"])),
                                fontsize=6, alpha=0.6, xytext=(2, 2), textcoords="offset points")
        ax.set_title("Node visits per ray vs SAH cost — %s" % scene, fontsize=10)
        ax.set_xlabel("SAH cost (Ct = Ci = 1, normalised by root area)")
        ax.set_ylabel("node visits / ray")
        ax.grid(alpha=0.3)
        outside_legend(ax, len(data.values(srows, "builder")) * max(1, len(markers)))
    fig.tight_layout()
    return fig, None


def builder_costs(data, rows):
    """SAH cost and build time per builder (vs leaf size when it varies), one row of panels per scene."""
    rows = [r for r in rows if num(r.get("sah_cost")) is not None or num(r.get("build_ms")) is not None]
    if not rows:
        return None, "no runs report SAH cost or build time"
    scenes = data.values(rows, "scene")
    fig, axs = plt.subplots(len(scenes), 2, figsize=(12, 3.4 * len(scenes)), squeeze=False)
    for (ax_sah, ax_ms), scene in zip(axs, scenes):
        srows = [r for r in rows if label(r, "scene") == scene]
        builders = data.values(srows, "builder")
        leaves = data.values(srows, "leaf_size")
        for ax, metric, ylab in ((ax_sah, "sah_cost", "SAH cost"), (ax_ms, "build_ms", "build time (ms)")):
            if len(leaves) >= 2:
                for b in builders:
                    by_leaf = group([r for r in srows if label(r, "builder") == b and num(r.get(metric)) is not None],
                                    lambda r: num(r.get("leaf_size")))
                    xs = sorted(k for k in by_leaf if k is not None)
                    if xs:
                        ax.plot(xs, [statistics.median(num(r[metric]) for r in by_leaf[v]) for v in xs],
                                marker="o", markersize=3, label=b)
                log2_ticks(ax, {num(x) for x in leaves})
                ax.set_xlabel("leaf size")
            else:
                vals = [statistics.median([num(r.get(metric)) for r in srows
                                           if label(r, "builder") == b and num(r.get(metric)) is not None] or [0])
                        for b in builders]
                ax.bar(range(len(builders)), vals, color="C0")
                ax.set_xticks(range(len(builders)))
                ax.set_xticklabels(builders, rotation=20, fontsize=8)
            ax.set_ylabel(ylab)
            ax.set_ylim(bottom=0)
            ax.set_title("%s per builder — %s" % (ylab, scene), fontsize=10)
            ax.grid(alpha=0.3)
            if len(leaves) >= 2:
                ax.legend(fontsize=7)
    fig.tight_layout()
    return fig, None


def pareto_front(points):
    """Points (time, error, row) not dominated by another (lower-or-equal in both, lower in one)."""
    front, best_err = [], math.inf
    for t, e, r in sorted(points, key=lambda p: (p[0], p[1])):
        if e < best_err:
            front.append((t, e, r))
            best_err = e
    return front


def pareto_plot(data, rows):
    rows = [r for r in rows if num(r.get("image_mae")) is not None and num(r.get("frame_ms")) is not None]
    if len(rows) < 2:
        return None, [], "no image-error data (the config needs a [experiment.reference] and runs with images)"
    scenes = data.values(rows, "scene")
    label_axes = data.varying(rows, exclude=("scene",))
    fig, axs = facet_axes(len(scenes))
    fronts = []
    for ax, scene in zip(axs, scenes):
        srows = [r for r in rows if label(r, "scene") == scene]
        pts = [(num(r["frame_ms"]), num(r["image_mae"]), r) for r in srows]
        ax.scatter([p[0] for p in pts], [p[1] for p in pts], s=10, color="0.6", label="runs")
        front = pareto_front(pts)
        fronts.append((scene, front))
        ax.step([p[0] for p in front], [p[1] for p in front], where="post", color="C3", label="Pareto front")
        ax.scatter([p[0] for p in front], [p[1] for p in front], s=18, color="C3")
        for t, e, r in front:
            ax.annotate(describe(r, label_axes)[:MAX_SERIES_LABEL], (t, e), fontsize=6,
                        xytext=(3, 3), textcoords="offset points")
        ax.set_xscale("log")
        ax.set_title("Image error vs frame time — %s" % scene, fontsize=10)
        ax.set_xlabel("frame time (ms, log)")
        ax.set_ylabel("mean abs error vs reference (8-bit)")
        ax.grid(alpha=0.3)
        outside_legend(ax, 2)
    fig.tight_layout()
    return fig, fronts, None


# ---------------------------------------------------------------- findings
def best_builders(data):
    out = []
    for scene in data.values(data.sweep, "scene"):
        srows = [r for r in data.sweep if label(r, "scene") == scene]
        builders = data.values(srows, "builder")
        if len(builders) < 2:
            continue
        best = {b: min((r for r in srows if label(r, "builder") == b), key=lambda r: num(r["frame_ms"]))
                for b in builders}
        ranked = sorted(best.values(), key=lambda r: num(r["frame_ms"]))
        top = ranked[0]
        others = ", ".join("%s %s×" % (label(r, "builder"), fmt(ratio(num(r["frame_ms"]), num(top["frame_ms"]))))
                           for r in ranked[1:])
        out.append("<b>%s</b>: fastest builder <b>%s</b> (%s ms, %s); the others at their best are slower by: %s."
                   % (html.escape(scene), html.escape(label(top, "builder")), fmt(top["frame_ms"]),
                      html.escape(describe(top, data.varying(srows, exclude=("scene", "builder")))), others))
    return out


def leaf_size_findings(data):
    """Per scene and builder: the best leaf size and the range within SAME_TIME of it, on the series
    (other axes fixed) with the most leaf sizes; among those, the one holding the fastest run."""
    out = []
    rows = [r for r in data.sweep if num(r.get("leaf_size")) is not None]
    if len(data.values(rows, "leaf_size")) < 3:
        return out
    others = data.varying(rows, exclude=("leaf_size", "scene", "builder"))
    for (scene, builder), members in group(rows, lambda r: (label(r, "scene"), label(r, "builder"))).items():
        candidates = group(members, lambda r: tuple(label(r, a) for a in others)).values()
        series = max(candidates, key=lambda c: (len({label(r, "leaf_size") for r in c}),
                                                -min(num(r["frame_ms"]) for r in c)))
        best_run = min(series, key=lambda r: num(r["frame_ms"]))
        by_leaf = {num(r["leaf_size"]): num(r["frame_ms"]) for r in series}
        if len(by_leaf) < 3:
            continue
        best_leaf = min(by_leaf, key=by_leaf.get)
        best_ms = by_leaf[best_leaf]
        flat = sorted(l for l, ms in by_leaf.items() if ms <= best_ms * (1 + SAME_TIME))
        worst_leaf = max(by_leaf, key=by_leaf.get)
        if len(flat) > 1:
            band = "leaf sizes %s are within %d%% of it" % (", ".join(fmt(l) for l in flat), round(SAME_TIME * 100))
        else:
            band = "no other leaf size is within %d%% of it" % round(SAME_TIME * 100)
        out.append("<b>%s / %s</b>%s: best leaf size %s (%s ms); %s; the worst, %s, is %s× slower."
                   % (html.escape(scene), html.escape(builder),
                      (" (" + html.escape(describe(best_run, others)) + ")") if others else "",
                      fmt(best_leaf), fmt(best_ms), band, fmt(worst_leaf), fmt(by_leaf[worst_leaf] / best_ms)))
    return out


def knob_costs(data):
    """For each knob axis: the frame-time ratio of each value against the config's first value, over
    pairs of runs that differ in that axis only."""
    table = []
    for axis in KNOBS:
        values = data.values(data.ok, axis)
        base = data.baseline(axis)
        if len(values) < 2 or base not in values:
            continue
        others = [a for a in AXES if a != axis]
        index = group(data.ok, lambda r: tuple(label(r, a) for a in others))
        for v in values:
            if v == base:
                continue
            ratios, d_err = [], []
            for members in index.values():
                b = [r for r in members if label(r, axis) == base]
                o = [r for r in members if label(r, axis) == v]
                if b and o:
                    ratios.append(ratio(num(o[0]["frame_ms"]), num(b[0]["frame_ms"])))
                    eb, eo = num(b[0].get("image_mae")), num(o[0].get("image_mae"))
                    if eb is not None and eo is not None:
                        d_err.append(eo - eb)
            ratios = [x for x in ratios if x is not None]
            if ratios:
                table.append((axis, base, v, len(ratios), geomean(ratios), min(ratios), max(ratios),
                              statistics.mean(d_err) if d_err else None))
    return table


def timing_spread(data):
    spreads = [ratio(num(r.get("frame_ms_max")) - num(r.get("frame_ms_min")), num(r["frame_ms"]))
               for r in data.ok if num(r.get("frame_ms_max")) is not None and num(r.get("frame_ms_min")) is not None]
    spreads = [s for s in spreads if s is not None]
    return statistics.median(spreads) if spreads else None


def correlation(xs, ys):
    if len(xs) < 3:
        return None
    mx, my = statistics.mean(xs), statistics.mean(ys)
    sx = math.sqrt(sum((x - mx) ** 2 for x in xs))
    sy = math.sqrt(sum((y - my) ** 2 for y in ys))
    if sx == 0 or sy == 0:
        return None
    return sum((x - mx) * (y - my) for x, y in zip(xs, ys)) / (sx * sy)


# ---------------------------------------------------------------- sections
def section_findings(page, data, knobs, fronts):
    page.section("findings", "Findings (computed from the rows)")
    items = []
    spread = timing_spread(data)
    if spread is not None:
        items.append("Timing noise: the median run's (max − min) / median frame time is %s%%; the findings "
                     "treat frame times within %d%% as equal." % (fmt(spread * 100), round(SAME_TIME * 100)))
    items += best_builders(data)
    items += leaf_size_findings(data)
    for axis, base, v, n, g, lo, hi, d_err in knobs:
        s = "<b>%s = %s</b> costs %s× the frame time of %s = %s (geometric mean over %s, range %s–%s)" % (
            axis, html.escape(v), fmt(g), axis, html.escape(base), plural(n, "matched pair"), fmt(lo), fmt(hi))
        if d_err is not None:
            s += " and changes the image error by %s (8-bit mean abs)" % fmt(d_err)
        items.append(s + ".")
    # Per scene and kernel: kernels visit different node counts for the same tree.
    for (scene, kernel), members in group(data.sweep, lambda r: (label(r, "scene"), label(r, "kernel"))).items():
        pts = [(num(r.get("sah_cost")), num(r.get("node_visits_per_ray"))) for r in members]
        pts = [p for p in pts if p[0] is not None and p[1] is not None]
        r = correlation([p[0] for p in pts], [p[1] for p in pts])
        if r is not None:
            items.append("<b>%s</b>%s: SAH cost and node visits per ray correlate with Pearson r = %s over %s."
                         % (html.escape(scene), (" / " + html.escape(kernel)) if kernel else "", fmt(r),
                            plural(len(pts), "run")))
    for scene, front in fronts:
        if len(front) >= 1:
            items.append("<b>%s</b>: the accuracy/time Pareto front has %s: %s." % (
                html.escape(scene), plural(len(front), "run"),
                "; ".join("%s ms → error %s" % (fmt(t), fmt(e)) for t, e, _ in front)))
    if data.failed:
        items.append("%s failed (listed below with their errors)." % plural(len(data.failed), "run"))
    if not items:
        page.note("Not enough finished runs for any finding.")
        return
    page.add('<ul class="findings">' + "".join("<li>%s</li>" % i for i in items) + "</ul>")


def section_plot(page, sid, title, result, caption):
    page.section(sid, title)
    fig, reason = result
    if fig is None:
        page.note("Plot omitted: %s." % html.escape(reason))
    else:
        page.figure(fig, caption)


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


def section_images(page, data):
    page.section("images-per-builder", "Rendered images and node-visit heatmaps per builder")
    rows = [r for r in data.sweep if r.get("image")]
    if not rows:
        page.note("No images: no finished run wrote one.")
        return
    shown = data.varying(rows, exclude=("scene", "builder"))
    for scene in data.values(rows, "scene"):
        page.add("<h3>%s</h3>" % html.escape(scene))
        srows = [r for r in rows if label(r, "scene") == scene]
        typical = typical_values(data, srows)
        cells = []
        for b in data.values(srows, "builder") or [None]:
            r = representative([x for x in srows if label(x, "builder") == b] if b else srows, typical)
            img = data.image_uri(r.get("image"), max_width=THUMBNAIL_WIDTH)
            heat = data.image_uri(r.get("visits_image"), max_width=THUMBNAIL_WIDTH)
            cap = "%s<br>%s ms, %s visits/ray" % (html.escape(describe(r, shown) or "the only run"),
                                                  fmt(r.get("frame_ms")), fmt(r.get("node_visits_per_ray")))
            cells.append(["<b>%s</b>" % html.escape(b or "–"),
                          '<img class="render" src="%s">' % img if img else "–",
                          '<img class="render" src="%s">' % heat if heat else "no heatmap",
                          cap])
        page.table("images-%s" % html.escape(scene), ["builder", "image", "node visits", "run"], cells)


def section_builder_table(page, data):
    page.section("table-builders", "Per builder")
    rows = data.sweep
    if not rows:
        page.note("No finished runs.")
        return
    out = []
    for (scene, builder), members in sorted(group(rows, lambda r: (label(r, "scene"), label(r, "builder"))).items(),
                                            key=lambda kv: [str(x) for x in kv[0]]):
        best = min(members, key=lambda r: num(r["frame_ms"]))
        med = lambda k: (statistics.median([num(r.get(k)) for r in members if num(r.get(k)) is not None])
                         if any(num(r.get(k)) is not None for r in members) else None)
        out.append([html.escape(str(scene)), html.escape(str(builder)), str(len(members)), fmt(best["frame_ms"]),
                    html.escape(describe(best, ["kernel", "leaf_size", "depth", "storage"])),
                    fmt(med("frame_ms")), fmt(med("sah_cost")), fmt(med("build_ms")),
                    fmt(med("node_visits_per_ray")), fmt(med("triangle_tests_per_ray"))])
    page.table("table-builders-data", ["scene", "builder", "runs", "best ms", "best run", "median ms",
                                       "median SAH", "median build ms", "median visits/ray",
                                       "median tri tests/ray"], out)


def section_knobs(page, knobs):
    page.section("table-knobs", "Cost of each knob (frame-time ratio vs the config's first value)")
    if not knobs:
        page.note("No axis among %s has two values with matched runs." % ", ".join(KNOBS))
        return
    page.table("table-knobs-data", ["axis", "baseline", "value", "pairs", "time ratio (geo. mean)", "min", "max",
                                    "Δ image error"],
               [[a, html.escape(b), html.escape(v), str(n), fmt(g), fmt(lo), fmt(hi), fmt(d)]
                for a, b, v, n, g, lo, hi, d in knobs])


def section_all_rows(page, data):
    page.section("table-results", "Every run")
    columns = [c for c in data.results.get("columns", []) if c not in ("scene_file",)]
    if not data.rows:
        page.note("No finished runs yet.")
    cells = []
    for r in data.rows:
        line = []
        for c in columns:
            v = r.get(c)
            if c == "error" and v:
                v = str(v)[:200]
            is_number = isinstance(v, (int, float)) and not isinstance(v, bool)
            line.append(fmt(v) if is_number else html.escape("" if v is None else str(v)))
        cells.append(line)
    page.table("table-results-data", columns, cells)
    page.p("Also in <code>results.csv</code> and <code>results.json</code> next to this file.")


def section_failed(page, data):
    page.section("table-failed", "Failed runs")
    if not data.failed:
        page.p("No failed runs.")
        return
    for r in data.failed:
        key = r.get("key", "")
        log = ""
        path = os.path.join(data.root, "runs", key + ".json")
        if os.path.isfile(path):
            with open(path) as f:
                rec = json.load(f)
            log = rec.get("log", "")
            cmd = rec.get("command", "")
        else:
            cmd = ""
        page.add("<h3>%s — %s</h3><p><b>%s</b></p>%s%s" % (
            html.escape(key), html.escape(describe(r, AXES)), html.escape(str(r.get("error", ""))),
            "<pre>%s</pre>" % html.escape(cmd) if cmd else "",
            "<details><summary>stderr</summary><pre>%s</pre></details>" % html.escape(log) if log else ""))


def section_provenance(page, data):
    page.section("provenance", "Provenance")
    res, prov, summ = data.results, data.results.get("provenance", {}), data.results.get("summary", {})
    starts = sorted(r["started_at"] for r in data.rows if r.get("started_at"))
    items = [
        ("config", html.escape(str(res.get("config", {}).get("file", "?")))),
        ("config hash", html.escape(str(res.get("config", {}).get("hash", "?")))),
        ("runs", "%s planned, %s ok, %s failed, %s pending, %s stale records" % tuple(
            summ.get(k, "?") for k in ("planned", "ok", "failed", "pending", "stale"))),
        ("git commits", html.escape(", ".join(prov.get("git_commits", [])) or "unknown")),
        ("GL renderers", html.escape(", ".join(prov.get("gl_renderers", [])) or "unknown")),
        ("machines", "<br>".join(html.escape("%s: %s, %s cores" % (m.get("hostname"), m.get("cpu"), m.get("cores")))
                                 for m in prov.get("machines", []) if m) or "unknown"),
        ("run times (UTC)", "%s … %s" % (starts[0], starts[-1]) if starts else "–"),
        ("report generated", datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ")
         + " by report.py, Python %s, matplotlib %s" % (platform.python_version(), matplotlib.__version__)),
    ]
    page.table("provenance-data", ["", ""], [["<b>%s</b>" % k, v] for k, v in items])
    plan = os.path.join(data.root, "plan.json")
    if os.path.isfile(plan):
        with open(plan) as f:
            text = json.load(f).get("config", {}).get("text", "")
        page.add("<details><summary>config file as run</summary><pre>%s</pre></details>" % html.escape(text))


# ---------------------------------------------------------------- seed report figures
def in_sweep(rows, name):
    return [r for r in rows if name in str(r.get("sweeps", "")).split(";")]


def fps(r):
    return ratio(1000.0, num(r.get("frame_ms")))


def seed_sections(page, data):
    page.section("seed-figures", "The seed report's figures, measured")
    page.p("Sections mirror Figs. 8–12 of the seed report (Zhu &amp; Li, <i>Real-Time Ray Tracing</i>, 2022). "
           "The seed plots frame rate (FPS); so do these, from the median frame time of each run.")

    # Fig. 8: with/without the mesh, with/without SMAA.
    page.section("seed-fig8", "Fig. 8 — frame rate with and without the mesh, SMAA off and on", level=3)
    rows = in_sweep(data.ok, "fig8")
    if not rows:
        page.note("No finished runs in the sweep named fig8.")
    else:
        scenes = data.values(rows, "scene")
        aas = data.values(rows, "aa") or [None]
        fig, ax = plt.subplots(figsize=(6.5, 3.4))
        width = 0.8 / max(1, len(aas))
        cells = []
        for j, aa in enumerate(aas):
            vals = []
            for s in scenes:
                m = [r for r in rows if label(r, "scene") == s and label(r, "aa") == aa]
                vals.append(fps(m[0]) if m else 0)
                if m:
                    cells.append([html.escape(s), "yes" if (num(m[0].get("triangles")) or 0) > 0 else "no",
                                  html.escape(str(aa)), fmt(fps(m[0])), fmt(m[0]["frame_ms"])])
            ax.bar([i + j * width for i in range(len(scenes))], vals, width, label="aa=%s" % aa)
        ax.set_xticks([i + width * (len(aas) - 1) / 2 for i in range(len(scenes))])
        ax.set_xticklabels(scenes)
        ax.set_ylabel("frames per second")
        ax.legend(fontsize=8)
        ax.grid(axis="y", alpha=0.3)
        page.figure(fig, "Fig. 8 measured: FPS per scene and anti-aliasing mode.")
        page.table("seed-fig8-data", ["scene", "has mesh", "aa", "FPS", "frame ms"], cells)
        notes = []
        for s in scenes:
            base = [r for r in rows if label(r, "scene") == s and label(r, "aa") in ("none", None)]
            smaa = [r for r in rows if label(r, "scene") == s and label(r, "aa") == "smaa"]
            if base and smaa:
                notes.append("%s: SMAA costs %s× the frame time (the seed's §4.5 says SMAA barely lowers the frame rate)."
                             % (html.escape(s), fmt(ratio(num(smaa[0]["frame_ms"]), num(base[0]["frame_ms"])))))
        mesh = [r for r in rows if (num(r.get("triangles")) or 0) > 0 and label(r, "aa") in ("none", None)]
        nomesh = [r for r in rows if (num(r.get("triangles")) or 0) == 0 and label(r, "aa") in ("none", None)]
        if mesh and nomesh:
            notes.append("The mesh costs %s× the frame time (%s vs %s FPS)." % (
                fmt(ratio(num(mesh[0]["frame_ms"]), num(nomesh[0]["frame_ms"]))), fmt(fps(mesh[0])),
                fmt(fps(nomesh[0]))))
        for n in notes:
            page.p(n)

    # Fig. 9: FPS vs recursion depth.
    page.section("seed-fig9", "Fig. 9 — frame rate vs recursion depth", level=3)
    page.p("The seed (§4.3, Fig. 9): the frame rate falls as the recursion depth grows.")
    seed_fps_plot(page, data, in_sweep(data.ok, "fig9"), "depth", "recursion depth", "seed-fig9-data",
                  "fig9")

    # Fig. 10: FPS vs triangles per leaf.
    page.section("seed-fig10", "Fig. 10 — frame rate vs triangles per BVH leaf", level=3)
    page.p("The seed (§4.4, Fig. 10): too few triangles per leaf and too many are both slow.")
    seed_fps_plot(page, data, in_sweep(data.ok, "fig10"), "leaf_size", "max triangles per leaf", "seed-fig10-data",
                  "fig10")

    # Fig. 11: depth-1 render.
    page.section("seed-fig11", "Fig. 11 — a render at recursion depth 1", level=3)
    rows = [r for r in in_sweep(data.ok, "fig9") if r.get("image") and num(r.get("depth")) is not None]
    if not rows:
        page.note("No images from the sweep named fig9.")
    else:
        shallow = min(rows, key=lambda r: num(r["depth"]))
        deep = max(rows, key=lambda r: num(r["depth"]))
        images = [(shallow, "depth %s" % label(shallow, "depth"))]
        if deep is not shallow:
            images.append((deep, "depth %s (for comparison)" % label(deep, "depth")))
        page.add('<div class="pair">' + "".join(
            '<div><img class="render" src="%s"><br>%s, %s ms</div>' % (data.image_uri(r["image"]), c,
                                                                        fmt(r["frame_ms"]))
            for r, c in images) + "</div>")
        a, b = data.load_image(shallow["image"]), data.load_image(deep["image"])
        if a is not None and b is not None and a.shape == b.shape and deep is not shallow:
            page.p("Mean luminance: %s at depth %s vs %s at depth %s (the seed's §4.3: depth 1 is darker)." % (
                fmt(float(np.mean(a[..., :3]))), label(shallow, "depth"), fmt(float(np.mean(b[..., :3]))),
                label(deep, "depth")))

    # Fig. 12: SMAA comparison.
    page.section("seed-fig12", "Fig. 12 — SMAA off vs on", level=3)
    rows = [r for r in in_sweep(data.ok, "fig8") if r.get("image")]
    pairs = []
    for s in data.values(rows, "scene"):
        off = [r for r in rows if label(r, "scene") == s and label(r, "aa") in ("none", None)]
        on = [r for r in rows if label(r, "scene") == s and label(r, "aa") == "smaa"]
        if off and on:
            pairs.append((s, off[0], on[0]))
    if not pairs:
        page.note("No pair of fig8 runs with aa=none and aa=smaa on the same scene.")
    # The seed shows the scene with the mesh; prefer it when there is one.
    pairs.sort(key=lambda p: 0 if (num(p[1].get("triangles")) or 0) > 0 else 1)
    for s, off, on in pairs[:1]:
        a, b = data.load_image(off["image"]), data.load_image(on["image"])
        if a is None or b is None or a.shape != b.shape:
            page.note("Images of %s missing or of different sizes." % html.escape(s))
            continue
        diff = np.abs(a[..., :3].astype(float) - b[..., :3].astype(float)).sum(axis=2)
        # Zoom on the window where SMAA changed the most (data-driven crop), 1/4 of each side.
        h, w = diff.shape
        ch, cw = max(1, h // 4), max(1, w // 4)
        best, at = -1.0, (0, 0)
        for y in range(0, h - ch + 1, max(1, ch // 2)):
            for x in range(0, w - cw + 1, max(1, cw // 2)):
                v = float(diff[y:y + ch, x:x + cw].sum())
                if v > best:
                    best, at = v, (y, x)
        fig, axs = plt.subplots(2, 2, figsize=(9, 9 * h / w * 1.0 + 0.5))
        for col, (img, name) in enumerate(((a, "SMAA off"), (b, "SMAA on"))):
            axs[0][col].imshow(img)
            axs[0][col].add_patch(matplotlib.patches.Rectangle((at[1], at[0]), cw, ch, fill=False, color="r"))
            axs[0][col].set_title(name, fontsize=9)
            axs[1][col].imshow(img[at[0]:at[0] + ch, at[1]:at[1] + cw], interpolation="nearest")
            axs[1][col].set_title("%s, zoomed 4×" % name, fontsize=9)
        for ax in axs.flat:
            ax.set_axis_off()
        page.figure(fig, "Fig. 12 measured (%s): the red window is where SMAA changed the image most." % html.escape(s))
        mae = float(np.mean(np.abs(a[..., :3] - b[..., :3]))) * (255.0 if a.dtype != np.uint8 else 1.0)
        page.p("SMAA changes the image by a mean of %s (8-bit units) and costs %s× the frame time." % (
            fmt(mae), fmt(ratio(num(on["frame_ms"]), num(off["frame_ms"])))))


def aa_preset(row):
    """'smaa' runs name their preset in smaa_preset; show them as smaa-PRESET like the axis values."""
    v = label(row, "aa")
    v = "smaa-%s" % row["smaa_preset"] if v == "smaa" and row.get("smaa_preset") else v
    # Colour edge detection is a variant of the SMAA mode, not another scene setting (luma: the default).
    return v + " (colour edges)" if v.startswith("smaa") and row.get("smaa_edges") == "color" else v


def worst_window(diff, frac=6):
    """Top-left corner and size of the window (1/frac of each side) with the largest summed diff."""
    h, w = diff.shape
    ch, cw = max(1, h // frac), max(1, w // frac)
    best, at = -1.0, (0, 0)
    for y in range(0, h - ch + 1, max(1, ch // 2)):
        for x in range(0, w - cw + 1, max(1, cw // 2)):
            v = float(diff[y:y + ch, x:x + cw].sum())
            if v > best:
                best, at = v, (y, x)
    return at, (ch, cw)


def section_antialiasing(page, data):
    """Issue 5's comparison: per scene, every anti-aliasing mode's frame time and image error against
    the config's reference (16x supersampling), with the seed's two targets and crops (Fig. 12)."""
    rows = [r for r in data.ok if r.get("aa")]
    if len(data.values(rows, "aa")) < 2:
        return
    page.section("antialiasing", "Anti-aliasing: accuracy vs time")
    page.p("Error = mean absolute difference over 8-bit RGB against the reference run (its image is "
           "supersampled 16× when the config says so). Targets from issue 5: SMAA error ≤ 0.5× the error "
           "without AA, SMAA frame time ≤ 0.25× SSAA 4×'s. The post-process column is the time of the three SMAA "
           "passes alone, included in the frame time. The frame-time ratio cannot fall below time(none) / "
           "time(SSAA 4×), because the SMAA frame still traces every pixel once; the added-time column "
           "compares what each mode adds to the frame without AA, (t − t_none) / (t_SSAA4 − t_none), which "
           "is the anti-aliasing's own cost.")
    by_key = {r.get("key"): r for r in data.ok}
    others = [a for a in AXES if a not in ("aa", "smaa_edges")]
    for combo, members in sorted(group(rows, lambda r: tuple(label(r, a) for a in others)).items(),
                                 key=lambda kv: [str(x) for x in kv[0]]):
        modes = {}
        for r in members:
            modes.setdefault(aa_preset(r), r)
        if len(modes) < 2:
            continue
        scene = label(members[0], "scene")
        varying = [a for a in data.varying(rows, exclude=("aa", "smaa_edges"))]
        title = describe(members[0], varying) or scene
        page.add("<h3>%s</h3>" % html.escape(title))
        none, ssaa4 = modes.get("none"), modes.get("ssaa4")
        cells = []
        for mode in sorted(modes, key=lambda m: (data.values(rows, "aa").index(label(modes[m], "aa"))
                                                 if label(modes[m], "aa") in data.values(rows, "aa") else 99, m)):
            r = modes[mode]
            e, e0 = num(r.get("image_mae")), num(none.get("image_mae")) if none else None
            t = num(r["frame_ms"])
            err_ratio = ratio(e, e0) if e is not None and e0 else None
            time_vs_ssaa4 = ratio(t, num(ssaa4["frame_ms"])) if ssaa4 else None
            added_vs_ssaa4 = None
            t_none = num(none["frame_ms"]) if none else None
            t_ssaa4 = num(ssaa4["frame_ms"]) if ssaa4 else None
            if mode != "none" and None not in (t, t_none, t_ssaa4) and t_ssaa4 > t_none:
                added_vs_ssaa4 = ratio(t - t_none, t_ssaa4 - t_none)
            verdict = ""
            if mode.startswith("smaa"):
                checks = []
                if err_ratio is not None:
                    checks.append("error %s" % ("✓" if err_ratio <= 0.5 else "✗ (target ≤ 0.5)"))
                if time_vs_ssaa4 is not None:
                    checks.append("time %s" % ("✓" if time_vs_ssaa4 <= 0.25 else "✗ (target ≤ 0.25)"))
                if added_vs_ssaa4 is not None:
                    checks.append("added time %s" % ("✓" if added_vs_ssaa4 <= 0.25 else "✗ (≤ 0.25)"))
                verdict = ", ".join(checks)
            cells.append([html.escape(mode), fmt(t), fmt(r.get("aa_ms")) if r.get("aa_ms") is not None else "–",
                          fmt(ratio(t, num(none["frame_ms"]))) if none else "–", fmt(time_vs_ssaa4),
                          fmt(added_vs_ssaa4) if added_vs_ssaa4 is not None else "–",
                          fmt(e), fmt(err_ratio), fmt(r.get("image_psnr")), verdict])
        page.table("aa-%s" % html.escape(str(title)), ["mode", "frame ms", "post-process ms", "time / none",
                                                      "time / SSAA 4×", "added time / SSAA 4×'s", "error", "error / none", "PSNR dB",
                                                      "targets"], cells)
        # Crops where the unfiltered image is furthest from the reference.
        ref = by_key.get(none.get("reference_key")) if none else None
        images = [(m, data.load_image(modes[m].get("image"))) for m in modes]
        refimg = data.load_image(ref.get("image")) if ref else None
        images = [(m, im) for m, im in images if im is not None]
        if none is None or refimg is None or not images:
            page.note("No crops: the aa=none run or the reference image is missing.")
            continue
        base = dict(images).get("none")
        if base is None or base.shape != refimg.shape:
            continue
        # Where the error is: SMAA 1x can only act next to an edge its detector sees (luma contrast of the
        # sRGB values above the high preset's 0.1); aliasing of shading below that stays.
        luma = (base[..., :3] * np.array([0.2126, 0.7152, 0.0722])).sum(axis=2)
        near_edge = np.zeros(luma.shape, dtype=bool)
        dx, dy = np.abs(np.diff(luma, axis=1)) > 0.1, np.abs(np.diff(luma, axis=0)) > 0.1
        near_edge[:, 1:] |= dx
        near_edge[:, :-1] |= dx
        near_edge[1:, :] |= dy
        near_edge[:-1, :] |= dy
        err_none = np.abs(base[..., :3].astype(float) - refimg[..., :3]).sum(axis=2)
        total = float(err_none.sum())
        smaa_img = dict(images).get("smaa-high", dict(images).get("smaa"))
        if total > 0:
            text = ("Without AA, %s%% of the error lies in the %s%% of pixels next to an edge above the detection "
                    "threshold; the rest is aliasing of shading, textures or sub-pixel detail that no edge detector "
                    "sees." % (fmt(100 * float(err_none[near_edge].sum()) / total),
                               fmt(100 * float(near_edge.mean()))))
            if smaa_img is not None and smaa_img.shape == refimg.shape:
                err_smaa = np.abs(smaa_img[..., :3].astype(float) - refimg[..., :3]).sum(axis=2)
                on = float(err_none[near_edge].sum())
                if on > 0:
                    text += (" SMAA high removes %s%% of the error next to edges and changes the rest by %s%%." % (
                        fmt(100 * (1 - float(err_smaa[near_edge].sum()) / on)),
                        fmt(100 * (float(err_smaa[~near_edge].sum()) / max(total - on, 1e-12) - 1))))
            page.p(text)
        (y, x), (ch, cw) = worst_window(err_none)
        shown = [(m, im) for m, im in images if im.shape == refimg.shape] + [("reference", refimg)]
        fig, axs = plt.subplots(1, len(shown), figsize=(2.0 * len(shown), 2.0 * ch / cw + 0.4))
        for ax, (m, im) in zip(np.atleast_1d(axs), shown):
            ax.imshow(im[y:y + ch, x:x + cw], interpolation="nearest")
            ax.set_title(m, fontsize=8)
            ax.set_axis_off()
        page.figure(fig, "Crops (%d×%d pixels at x = %d, y = %d from the top, nearest-neighbour zoom) where the "
                         "image without anti-aliasing differs most from the reference." % (cw, ch, x, y))


def seed_fps_plot(page, data, rows, axis, xlabel, tid, sweep):
    rows = [r for r in rows if num(r.get(axis)) is not None]
    if len(data.values(rows, axis)) < 2:
        page.note("Fewer than two values of %s in the sweep named %s." % (axis, sweep))
        return
    fig, ax = plt.subplots(figsize=(6.5, 3.4))
    cells = []
    for scene in data.values(rows, "scene"):
        srows = sorted((r for r in rows if label(r, "scene") == scene), key=lambda r: num(r[axis]))
        ax.plot([num(r[axis]) for r in srows], [fps(r) for r in srows], marker="o", label=scene)
        cells += [[html.escape(scene), label(r, axis), fmt(fps(r)), fmt(r["frame_ms"])] for r in srows]
        ys = [fps(r) for r in srows]
        trend = ("falls monotonically" if all(b <= a for a, b in zip(ys, ys[1:]))
                 else "rises monotonically" if all(b >= a for a, b in zip(ys, ys[1:])) else "is not monotonic")
        best = max(srows, key=fps)
        page.p("%s: FPS goes from %s at %s = %s to %s at %s = %s and %s; the highest is %s at %s = %s." % (
            html.escape(scene), fmt(ys[0]), axis, label(srows[0], axis), fmt(ys[-1]), axis, label(srows[-1], axis),
            trend, fmt(fps(best)), axis, label(best, axis)))
    if axis == "leaf_size":
        log2_ticks(ax, {num(r[axis]) for r in rows})
    ax.set_xlabel(xlabel)
    ax.set_ylabel("frames per second")
    ax.set_ylim(bottom=0)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    page.figure(fig, "Measured counterpart of the seed's plot.")
    page.table(tid, ["scene", axis, "FPS", "frame ms"], cells)


# ---------------------------------------------------------------- main
def build(root):
    with open(os.path.join(root, "results.json")) as f:
        results = json.load(f)
    data = Data(results, root)
    exp = data.experiment
    knobs = knob_costs(data)
    pareto_fig, fronts, pareto_reason = pareto_plot(data, data.ok)

    body = Page()
    section_findings(body, data, knobs, fronts)
    if exp.get("seed_figures"):
        seed_sections(body, data)
    section_plot(body, "plot-frame-vs-leaf", "Frame time vs leaf size",
                 line_plot(data, data.sweep, "leaf_size", "frame_ms", "frame time (ms)", "Frame time", logx=True),
                 "Median frame time per run; one line per combination of the other swept axes.")
    section_plot(body, "plot-frame-vs-depth", "Frame time vs recursion depth",
                 line_plot(data, data.sweep, "depth", "frame_ms", "frame time (ms)", "Frame time"),
                 "Depth = path segments per pixel, primary ray included.")
    section_plot(body, "plot-visits-vs-sah", "Node visits per ray vs SAH cost", scatter_visits_vs_sah(data, data.sweep),
                 "Each point is a run; numbers are leaf sizes.")
    section_plot(body, "plot-builders", "SAH cost and build time per builder", builder_costs(data, data.sweep),
                 "Median over runs with the same scene, builder and leaf size.")
    section_plot(body, "plot-pareto", "Accuracy vs time (Pareto fronts)", (pareto_fig, pareto_reason),
                 "Image error against each run's reference run (mean absolute error over 8-bit RGB).")
    section_antialiasing(body, data)
    section_images(body, data)
    section_builder_table(body, data)
    section_knobs(body, knobs)
    if len(data.values(data.ok, "robust")) > 1 or os.path.isfile(os.path.join(root, "hard_cases.json")):
        section_robustness(body, data, root)
    section_failed(body, data)
    section_all_rows(body, data)
    section_provenance(body, data)

    summ = results.get("summary", {})
    title = "bvhlab experiment: %s" % exp.get("name", "?")
    head = ["<!DOCTYPE html><html><head><meta charset='utf-8'><title>%s</title><style>%s</style></head><body>"
            % (html.escape(title), CSS),
            "<h1>%s</h1><p>%s</p>" % (html.escape(title), html.escape(exp.get("description", ""))),
            "<p>%s runs planned: %s ok, %s failed, %s pending.</p>" % tuple(
                summ.get(k, "?") for k in ("planned", "ok", "failed", "pending")),
            "<nav><b>Contents:</b> " + " · ".join('<a href="#%s">%s</a>' % (sid, html.escape(t))
                                                  for sid, t in body.toc) + "</nav>"]
    out = "\n".join(head + body.parts + ["</body></html>"])
    path = os.path.join(root, "report.html")
    tmp = path + ".tmp"
    with open(tmp, "w") as f:
        f.write(out)
    os.replace(tmp, path)
    return path


def main(argv):
    if len(argv) != 2:
        sys.stderr.write("usage: /usr/bin/python3 experiments/report.py DIR\n")
        return 2
    root = argv[1]
    if not os.path.isfile(os.path.join(root, "results.json")):
        sys.stderr.write("report.py: %s has no results.json (run `bvhlab run` or `bvhlab merge` first)\n" % root)
        return 2
    print(build(root))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
