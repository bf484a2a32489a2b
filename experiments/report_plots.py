"""The report's matplotlib plots. Each returns (figure, None) or (None, why there is no plot).

One style per run everywhere: the colour (and, alone, the marker) says the builder, the line style says
the kernel, so a builder reads the same in every plot. Series that share an x are nudged apart
sideways so that no marker hides another; vertical bars are the runs' 95% intervals of the median
frame time (frame_ms_ci_low / frame_ms_ci_high; none for rows measured before intervals existed).
"""
import html
import math
import statistics

from report_data import (AXES, MAX_SERIES_LABEL, describe, fmt, frame_ci, group, label, matplotlib, num, plt,
                         representative, shared_setting, typical_values)
import matplotlib.colors  # noqa: E402
import matplotlib.lines  # noqa: E402
import matplotlib.ticker  # noqa: E402

MARKERS = "osD^v<>pPhX*"
LINESTYLES = ["-", "--", ":", "-."]
# Image error differences at or below this (8-bit mean abs) are "the same error" (float noise of the mean).
SAME_ERROR = 1e-9


class Styles:
    """Builder -> colour and marker, kernel -> line style, fixed over the whole report."""

    def __init__(self, data):
        builders = data.values(data.sweep, "builder")
        kernels = data.values(data.sweep, "kernel")
        palette = plt.cm.tab10.colors if len(builders) <= 10 else plt.cm.tab20.colors
        self.colour = {b: palette[i % len(palette)] for i, b in enumerate(builders)}
        self.marker = {b: MARKERS[i % len(MARKERS)] for i, b in enumerate(builders)}
        self.line = {k: LINESTYLES[i % len(LINESTYLES)] for i, k in enumerate(kernels)}

    def of(self, row):
        b, k = label(row, "builder"), label(row, "kernel")
        return {"color": self.colour.get(b, "0.3"), "marker": self.marker.get(b, "o"),
                "linestyle": self.line.get(k, "-")}

    def legend(self, ax, builders, kernels, extra=()):
        """Builders as colour + marker, kernels as line styles (grey), then any extra handles."""
        handles = [matplotlib.lines.Line2D([], [], color=self.colour.get(b, "0.3"), marker=self.marker.get(b, "o"),
                                           linestyle="-", markersize=5, label=b) for b in builders]
        if len(kernels) > 1:
            handles += [matplotlib.lines.Line2D([], [], color="0.35", linestyle=self.line.get(k, "-"), label=k)
                        for k in kernels]
        handles += list(extra)
        if handles:
            ax.legend(handles=handles, fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0,
                      ncol=1 if len(handles) <= 16 else 2)


def facet_axes(n, width=8.5, height=3.6):
    """One panel per scene, stacked, with room on the right for the legend."""
    fig, axs = plt.subplots(n, 1, figsize=(width, height * n), squeeze=False)
    return fig, [row[0] for row in axs]


def log2_ticks(ax, values):
    ax.set_xscale("log", base=2)
    ax.set_xticks(sorted(values))
    ax.get_xaxis().set_major_formatter(matplotlib.ticker.ScalarFormatter())
    ax.get_xaxis().set_minor_locator(matplotlib.ticker.NullLocator())


def nudge(xs, i, n, logx):
    """Series i of n moved sideways: a fraction of an octave (log x) or of the smallest x step."""
    if n <= 1:
        return list(xs)
    f = (i - (n - 1) / 2.0) / n
    if logx:
        return [x * 2 ** (0.3 * f) for x in xs]
    steps = [b - a for a, b in zip(xs, xs[1:]) if b > a]
    return [x + 0.35 * f * (min(steps) if steps else 1.0) for x in xs]


def tree_rows(data, rows):
    """Per scene, the runs that differ only in builder, kernel, leaf size or bins (see shared_setting): a depth or
    anti-aliasing sweep would otherwise put one tree at several costs and times."""
    return [r for scene in data.values(rows, "scene")
            for r in shared_setting([x for x in rows if label(x, "scene") == scene])]


