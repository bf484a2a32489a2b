"""Report sections that mirror the seed report's Figs. 8-12 (configs with seed_figures = true) and the
anti-aliasing comparison (every AA mode's frame time and image error against the reference)."""
import html

from report_data import (AXES, describe, fmt, fmt_fps, fmt_ms, fps, frame_ci, group, in_sweep, label, matplotlib,
                         np, num, plt, ratio)
from report_plots import log2_ticks
import matplotlib.patches  # noqa: E402


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
            vals, found = [], []
            for s in scenes:
                m = [r for r in rows if label(r, "scene") == s and label(r, "aa") == aa]
                vals.append(fps(m[0]) if m else 0)
                found.append(m[0] if m else {})
                if m:
                    cells.append([html.escape(s), "yes" if (num(m[0].get("triangles")) or 0) > 0 else "no",
                                  html.escape(str(aa)), fmt_fps(m[0]), fmt_ms(m[0])])
            ax.bar([i + j * width for i in range(len(scenes))], vals, width, label="aa=%s" % aa,
                   yerr=fps_err(found, vals), capsize=3)
        ax.set_xticks([i + width * (len(aas) - 1) / 2 for i in range(len(scenes))])
        ax.set_xticklabels(scenes)
        ax.set_ylabel("frames per second")
        ax.legend(fontsize=8)
        ax.grid(axis="y", alpha=0.3)
        page.figure(fig, "Fig. 8 measured: FPS per scene and anti-aliasing mode.")
        page.table("seed-fig8-data", ["scene", "has mesh", "aa", "FPS [95%]", "frame ms [95%]"], cells)
        notes = []
        for s in scenes:
            base = [r for r in rows if label(r, "scene") == s and label(r, "aa") in ("none", None)]
            smaa = [r for r in rows if label(r, "scene") == s and label(r, "aa") == "smaa"]
            if base and smaa:
                notes.append("%s: SMAA takes %s the frame time without it (the seed's §4.5 says SMAA barely lowers "
                             "the frame rate)." % (html.escape(s), data.ratio_text(smaa[0], base[0])))
        mesh = [r for r in rows if (num(r.get("triangles")) or 0) > 0 and label(r, "aa") in ("none", None)]
        nomesh = [r for r in rows if (num(r.get("triangles")) or 0) == 0 and label(r, "aa") in ("none", None)]
        if mesh and nomesh:
            notes.append("The mesh costs %s× the frame time (%s vs %s FPS; two scenes, so no paired interval)." % (
                fmt(ratio(num(mesh[0]["frame_ms"]), num(nomesh[0]["frame_ms"]))), fmt_fps(mesh[0]),
                fmt_fps(nomesh[0])))
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
            '<div><img class="render" src="%s" alt="%s"><br>%s, %s ms</div>'
            % (data.image_uri(r["image"]), html.escape("render at " + c), c, fmt_ms(r))
            for r, c in images) + "</div>")
        a, b = data.load_image(shallow["image"]), data.load_image(deep["image"])
        if a is not None and b is not None and a.shape == b.shape and deep is not shallow:
            page.p("Mean luminance: %s at depth %s vs %s at depth %s (the seed's §4.3: depth 1 is darker)." % (
                fmt(float(np.mean(a[..., :3]))), label(shallow, "depth"), fmt(float(np.mean(b[..., :3]))),
                label(deep, "depth")))

    # Fig. 12: SMAA comparison; again with ray-cone texture LOD when the config has its sweep.
    page.section("seed-fig12", "Fig. 12 — SMAA off vs on", level=3)
    seed_fig12(page, data, "fig8", "")
    if in_sweep(data.ok, "fig12-cones"):
        seed_fig12(page, data, "fig12-cones", " with ray-cone texture LOD")


