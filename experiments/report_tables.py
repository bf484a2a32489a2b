"""The report's per-run sections: images and heatmaps per builder, the per-builder table, the Pareto
fronts, failed runs, every row, provenance."""
import datetime
import html
import json
import os
import platform

from report_data import (AXES, build_ms_cell, builder_bests, describe, fmt, fmt_ms, label, matplotlib, num, plural,
                         representative, typical_values)
from report_html import figure_uri
from report_plots import heatmap_scale

THUMBNAIL_WIDTH = 400  # per-builder images wider than this are shown downscaled (full size in DIR/images)


def section_images(page, data):
    page.section("images-per-builder", "Rendered images and node-visit heatmaps per builder")
    rows = [r for r in data.sweep if r.get("image")]
    if not rows:
        page.note("No images: no finished run wrote one.")
        return
    if any(r.get("visits_image") for r in rows):
        page.add('<img class="scale" alt="heatmap colour scale" src="%s">' % figure_uri(heatmap_scale(), dpi=110))
        page.p("Heatmaps (<code>render/heatmap.cpp</code>): each pixel's node visits summed over all of that pixel's "
               "rays into the mesh (primary, secondary and shadow rays), through viridis from 0 to the image's own "
               "99th percentile over pixels (brighter pixels are clamped to yellow); black = no ray entered the "
               "mesh's BVH. The scale is per image, so colours compare places within one heatmap; across builders "
               "compare the visits per ray printed under each.")
    shown = data.varying(rows, exclude=("scene", "builder"))
    for scene in data.values(rows, "scene"):
        page.add("<h3>%s</h3>" % html.escape(scene))
        srows = [r for r in rows if label(r, "scene") == scene]
        typical = typical_values(data, srows)
        blocks = []
        for b in data.values(srows, "builder") or [None]:
            r = representative([x for x in srows if label(x, "builder") == b] if b else srows, typical)
            img = data.image_uri(r.get("image"), max_width=THUMBNAIL_WIDTH)
            heat = data.image_uri(r.get("visits_image"), max_width=THUMBNAIL_WIDTH)
            scale = num(r.get("visits_heatmap_max"))
            cap = "%s<br>%s ms<br>%s visits/ray (p95 %s), %s tests/ray%s" % (
                html.escape(describe(r, shown) or "the only run"), fmt_ms(r), fmt(r.get("node_visits_per_ray")),
                fmt(r.get("node_visits_p95")), fmt(r.get("triangle_tests_per_ray")),
                "<br>yellow = ≥ %s visits per pixel" % fmt(scale) if scale else "")
            blocks.append('<div><b>%s</b><br>%s<br>%s<br>%s</div>' % (
                html.escape(b or "–"),
                '<img class="render" src="%s" alt="%s">' % (img, html.escape("render: " + (b or "the run"))) if img
                else "no image",
                '<img class="render" src="%s" alt="%s">'
                % (heat, html.escape("node visits heatmap: " + (b or "the run")))
                if heat else "no heatmap", cap))
        page.add('<div class="pair" id="images-%s">%s</div>' % (html.escape(scene), "".join(blocks)))


def sah_before(row):
    """The builder's own SAH when a post-pass (--optimize) changed it, else a dash."""
    if not row.get("optimize"):
        return "–"
    return fmt(row.get("sah_before_optimize"), 4)


def references(row):
    """Leaf references, and their ratio to the triangles when a builder splits primitives (sbvh)."""
    refs, tris = num(row.get("references")), num(row.get("triangles"))
    if refs is None:
        return "–"
    if tris and refs != tris:
        return "%s (%s×)" % (fmt(refs), fmt(refs / tris, 3))
    return fmt(refs)


def section_builder_table(page, data):
    page.section("table-builders", "Per builder: each at its best")
    rows = data.sweep
    if not rows:
        page.note("No finished runs.")
        return
    page.p("One row per builder and scene: its run with the lowest median frame time over its own choices "
           "(kernel, leaf size, bins), the other axes held at the setting the builders share. <i>vs fastest</i> "
           "is that run against the scene's fastest builder at its best, with the interval and verdict from "
           "findings.json when it has them. <i>build ms</i> is the CPU builders' wall-clock build and the GPU "
           "builders' GL-timed build (median and interval over repeated builds) where the runs timed it.")
    config_axes = [a for a in data.varying(rows, exclude=("scene", "builder"))]
    out = []
    for scene in data.values(rows, "scene"):
        srows = [r for r in rows if label(r, "scene") == scene]
        bests = builder_bests(data, srows)
        if not bests:
            continue
        top = min(bests.values(), key=lambda r: num(r["frame_ms"]))
        for b, best in sorted(bests.items(), key=lambda kv: num(kv[1]["frame_ms"])):
            n = sum(1 for r in srows if label(r, "builder") == b)
            mb = num(best.get("bytes"))
            out.append([html.escape(str(scene)), "<b>%s</b>" % html.escape(str(b)), str(n),
                        html.escape(describe(best, config_axes) or "–"), fmt_ms(best),
                        "fastest" if best is top else data.ratio_cell(best, top),
                        fmt(best.get("sah_cost"), 4), fmt(best.get("epo"), 4),
                        "%s (%s)" % (fmt(best.get("node_visits_per_ray"), 4), fmt(best.get("node_visits_p95"))),
                        "%s (%s)" % (fmt(best.get("triangle_tests_per_ray"), 4), fmt(best.get("triangle_tests_p95"))),
                        fmt(best.get("ray_cost"), 4), build_ms_cell(best), sah_before(best),
                        fmt(best.get("optimize_ms")), references(best), fmt(best.get("nodes")),
                        fmt(mb / 1e6 if mb is not None else None)])
    page.table("table-builders-data", ["scene", "builder", "runs", "best configuration", "frame ms [95%]",
                                       "vs fastest [95%]", "SAH", "EPO", "visits/ray (p95)", "tests/ray (p95)",
                                       "ray cost", "build ms", "SAH before optimize", "optimize ms",
                                       "references (/ triangles)", "nodes", "MB"], out)


