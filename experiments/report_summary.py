"""The report's first screen: per scene, one table of builders (rows) by ray type (columns: each traced
workload, and "frames" for rendered runs), each cell a builder's time ratio to the baseline builder with
its interval and verdict, copied from findings.json (never recomputed here). Below the tables: the noise
floor (the A/A bands of each measured group) and the machine's load while each group ran, with a warning
banner when a busy machine widened the intervals past the config's target.

The cells come from findings.json's builder comparisons against the fixed baseline builder (kind "axis",
axis "builder", baseline true), which hold every other axis equal: a builder is never credited with a
kernel's effect. Of those, a table shows one setting of the other axes, the config's baseline
(findings.json "baselines": kernel, layout, leaf size, ...); other kernels' comparisons stay in the
findings section below.
"""
import html

from report_data import fmt_band, fmt_ratio, label, num, plt, band_of
from report_html import figure_uri
from report_plots import log_ratio_axis

# Verdict -> cell class (colour): faster green, slower red, anything else grey.
CELL_CLASS = {"faster": "c-faster", "slower": "c-slower"}
# Steal above this share of CPU time (%) marks a group as measured on a busy machine. A dedicated machine
# steals ~0%; a few percent means the hypervisor gave the cores to other guests often enough to
# stretch frames.
BUSY_STEAL_PCT = 3.0
FRAMES = "frames"  # the column of rendered runs (no rays value)

CSS = """
table.summary td.cell{text-align:center;min-width:9em}table.summary td.c-faster{background:#dff3e3}
table.summary td.c-slower{background:#fbe0dd}table.summary td.c-none{background:#f0f0f0;color:#555}
table.summary td.base{background:#fff;color:#777;font-style:italic;text-align:center}
.banner{border:2px solid #b3261e;background:#fdecea;padding:.6em 1em;margin:1em 0;font-weight:bold}
p.load,p.noise{font-size:12px;margin:.3em 0}
"""


# a_values' name for the ray type: "rays" (the config's axis name) or "workload" (the row column's name).
RAY_KEYS = ("rays", "workload")
# Axes a caption always names (the tree and how it is walked); others only where the scene's cells vary.
CAPTION_AXES = ("kernel", "layout", "leaf_size", "triangle_format")


def _column(c):
    values = c.get("a_values") or {}
    rays = next((values[k] for k in RAY_KEYS if isinstance(values.get(k), str) and values[k]), None)
    return rays or FRAMES


def _setting(c):
    """The comparison's held axes (all but builder and the ray type), as a sorted tuple of (axis, label)."""
    values = c.get("a_values") or {}
    return tuple(sorted((str(k), str(v)) for k, v in values.items() if k != "builder" and k not in RAY_KEYS))


def _at_baseline(data, setting):
    """Whether every held axis that findings.json names a baseline for is at that baseline."""
    want = {str(k): str(v) for k, v in ((data.findings or {}).get("baselines") or {}).items()}
    return all(want.get(k, v) == v for k, v in setting)


def _baseline_builder(data):
    base = ((data.findings or {}).get("baselines") or {}).get("builder")
    return str(base) if base is not None else data.baseline("builder")


def builder_cells(data, scene):
    """(columns, {column: {builder: comparison}}, {column: setting}) for one scene: per column, the
    comparisons at the config's baseline setting (else, when no run of the column was made there, the
    setting with the most builders)."""
    findings = data.findings or {}
    comps = [c for c in findings.get("comparisons") or []
             if c.get("scene") == scene and c.get("kind") == "axis" and c.get("axis") == "builder"
             and c.get("baseline") is True and isinstance(c.get("a_values"), dict)]
    by_column = {}
    for c in comps:
        by_column.setdefault(_column(c), {}).setdefault(_setting(c), []).append(c)
    cells, settings = {}, {}
    for col, per_setting in by_column.items():
        at_base = [s for s in per_setting if _at_baseline(data, s)]
        pool = at_base or list(per_setting)
        best = max(pool, key=lambda s: (len({str(c["a_values"].get("builder")) for c in per_setting[s]}), s))
        settings[col] = best
        row = {}
        for c in per_setting[best]:
            row.setdefault(str(c["a_values"].get("builder")), c)  # the first one wins; a setting names one run
        cells[col] = row
    order = [str(v) for v in data.order.get("workload", []) + data.order.get("rays", [])]
    columns = ([FRAMES] if FRAMES in cells else []) + [w for w in order if w in cells and w != FRAMES]
    columns += sorted(c for c in cells if c not in columns)
    return columns, cells, settings


