"""The robustness section of the experiment report: what accuracy costs in time.

report.py calls section_robustness(page, data, root) with its Page, its Data and the sweep directory.
Per scene, one table over the robustness variants (traversal/robustness.hpp) of runs that differ in
the robust axis only: frame time with its interval, its ratio to the fast variant of the same settings
(with findings.json's interval and verdict when it compared the two),
the variant's hard-case counts from DIR/hard_cases.json (written by `bvhlab run` with
`bvhlab hard-cases`: leaks, disagreement with the exact oracle, secondary-ray failures; the same for
every scene), and the image error against the config's reference and against the watertight run of
the same settings. Every number is computed from the files; nothing is hand-written.
"""
import html
import json
import os
import sys

# The small helpers (num, fmt, fmt_ms, label, AXES) are report_data.py's. They are taken from the module
# that defined the Data object passed in, so this file imports nothing from the report's modules and
# works however they were loaded.


def _helpers(data):
    return sys.modules[type(data).__module__]


def load_hard_cases(root):
    """DIR/hard_cases.json as (record, variants by name, problem); problem is None when usable."""
    path = os.path.join(root, "hard_cases.json")
    if not os.path.isfile(path):
        return None, {}, ("no hard_cases.json in this directory (`bvhlab run` writes it when a sweep has more "
                          "than one robust value)")
    try:
        with open(path) as f:
            record = json.load(f)
    except (OSError, ValueError) as e:
        return None, {}, "hard_cases.json is unreadable: %s" % e
    if record.get("status") != "ok":
        return record, {}, "the hard-case run failed: %s" % record.get("error", "unknown error")
    variants = {v.get("robust"): v for v in record.get("result", {}).get("variants", [])}
    return record, variants, None


def image_mae(data, a, b):
    """Mean |a - b| over 8-bit R, G, B of two runs' images (None when either is missing or sizes differ)."""
    ia, ib = data.load_image(a.get("image")), data.load_image(b.get("image"))
    if ia is None or ib is None or ia.shape != ib.shape:
        return None
    diff = abs(ia[..., :3].astype("float64") - ib[..., :3].astype("float64"))
    return float(diff.mean() * 255.0)


def robust_groups(data, rows):
    """Runs that differ in the robust axis only: {other axes' labels: {variant: row}} with >= 2 variants."""
    h = _helpers(data)
    others = [a for a in h.AXES if a != "robust"]
    groups = {}
    for r in rows:
        v = h.label(r, "robust")
        if v is None:
            continue
        groups.setdefault(tuple(h.label(r, a) for a in others), {})[v] = r
    return {k: g for k, g in groups.items() if len(g) >= 2}, others


def _count(v, *path):
    for p in path:
        if not isinstance(v, dict):
            return None
        v = v.get(p)
    return v