def scatter_visits_vs_sah(data, styles, rows):
    rows = [r for r in tree_rows(data, rows)
            if num(r.get("sah_cost")) is not None and num(r.get("node_visits_per_ray")) is not None]
    if len(rows) < 2:
        return None, "no runs report both SAH cost and node visits per ray"
    scenes = data.values(rows, "scene")
    fig, axs = facet_axes(len(scenes))
    for ax, scene in zip(axs, scenes):
        srows = [r for r in rows if label(r, "scene") == scene]
        kernels = data.values(srows, "kernel")
        kmark = dict(zip(kernels, "o^sDv<>pH*"))
        leaf_labels = {}  # runs on one spot (e.g. leaf sizes that build the same tree) share one label
        for r in srows:
            st = styles.of(r)
            m = kmark.get(label(r, "kernel"), "o") if len(kernels) > 1 else st["marker"]
            xy = (num(r["sah_cost"]), num(r["node_visits_per_ray"]))
            ax.scatter([xy[0]], [xy[1]], s=20, color=st["color"], marker=m, alpha=0.8, edgecolors="none")
            if label(r, "leaf_size") is not None:
                spot = leaf_labels.setdefault((round(xy[0], 3), round(xy[1], 3)), (xy, []))[1]
                if label(r, "leaf_size") not in spot:
                    spot.append(label(r, "leaf_size"))
        for xy, leaves in leaf_labels.values():
            ax.annotate(",".join(leaves), xy, fontsize=6, alpha=0.7, xytext=(3, 2), textcoords="offset points")
        kernel_handles = [matplotlib.lines.Line2D([], [], color="0.35", marker=kmark[k], linestyle="none", label=k)
                          for k in kernels] if len(kernels) > 1 else []
        builders = data.values(srows, "builder")
        handles = [matplotlib.lines.Line2D([], [], color=styles.colour.get(b, "0.3"),
                                           marker="o" if kernel_handles else styles.marker.get(b, "o"),
                                           linestyle="none", label=b) for b in builders]
        ax.legend(handles=handles + kernel_handles, fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0),
                  borderaxespad=0)
        ax.set_title("Node visits per ray vs SAH cost — %s" % scene, fontsize=10)
        ax.set_xlabel("SAH cost (Ct = Ci = 1, normalised by root area)")
        ax.set_ylabel("node visits / ray")
        ax.grid(alpha=0.3)
    fig.tight_layout()
    return fig, None


PREDICTOR_AXES = [("sah_cost", "SAH cost"), ("epo", "EPO"), ("node_visits_per_ray", "node visits / ray"),
                  ("ray_cost", "ray cost (Ct·visits + Ci·tests)")]


def _cost_ratio(c, metric):
    """a / b of one deterministic count of a comparison (findings.json's counts), or None."""
    pair = (c.get("counts") or {}).get(metric)
    if not isinstance(pair, list) or len(pair) != 2:
        return None
    a, b = num(pair[0]), num(pair[1])
    return a / b if a is not None and b is not None and a > 0 and b > 0 else None


