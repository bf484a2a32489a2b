"""The findings section: DIR/findings.json (written by the runner, experiments/findings.cpp) said in words
and tables. Nothing here computes a verdict; every ratio, interval and verdict is the file's, so the page
and the file say the same. Rows are only read to describe a run's configuration and to fill a count the
file lacks.
"""
import html

from report_data import (COUNTS, describe, fmt, fmt_band, fmt_ms, fmt_ratio, label, num, plural, band_of,
                         verdict_tag)

PREDICTORS = [("sah_cost", "SAH"), ("epo", "EPO"), ("node_visits_per_ray", "visits/ray"), ("ray_cost", "ray cost")]
VERDICTS = ["slower", "faster", "no detectable difference", "same tree", "not called: no noise band"]


def _scenes(data, entries):
    """Scenes of the entries, in the sweep's scene order, unknown ones last."""
    present = [e.get("scene") for e in entries]
    known = [s for s in data.values(data.rows, "scene") if s in present]
    return known + sorted({s for s in present if s not in known}, key=str)


def _run_text(data, key, fallback, exclude=("scene",)):
    """A run's configuration in words, from its row (the axes that vary in the sweep), else the file's label."""
    row = data.by_key.get(key)
    if row is None:
        return html.escape(str(fallback or key or "?"))
    return html.escape(describe(row, data.swept(exclude)) or str(fallback or key))


def _verdict_words(c):
    v = c.get("verdict")
    if v == "same tree":
        return "<i>same tree</i> (identical BVH, same kernel: nothing to tell apart)"
    if v == "no detectable difference":
        if num(c.get("ci_low")) is None:
            return verdict_tag(v) + " (too few frames for an interval)"
        return verdict_tag(v) + " (adjusted p %s: the interval does not clear the %s noise band by enough)" % (
            fmt(c.get("p_adjusted"), 3), fmt_band(c.get("band")))
    if v == "not called: no noise band":
        return verdict_tag(v) + " (no A/A band measured for these runs' sessions or between their processes)"
    if v in ("faster", "slower") and num(c.get("p_adjusted")) is not None:
        return verdict_tag(v) + " (adjusted p %s)" % fmt(c.get("p_adjusted"), 3)
    return verdict_tag(v)


def _counts(data, c, metric):
    """[a, b] of one count: the file's values, else the rows'."""
    pair = (c.get("counts") or {}).get(metric)
    if isinstance(pair, list) and len(pair) == 2:
        return pair
    ra, rb = data.by_key.get(c.get("a")) or {}, data.by_key.get(c.get("b")) or {}
    return [ra.get(metric), rb.get(metric)]


def _over(c):
    """What n counts, when not paired rounds: program copies, replicates, or unpaired frames."""
    over = c.get("interval_over")
    if over == "program copies":
        return " copies"
    if over in ("replicates", "replicates (hull)"):
        return " " + over
    return "" if c.get("paired", True) else " (unpaired)"


def replicates_note(page, comparisons):
    """How comparisons pooled over replicates read (experiments/replicates.hpp)."""
    pooled = [c for c in comparisons if str(c.get("interval_over", "")).startswith("replicates")]
    if not pooled:
        return
    counts = sorted({int(c.get("n") or 0) for c in pooled})
    page.p("This sweep was measured in %s replicates: every group again, each time in a new process, after the "
           "whole previous pass. Each comparison is made within every replicate (paired rounds) and pooled: from "
           "6 replicates the median of their ratios with its 95%% interval across the replicates (no band on "
           "top: <i>replicates</i>), with fewer the median with the hull of their intervals and the widest band "
           "(<i>replicates (hull)</i>: a direction needs every replicate's interval beyond its noise floor). "
           "What a process shares across its rounds (the compiled program's code placement, the machine's "
           "state) varies between replicates and so shows in these intervals."
           % html.escape("/".join(str(n) for n in counts)))


def _pair(a, b, digits=4):
    if a is None and b is None:
        return "–"
    return "%s / %s" % (fmt(a, digits), fmt(b, digits))