def _cell(c):
    verdict = str(c.get("verdict") or "")
    cls = CELL_CLASS.get(verdict, "c-none")
    return ('<td class="cell %s" data-a="%s" data-b="%s" data-verdict="%s">%s<br><span class="verdict">%s</span></td>'
            % (cls, html.escape(str(c.get("a"))), html.escape(str(c.get("b"))), html.escape(verdict),
               fmt_ratio(c.get("ratio"), c.get("ci_low"), c.get("ci_high")), html.escape(verdict or "–")))


def _setting_text(data, setting, shown=None):
    text = ", ".join("%s %s" % (k.replace("_", " "), v) for k, v in (setting if shown is None else shown))
    text = text or "the only setting run"
    if _at_baseline(data, setting):
        return text + ": the config's baseline setting"
    return text + ": not the config's baseline setting, where no builder was compared"


def table_builders(data, cells, base):
    """The table's rows: the baseline and every compared builder, in config order (unknown ones last)."""
    order = [str(b) for b in data.order.get("builder", [])]
    present = {b for col in cells.values() for b in col} | {base}
    return [b for b in order if b in present] + sorted(present - set(order))


def summary_table(page, data, scene, columns, cells, settings, base):
    builders = table_builders(data, cells, base)
    out = ['<div class="scroll"><table class="summary" id="summary-%s" data-scene="%s"><thead><tr><th>builder</th>'
           % (_slug(scene), html.escape(scene))]
    out += ["<th>%s</th>" % html.escape(col) for col in columns]
    out.append("</tr></thead><tbody>")
    for b in builders:
        out.append('<tr data-builder="%s"><td>%s</td>' % (html.escape(b), html.escape(b)))
        for col in columns:
            c = cells[col].get(b)
            if b == base:
                out.append('<td class="base">baseline</td>')
            elif c is None:
                out.append('<td class="cell c-none">–</td>')
            else:
                out.append(_cell(c))
        out.append("</tr>")
    out.append("</tbody></table></div>")
    distinct = sorted(set(settings.values()))
    # Name the tree axes and whatever differs between the columns' settings; the rest is one value throughout.
    varying = {k for k in {k for st in distinct for k, _ in st}
               if len({dict(st)[k] for st in distinct if k in dict(st)}) > 1}
    distinct_shown = {st: tuple((k, v) for k, v in st if k in CAPTION_AXES or k in varying) for st in distinct}
    texts = {}  # caption text -> the columns held there
    for col in columns:
        texts.setdefault(_setting_text(data, settings[col], distinct_shown[settings[col]]), []).append(col)
    held = "; ".join("%s: %s" % (", ".join(cols), t) for t, cols in texts.items()) if len(texts) > 1 else \
        next(iter(texts), "")
    page.add("<p><b>%s</b> — time of each builder's tree / the baseline builder's (%s), with the 95%% interval "
             "and verdict from findings.json; below 1 is faster. Every other axis is held equal within a cell "
             "(%s; other kernels and leaf sizes are in the findings below).</p>"
             % (html.escape(scene), html.escape(base), html.escape(held)))
    page.add("".join(out))


def _slug(text):
    return "".join(ch if ch.isalnum() else "-" for ch in str(text)).strip("-") or "scene"