def time_vs_costs(data, styles):
    """Each builder's time ratio to the baseline builder (findings.json, with its paired 95% interval) against
    the same ratio of each deterministic cost measure, log-log, one row of panels per scene: where a point
    sits on the diagonal, the measure predicted the time. Colour = builder, marker = ray type (or frames)."""
    findings = data.findings or {}
    base = str((findings.get("baselines") or {}).get("builder") or data.baseline("builder"))
    comps = [c for c in findings.get("comparisons") or []
             if c.get("kind") == "axis" and c.get("axis") == "builder" and c.get("baseline") is True
             and num(c.get("ratio")) is not None and num(c.get("ratio")) > 0
             and str((c.get("a_values") or {}).get("builder")) != base]  # not a twin of the baseline run
    metrics = [(m, t) for m, t in PREDICTOR_AXES
               if len({_cost_ratio(c, m) for c in comps} - {None}) >= 2]
    if not metrics:
        return None, ("findings.json has no builder compared with the baseline builder on a cost measure "
                      "that differs between them")
    scenes = [s for s in data.values(data.rows, "scene") if any(c.get("scene") == s for c in comps)]
    fig, axs = plt.subplots(len(scenes), len(metrics), figsize=(3.4 * len(metrics) + 1.6, 3.2 * len(scenes)),
                            squeeze=False)
    columns = []
    for c in comps:
        v = c.get("a_values") or {}
        col = v.get("rays") or v.get("workload") or "frames"
        c["_column"] = str(col)
        if c["_column"] not in columns:
            columns.append(c["_column"])
    cmark = dict(zip(columns, "osD^v<>pH*"))
    for panel, scene in zip(axs, scenes):
        mine = [c for c in comps if c.get("scene") == scene]
        for ax, (m, title) in zip(panel, metrics):
            for c in mine:
                x, y = _cost_ratio(c, m), num(c["ratio"])
                if x is None:
                    continue
                lo, hi = num(c.get("ci_low")), num(c.get("ci_high"))
                err = [[y - lo], [hi - y]] if lo is not None and hi is not None and lo <= y <= hi else None
                b = str((c.get("a_values") or {}).get("builder") or c.get("a_label"))
                ax.errorbar([x], [y], yerr=err, color=styles.colour.get(b, "0.3"), marker=cmark[c["_column"]],
                            markersize=4, linestyle="none", elinewidth=0.8, capsize=1.5, alpha=0.85)
            log_ratio_axis(ax, "x")
            log_ratio_axis(ax, "y")
            (lo_x, hi_x), (lo_y, hi_y) = ax.get_xlim(), ax.get_ylim()
            span = (max(lo_x, lo_y), min(hi_x, hi_y))
            ax.plot(span, span, color="0.6", linewidth=0.8, linestyle=":")  # time ratio = cost ratio
            ax.set_xlabel("%s / baseline builder's" % title, fontsize=8)
            ax.set_ylabel("time / baseline builder's", fontsize=8)
            ax.set_title(scene, fontsize=9)
            ax.tick_params(labelsize=7)
            ax.grid(alpha=0.3)
        builders = [b for b in data.values(data.rows, "builder")
                    if any(str((c.get("a_values") or {}).get("builder")) == b for c in mine)]
        handles = [matplotlib.lines.Line2D([], [], color=styles.colour.get(b, "0.3"), marker="o", linestyle="none",
                                           label=b) for b in builders]
        handles += [matplotlib.lines.Line2D([], [], color="0.35", marker=cmark[k], linestyle="none", label=k)
                    for k in columns] if len(columns) > 1 else []
        panel[-1].legend(handles=handles, fontsize=7, loc="upper left", bbox_to_anchor=(1.02, 1.0), borderaxespad=0)
    for c in comps:
        c.pop("_column", None)
    fig.tight_layout()
    return fig, None


def builder_costs(data, styles, rows):
    """SAH cost, EPO (when measured) and build time per builder (vs leaf size when it varies), per scene."""
    metrics = [(m, t) for m, t in (("sah_cost", "SAH cost"), ("epo", "EPO"), ("build_ms", "build time (ms)"))
               if any(num(r.get(m)) is not None for r in rows)]
    rows = [r for r in rows if any(num(r.get(m)) is not None for m, _ in metrics)]
    if not rows:
        return None, "no runs report SAH cost or build time"
    scenes = data.values(rows, "scene")
    fig, axs = plt.subplots(len(scenes), len(metrics), figsize=(4.2 * len(metrics) + 1.4, 3.4 * len(scenes)),
                            squeeze=False)
    for panel, scene in zip(axs, scenes):
        srows = [r for r in rows if label(r, "scene") == scene]
        builders = data.values(srows, "builder")
        leaves = data.values(srows, "leaf_size")
        for ax, (metric, ylab) in zip(panel, metrics):
            if len(leaves) >= 2:
                for i, b in enumerate(builders):
                    by_leaf = group([r for r in srows if label(r, "builder") == b and num(r.get(metric)) is not None],
                                    lambda r: num(r.get("leaf_size")))
                    xs = sorted(k for k in by_leaf if k is not None)
                    if xs:
                        ax.plot(nudge(xs, i, len(builders), True),
                                [statistics.median(num(r[metric]) for r in by_leaf[v]) for v in xs],
                                marker=styles.marker.get(b, "o"), markersize=4, color=styles.colour.get(b, "0.3"))
                log2_ticks(ax, {num(x) for x in leaves})
                ax.set_xlabel("leaf size")
            else:
                vals = [statistics.median([num(r.get(metric)) for r in srows
                                           if label(r, "builder") == b and num(r.get(metric)) is not None] or [0])
                        for b in builders]
                ax.bar(range(len(builders)), vals, color=[styles.colour.get(b, "0.3") for b in builders])
                ax.set_xticks(range(len(builders)))
                ax.set_xticklabels(builders, rotation=20, fontsize=8)
            ax.set_ylabel(ylab)
            ax.set_ylim(bottom=0)
            ax.set_title("%s — %s" % (ylab, scene), fontsize=10)
            ax.grid(alpha=0.3)
        if len(leaves) >= 2:
            styles.legend(panel[-1], builders, [])
    fig.tight_layout()
    return fig, None


