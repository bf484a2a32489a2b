"""The report's layout section: runs that differ in the `layout` axis (the texture layout the tree is packed
in, each with its own kernels) or the `triangle_formats` axis. Per scene a table of layout x kernel (and
triangle format; time with its interval, ratio to Embree for traced runs, visits, box tests where the kernel
counts them, bytes fetched per ray where the rows have them, bytes per triangle), and one plot of bytes per
triangle against time: what memory costs in time."""
import html
import math

from report_data import fmt, fmt_ms, fmt_ratio, label, num, plt
from report_html import section_plot
from report_rays import mean_cell, slug


def layout_rows(data):
    """Every finished run (rendered or traced) of a sweep whose layout or triangle format takes two or more
    values."""
    rows = [r for r in data.sweep + data.traced if not r.get("reference_only")]
    return rows if len(data.values(rows, "layout")) > 1 or len(data.values(rows, "triangle_format")) > 1 else []


def layout_label(row, formats):
    """"bvh4", or "bvh4 indexed" when the triangle format varies."""
    text = str(label(row, "layout") or "?")
    return text + (" " + str(label(row, "triangle_format") or "raw") if formats else "")


def workload_of(row):
    """What a run measured: its ray workload, or 'render' for a rendered frame."""
    return label(row, "workload") or "render"


def section_layouts(page, data):
    rows = layout_rows(data)
    if not rows:
        return
    page.section("layouts", "Layouts: memory against time")
    page.p("Runs that differ in the texture layout the tree is packed in (<code>bvhlab layouts</code>); each layout "
           "has its own kernels. <i>time</i> is the median frame time (traced runs: one pass over the batch) "
           "with its 95% interval; <i>× Embree</i> (traced runs) is the GLSL time over Embree's on the same rays, "
           "median of per-round ratios with its interval. Visits and box tests are per ray (a wide node visit "
           "counts once, its child boxes as tests); bytes per triangle counts every stream all in (nodes, "
           "triangles, attributes). Rows sorted by time within each workload.")
    has_boxes = any(num(r.get("box_tests_per_ray")) is not None for r in rows)
    has_fetched = any(num(r.get("node_bytes_per_ray")) is not None for r in rows)
    if has_fetched:
        page.p("<i>Node, triangle, stack bytes/ray</i> (traced runs): the bytes the kernel fetches per ray, counted "
               "exactly by its C++ mirror over the same batch (a strided sample of it past 65,536 rays), with 95% "
               "intervals of the mean (docs/layouts.md).")
    formats = len(data.values(rows, "triangle_format")) > 1
    for scene in data.values(rows, "scene"):
        srows = [r for r in rows if label(r, "scene") == scene]
        page.section("layouts-" + slug(scene), str(scene), level=3)
        cells = []
        for w in sorted({workload_of(r) for r in srows}, key=lambda w: (w != "render", w)):
            wrows = sorted((r for r in srows if workload_of(r) == w),
                           key=lambda r: num(r.get("frame_ms")) or math.inf)
            for r in wrows:
                row = [html.escape(w), "<b>%s</b>" % html.escape(layout_label(r, formats)),
                       html.escape(str(label(r, "kernel") or "")), html.escape(str(label(r, "builder") or "")),
                       fmt_ms(r),
                       fmt_ratio(r.get("ratio_to_embree"), r.get("ratio_ci_low"), r.get("ratio_ci_high"))
                       if num(r.get("ratio_to_embree")) is not None else "–",
                       mean_cell(r, "node_visits_per_ray")]
                if has_boxes:
                    row.append(mean_cell(r, "box_tests_per_ray"))
                if has_fetched:
                    row += [mean_cell(r, k + "_bytes_per_ray") for k in ("node", "triangle", "stack")]
                row += [mean_cell(r, "triangle_tests_per_ray"), fmt(r.get("bytes_per_triangle"), 4),
                        fmt(r.get("bytes"))]
                cells.append(row)
        header = ["workload", "layout + triangles" if formats else "layout", "kernel", "builder", "time ms [95%]", "× Embree's time [95%]",
                  "visits/ray [95%]"]
        if has_boxes:
            header.append("box tests/ray [95%]")
        if has_fetched:
            header += ["node bytes/ray [95%]", "triangle bytes/ray [95%]", "stack bytes/ray [95%]"]
        header += ["tests/ray [95%]", "bytes/triangle", "bytes"]
        page.table("layouts-table-" + slug(scene), header, cells)
    section_plot(page, "plot-layout-memory", "What memory costs in time", memory_plot(data, rows, formats),
                 "Each point is a run: bytes per triangle (all streams) against its median time, bars = 95% "
                 "interval; one panel per scene and workload, one colour per layout, markers per kernel, labels "
                 "name the layout (and triangle format). Left and low is lean and fast.")


def memory_plot(data, rows, formats):
    panels = []
    for scene in data.values(rows, "scene"):
        srows = [r for r in rows if label(r, "scene") == scene]
        for w in sorted({workload_of(r) for r in srows}, key=lambda w: (w != "render", w)):
            pts = [r for r in srows if workload_of(r) == w and num(r.get("bytes_per_triangle")) is not None
                   and num(r.get("frame_ms")) is not None]
            if pts:
                panels.append(("%s, %s" % (scene, w), pts))
    if not panels:
        return None, "no run reported bytes_per_triangle and a time"
    cols = min(3, len(panels))
    nrows = (len(panels) + cols - 1) // cols
    fig, axs = plt.subplots(nrows, cols, figsize=(4.3 * cols, 3.4 * nrows), squeeze=False)
    layouts = data.values(rows, "layout")
    kernels = data.values(rows, "kernel")
    colours = plt.cm.tab10.colors
    markers = "osD^v<>ph*"
    for i, (title, pts) in enumerate(panels):
        ax = axs[i // cols][i % cols]
        for r in pts:
            x, y = num(r["bytes_per_triangle"]), num(r["frame_ms"])
            lo, hi = num(r.get("frame_ms_ci_low")), num(r.get("frame_ms_ci_high"))
            err = [[y - lo], [hi - y]] if lo is not None and hi is not None else None
            li = layouts.index(label(r, "layout")) if label(r, "layout") in layouts else 0
            ki = kernels.index(label(r, "kernel")) if label(r, "kernel") in kernels else 0
            ax.errorbar([x], [y], yerr=err, fmt=markers[ki % len(markers)], color=colours[li % len(colours)],
                        markersize=6, capsize=3)
            ax.annotate(layout_label(r, formats), (x, y), textcoords="offset points", xytext=(5, 4), fontsize=7)
        ax.set_title(title, fontsize=9)
        ax.set_xlabel("bytes per triangle")
        ax.set_ylabel("time (ms)")
    for j in range(len(panels), nrows * cols):
        axs[j // cols][j % cols].axis("off")
    handles = [plt.Line2D([], [], color=colours[i % len(colours)], marker="o", linestyle="", label=l)
               for i, l in enumerate(layouts)]
    handles += [plt.Line2D([], [], color="0.4", marker=markers[i % len(markers)], linestyle="", label=k)
                for i, k in enumerate(kernels)]
    axs[0][-1].legend(handles=handles, fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0)
    fig.tight_layout()
    return fig, ""
