"""The report's ray-workload sections: runs on the `rays` axis (`bvhlab trace`) trace a batch of rays
with a GLSL kernel and, in the same process with interleaved rounds, with Embree on the same rays.
Per scene: throughput beside Embree's, counts per ray with intervals, and each builder's node visits
against the reference builder's; then the scaling series (cost against size)."""
import html
import math
import re

from report_data import build_ms_cell, fmt, fmt_ms, fmt_ratio, label, num, plt
from report_html import section_plot

REFERENCE_BUILDER = "sah-binned"  # visits are compared against it when the scene has it
Z95 = 1.959964  # the normal distribution's 97.5% quantile (the intervals trace gives are normal ones)


def mrays_cell(row):
    """Mrays/s with the interval that follows from the time's (a time interval [lo, hi] is a throughput
    interval [n/hi, n/lo])."""
    rays, mr = num(row.get("rays")), num(row.get("mrays_per_s"))
    lo, hi = num(row.get("frame_ms_ci_low")), num(row.get("frame_ms_ci_high"))
    if mr is None:
        return "–"
    if rays is None or not lo or not hi:
        return fmt(mr)
    return '%s <span class="ci">[%s, %s]</span>' % (fmt(mr), fmt(rays / (hi * 1e3)), fmt(rays / (lo * 1e3)))


def mean_cell(row, key):
    v, lo, hi = num(row.get(key)), num(row.get(key + "_ci_low")), num(row.get(key + "_ci_high"))
    if v is None:
        return "–"
    if lo is None or hi is None:
        return fmt(v, 4)
    return '%s <span class="ci">[%s, %s]</span>' % (fmt(v, 4), fmt(lo, 4), fmt(hi, 4))


def mean_ratio(a, b, key):
    """a's per-ray mean over b's with a 95% interval from the two means' normal intervals, combined on
    the log scale as if independent: the runs trace the same rays, so their counts correlate positively
    and the true interval is narrower (this one is conservative)."""
    va, vb = num(a.get(key)), num(b.get(key))
    if not va or not vb:
        return None
    r = va / vb
    parts = []
    for row, v in ((a, va), (b, vb)):
        lo, hi = num(row.get(key + "_ci_low")), num(row.get(key + "_ci_high"))
        if lo is None or hi is None:
            return r, None, None
        parts.append(((hi - lo) / (2.0 * Z95)) / v)  # standard error of log(mean), by the delta method
    se = math.sqrt(sum(p * p for p in parts))
    return r, r * math.exp(-Z95 * se), r * math.exp(Z95 * se)


def fmt_mean_ratio(t):
    if t is None:
        return "–"
    r, lo, hi = t
    text = fmt_ratio(r, lo, hi)
    if lo is not None and hi is not None and (lo > 1.0 or hi < 1.0):
        text += " <b>%s</b>" % ("more" if lo > 1.0 else "fewer")
    return text


def slug(text):
    return re.sub(r"[^a-z0-9]+", "-", str(text).lower()).strip("-") or "scene"