# ---------------------------------------------------------------- accuracy vs time
def error_axes(data, rows):
    """(axes whose values change image error among runs equal in every other axis, the other varying axes)."""
    changing, same = [], []
    for axis in data.varying(rows, exclude=("scene",)):
        others = [a for a in AXES if a != axis]
        differs, matched = False, False
        for members in group(rows, lambda r: tuple(label(r, a) for a in others)).values():
            errs = {label(r, axis): num(r.get("image_mae")) for r in members}
            if len(errs) >= 2:
                matched = True
                vals = list(errs.values())
                differs = differs or max(vals) - min(vals) > SAME_ERROR
        if matched and differs:
            changing.append(axis)
        else:
            same.append(axis)
    return changing, same


def pareto_front(points):
    """Points (time, error, row) not dominated by another (lower-or-equal in both, lower in one)."""
    front, best_err = [], math.inf
    for t, e, r in sorted(points, key=lambda p: (p[0], p[1])):
        if e < best_err:
            front.append((t, e, r))
            best_err = e
    return front


def pareto_plot(data, rows):
    """Image error vs frame time over the axes that change the error; one run per combination of their values
    (the one at the sweep's most common setting of the other axes), per scene. Returns (fig, fronts, reason, notes
    naming the axes left out)."""
    rows = [r for r in rows if num(r.get("image_mae")) is not None and num(r.get("frame_ms")) is not None]
    if len(rows) < 2:
        return None, [], "no image-error data (the config needs a [experiment.reference] and runs with images)", []
    panels, notes = [], []
    for scene in data.values(rows, "scene"):
        srows = [r for r in rows if label(r, "scene") == scene]
        changing, same = error_axes(data, srows)
        if changing:
            panels.append((scene, srows, changing))
        if same:
            notes.append("%s: %s left out (every matched pair of runs along %s has the same image error)."
                         % (html.escape(scene), ", ".join(same), "it" if len(same) == 1 else "them"))
    if not panels:
        return None, [], "no axis changes the image error (every matched pair of runs has the same error)", notes
    fig, axs = facet_axes(len(panels))
    fronts = []
    for ax, (scene, srows, changing) in zip(axs, panels):
        typical = typical_values(data, srows)
        combos = group(srows, lambda r: tuple(label(r, a) for a in changing))
        chosen = [representative(members, {a: v for a, v in typical.items() if a not in changing})
                  for members in combos.values()]
        pts = [(num(r["frame_ms"]), num(r["image_mae"]), r) for r in chosen]
        for t, e, r in pts:
            ci = frame_ci(r)
            ax.errorbar([t], [e], xerr=[[t - ci[0]], [ci[1] - t]] if ci else None, color="0.55", marker="o",
                        markersize=4, linestyle="none", elinewidth=0.8)
        front = pareto_front(pts)
        fronts.append((scene, front))
        ax.step([p[0] for p in front], [p[1] for p in front], where="post", color="C3", label="Pareto front")
        ax.scatter([p[0] for p in front], [p[1] for p in front], s=22, color="C3", zorder=3)
        for t, e, r in pts:
            ax.annotate(describe(r, changing)[:MAX_SERIES_LABEL], (t, e), fontsize=6, xytext=(3, 3),
                        textcoords="offset points")
        ax.set_xscale("log")
        plain = matplotlib.ticker.FuncFormatter(lambda v, _: fmt(v))
        ax.xaxis.set_major_formatter(plain)
        ax.xaxis.set_minor_formatter(plain)
        ax.tick_params(axis="x", which="both", labelsize=7)
        ax.set_title("Image error vs frame time — %s (over %s)" % (scene, ", ".join(changing)), fontsize=10)
        ax.set_xlabel("frame time (ms, log)")
        ax.set_ylabel("mean abs error vs reference (8-bit)")
        ax.grid(alpha=0.3)
        ax.legend(handles=[matplotlib.lines.Line2D([], [], color="0.55", marker="o", linestyle="none", label="runs"),
                           matplotlib.lines.Line2D([], [], color="C3", marker="o", label="Pareto front")],
                  fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0)
    fig.tight_layout()
    return fig, fronts, None, notes