# ---------------------------------------------------------------- pieces
def adjustment_note(page, f):
    """How many comparisons were tested and how many directional verdicts chance alone would give."""
    adj = f.get("adjustment")
    if not isinstance(adj, dict):
        return
    tests, directional = int(adj.get("tests") or 0), int(adj.get("directional") or 0)
    alpha = num(adj.get("alpha")) or 0.05
    method = {"benjamini-hochberg": "Benjamini-Hochberg", "holm": "Holm"}.get(adj.get("method"), adj.get("method"))
    page.p("%s tested against the noise band, %s called faster or slower (p-values adjusted by %s at %s). "
           "Without an adjustment, chance alone would call about %s of the tests; with it, about %s of the "
           "%s directional verdicts are expected to be chance (the expected share of false ones is at most %s)."
           % (plural(tests, "comparison"), fmt(directional), html.escape(str(method)), fmt(alpha),
              fmt(num(adj.get("expected_by_chance_unadjusted")) if adj.get("expected_by_chance_unadjusted") is not None
                  else alpha * tests, 3),
              fmt(adj.get("expected_by_chance"), 3), fmt(directional), fmt(alpha)))
    check = f.get("same_tree_check")
    if isinstance(check, dict) and int(check.get("tested") or 0) > 0:
        page.p("Pairs of identical computations (<i>same tree</i>), tested as if they differed: %s of %s "
               "would have been called (the verdict rule's false-positive rate on this sweep)."
               % (fmt(check.get("directional")), fmt(check.get("tested"))))


def noise_floor(page, data, f):
    """The A/A controls. An entry names either two runs (a = the control run, b = the run it repeats) or one
    run that carries its own A/A measurement (key; the row's aa_control_* columns)."""
    page.section("findings-noise", "Noise floor: A/A controls", level=3)
    noise = list(f.get("noise") or [])
    if not noise:  # a writer may list the controls among the comparisons instead
        noise = [c for c in f.get("comparisons") or [] if c.get("kind") == "aa-control"]
    if not noise:
        page.note("No A/A control in this sweep: no noise band was measured, so comparisons within a session are "
                  "not called faster or slower (<i>not called: no noise band</i>).")
        return
    page.p("Each group of runs measured together (one session) measures one configuration again, as if it were "
           "another (<i>A/A control</i>). The ratio of the two should be 1; its interval is what this machine's noise "
           "does to a ratio, and a difference inside that band is never called faster or slower.")
    kinds = {e.get("control") for e in noise if e.get("control")}
    if "shared" in kinds:
        page.p("Two controls per group: <i>program</i> draws the run with a second, separately compiled copy of its "
               "program (its band applies to runs with different shaders, e.g. kernels: each compiled copy gets its "
               "own code placement); <i>shared</i> draws it with the same program over its own buffers (its band "
               "applies to runs that drew with one program, e.g. builders and leaf sizes: "
               "<code>shared_program</code> in findings.json).")
    cells, bands = [], []
    for e in noise:
        band = band_of(e.get("ci_low"), e.get("ci_high"))
        bands.append(band)
        original = e.get("b") or e.get("key")
        keys = [k for k in (original, e.get("a") if e.get("b") else None) if k]
        cells.append([html.escape(str(e.get("scene", "?"))),
                      html.escape(str(e.get("group", e.get("session", "–")))) +
                      (" (%s)" % html.escape(str(e["control"])) if e.get("control") else "") +
                      (", replicate %s" % html.escape(str(e["replicate"])) if "replicate" in e else ""),
                      _run_text(data, original, e.get("description") or original),
                      " / ".join("<code>%s</code>" % html.escape(str(k)) for k in keys),
                      " / ".join(fmt_ms(data.by_key.get(k) or {}) for k in keys),
                      fmt_ratio(e.get("ratio"), e.get("ci_low"), e.get("ci_high")), fmt(e.get("n")), fmt_band(band)])
    page.table("findings-noise-data", ["scene", "session" if any("session" in e for e in noise) else "group",
                                       "configuration", "run", "frame ms [95%]",
                                       "second / first [95%]", "n", "band used"], cells)
    known = [b for b in bands if b is not None]
    if known and fmt_band(min(known)) == fmt_band(max(known)):
        page.p("The A/A interval%s reach%s %s around 1: the band the verdicts use."
               % ("s" if len(known) > 1 else "", "" if len(known) > 1 else "es", fmt_band(known[0])))
    elif known:
        page.p("The A/A intervals reach %s to %s around 1 (the band each group's verdicts use)."
               % (fmt_band(min(known)), fmt_band(max(known))))
    if len(known) < len(bands):
        page.note("%s without an interval (too few frames): their groups have no band from them."
                  % plural(len(bands) - len(known), "control"))