def section_rays(page, data):
    rows = data.traced
    if not rows:
        return
    page.section("rays", "Ray workloads: GLSL kernels beside Embree")
    page.p("Runs on the <code>rays</code> axis trace a batch of rays (<code>bvhlab trace</code>: primary, shadow, "
           "specular, diffuse = cosine-weighted, ao = short any-hit) with the run's kernel over its builder's tree, "
           "and with Embree 3 (its own BVH, robust mode, every core) on the same rays in the same process, rounds "
           "interleaved. <i>× Embree</i> is the GLSL time over Embree's, the median of per-round ratios with its "
           "95%% interval. Visits and tests are per ray over the batch, with 95%% intervals of the mean; "
           "<i>visits vs %s</i> compares the same rays traced over two trees (conservative interval). "
           "<i>mismatches</i>: rays whose closest triangle (any-hit: answer) differs from Embree's, ties at equal "
           "distance not counted. <i>build ms</i>: a CPU builder's wall-clock build; a GPU builder's GL-timed build "
           "(median and interval over <code>gpu_builds</code> builds) where the run timed it." % REFERENCE_BUILDER)
    for scene in data.values(rows, "scene"):
        srows = [r for r in rows if label(r, "scene") == scene]
        page.section("rays-" + slug(scene), "%s" % scene, level=3)
        tris = num(srows[0].get("triangles"))
        if tris is not None:
            page.p("%s triangles." % fmt(tris))
        cells = []
        for w in data.values(srows, "workload"):
            wrows = [r for r in srows if label(r, "workload") == w]
            ref = {}
            for r in wrows:
                if label(r, "builder") == REFERENCE_BUILDER:
                    ref[(label(r, "kernel"), label(r, "leaf_size"))] = r
            for r in sorted(wrows, key=lambda r: num(r.get("frame_ms")) or math.inf):
                base = ref.get((label(r, "kernel"), label(r, "leaf_size")))
                vs = "reference" if base is r else fmt_mean_ratio(mean_ratio(r, base, "node_visits_per_ray")
                                                                  if base else None)
                cells.append([html.escape(str(w)), "<b>%s</b>" % html.escape(str(label(r, "builder"))),
                              html.escape(str(label(r, "kernel") or "")), html.escape(str(label(r, "leaf_size") or "")),
                              fmt(r.get("rays")), fmt_ms(r), mrays_cell(r), fmt(r.get("embree_mrays_per_s")),
                              fmt_ratio(r.get("ratio_to_embree"), r.get("ratio_ci_low"), r.get("ratio_ci_high")),
                              mean_cell(r, "node_visits_per_ray"), vs, mean_cell(r, "triangle_tests_per_ray"),
                              fmt(r.get("ray_cost"), 4), fmt(r.get("sah_cost"), 4), build_ms_cell(r),
                              fmt(r.get("hit_mismatches"))])
        page.table("rays-table-" + slug(scene),
                   ["workload", "builder", "kernel", "leaf", "rays", "GLSL ms [95%]", "Mrays/s [95%]",
                    "Embree Mrays/s", "× Embree's time [95%]", "visits/ray [95%]",
                    "visits vs %s [95%%]" % REFERENCE_BUILDER, "tests/ray [95%]", "ray cost", "SAH", "build ms",
                    "mismatches"],
                   cells)
    section_plot(page, "plot-scaling", "Scaling series: cost against size", scaling_plot(data, rows),
                 "Scenes named scaling_*: one generator at sizes from 10k triangles up. Build time, SAH, node visits "
                 "per ray and GLSL/Embree throughput per builder (one line per builder; Embree dashed), for the "
                 "first workload the series was traced with.")


def scaling_plot(data, rows):
    series = [r for r in rows if str(label(r, "scene")).startswith("scaling") and num(r.get("triangles"))]
    if len({num(r["triangles"]) for r in series}) < 2:
        return None, "no scaling_* scenes at two or more sizes among the traced runs"
    workload = data.values(series, "workload")[0]
    series = [r for r in series if label(r, "workload") == workload]
    metrics = [("build_ms", "build time (ms)"), ("sah_cost", "SAH cost"),
               ("node_visits_per_ray", "node visits per ray (%s)" % workload),
               ("mrays_per_s", "Mrays/s (%s)" % workload)]
    fig, axs = plt.subplots(1, len(metrics), figsize=(4.2 * len(metrics), 3.4), squeeze=False)
    builders = data.values(series, "builder")
    colours = plt.cm.tab10.colors
    for ax, (metric, title) in zip(axs[0], metrics):
        for i, b in enumerate(builders):
            pts = sorted((num(r["triangles"]), num(r.get(metric))) for r in series
                         if label(r, "builder") == b and num(r.get(metric)) is not None)
            if pts:
                ax.plot([p[0] for p in pts], [p[1] for p in pts], marker="o", markersize=4,
                        color=colours[i % len(colours)], label=b)
        if metric == "mrays_per_s":
            pts = {}
            for r in series:
                if num(r.get("embree_mrays_per_s")) is not None:
                    pts.setdefault(num(r["triangles"]), []).append(num(r["embree_mrays_per_s"]))
            xs = sorted(pts)
            if xs:
                ax.plot(xs, [sorted(pts[x])[len(pts[x]) // 2] for x in xs], linestyle="--", color="0.3",
                        label="Embree")
        ax.set_xscale("log")
        ax.set_xlabel("triangles")
        ax.set_title(title, fontsize=9)
        if metric in ("build_ms", "mrays_per_s"):  # both span orders of magnitude over the series
            ax.set_yscale("log")
    axs[0][-1].legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0)
    fig.tight_layout()
    return fig, ""
