#!/usr/bin/python3
"""bvhlab experiment report: DIR/results.json + DIR/findings.json (+ DIR/images) -> DIR/report.html.

The page is self-contained and works offline: plots are matplotlib PNGs and rendered images are
embedded as base64. The findings (every ratio, interval and verdict) are read from DIR/findings.json,
which the runner writes; everything else is computed from the rows; nothing is hand-written. A plot
with no data for this config is replaced by a note saying so. A/A controls only feed the noise floor:
separate control rows (control_of set) are kept out of every plot and table but the list of every run,
and a run's own A/A columns (aa_control_*) are only read through findings.json's noise entries.

Modules, next to this file: report_data (rows, findings.json, formatting), report_html (the page),
report_plots, report_findings, report_tables, report_summary (the first screen), report_seed (seed figures,
anti-aliasing), report_robust (robustness variants), report_rays (traced workloads), report_layouts
(layouts: memory vs time).

Run with Debian's interpreter, which has python3-matplotlib:
    /usr/bin/python3 experiments/report.py DIR
(`bvhlab run`, `bvhlab merge` and `bvhlab report DIR` call it.)
"""
import html
import json
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
# The sibling modules (experiments/report_*.py); report_data exits with a hint when matplotlib is missing.
from report_data import Data  # noqa: E402
from report_dynamic import section_dynamic  # noqa: E402
from report_findings import section_findings  # noqa: E402
from report_html import CSS, Page, section_plot  # noqa: E402
from report_plots import (Styles, builder_costs, pareto_plot, ratio_plot, scatter_visits_vs_sah,  # noqa: E402
                          time_vs_costs)
from report_layouts import section_layouts  # noqa: E402
from report_rays import section_rays  # noqa: E402
from report_robust import section_robustness  # noqa: E402
from report_seed import section_antialiasing, seed_sections  # noqa: E402
from report_summary import CSS as SUMMARY_CSS, section_summary  # noqa: E402
from report_tables import (pareto_table, section_all_rows, section_builder_table, section_failed,  # noqa: E402
                           section_images, section_provenance)


def build(root):
    with open(os.path.join(root, "results.json")) as f:
        results = json.load(f)
    data = Data(results, root)
    exp = data.experiment
    styles = Styles(data)

    body = Page()
    section_summary(body, data)  # the first screen: builders x ray types per scene, noise floor, machine load
    section_findings(body, data)
    if exp.get("seed_figures"):
        seed_sections(body, data)
    ratio_caption = ("Each point is findings.json's ratio of a run's frame time to the run with the axis's baseline "
                     "value and every other axis equal (at 1 by definition), log scale; bars = the ratio's 95%% "
                     "interval from paired rounds, which the machine's drift over the session does not widen. "
                     "One line per setting of the other axes.")
    section_plot(body, "plot-frame-vs-leaf", "Frame time vs leaf size, as a ratio to the baseline leaf size",
                 ratio_plot(data, "leaf_size", "Time ratio vs leaf size"), ratio_caption)
    section_plot(body, "plot-frame-vs-depth", "Frame time vs recursion depth, as a ratio to the baseline depth",
                 ratio_plot(data, "depth", "Time ratio vs depth"),
                 ratio_caption + " Depth = path segments per pixel, primary ray included; scenes whose effective "
                 "depth is 1 are not compared (findings.json's skipped list).")
    section_plot(body, "plot-time-vs-costs", "Frame time vs the deterministic cost measures, as ratios to the baseline",
                 time_vs_costs(data, styles),
                 "Each point is a builder against the baseline builder with every other axis equal: its time ratio "
                 "(findings.json, bars = the paired 95% interval) against the same ratio of each cost measure, "
                 "log-log; on the dotted diagonal the measure predicted the time. Colour = builder, marker = ray "
                 "type or frames. How well each measure ranks the runs is in the findings (Spearman).")
    section_plot(body, "plot-visits-vs-sah", "Node visits per ray vs SAH cost",
                 scatter_visits_vs_sah(data, styles, data.sweep),
                 "Each point is a run (per scene, the runs that differ only in builder, kernel, leaf size or bins); "
                 "colour = builder, numbers are leaf sizes.")
    section_plot(body, "plot-builders", "SAH cost and build time per builder", builder_costs(data, styles, data.sweep),
                 "Median over runs with the same scene, builder and leaf size; builders drawn slightly apart.")
    pareto_fig, fronts, pareto_reason, pareto_notes = pareto_plot(data, data.ok)
    section_plot(body, "plot-pareto", "Accuracy vs time (Pareto fronts)", (pareto_fig, pareto_reason),
                 "Image error against each run's reference run (mean absolute error over 8-bit RGB), over the axes "
                 "that change it: one run per combination of their values, the others at the sweep's most common "
                 "setting. Bars = 95% intervals of the frame time.",
                 notes=pareto_notes)
    pareto_table(body, data, fronts)
    section_rays(body, data)
    section_layouts(body, data)
    section_dynamic(body, data)
    section_antialiasing(body, data)
    section_images(body, data)
    section_builder_table(body, data)
    if len(data.values(data.ok, "robust")) > 1 or os.path.isfile(os.path.join(root, "hard_cases.json")):
        section_robustness(body, data, root)
    section_failed(body, data)
    section_all_rows(body, data)
    section_provenance(body, data)

    summ = results.get("summary", {})
    title = "bvhlab experiment: %s" % exp.get("name", "?")
    head = ["<!DOCTYPE html><html><head><meta charset='utf-8'><title>%s</title><style>%s</style></head><body>"
            % (html.escape(title), CSS + SUMMARY_CSS),
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