# ---------------------------------------------------------------- heatmap colour scale
# render/heatmap.cpp: per pixel, node visits summed over every mesh ray of that pixel (closest and shadow
# rays), divided by that image's own 99th percentile over pixels, clamped to 1, through five stops of
# viridis (linear between them); 0 visits is black.
HEATMAP_STOPS = [(0.267, 0.005, 0.329), (0.229, 0.322, 0.546), (0.128, 0.567, 0.551), (0.369, 0.789, 0.383),
                 (0.993, 0.906, 0.144)]


def heatmap_scale(max_visits=None):
    """The heatmaps' colour bar. With max_visits (the image's 99th percentile, when the run reports it) the
    ticks are visit counts, otherwise fractions of that percentile."""
    cmap = matplotlib.colors.LinearSegmentedColormap.from_list("bvhlab_visits", HEATMAP_STOPS)
    fig = plt.figure(figsize=(5.0, 0.75))
    ax = fig.add_axes([0.16, 0.5, 0.8, 0.25])
    black = fig.add_axes([0.02, 0.5, 0.06, 0.25])
    black.imshow([[0]], cmap=matplotlib.colors.ListedColormap([(0, 0, 0)]), aspect="auto")
    black.set_xticks([])
    black.set_yticks([])
    black.set_xlabel("0 (no\nmesh ray)", fontsize=6)
    fig.colorbar(matplotlib.cm.ScalarMappable(norm=matplotlib.colors.Normalize(0, 1), cmap=cmap), cax=ax,
                 orientation="horizontal")
    ticks = [0, 0.25, 0.5, 0.75, 1.0]
    ax.set_xticks(ticks)
    if max_visits:
        ax.set_xticklabels([fmt(t * max_visits) for t in ticks[:-1]] + ["≥ %s" % fmt(max_visits)], fontsize=7)
    else:
        ax.set_xticklabels(["0", "¼ p99", "½ p99", "¾ p99", "≥ p99"], fontsize=7)
    ax.set_xlabel("node visits per pixel (all of the pixel's rays)%s" % ("" if max_visits else
                  ", relative to each image's 99th percentile"), fontsize=7)
    return fig


# ---------------------------------------------------------------- ratios to a baseline (findings.json)
# Tick steps of a ratio axis, finest first: the first that puts at most RATIO_TICKS ticks in view wins.
RATIO_STEPS = (0.01, 0.02, 0.05, 0.1, 0.2, 0.25, 0.5, 1.0, 2.0, 5.0)
RATIO_TICKS = 8


def log_ratio_axis(ax, which="y"):
    """A log axis of time (or cost) ratios: a line at 1 (the baseline), evenly stepped ticks around 1 written as
    ratios (call after plotting: the ticks cover the data's range)."""
    axis = ax.yaxis if which == "y" else ax.xaxis
    (ax.axhline if which == "y" else ax.axvline)(1.0, color="0.3", linewidth=1)
    (ax.set_yscale if which == "y" else ax.set_xscale)("log")
    lo, hi = ax.get_ylim() if which == "y" else ax.get_xlim()
    lo, hi = min(lo, 1.0), max(hi, 1.0)
    for step in RATIO_STEPS:
        first, last = int(math.floor((lo - 1.0) / step)), int(math.ceil((hi - 1.0) / step))
        ticks = [1.0 + i * step for i in range(first, last + 1)]
        ticks = [t for t in ticks if lo <= t <= hi and t > 0]
        if len(ticks) <= RATIO_TICKS:
            break
    axis.set_major_locator(matplotlib.ticker.FixedLocator(ticks))
    axis.set_minor_locator(matplotlib.ticker.NullLocator())
    axis.set_major_formatter(matplotlib.ticker.FuncFormatter(lambda v, _pos: "%.3g×" % v))
    (ax.set_ylim if which == "y" else ax.set_xlim)(lo, hi)