def builder_verdicts(data, scene, entries):
    """One sentence per builder: its best run against the baseline builder at its best."""
    best = [c for c in entries if c.get("kind") == "builder-best"]
    if not best:
        return []
    bases = []
    for c in best:
        if c.get("b") not in [f.get("b") for f in bases]:
            bases.append(c)
    who = ("scene", "builder")
    items = []
    for c in bases:
        r = data.by_key.get(c.get("b"))
        fastest = (c.get("fastest") or {}).get("label")
        items.append("<b>%s</b>: baseline builder <b>%s</b> at its best (%s), %s ms%s." % (
            html.escape(str(scene)), html.escape(str(c.get("b_label") or (label(r, "builder") if r else "?"))),
            _run_text(data, c.get("b"), c.get("b_description"), who), fmt_ms(r or {}),
            "; fastest point estimate: <b>%s</b> (reported, not the reference)" % html.escape(str(fastest))
            if fastest else ""))
    for c in best:
        if c.get("a") == c.get("b"):
            continue
        items.append("<b>%s</b> at its best (%s) takes %s the frame time of <b>%s</b> at its best (%s): %s." % (
            html.escape(str(c.get("a_label"))), _run_text(data, c.get("a"), c.get("a_description"), who),
            fmt_ratio(c.get("ratio"), c.get("ci_low"), c.get("ci_high")), html.escape(str(c.get("b_label"))),
            _run_text(data, c.get("b"), c.get("b_description"), who), _verdict_words(c)))
    return items


def _baseline(f, data, axis):
    """The baseline value findings.json names for an axis (format 2), else the config's first."""
    b = (f.get("baselines") or {}).get(axis) if isinstance(f, dict) else None
    return b if b is not None else data.baseline(axis)


def verdict_summary(data, entries, f=None):
    """Per axis: how many comparisons went which way, and against what."""
    out = []
    axes = []
    for c in entries:
        a = c.get("axis") if c.get("kind") == "axis" else None
        if a and a not in axes:
            axes.append(a)
    for a in axes:
        mine = [c for c in entries if c.get("kind") == "axis" and c.get("axis") == a]
        counts = {v: sum(1 for c in mine if c.get("verdict") == v) for v in VERDICTS}
        other = len(mine) - sum(counts.values())
        parts = ["%d %s" % (n, v) for v, n in counts.items() if n] + (["%d other" % other] if other else [])
        base = _baseline(f, data, a)
        against = ("each value against %s" % html.escape("%s=%s" % (a, base)) if base is not None
                   else "each value against the config's first value")
        if a == "layout":
            against += " (each layout at its first kernel in config order)"
        out.append("<b>%s</b> (%s): %s — %s." % (html.escape(str(a)), against, plural(len(mine), "comparison"),
                                                 ", ".join(parts)))
    return out


def comparison_table(page, data, scene, entries, tid):
    shown = [c for c in entries if c.get("kind") in ("axis", "builder-best")]
    if not shown:
        return
    with_error = any(num((data.by_key.get(k) or {}).get("image_mae")) is not None
                     for c in shown for k in (c.get("a"), c.get("b")))
    header = ["kind / axis", "context", "a", "b", "a / b time [95%]", "n", "band", "verdict"]
    header += ["%s a / b" % name for _, name in COUNTS] + (["image error a / b"] if with_error else [])
    cells = []
    for c in shown:
        kind = "best builder" if c.get("kind") == "builder-best" else str(c.get("axis") or "?")
        n = fmt(c.get("n")) + _over(c)
        line = [html.escape(kind), html.escape(str(c.get("context") or "")),
                html.escape(str(c.get("a_label") or c.get("a"))), html.escape(str(c.get("b_label") or c.get("b"))),
                fmt_ratio(c.get("ratio"), c.get("ci_low"), c.get("ci_high")), n, fmt_band(c.get("band")),
                verdict_tag(c.get("verdict"))]
        line += [_pair(*_counts(data, c, m)) for m, _ in COUNTS]
        if with_error:
            line.append(_pair((data.by_key.get(c.get("a")) or {}).get("image_mae"),
                              (data.by_key.get(c.get("b")) or {}).get("image_mae")))
        cells.append(line)
    page.table(tid, header, cells, cls="comparisons")