def seed_fig12(page, data, sweep, what):
    """SMAA off and on, side by side with a zoom on where SMAA changed the image most, from the runs of
    `sweep` (aa none and smaa on one scene: the scene with the mesh first)."""
    rows = [r for r in in_sweep(data.ok, sweep) if r.get("image")]
    pairs = []
    for s in data.values(rows, "scene"):
        off = [r for r in rows if label(r, "scene") == s and label(r, "aa") in ("none", None)]
        on = [r for r in rows if label(r, "scene") == s and label(r, "aa") == "smaa"]
        if off and on:
            pairs.append((s, off[0], on[0]))
    if not pairs:
        page.note("No pair of %s runs with aa=none and aa=smaa on the same scene." % html.escape(sweep))
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
        at, (ch, cw) = worst_window(diff, 4)
        fig, axs = plt.subplots(2, 2, figsize=(9, 9 * h / w * 1.0 + 0.5))
        for col, (img, name) in enumerate(((a, "SMAA off"), (b, "SMAA on"))):
            axs[0][col].imshow(img)
            axs[0][col].add_patch(matplotlib.patches.Rectangle((at[1], at[0]), cw, ch, fill=False, color="r"))
            axs[0][col].set_title(name, fontsize=9)
            axs[1][col].imshow(img[at[0]:at[0] + ch, at[1]:at[1] + cw], interpolation="nearest")
            axs[1][col].set_title("%s, zoomed 4×" % name, fontsize=9)
        for ax in axs.flat:
            ax.set_axis_off()
        lod = on.get("texture_lod")
        setting = "" if not lod or lod == "none" else " (texture LOD %s, SMAA %s edges)" % (
            html.escape(str(lod)), html.escape(str(on.get("smaa_edges") or "luma")))
        page.figure(fig, "Fig. 12 measured%s%s (%s): the red window is where SMAA changed the image most." % (
            what, setting, html.escape(s)))
        mae = float(np.mean(np.abs(a[..., :3] - b[..., :3]))) * (255.0 if a.dtype != np.uint8 else 1.0)
        page.p("SMAA changes the image by a mean of %s (8-bit units) and takes %s the frame time without it." % (
            fmt(mae), data.ratio_text(on, off)))