def ratio_plot(data, axis, title):
    """findings.json's comparisons along `axis` against its fixed baseline value: each ratio with its paired 95%
    interval on a log axis (the interval of the ratio, not of either run's time, so the machine's drift over
    the session does not hide the effect). One panel per scene, one series per setting of the other axes."""
    findings = data.findings or {}
    comps = [c for c in findings.get("comparisons") or []
             if c.get("kind") == "axis" and c.get("axis") == axis and c.get("baseline") is True
             and isinstance(c.get("a_values"), dict) and num(c["a_values"].get(axis)) is not None
             and num(c.get("ratio")) is not None and num(c.get("ratio")) > 0]
    base = num((findings.get("baselines") or {}).get(axis))
    # A run at the baseline value itself (a twin of the baseline run, e.g. one config setting reached by two
    # sweeps) is not a point on the curve: the baseline is drawn at 1.
    comps = [c for c in comps if base is None or num(c["a_values"][axis]) != base]
    if not comps:
        return None, "findings.json has no comparison along %s against its baseline value" % axis.replace("_", " ")
    scenes = [s for s in data.values(data.rows, "scene") if any(c.get("scene") == s for c in comps)]
    fig, axs = facet_axes(len(scenes))
    for ax, scene in zip(axs, scenes):
        mine = [c for c in comps if c.get("scene") == scene]
        series = group(mine, lambda c: tuple(sorted((k, str(v)) for k, v in c["a_values"].items() if k != axis)))
        # Label a series by the axes that differ between series only.
        keys = sorted(series, key=str)
        differ = [k for k in {k for key in keys for k, _ in key}
                  if len({dict(key).get(k) for key in keys}) > 1]
        xs_all = set()
        for i, key in enumerate(keys):
            cs = sorted(series[key], key=lambda c: num(c["a_values"][axis]))
            xs = [num(c["a_values"][axis]) for c in cs]
            ys = [num(c["ratio"]) for c in cs]
            lo = [max(0.0, y - num(c.get("ci_low"))) if num(c.get("ci_low")) is not None else 0.0
                  for c, y in zip(cs, ys)]
            hi = [max(0.0, num(c.get("ci_high")) - y) if num(c.get("ci_high")) is not None else 0.0
                  for c, y in zip(cs, ys)]
            if base is not None:  # the baseline itself: 1 by definition
                xs, ys, lo, hi = [base] + xs, [1.0] + ys, [0.0] + lo, [0.0] + hi
            xs_all.update(xs)
            name = " ".join("%s=%s" % (k, v) for k, v in key if k in sorted(differ)) or "runs"
            ax.errorbar(nudge(xs, i, len(keys), axis == "leaf_size"), ys, yerr=[lo, hi],
                        marker=MARKERS[i % len(MARKERS)], linestyle=LINESTYLES[i % len(LINESTYLES)], markersize=4,
                        linewidth=1.0, elinewidth=0.9, capsize=2, label=name[:MAX_SERIES_LABEL])
        if axis == "leaf_size":
            log2_ticks(ax, xs_all)
        else:
            ax.set_xticks(sorted(xs_all))
        log_ratio_axis(ax)
        ax.set_title("%s — %s" % (title, scene), fontsize=10)
        ax.set_xlabel(axis.replace("_", " "))
        ax.set_ylabel("time / baseline's (log)")
        ax.grid(alpha=0.3, which="both")
        ax.legend(fontsize=7 if len(keys) <= 12 else 6, loc="upper left", bbox_to_anchor=(1.01, 1.0),
                  borderaxespad=0, ncol=1 if len(keys) <= 16 else 2)
    fig.tight_layout()
    return fig, None