def predictors(page, data, f):
    entries = f.get("predictors") or []
    page.section("findings-predictors", "Which cost measure predicts the frame time", level=3)
    if not entries:
        page.note("findings.json has no predictor entries (too few runs per scene and context).")
        return
    page.p("Spearman rank correlation, across the runs of one scene and context, between each deterministic "
           "cost measure and the measured median frame time: 1 = the measure orders the runs exactly as the "
           "clock does.")
    cells = []
    for e in entries:
        rho = e.get("spearman") or {}
        best = max((num(rho.get(k)) for k, _ in PREDICTORS if num(rho.get(k)) is not None), default=None)
        row = [html.escape(str(e.get("scene", "?"))), html.escape(str(e.get("context") or "")), fmt(e.get("n"))]
        for k, _ in PREDICTORS:
            v = num(rho.get(k))
            cell = "%.2f" % v if v is not None else "–"
            row.append("<b>%s</b>" % cell if v is not None and v == best else cell)
        cells.append(row)
    page.table("findings-predictors-data", ["scene", "context", "runs"] + ["ρ %s" % n for _, n in PREDICTORS], cells)


def misranked(page, data, f):
    if "misranked" not in f:
        return
    entries = f.get("misranked") or []
    page.section("findings-misranked", "Pairs SAH ranks wrongly", level=3)
    if not entries:
        page.p("SAH ranks every pair of runs whose times differ measurably in the right order.")
        return
    page.p("SAH says <i>a</i> is the cheaper tree, yet <i>a</i> measured slower than <i>b</i> (interval above the "
           "noise band, the pairs of each context adjusted as one family).")
    cells = []
    for e in entries:
        sah = e.get("sah") if isinstance(e.get("sah"), list) and len(e.get("sah")) == 2 else [None, None]
        cells.append([html.escape(str(e.get("scene", "?"))), html.escape(str(e.get("context") or "")),
                      html.escape(str(e.get("a_label") or e.get("a"))),
                      html.escape(str(e.get("b_label") or e.get("b"))),
                      fmt(sah[0], 4), fmt(sah[1], 4), fmt_ratio(e.get("ratio"), e.get("ci_low"), e.get("ci_high"))])
    page.table("findings-misranked-data", ["scene", "context", "a", "b", "SAH a", "SAH b", "a / b time [95%]"], cells)


# ---------------------------------------------------------------- the section
def section_findings(page, data):
    page.section("findings", "Findings")
    f = data.findings
    if f is None:
        why = data.findings_problem or "missing"
        if why == "missing":
            page.note("No comparisons: this directory has no findings.json (results measured before per-run "
                      "intervals and A/A controls). Re-run the sweep with a current bvhlab to get verdicts with "
                      "intervals.")
        else:
            page.note("No comparisons: findings.json is %s." % html.escape(why))
        if data.failed:
            page.items(["%s failed (listed below with their errors)." % plural(len(data.failed), "run")])
        return
    page.p("Every ratio is <i>a</i>'s median frame time over <i>b</i>'s (the baseline of its axis) with its 95% "
           "interval, from frames measured in the same rounds (paired) where the runs shared a session; the "
           "interval resamples the rounds in blocks, so it holds when consecutive rounds are correlated. "
           "<b>faster</b> / <b>slower</b> only when the test against the noise band measured by the A/A controls "
           "passes after the adjustment for the number of comparisons (the whole interval then lies outside the "
           "band); <i>not called</i> when no band was measured for the runs; <i>same tree</i> when both runs walk "
           "an identical BVH with the same kernel; otherwise <i>no detectable difference</i>. Everything here is "
           "read from <code>findings.json</code> (its fields: docs/measurement.md).")
    noise_floor(page, data, f)
    adjustment_note(page, f)
    comparisons = [c for c in f.get("comparisons") or [] if c.get("kind") != "aa-control"]
    replicates_note(page, comparisons)
    if not comparisons:
        page.note("findings.json lists no comparisons (no axis has two values among matched runs).")
    for i, scene in enumerate(_scenes(data, comparisons)):
        entries = [c for c in comparisons if c.get("scene") == scene]
        page.section("findings-scene-%d" % (i + 1), "%s" % scene, level=3)
        page.items(builder_verdicts(data, scene, entries) + verdict_summary(data, entries, f))
        comparison_table(page, data, scene, entries, "findings-comparisons-%d" % (i + 1))
    predictors(page, data, f)
    misranked(page, data, f)
    skipped = list(f.get("skipped") or [])
    if skipped:
        page.section("findings-skipped", "Comparisons not made", level=3)
        page.items([html.escape(str(s)) for s in skipped])
    if data.failed:
        page.p("%s failed (listed below with their errors)." % plural(len(data.failed), "run"))