# ---------------------------------------------------------------- noise floor and machine load
def noise_line(page, data, scene):
    entries = [n for n in (data.findings or {}).get("noise") or [] if n.get("scene") == scene]
    if not entries:
        page.add('<p class="noise">Noise floor: no A/A control in this scene\'s groups, so no band: a verdict '
                 'needs only its interval to clear 1.</p>')
        return
    parts = []
    for n in entries:
        band = band_of(n.get("ci_low"), n.get("ci_high"))
        parts.append('<span title="%s">%s</span>' % (html.escape("%s, %s control: %s" % (
            n.get("description") or n.get("key"), n.get("control"),
            html.unescape(fmt_ratio(n.get("ratio"), n.get("ci_low"), n.get("ci_high"))).replace(
                '<span class="ci">', "").replace("</span>", ""))), fmt_band(band)))
    widest = max((b for b in (band_of(n.get("ci_low"), n.get("ci_high")) for n in entries) if b is not None),
                 default=None)
    page.add('<p class="noise">Noise floor (A/A band of each group, %d): %s; widest %s.</p>'
             % (len(entries), " · ".join(parts), fmt_band(widest)))


def load_groups(rows):
    """Per measured group (session): its runs' recorded machine load, in the order the groups ran."""
    groups = {}
    for r in rows:
        if num(r.get("load_avg_1m_start")) is None and num(r.get("load_avg_1m_end")) is None:
            continue
        sid = (r.get("session") or r.get("key"), r.get("replicate") or 0)
        g = groups.setdefault(sid, {"rows": [], "start": r.get("started_at") or ""})
        g["rows"].append(r)
    out = []
    for sid, g in sorted(groups.items(), key=lambda kv: str(kv[1]["start"])):
        r0 = g["rows"][0]
        cores = num(r0.get("cores"))
        load = [v for v in (num(r0.get("load_avg_1m_start")), num(r0.get("load_avg_1m_end"))) if v is not None]
        steal = num(r0.get("steal_pct"))
        busy = bool((cores and load and max(load) > cores) or (steal is not None and steal > BUSY_STEAL_PCT))
        out.append({"session": sid[0], "rows": g["rows"], "cores": cores, "load": load, "steal": steal, "busy": busy,
                    "scene": label(r0, "scene")})
    return out


def _wide(row):
    """True when the run's interval is wider than the target it was measured to (None: no target or interval)."""
    target, pct = num(row.get("ci_target_pct")), num(row.get("ci_pct"))
    if pct is None:
        lo, hi, ms = num(row.get("frame_ms_ci_low")), num(row.get("frame_ms_ci_high")), num(row.get("frame_ms"))
        pct = 50.0 * (hi - lo) / ms if None not in (lo, hi, ms) and ms > 0 else None
    if target is None or pct is None:
        return None
    return pct > target


def busy_banner(page, groups):
    """The warning when groups ran on a busy machine and their runs' intervals missed the target. Returns
    whether it was shown."""
    busy = [g for g in groups if g["busy"]]
    if not busy:
        return False
    runs = [r for g in busy for r in g["rows"]]
    wide = [r for r in runs if _wide(r)]
    if not wide:
        return False
    loads = [v for g in busy for v in g["load"]]
    steals = [g["steal"] for g in busy if g["steal"] is not None]
    cores = {int(g["cores"]) for g in busy if g["cores"]}
    page.add('<div class="banner" id="busy-machine">The machine was busy while measuring: %d of %d groups ran at '
             'a load average up to %.2f on %s cores%s. %d of their %d runs have intervals wider than the target '
             '(%s): fewer differences could be called, so "no detectable difference" here may only mean '
             '"not resolved"; rerun on an idle machine to narrow them.</div>'
             % (len(busy), len(groups), max(loads),  # every listed group has a load sample (load_groups)
                "/".join(str(c) for c in sorted(cores)) or "?",
                ", CPU time stolen up to %.1f%%" % max(steals) if steals and max(steals) > 0 else "",
                len(wide), len(runs), ", ".join("±%g%%" % t for t in sorted(
                    {num(r.get("ci_target_pct")) for r in wide}))))
    return True