def section_robustness(page, data, root):
    h = _helpers(data)
    page.section("robustness", "Robustness variants: what accuracy costs")
    rows = [r for r in data.ok if not r.get("reference_only")]
    groups, others = robust_groups(data, rows)
    record, hard, problem = load_hard_cases(root)
    if not groups:
        page.note("No runs that differ in the robust axis only; sweep <code>robust</code> to fill this section.")
        return
    page.p("Variants: <b>tri</b> = watertight ray/triangle test (Woop, Benthin &amp; Wald 2013) instead of "
           "Möller–Trumbore; <b>box</b> = Ize's conservative slab test (2013) instead of the plain one; "
           "<b>ulp</b> = Wächter &amp; Binder's ULP ray-origin offset instead of a fixed relative epsilon; "
           "<b>fast</b> = none of them, <b>watertight</b> = all three. Time ratios are against the fast "
           "variant of the same settings in the same sweep.")
    if problem:
        page.note("Hard-case columns are empty: " + html.escape(problem))
    else:
        res = record["result"]
        suite = res.get("suite", {})
        page.p("Hard-case columns come from <code>bvhlab hard-cases</code> (kernel %s, builder %s; the same for "
               "every scene): <i>leaks</i> of %s must-hit rays (C++ mirror through a BVH)%s; <i>oracle ≠</i> = "
               "hit/miss decisions that differ from CGAL's exact answer on %s non-tie rays, plus first hits on "
               "another triangle than the exact one (of %s decided first hits; in brackets those at least 2<sup>-16</sup> "
               "inside their triangle, where no float test has an excuse); <i>secondary</i> = reflected or "
               "outgoing rays on the closed meshes that re-hit their own surface / left the mesh, of %s."
               % (html.escape(str(res.get("kernel", "?"))), html.escape(str(res.get("builder", "?"))),
                  h.fmt(suite.get("must_hit")),
                  "; <i>GLSL leaks</i> of %s pixels looking out from inside closed meshes" % h.fmt(res.get("gpu_rays"))
                  if res.get("gpu") else "",
                  h.fmt(suite.get("oracle_decisive")), h.fmt(suite.get("oracle_first_decisive")),
                  h.fmt(_count(next(iter(hard.values()), {}), "total", "secondary_rays"))))

    order = data.values(rows, "robust")
    header = ["variant", "frame ms [95%]", "× fast", "leaks", "GLSL leaks", "oracle ≠ hit/miss",
              "oracle ≠ first hit (clear)",
              "secondary self-hit / lost", "MAE vs reference", "MAE vs watertight"]
    findings = []
    table_id = 0
    for scene in data.values(rows, "scene"):
        scene_groups = [(k, g) for k, g in groups.items() if k[others.index("scene")] == scene]
        for key, g in scene_groups:
            table_id += 1
            varying = [a for a in others if a != "scene" and len(data.values(rows, a)) > 1]
            where = " ".join("%s=%s" % (a, key[others.index(a)]) for a in varying if key[others.index(a)] is not None)
            page.section("robustness-%d" % table_id,
                         "%s%s" % (scene, (" (" + where + ")") if where and len(scene_groups) > 1 else ""), level=3)
            fast, watertight = g.get("fast"), g.get("watertight")
            fast_ms = h.num(fast.get("frame_ms")) if fast else None
            cells = []
            for v in order:
                r = g.get(v)
                if r is None:
                    continue
                hc = hard.get(v, {})
                total = hc.get("total", {})
                gpu = hc.get("gpu")
                first = total.get("oracle_first_disagree")
                clear = total.get("oracle_first_clear_disagree")
                cells.append([
                    "<b>%s</b>" % html.escape(v),
                    h.fmt_ms(r),
                    data.ratio_cell(r, fast) if fast is not None else "–",
                    h.fmt(total.get("leaks")),
                    h.fmt(gpu.get("leaks")) if isinstance(gpu, dict) else "–",
                    h.fmt(total.get("oracle_hit_disagree")),
                    "%s (%s)" % (h.fmt(first), h.fmt(clear)) if first is not None else "–",
                    "%s / %s" % (h.fmt(total.get("secondary_self_hits")), h.fmt(total.get("secondary_lost")))
                    if total else "–",
                    h.fmt(r.get("image_mae")),
                    h.fmt(image_mae(data, r, watertight)) if watertight else "–",
                ])
            page.table("robustness-table-%d" % table_id, header, cells)
            if fast_ms and watertight and h.num(watertight.get("frame_ms")):
                w = hard.get("watertight", {}).get("total", {})
                f = hard.get("fast", {}).get("total", {})
                leak_text = (" and leaks %s of the hard cases' must-hit rays where fast leaks %s"
                             % (h.fmt(w.get("leaks")), h.fmt(f.get("leaks")))) if w and f else ""
                findings.append("%s: watertight takes %s the fast variant's frame time%s."
                                % (html.escape(scene + ((" (" + where + ")") if where else "")),
                                   data.ratio_text(watertight, fast), leak_text))
    if findings:
        page.add('<ul class="findings">%s</ul>' % "".join("<li>%s</li>" % f for f in findings))
    if record and not problem:
        page.p("Hard-case run: %s, %s s, commit %s." % (
            html.escape(str(record.get("started_at", "?"))), h.fmt(record.get("wall_s")),
            html.escape(str(record.get("git_commit", "?"))[:12])))