def aa_preset(row):
    """'smaa' runs name their preset in smaa_preset; show them as smaa-PRESET like the axis values."""
    v = label(row, "aa")
    v = "smaa-%s" % row["smaa_preset"] if v == "smaa" and row.get("smaa_preset") else v
    # Colour edge detection is a variant of the SMAA mode, not another scene setting (luma: the default).
    edges = {"color": " (colour edges)", "geometry": " (geometry edges)"}.get(row.get("smaa_edges"), "")
    v = v + edges if v.startswith("smaa") else v
    # Texture filtering by ray cones is part of the mode too: "smaa-high + cones".
    lod = row.get("texture_lod")
    return v + " + " + str(lod) if lod and lod != "none" else v


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
    """The anti-aliasing comparison: per scene, every anti-aliasing mode's frame time and image error against
    the config's reference (16x supersampling), with the seed's two targets and crops (Fig. 12)."""
    rows = [r for r in data.ok if r.get("aa")]
    if len(data.values(rows, "aa")) < 2:
        return
    page.section("antialiasing", "Anti-aliasing: accuracy vs time")
    page.p("Error = mean absolute difference over 8-bit RGB against the reference run (its image is "
           "supersampled 16× when the config says so). Targets: SMAA error ≤ 0.5× the error "
           "without AA, SMAA frame time ≤ 0.25× SSAA 4×'s. The post-process column is the time of the three SMAA "
           "passes alone, included in the frame time. The frame-time ratio cannot fall below time(none) / "
           "time(SSAA 4×), because the SMAA frame still traces every pixel once; the added-time column "
           "compares what each mode adds to the frame without AA, (t − t_none) / (t_SSAA4 − t_none), which "
           "is the anti-aliasing's own cost. A mode ending in + cones or + cones-aniso also filters textures by "
           "ray cones (docs/texture-lod.md); its targets: with SMAA, error ≤ 0.5× the error without AA "
           "and texture LOD, frame time ≤ 1.1× the same mode's without texture LOD (the interval shown is the "
           "conservative one from the two runs' own intervals).")
    by_key = {r.get("key"): r for r in data.ok}
    others = [a for a in AXES if a not in ("aa", "smaa_edges", "texture_lod")]
    for combo, members in sorted(group(rows, lambda r: tuple(label(r, a) for a in others)).items(),
                                 key=lambda kv: [str(x) for x in kv[0]]):
        modes = {}
        for r in members:
            modes.setdefault(aa_preset(r), r)
        if len(modes) < 2:
            continue
        scene = label(members[0], "scene")
        varying = [a for a in data.varying(rows, exclude=("aa", "smaa_edges", "texture_lod"))]
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
            base = modes.get(mode.split(" + ")[0]) if " + " in mode else None
            if base is not None:  # a texture-LOD mode: its targets
                checks = []
                if err_ratio is not None and mode.startswith("smaa"):
                    checks.append("error %s" % ("✓" if err_ratio <= 0.5 else "✗ (target ≤ 0.5)"))
                lo, hi = num(r.get("frame_ms_ci_low")), num(r.get("frame_ms_ci_high"))
                blo, bhi = num(base.get("frame_ms_ci_low")), num(base.get("frame_ms_ci_high"))
                cost = ratio(t, num(base["frame_ms"]))
                # Conservative interval of the ratio from the two runs' own intervals; a verdict only
                # when it lies on one side of the 1.1 target.
                if cost is not None and None not in (lo, hi, blo, bhi) and blo > 0 and bhi > 0:
                    clo, chi = lo / bhi, hi / blo
                    checks.append("time / without LOD %s [%s, %s] %s" % (
                        fmt(cost), fmt(clo), fmt(chi),
                        "✓" if chi <= 1.1 else "✗ (target ≤ 1.1)" if clo > 1.1 else "undecided (interval spans 1.1)"))
                elif cost is not None:
                    checks.append("time / without LOD %s (no interval, no verdict)" % fmt(cost))
                verdict = ", ".join(checks)
            elif mode.startswith("smaa"):
                checks = []
                if err_ratio is not None:
                    checks.append("error %s" % ("✓" if err_ratio <= 0.5 else "✗ (target ≤ 0.5)"))
                if time_vs_ssaa4 is not None:
                    checks.append("time %s" % ("✓" if time_vs_ssaa4 <= 0.25 else "✗ (target ≤ 0.25)"))
                if added_vs_ssaa4 is not None:
                    checks.append("added time %s" % ("✓" if added_vs_ssaa4 <= 0.25 else "✗ (≤ 0.25)"))
                verdict = ", ".join(checks)
            cells.append([html.escape(mode), fmt_ms(r), fmt(r.get("aa_ms")) if r.get("aa_ms") is not None else "–",
                          data.ratio_cell(r, none) if none and r is not none else "1" if none else "–",
                          data.ratio_cell(r, ssaa4) if ssaa4 and r is not ssaa4 else fmt(time_vs_ssaa4),
                          fmt(added_vs_ssaa4) if added_vs_ssaa4 is not None else "–",
                          fmt(e), fmt(err_ratio), fmt(r.get("image_psnr")), verdict])
        page.table("aa-%s" % html.escape(str(title)), ["mode", "frame ms [95%]", "post-process ms", "time / none",
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
        ys = [fps(r) for r in srows]
        ax.errorbar([num(r[axis]) for r in srows], ys, yerr=fps_err(srows, ys), marker="o", capsize=2, label=scene)
        cells += [[html.escape(scene), label(r, axis), fmt_fps(r), fmt_ms(r)] for r in srows]
        best = max(srows, key=fps)
        page.p("%s: FPS goes from %s at %s = %s to %s at %s = %s and %s; the highest median is %s at %s = %s." % (
            html.escape(scene), fmt_fps(srows[0]), axis, label(srows[0], axis), fmt_fps(srows[-1]), axis,
            label(srows[-1], axis), trend(srows), fmt(fps(best)), axis, label(best, axis)))
    if axis == "leaf_size":
        log2_ticks(ax, {num(r[axis]) for r in rows})
    else:
        ax.set_xticks(sorted({num(r[axis]) for r in rows}))
    ax.set_xlabel(xlabel)
    ax.set_ylabel("frames per second")
    ax.set_ylim(bottom=0)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    page.figure(fig, "Measured counterpart of the seed's plot.")
    page.table(tid, ["scene", axis, "FPS [95%]", "frame ms [95%]"], cells)




def fps_err(rows, ys):
    """FPS error bars (below, above) from the rows' frame-time intervals; None when no row has one."""
    lo, hi = [], []
    for r, y in zip(rows, ys):
        ci = frame_ci(r) if r else None
        lo.append(max(0.0, y - 1000.0 / ci[1]) if ci and ci[1] else 0.0)
        hi.append(max(0.0, 1000.0 / ci[0] - y) if ci and ci[0] else 0.0)
    return [lo, hi] if any(lo) or any(hi) else None


def trend(rows):
    """How frame time moves along rows. With intervals, a step counts only when the two intervals do not
    overlap (otherwise it is within noise); without them, the medians decide."""
    steps = []
    for a, b in zip(rows, rows[1:]):
        ca, cb = frame_ci(a), frame_ci(b)
        ta, tb = num(a["frame_ms"]), num(b["frame_ms"])
        if ca and cb:
            steps.append(1 if cb[0] > ca[1] else -1 if cb[1] < ca[0] else 0)
        else:
            steps.append(1 if tb > ta else -1 if tb < ta else 0)
    if all(s == 1 for s in steps):
        return "falls at every step"
    if all(s == -1 for s in steps):
        return "rises at every step"
    if all(s >= 0 for s in steps):
        return "never rises (%d of %d steps within noise)" % (steps.count(0), len(steps))
    if all(s <= 0 for s in steps):
        return "never falls (%d of %d steps within noise)" % (steps.count(0), len(steps))
    return "is not monotonic"