def load_line(page, groups, scene):
    mine = [g for g in groups if g["scene"] == scene]
    if not mine:
        page.add('<p class="load">Machine load: not recorded for this scene\'s groups.</p>')
        return
    parts = []
    for i, g in enumerate(mine, 1):
        load = "→".join("%.2f" % v for v in g["load"]) or "?"
        steal = "steal %.1f%%" % g["steal"] if g["steal"] is not None else "steal ?"
        parts.append('<span title="group %s, %d runs"%s>%s, %s</span>'
                     % (html.escape(str(g["session"])), len(g["rows"]), ' class="v-slower"' if g["busy"] else "",
                        load, steal))
    cores = {int(g["cores"]) for g in mine if g["cores"]}
    page.add('<p class="load">Machine load per group (1-minute load average at start→end on %s cores; CPU time '
             'stolen): %s.</p>' % ("/".join(str(c) for c in sorted(cores)) or "?", " · ".join(parts)))


# ---------------------------------------------------------------- the plot
def ratio_figure(scene, columns, cells, builders, base):
    """The table as a log-ratio plot: each builder's ratio to the baseline with its interval, per column."""
    builders = [b for b in builders if b != base]
    if not builders:
        return None
    fig, ax = plt.subplots(figsize=(8.5, 3.2))
    n = len(columns)
    for j, col in enumerate(columns):
        xs, ys, lo, hi = [], [], [], []
        for i, b in enumerate(builders):
            c = cells[col].get(b)
            r, l, h = (num(c.get(k)) for k in ("ratio", "ci_low", "ci_high")) if c else (None, None, None)
            if r is None or r <= 0:
                continue
            xs.append(i + (j - (n - 1) / 2.0) * 0.7 / max(n, 1))
            ys.append(r)
            lo.append(r - l if l is not None and 0 < l <= r else 0.0)
            hi.append(h - r if h is not None and h >= r else 0.0)
        if xs:
            ax.errorbar(xs, ys, yerr=[lo, hi], marker="os^Dv<>"[j % 7], linestyle="none", capsize=3, markersize=5,
                        label=col)
    log_ratio_axis(ax)
    ax.set_xticks(range(len(builders)))
    ax.set_xticklabels(builders, fontsize=8)
    ax.set_ylabel("time / %s's (log)" % base)
    ax.set_title("%s — ratio to the baseline builder, 95%% intervals" % scene, fontsize=10)
    ax.grid(alpha=0.3, which="both", axis="y")
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0)
    fig.tight_layout()
    return fig


# ---------------------------------------------------------------- the section
def section_summary(page, data):
    page.section("summary", "Which builder, per scene and ray type")
    findings = data.findings
    if not findings:
        page.note("No summary: findings.json is %s." % html.escape(data.findings_problem or "missing"))
        return
    base = _baseline_builder(data)
    rows = data.rows + data.controls
    groups = load_groups(rows)
    busy_banner(page, groups)
    scenes = [s for s in data.values(data.rows, "scene")]
    scenes += sorted({c.get("scene") for c in findings.get("comparisons") or []} - set(scenes) - {None}, key=str)
    shown = 0
    for scene in scenes:
        columns, cells, settings = builder_cells(data, scene)
        if not columns:
            continue
        shown += 1
        page.section("summary-" + _slug(scene), scene, level=3)
        summary_table(page, data, scene, columns, cells, settings, base)
        noise_line(page, data, scene)
        load_line(page, groups, scene)
        fig = ratio_figure(scene, columns, cells, table_builders(data, cells, base), base)
        if fig is not None:
            alt = ("Log-scale plot of each builder's time ratio to %s on %s with 95%% intervals, one marker per "
                   "ray type; the line at 1 is the baseline." % (base, scene))
            page.add('<figure><img src="%s" alt="%s"></figure>' % (figure_uri(fig), html.escape(alt)))
    if not shown:
        page.note("No builder was compared with the baseline builder (%s) in this sweep (findings.json has no "
                  "comparison of kind \"axis\" along builder with baseline true)." % html.escape(str(base)))
    if not groups:
        page.add('<p class="load">Machine load: not recorded (these runs predate the load fields).</p>')
