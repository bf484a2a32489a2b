"""The report's animation section: runs on the `updates` axis (`bvhlab trace --update`, docs/animation.md).
Per scene: the time of every traced frame stacked as update + upload + trace, one panel per strategy; the
SAH and the ray cost over the clip, one line per strategy; and a table of the clip's total time with its
bootstrap interval and its parts. The per-frame values come from each run's record (DIR/runs/KEY.json)."""
import html

from report_data import fmt, label, num, plt
from report_html import section_plot
from report_rays import slug


def clip_rows(data):
    """Finished traced runs that carry a clip (a `frames` array and a `clip` object in their record)."""
    rows = []
    for r in data.traced:
        rec = data.record(r.get("key"))
        if label(r, "update") is not None and isinstance(rec.get("frames"), list) and isinstance(rec.get("clip"), dict):
            rows.append((r, rec))
    return rows


def strategy(row):
    """"refit over sah-binned": the update spec and the builder of its builds."""
    return "%s (%s)" % (label(row, "update"), label(row, "builder"))


def per_frame(rec, key):
    return [num(f.get(key)) for f in rec["frames"]], [f.get("frame") for f in rec["frames"]]


def stacked_plot(scene, runs):
    if not runs:
        return None, "no runs"
    n = len(runs)
    fig, axes = plt.subplots(1, n, figsize=(3.2 * n, 2.8), sharey=True, squeeze=False)
    for ax, (row, rec) in zip(axes[0], runs):
        update, frames = per_frame(rec, "update_ms")
        upload, _ = per_frame(rec, "upload_ms")
        trace, _ = per_frame(rec, "ms")
        if any(v is None for v in update + upload + trace):
            ax.set_title(strategy(row) + "\n(missing times)", fontsize=8)
            continue
        ax.stackplot(frames, update, upload, trace, labels=["update", "upload", "trace"], alpha=0.85)
        ax.set_title(strategy(row), fontsize=8)
        ax.set_xlabel("frame")
    axes[0][0].set_ylabel("ms per frame")
    axes[0][-1].legend(fontsize=7, loc="upper left")
    fig.suptitle(str(scene), fontsize=9)
    return fig, ""


def quality_plot(scene, runs):
    if not runs:
        return None, "no runs"
    fig, (a, b) = plt.subplots(1, 2, figsize=(10, 3))
    for row, rec in runs:
        sah, frames = per_frame(rec, "sah_cost")
        cost, _ = per_frame(rec, "ray_cost")
        a.plot(frames, sah, marker=".", label=strategy(row))
        b.plot(frames, cost, marker=".", label=strategy(row))
    a.set_xlabel("frame")
    a.set_ylabel("SAH cost")
    b.set_xlabel("frame")
    b.set_ylabel("ray cost (visits + tests per ray)")
    b.legend(fontsize=7)
    fig.suptitle(str(scene), fontsize=9)
    return fig, ""


def total_cell(clip):
    t, lo, hi = num(clip.get("total_ms")), num(clip.get("total_ms_ci_low")), num(clip.get("total_ms_ci_high"))
    if t is None:
        return "–"
    if lo is None or hi is None:
        return fmt(t)
    return '%s <span class="ci">[%s, %s]</span>' % (fmt(t), fmt(lo), fmt(hi))


def section_dynamic(page, data):
    rows = clip_rows(data)
    if not rows:
        return
    page.section("dynamic", "Animated scenes: update strategies over a clip")
    page.p("Runs on the <code>updates</code> axis trace an animated scene's clip frame by frame, the tree kept up to "
           "date by the strategy (docs/animation.md). <i>Total</i> is the sum over the traced frames of the median "
           "update, upload (pack + GL re-upload) and trace times, with a bootstrap 95% interval (each frame's samples "
           "resampled). The clips of a group are stepped in lockstep (<code>interleaved_with</code>): frame f of "
           "every strategy before frame f + 1 of any. Ray cost is node visits + triangle tests per ray (Ct = Ci = 1).")
    for scene in data.values([r for r, _ in rows], "scene"):
        runs = [(r, rec) for r, rec in rows if label(r, "scene") == scene]
        runs.sort(key=lambda x: num(x[1]["clip"].get("total_ms")) or float("inf"))
        page.section("dynamic-" + slug(scene), str(scene), level=3)
        cells = []
        for r, rec in runs:
            c = rec["clip"]
            cost, _ = per_frame(rec, "ray_cost")
            first, last = (cost[0], cost[-1]) if cost else (None, None)
            growth = last / first if first and last is not None else None
            cells.append(["<b>%s</b>" % html.escape(strategy(r)), total_cell(c), fmt(c.get("update_ms_total")),
                          fmt(c.get("upload_ms_total")), fmt(c.get("trace_ms_total")), fmt(c.get("rebuilds")),
                          fmt(first), fmt(last), fmt(growth), fmt(c.get("frames"))])
        page.table("dynamic-table-" + slug(scene),
                   ["strategy", "total ms [95%]", "update ms", "upload ms", "trace ms", "rebuilds",
                    "ray cost, first frame", "ray cost, last frame", "growth", "frames"], cells)
        section_plot(page, "plot-dynamic-time-" + slug(scene), "%s: time per frame" % scene,
                     stacked_plot(scene, runs), "Per traced frame: update (CPU), upload (pack + GL re-upload) and "
                     "trace (median of the timed passes), stacked; one panel per strategy.")
        section_plot(page, "plot-dynamic-quality-" + slug(scene), "%s: SAH and ray cost over the clip" % scene,
                     quality_plot(scene, runs), "Per traced frame: the tree's SAH cost and the ray cost the kernel's "
                     "counters give, one line per strategy.")
