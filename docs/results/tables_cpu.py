"""The tables of the CPU runs on the development machine (docs/results/builders-quality, build-time,
robustness, sbvh-knobs), for docs/results/generate.py."""

import math
import os

from tables_io import (DataError, num, pick, read_csv, read_json, read_json_lines, result_path, rel, source,
                       commands, provenance, table, sig, f3, with_ci, band_cell)

# ---- CPU runs on the development machine -------------------------------------------------------

BQ = "builders-quality"


def cpu_build_quality():
    path, rows = read_json_lines(BQ, "build.jsonl")
    src = source(BQ)
    meshes = []
    for r in rows:
        if r.get("input") not in meshes:
            meshes.append(r.get("input"))
    builders = []
    for r in rows:
        if r.get("builder") not in builders:
            builders.append(r.get("builder"))
    out = []
    for m in meshes:
        ref = [r for r in rows if r.get("input") == m and r.get("builder") == "sah-binned"]
        if len(ref) != 1:
            raise DataError(f"{rel(path)}: no single sah-binned row for {m}")
        ref = ref[0]
        name = os.path.splitext(os.path.basename(m))[0]
        for b in builders:
            r = [x for x in rows if x.get("input") == m and x.get("builder") == b]
            if len(r) != 1:
                raise DataError(f"{rel(path)}: {len(r)} rows for {m} / {b}, expected 1")
            r = r[0]
            sah = num(r, "sah_cost", path)
            out.append([name, f"`{b}`", f"{sah:.2f}", f3(sah / num(ref, "sah_cost", path)),
                        f"{num(r, 'epo', path):.2f}",
                        f3(num(r, "references", path) / num(r, "primitives", path)),
                        str(int(num(r, "depth", path)))])
    header = ["mesh", "builder", "SAH cost", "x sah-binned", "EPO", "references per triangle", "depth"]
    lines = table(header, out)
    lines += ["", "Leaf size 4, traversal and intersection costs 1 (Ct = Ci = 1). SAH cost and end-point overlap "
                  "(EPO) are exact functions of the tree; no time is shown because one build per builder gives "
                  "no interval."]
    return lines + provenance([(path, rows)], src, commands(BQ, src))


def cpu_layout_bytes():
    path, rows = read_json_lines(BQ, "layout-bytes.jsonl")
    src = source(BQ)
    formats = ["raw", "precomputed", "indexed"]
    out = []
    for lay in ["v1", "bvh2-cb", "bvh4", "bvh8", "cwbvh"]:
        row = [f"`{lay}`"]
        for tri in formats:
            r = [x for x in rows if x.get("layout") == lay and x.get("triangle_format") == tri]
            if len(r) != 1:
                raise DataError(f"{rel(path)}: {len(r)} rows for layout {lay} / {tri}, expected 1")
            row.append(f"{num(r[0], 'bytes_per_triangle', path):.2f}")
        out.append(row)
    meshes = sorted({os.path.basename(str(r.get("input"))) for r in rows})
    builders = sorted({str(r.get("builder")) for r in rows})
    leaves = sorted({str(r.get("leaf_size")) for r in rows})
    header = ["layout"] + [f"`{t}`, bytes per triangle" for t in formats]
    lines = table(header, out)
    lines += ["", f"All streams (nodes, triangles, attributes, vertices) over the input triangles; "
                  f"{', '.join(meshes)}, {', '.join(builders)} tree, leaf size {', '.join(leaves)}."]
    return lines + provenance([(path, rows)], src, commands(BQ, src))


BT = "build-time"