def pareto_table(page, data, fronts):
    """The runs on each Pareto front: what they set, their time and error."""
    cells = []
    shown = data.varying(data.ok, exclude=("scene",))
    for scene, front in fronts:
        for t, e, r in front:
            cells.append([html.escape(str(scene)), html.escape(describe(r, shown)), html.escape(r.get("key", "")),
                          fmt_ms(r), fmt(e)])
    if cells:
        page.table("pareto-fronts", ["scene", "run", "key", "frame ms [95%]", "image error"], cells)


def section_all_rows(page, data):
    page.section("table-results", "Every run")
    columns = [c for c in data.results.get("columns", []) if c not in ("scene_file", "frame_ms_all")]
    if not data.rows:
        page.note("No finished runs yet.")

    def cells(rows):
        out = []
        for r in rows:
            line = []
            for c in columns:
                v = r.get(c)
                if c == "error" and v:
                    v = str(v)[:200]
                is_number = isinstance(v, (int, float)) and not isinstance(v, bool)
                line.append(fmt(v) if is_number else html.escape("" if v is None else str(v)))
            out.append(line)
        return out

    page.table("table-results-data", columns, cells(data.rows))
    if data.controls:
        page.p("A/A control runs (%s; a second measurement of the run named in <code>control_of</code>, used only "
               "for the noise floor):" % plural(len(data.controls), "run"))
        page.table("table-controls-data", columns, cells(data.controls))
    page.p("Also in <code>results.csv</code> and <code>results.json</code> next to this file.")


def section_failed(page, data):
    page.section("table-failed", "Failed runs")
    if not data.failed:
        page.p("No failed runs.")
        return
    for r in data.failed:
        key = r.get("key", "")
        log, cmd = "", ""
        path = os.path.join(data.root, "runs", key + ".json")
        if os.path.isfile(path):
            with open(path) as f:
                rec = json.load(f)
            log = rec.get("log", "")
            cmd = rec.get("command", "")
        control = " (A/A control of %s)" % r["control_of"] if r.get("control_of") else ""
        page.add("<h3>%s — %s%s</h3><p><b>%s</b></p>%s%s" % (
            html.escape(key), html.escape(describe(r, AXES)), html.escape(control),
            html.escape(str(r.get("error", ""))),
            "<pre>%s</pre>" % html.escape(cmd) if cmd else "",
            "<details><summary>stderr</summary><pre>%s</pre></details>" % html.escape(log) if log else ""))


def section_provenance(page, data):
    page.section("provenance", "Provenance")
    res, prov, summ = data.results, data.results.get("provenance", {}), data.results.get("summary", {})
    starts = sorted(r["started_at"] for r in data.rows if r.get("started_at"))
    stops = {}
    for r in data.sweep:
        if r.get("measure_stop"):
            stops[r["measure_stop"]] = stops.get(r["measure_stop"], 0) + 1
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
    if stops:
        met = sum(1 for r in data.sweep if r.get("ci_target_met") is True)
        items.insert(3, ("frames", "measurement stopped: %s; %d of %d runs met the interval target" % (
            ", ".join("%s %d" % (k, v) for k, v in sorted(stops.items())), met, len(data.sweep))))
    # Trace runs on a GPU time each sample as several dispatches back to back ([trace] min_sample_ms):
    # said here, since every GLSL time above is then a mean per dispatch.
    samples = {}
    for r in data.traced:
        k = r.get("dispatches_per_sample")
        if isinstance(k, (int, float)) and k > 1:
            key = (int(k), r.get("min_sample_ms"))
            samples[key] = samples.get(key, 0) + 1
    if samples:
        items.insert(3, ("trace samples", "; ".join(
            "%d dispatches a timed sample (at least %s ms): %d runs" % (k, fmt(ms), n)
            for (k, ms), n in sorted(samples.items())) + "; each GLSL time is the mean per dispatch"))
    page.table("provenance-data", ["", ""], [["<b>%s</b>" % k, v] for k, v in items])
    plan = os.path.join(data.root, "plan.json")
    if os.path.isfile(plan):
        with open(plan) as f:
            text = json.load(f).get("config", {}).get("text", "")
        page.add("<details><summary>config file as run</summary><pre>%s</pre></details>" % html.escape(text))