def cpu_build_time():
    bpath, bench = read_json(BT, "bench.json")
    tpath = result_path(BT, "paired.tsv")
    src = source(BT)
    try:
        with open(tpath) as f:
            paired = [line.rstrip("\n").split("\t") for line in f if line.strip()]
    except OSError as e:
        raise DataError(f"{rel(tpath)}: {e.strerror}") from None
    ratios = {}
    for n, p in enumerate(paired, 1):
        if len(p) != 6:
            raise DataError(f"{rel(tpath)}: line {n}: expected 6 tab-separated fields, got {len(p)}")
        try:
            ratios[(p[0], p[1].split(" ")[0])] = tuple(float(x) for x in p[3:6])
        except ValueError:
            raise DataError(f"{rel(tpath)}: line {n}: the ratio and its interval are not numbers") from None
    reps = {}
    for b in bench.get("benchmarks", []):
        if b.get("run_type") != "iteration":
            continue
        builder, mesh = b["name"].split("/")[:2]
        reps.setdefault((mesh, builder), []).append(b)
    if not reps:
        raise DataError(f"{rel(bpath)}: no benchmark repetitions")
    out = []
    for (mesh, builder), rs in sorted(reps.items(), key=lambda kv: (kv[0][0], kv[0][1] != "sah-binned", kv[0][1])):
        times = sorted(num(r, "real_time", bpath) for r in rs)
        med = times[len(times) // 2]
        unit = rs[0].get("time_unit", "?")
        if builder == "sah-binned":
            cell = "1 (reference)"
        elif (mesh, builder) in ratios:
            cell = with_ci(*ratios[(mesh, builder)], fmt=lambda x: sig(x, 3))
        else:
            cell = "-"
        out.append([mesh, f"`{builder}`", f"{sig(med)} {unit} [{sig(times[0])}, {sig(times[-1])}]", cell,
                    f"{num(rs[0], 'sah', bpath):.2f}"])
    load = bench.get("context", {}).get("load_avg")
    ctx = bench.get("context", {})
    header = ["mesh", "builder", f"build time, median [min, max] of {len(times)} repetitions", "x sah-binned, paired [95%]",
              "SAH cost"]
    lines = table(header, out)
    lines += ["", f"One build thread (`embree` and `embree-low` use Embree's own thread pool whatever the setting). "
                  f"Repetition r of every builder runs in round r of a random interleaving; the paired ratio is the "
                  f"median of the per-round ratios with its order-statistic interval. Load average when it started: "
                  f"{', '.join(f'{x:.1f}' for x in load or [])} on {ctx.get('num_cpus', '?')} CPUs."]
    rows = [{"hostname": ctx.get("host_name", "?"), "cpu": f"{ctx.get('mhz_per_cpu', '?')} MHz",
             "cores": ctx.get("num_cpus", "?")}]
    return lines + provenance([(bpath, rows), (tpath, [])], src, commands(BT, src))


RB = "robustness"


def cpu_hard_cases():
    path, d = read_json(RB, "hard-cases.json")
    src = source(RB)
    suite = d.get("suite") or {}
    out = []
    for v in d.get("variants") or []:
        t = v.get("total") or {}
        g = v.get("gpu") or {}
        out.append([f"`{v.get('robust')}`", f"{v.get('triangle_test')} / {v.get('box_test')} / {v.get('origin_offset')}",
                    f"{int(num(t, 'leaks', path)):,}", f"{int(num(g, 'leaks', path)):,}" if g else "-",
                    f"{int(num(t, 'oracle_hit_disagree', path)):,}", f"{int(num(t, 'oracle_first_disagree', path)):,}",
                    f"{int(num(t, 'oracle_first_clear_disagree', path)):,}",
                    f"{int(num(t, 'nan_box_entries', path)) + int(num(t, 'nonfinite_hits', path)):,}",
                    f"{int(num(t, 'secondary_self_hits', path)):,}", f"{int(num(t, 'secondary_lost', path)):,}"])
    if not out:
        raise DataError(f"{rel(path)}: key 'variants' is empty")
    ms, gr = int(num(suite, "must_hit", path)), d.get("gpu_rays")
    header = ["variant", "triangle / box / offset", f"leaks (of {ms:,} must-hit rays)",
              f"GLSL leaks (of {gr:,} pixels)" if gr else "GLSL leaks",
              f"hit/miss != oracle (of {int(num(suite, 'oracle_decisive', path)):,})",
              f"first hit != oracle (of {int(num(suite, 'oracle_first_decisive', path)):,})",
              f"of those clear of edges (of {int(num(suite, 'oracle_first_clear', path)):,})",
              "NaN entries + non-finite hits", "secondary self-hits", "secondary rays lost inside closed meshes"]
    lines = table(header, out)
    lines += ["", f"{int(num(suite, 'cases', path))} cases, {int(num(suite, 'rays', path)):,} rays traced by the C++ "
                  f"mirror through a {d.get('builder')} tree in the {d.get('layout')} layout ({d.get('kernel')}); the "
                  f"exact oracle decides {int(num(suite, 'oracle_rays', path)):,} unit-scale rays, of which "
                  f"{int(num(suite, 'oracle_ties', path)):,} are exact ties and not scored. These are counts; they do not "
                  f"depend on the machine's load."]
    return lines + provenance([(path, [d])], src, commands(RB, src))


def cpu_robust_cost():
    fpath, findings = read_json(RB, "findings.json")
    cpath, rows = read_csv(RB, "results.csv")
    src = source(RB)
    rpath, _ = read_json(RB, "results.json")
    out = []
    for c in findings.get("comparisons") or []:
        if c.get("kind") != "axis" or c.get("axis") != "robust":
            continue
        lo, hi = c.get("ci_low"), c.get("ci_high")
        ratio = num(c, "ratio", fpath)
        cell = with_ci(ratio, num(c, "ci_low", fpath), num(c, "ci_high", fpath), f3) \
            if lo is not None and hi is not None else f3(ratio)
        out.append([str(c.get("scene")), f"`{c.get('a_label')}`", f"`{c.get('b_label')}`", cell,
                    str(c.get("verdict")), band_cell(c)])
    if not out:
        raise DataError(f"{rel(fpath)}: no comparison along the robust axis")
    r0 = rows[0]
    header = ["scene", "a", "b (reference)", "frame time a/b [95%]", "verdict", "noise band"]
    lines = table(header, out)
    lines += ["", f"{r0.get('width')}x{r0.get('height')} frames, {r0.get('builder')}, {r0.get('kernel')}, leaf "
                  f"{r0.get('leaf_size')}; every variant of a scene interleaved in one process. Every ratio, interval, "
                  f"band and verdict is findings.json's (docs/measurement.md); `bvhlab findings "
                  f"docs/results/{RB} --check` re-derives them from the per-round times in results.json."]
    return lines + provenance([(cpath, rows), (fpath, []), (rpath, [])], src, commands(RB, src))


KNOBS = "sbvh-knobs"


def cpu_sbvh_knobs():
    fpath, findings = read_json(KNOBS, "findings.json")
    cpath, rows = read_csv(KNOBS, "results.csv")
    src = source(KNOBS)
    comps = findings.get("comparisons")
    if not isinstance(comps, list):
        raise DataError(f"{rel(fpath)}: key 'comparisons' is not a list")
    rpath, _ = read_json(KNOBS, "results.json")
    out = []
    for c in comps:
        if c.get("kind") != "axis" or c.get("axis") != "builder":
            continue
        a = pick(rows, cpath, key=c.get("a"))
        b = pick(rows, cpath, key=c.get("b"))
        lo, hi = c.get("ci_low"), c.get("ci_high")
        ratio = num(c, "ratio", fpath)
        cell = with_ci(ratio, num(c, "ci_low", fpath), num(c, "ci_high", fpath), f3) \
            if lo is not None and hi is not None else f3(ratio)
        out.append([str(c.get("scene", "?")), f"`{c.get('a_label')}`", f"`{c.get('b_label')}`", cell,
                    str(c.get("verdict", "?")), band_cell(c),
                    f3(num(a, "sah_cost", cpath) / num(b, "sah_cost", cpath)),
                    f3(num(a, "ray_cost", cpath) / num(b, "ray_cost", cpath))])
    if not out:
        raise DataError(f"{rel(fpath)}: no comparison along the builder axis")
    r0 = rows[0]
    header = ["scene", "a", "b (reference)", "frame time a/b [95%]", "verdict", "noise band", "SAH a/b",
              "ray cost a/b"]
    lines = table(header, out)
    lines += ["", f"{r0.get('width')}x{r0.get('height')} frames, depth {r0.get('depth')}, {r0.get('kernel')} "
                  f"kernel, leaf {r0.get('leaf_size')}; frames of one scene interleaved in one process. Every "
                  f"ratio, interval, band and reference is findings.json's (docs/measurement.md explains them); "
                  f"generate.py re-derives each ratio and interval from the per-round times in results.json. "
                  f"SAH and ray cost are exact counts from results.csv."]
    return lines + provenance([(cpath, rows), (fpath, []), (rpath, [])], src, commands(KNOBS, src))


TL = "texture-lod"


def cpu_texture_lod():
    """Texture LOD by ray cones, without AA and with SMAA high: image error against the 16x
    supersampled reference (no LOD) and the frame time over the same AA mode without LOD (paired)."""
    fpath, findings = read_json(TL, "findings.json")
    cpath, rows = read_csv(TL, "results.csv")
    src = source(TL)
    rpath, _ = read_json(TL, "results.json")
    runs = [r for r in rows if r.get("status") == "ok" and r.get("reference_only") not in ("true", "1", "True")]
    # Paired frame-time ratios along the texture_lod axis, keyed by (a's key): mode over the same run without LOD.
    cost = {}
    for c in findings.get("comparisons") or []:
        if c.get("kind") != "axis" or c.get("axis") != "texture_lod":
            continue
        labels = (c.get("a_label"), c.get("b_label"))
        if "none" not in labels or labels[0] == labels[1]:
            continue
        ratio, lo, hi = num(c, "ratio", fpath), num(c, "ci_low", fpath), num(c, "ci_high", fpath)
        key = c.get("a")
        if labels[0] == "none":  # b over a: invert to "with LOD over without"
            ratio, lo, hi, key = 1.0 / ratio, 1.0 / hi, 1.0 / lo, c.get("b")
        cost[key] = (ratio, lo, hi, str(c.get("verdict")))
    scenes = []
    for r in runs:
        if r.get("scene") not in scenes:
            scenes.append(r.get("scene"))
    out = []
    for s in scenes:
        mine = [r for r in runs if r.get("scene") == s]
        base = [r for r in mine if r.get("aa") == "none" and r.get("texture_lod") == "none"]
        if len(base) != 1:
            raise DataError(f"{rel(cpath)}: {len(base)} runs of {s} without AA and without LOD, expected 1")
        e0 = num(base[0], "image_mae", cpath)
        # SMAA's edge detection: luma (the paper's) re-blurs the texture edges cones filtered; geometry
        # edges leave them alone. Runs of an older result directory have luma only.
        edges = [m for m in ("luma", "geometry")
                 if any(x.get("aa") == "smaa-high" and (x.get("smaa_edges") or "luma") == m for x in mine)]
        for aa, edge in [("none", None)] + [("smaa-high", m) for m in edges]:
            for lod in ("none", "cones", "cones-aniso"):
                r = [x for x in mine if x.get("aa") == aa and x.get("texture_lod") == lod and
                     (edge is None or (x.get("smaa_edges") or "luma") == edge)]
                if len(r) != 1:
                    raise DataError(f"{rel(cpath)}: {len(r)} runs of {s} with aa={aa}, smaa_edges={edge}, "
                                    f"texture_lod={lod}, expected 1")
                r = r[0]
                e = num(r, "image_mae", cpath)
                ms = with_ci(num(r, "frame_ms", cpath), num(r, "frame_ms_ci_low", cpath),
                             num(r, "frame_ms_ci_high", cpath), lambda x: f"{x:.1f}")
                if lod == "none":
                    c = "1"
                    verdict = "–"
                else:
                    if r.get("key") not in cost:
                        raise DataError(f"{rel(fpath)}: no paired texture_lod comparison for run {r.get('key')}")
                    ratio, lo, hi, verdict = cost[r.get("key")]
                    c = with_ci(ratio, lo, hi, f3)
                out.append([str(s), f"`{aa}`", "–" if edge is None else f"`{edge}`", f"`{lod}`", f"{e:.2f}",
                            f3(e / e0), ms, c, verdict])
    header = ["scene", "aa", "smaa edges", "texture_lod", "error", "error / (none, none)", "frame ms [95%]",
              "time / same aa without LOD [95%]", "verdict"]
    lines = table(header, out)
    r0 = runs[0]
    lines += ["", f"Error: mean absolute difference over 8-bit RGB against the scene's 16x supersampled render "
                  f"without texture LOD. {r0.get('width')}x{r0.get('height')} frames, {r0.get('builder')}, "
                  f"{r0.get('kernel')}, depth {r0.get('depth')}; every run of a scene interleaved in one process. "
                  f"Ratios, intervals and verdicts are findings.json's paired comparisons (docs/measurement.md); "
                  f"`bvhlab findings docs/results/{TL} --check` re-derives them from the per-round times in "
                  f"results.json."]
    return lines + provenance([(cpath, rows), (fpath, []), (rpath, [])], src, commands(TL, src))


# ---- update strategies over the bench animations (experiments/configs/dynamic.toml) -----------------

DYN = "dynamic"


def cpu_dynamic():
    """Every update strategy over the bench animations, each clip traced frame by frame
    (`bvhlab trace --update`): the clip's total time with its bootstrap interval and its parts, and the
    ray cost of the first and last traced frame, from each run's record (runs/KEY.json)."""
    cpath, rows = read_csv(DYN, "results.csv")
    src = source(DYN)
    runs = [r for r in rows if r.get("status") == "ok"]
    if len(runs) != len(rows):
        raise DataError(f"{rel(cpath)}: {len(rows) - len(runs)} runs did not finish")
    # Clip verdicts (findings.json): each strategy against the baseline strategy of its builder, on total
    # clip time paired over frames, called beyond the clip group's A/A band.
    fpath, findings = read_json(DYN, "findings.json")
    verdicts = {}
    for c in findings.get("comparisons", []):
        if c.get("axis") == "update" and c.get("interval_over") == "clip frames":
            verdicts[c.get("a")] = c
    # A mixed strategy's update time and mean ray cost over its builder's rebuild clip, with intervals
    # (findings.json clip_mixed: paired over frames).
    parts = {}
    for entry in findings.get("clip_mixed", []):
        for st in entry.get("strategies", []):
            parts[st.get("key")] = (st.get("vs_rebuild") or {})
    bands = {}
    for n in findings.get("noise", []):
        if n.get("control") == "clip":
            bands[n.get("scene")] = n
    out = []
    rays = {}  # rays a frame, per scene
    scenes = list(dict.fromkeys(r.get("scene") for r in runs))
    for s in scenes:
        mine = []
        for r in runs:
            if r.get("scene") != s:
                continue
            rpath, rec = read_json(DYN, os.path.join("runs", r["key"] + ".json"))
            result = rec.get("result") or {}
            clip, frames = result.get("clip"), result.get("frames")
            if not isinstance(clip, dict) or not isinstance(frames, list) or not frames:
                raise DataError(f"{rel(rpath)}: no clip and frames in the run's result")
            mine.append((r, clip, frames, rpath))
            rays[s] = frames[0].get("rays")
        mine.sort(key=lambda m: num(m[1], "total_ms", m[3]))
        # Per-frame rebuild's update time and mean ray cost, per builder: what the mixed strategies trade against.
        rebuilt = {}
        for r, clip, frames, rpath in mine:
            if r.get("update") == "rebuild":
                rebuilt[r.get("builder")] = (num(clip, "update_ms_total", rpath),
                                             sum(num(f, "ray_cost", rpath) for f in frames) / len(frames))
        for r, clip, frames, rpath in mine:
            first, last = num(frames[0], "ray_cost", rpath), num(frames[-1], "ray_cost", rpath)
            peak = max(num(f, "ray_cost", rpath) for f in frames)
            mean = sum(num(f, "ray_cost", rpath) for f in frames) / len(frames)
            base = rebuilt.get(r.get("builder"))
            mixed = parts.get(r.get("key")) or {}
            if isinstance(mixed.get("update"), dict) and isinstance(mixed.get("ray_cost"), dict):
                u, c = mixed["update"], mixed["ray_cost"]
                versus = (with_ci(num(u, "ratio", fpath), num(u, "ci_low", fpath), num(u, "ci_high", fpath),
                                  lambda x: f"{x:.2f}") + " / " +
                          with_ci(num(c, "ratio", fpath), num(c, "ci_low", fpath), num(c, "ci_high", fpath),
                                  lambda x: f"{x:.2f}"))
            elif r.get("update") == "rebuild" or base is None or base[0] <= 0 or base[1] <= 0:
                versus = "–"
            else:
                versus = f"{num(clip, 'update_ms_total', rpath) / base[0]:.2f} / {mean / base[1]:.2f}"
            c = verdicts.get(r.get("key"))
            if c is None or c.get("ci_low") is None:
                vs = "baseline" if r.get("update") == findings.get("baselines", {}).get("update") else "–"
            else:
                vs = (with_ci(num(c, "ratio", fpath), num(c, "ci_low", fpath), num(c, "ci_high", fpath),
                              lambda x: f"{x:.2f}") + f" {c.get('verdict')}")
            out.append([str(s), f"`{r.get('update')}`", str(r.get("builder")),
                        with_ci(num(clip, "total_ms", rpath), num(clip, "total_ms_ci_low", rpath),
                                num(clip, "total_ms_ci_high", rpath), lambda x: f"{x:.0f}"), vs,
                        f"{num(clip, 'update_ms_total', rpath):.0f}", f"{num(clip, 'upload_ms_total', rpath):.0f}",
                        f"{num(clip, 'trace_ms_total', rpath):.0f}",
                        f"{clip.get('rebuilds')} of {clip.get('frames')} (step {clip.get('step')})",
                        f"{first:.1f}", f"{last:.1f}", f"{last / first:.2f}", f"{peak:.1f}", f"{mean:.1f}", versus])
    header = ["scene", "update", "builder", "clip ms [95%]", "vs rebuild [95%], verdict", "update ms", "upload ms",
              "trace ms", "rebuilds of traced frames", "ray cost, frame 0", "ray cost, last frame", "last / frame 0",
              "peak ray cost", "mean ray cost", "update / mean ray cost vs rebuild"]
    lines = table(header, out)
    band_text = "; ".join(f"{sc} {num(n, 'ratio', fpath):.3f} [{num(n, 'ci_low', fpath):.3f}, {num(n, 'ci_high', fpath):.3f}]"
                          for sc, n in bands.items())
    mixed = findings.get("clip_mixed_summary") or {}
    lines += ["", "Verdicts: each clip's total over the same builder's `rebuild` clip, paired over the traced frames "
              "(bootstrap over frames; experiments/findings_clip.hpp), called `faster`/`slower` only when the "
              "interval clears the band of the scene's A/A control (its first clip traced twice in the same "
              f"lockstep) after the Benjamini-Hochberg adjustment. A/A controls: {band_text or 'none'}. "
              "A mixed strategy (refit+rebuild:K, refit+rebuild:sah>R, refit+rotate) beats both pure refit and "
              "pure rebuild (both intervals below 1) on: "
              f"{', '.join(mixed.get('scenes_beats_both', [])) or 'no scene'}; beyond the A/A band on: "
              f"{', '.join(mixed.get('scenes_beats_both_beyond_band', [])) or 'no scene'} "
              "(findings.json `clip_mixed`)."]
    r0 = runs[0]
    lines += ["", "Update / mean ray cost vs rebuild: the clip's update time and its mean ray cost over the traced "
              "frames, each over those of the same builder's `rebuild` clip (what a mixed strategy saves in updates "
              "and pays in rays); for the mixed strategies with their 95% intervals, paired over frames as the "
              "clip totals are (findings.json `clip_mixed`, `vs_rebuild.update` and `.ray_cost`). Frames are traced "
              "every `step` frames of the scene's clip, from frame 0."]
    on_gpu = sorted({r.get("builder") for r in rows if r.get("update_on") == "gpu"})
    gpu_note = (f" Rows of {', '.join(f'`{b}`' for b in on_gpu)} updated on the GPU (`update_on` gpu): their update is "
                "the build and pack by compute passes and their upload the frame's triangles alone; on llvmpipe "
                "those passes run on the CPU." if on_gpu else "")
    lines += ["", "Each row is one clip traced frame by frame (docs/animation.md): the traced frames' update, upload "
              "(pack + GL re-upload) and trace medians summed; the interval is the bootstrap over each frame's "
              "samples." + gpu_note + " The clips of a scene ran in lockstep in one process (frame f of every strategy, in a shuffled "
              f"order, before frame f + 1 of any). {r0.get('workload')} rays "
              f"({', '.join(f'{sc} {n}' for sc, n in rays.items())} a frame), {r0.get('kernel')} kernel, leaf size {r0.get('leaf_size')}; "
              "ray cost = node visits + triangle tests per ray, from the kernel's counters. Per-frame values: "
              f"`{rel(result_path(DYN, 'runs'))}/KEY.json` (the run's `trace --json` object)."]
    return lines + provenance([(cpath, rows)], src, commands(DYN, src))


# ---- every layout with every kernel, on llvmpipe (experiments/configs/layouts-kernels.toml) ---------------

LK = "layouts-kernels"


def cpu_layout_kernels():
    """Every (layout, kernel) on the bunny's primary and diffuse rays, one trace group: each kernel's time
    against its baseline (the layout's first kernel against v1's stack-ordered, every other kernel
    against its layout's first) as findings.json calls it, beside the diffuse rays' exact counts."""
    fpath, findings = read_json(LK, "findings.json")
    cpath, rows = read_csv(LK, "results.csv")
    src = source(LK)
    read_json(LK, "results.json")  # the per-round times the intervals come from must be committed too
    runs = [r for r in rows if r.get("status") == "ok"]
    # findings.json: the comparison whose `a` is this run (kernel axis within a layout, layout axis for a
    # layout's baseline kernel against v1).
    against = {}
    for c in findings.get("comparisons") or []:
        if c.get("kind") == "axis" and c.get("axis") in ("layout", "kernel") and c.get("metric") == "frame_ms":
            against[c.get("a")] = c
    base = findings.get("baselines") or {}
    order = []
    for r in runs:
        if (r.get("layout"), r.get("kernel")) not in order:
            order.append((r.get("layout"), r.get("kernel")))
    out = []
    for lay, kern in order:
        row = [f"`{lay}`", f"`{kern}`"]
        ref = None
        for workload in ("primary", "diffuse"):
            r = pick(runs, cpath, layout=lay, kernel=kern, workload=workload)
            c = against.get(r.get("key"))
            if c is None:
                if lay != base.get("layout") or kern != base.get("kernel"):
                    raise DataError(f"{rel(fpath)}: no comparison for run {r.get('key')} ({lay}, {kern}, {workload})")
                row.append(f"**{sig(num(r, 'frame_ms', cpath))} ms**")
                ref = "baseline"
                continue
            other = c.get("b_values") or {}
            ref = f"`{other.get('kernel')}`" + (f" (`{other.get('layout')}`)" if c.get("axis") == "layout" else "")
            row.append(with_ci(num(c, "ratio", fpath), num(c, "ci_low", fpath), num(c, "ci_high", fpath), f3)
                       + f" {c.get('verdict')}")
        row.insert(2, ref)
        d = pick(runs, cpath, layout=lay, kernel=kern, workload="diffuse")
        row += [f"{num(d, 'node_visits_per_ray', cpath):.1f}", f"{num(d, 'box_tests_per_ray', cpath):.1f}",
                f"{num(d, 'triangle_tests_per_ray', cpath):.1f}",
                " + ".join(f"{num(d, k, cpath):.0f}" for k in
                           ("node_bytes_per_ray", "triangle_bytes_per_ray", "stack_bytes_per_ray"))]
        out.append(row)
    header = ["layout", "kernel", "against", "primary: time ratio [95% CI], verdict",
              "diffuse: time ratio [95% CI], verdict", "diffuse: node visits / ray", "box tests / ray",
              "triangle tests / ray", "bytes / ray (node + triangle + stack)"]
    lines = table(header, out)
    r0 = runs[0]
    bands = sorted({band_cell(c) for c in against.values()})
    counts = ", ".join(f"{pick(runs, cpath, layout=base.get('layout'), kernel=base.get('kernel'), workload=w).get('rays')} {w}"
                       for w in ("primary", "diffuse"))
    lines += ["", f"One trace group: every run traced the same {r0.get('scene')} rays ({counts}) in every round, "
              f"rounds interleaved; {r0.get('builder')} tree, leaf size "
              f"{r0.get('leaf_size')}, robust `{r0.get('robust')}`. Each ratio is the kernel's time over the run "
              "named in `against` (a layout's first kernel against v1's `stack-ordered`, its other kernels against "
              "its first), the median of the paired per-round ratios with its 95% interval, and findings.json's "
              "verdict: `faster`/`slower` only where the interval clears the group's A/A noise band "
              f"({', '.join(bands)}) after the Benjamini-Hochberg adjustment (docs/measurement.md). v1's "
              "`stack-ordered` row gives its median time. The counts are exact (the kernels' counters, equal to "
              "their C++ mirrors'); bytes per ray are what the kernel fetches, the figure a GPU's memory pays "
              "for, where llvmpipe's time follows the box tests and the loop passes (\"Why the loop shape "
              "matters on llvmpipe\" above)."]
    return lines + provenance([(cpath, rows)], src, commands(LK, src))
