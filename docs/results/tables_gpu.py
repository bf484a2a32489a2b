"""The tables of the committed GPU run (docs/results/gpu-h200), for docs/results/generate.py."""

import os

from tables_io import (num, pick, read_csv, read_json, read_json_lines, rel, source, commands, provenance, table,
                       sig, f3, with_ci)

# ---- the GPU run (docs/results/gpu-h200) ---------------------------------------------------------

GPU = "gpu-h200"
GPU_SCENES = [("bunny", "primary"), ("bunny", "diffuse"), ("interior", "primary"), ("interior", "diffuse"),
              ("ship", "primary"), ("ship", "diffuse")]
BUILDERS = ["median", "sah-sweep", "sah-binned", "sbvh", "lbvh", "ploc", "ploc[top-down=4]", "embree",
            "embree-low"]
NO_PAIRED = ("Ratios are ratios of the two runs' medians: the per-round times were not committed with these "
             "rows, so no paired interval or verdict can be derived from them (docs/gpu.md).")


def half_width_pct(r, path):
    x = num(r, "frame_ms", path)
    return 100 * (num(r, "frame_ms_ci_high", path) - num(r, "frame_ms_ci_low", path)) / 2 / x


def gpu_render():
    path, r = read_json(GPU, "render-report-720p.json")
    src = source(GPU)
    lines = table(["what", "value"], [
        ["frame time, ms (median [95% interval])",
         with_ci(num(r, "frame_ms", path), num(r, "frame_ms_ci_low", path), num(r, "frame_ms_ci_high", path))],
        ["timed frames", str(int(num(r, "frames", path)))],
        ["image", f"{int(num(r, 'width', path))}x{int(num(r, 'height', path))}, depth {r.get('depth')}"],
        ["tree", f"{r.get('builder')}, {r.get('layout')}, {r.get('kernel')}, leaf {r.get('leaf_size')}"],
        ["node visits per mesh ray", f"{num(r, 'node_visits_per_ray', path):.4f}"],
        ["mesh rays", str(int(num(r, "mesh_rays", path)))],
    ])
    return lines + provenance([(path, [{**r, "git_commit": src.get("git_commit", "")}])], src, commands(GPU, src))


def gpu_sample_length():
    src = source(GPU)
    data = [(label, *read_csv(GPU, f"sample-length-{ms}.csv"))
            for label, ms in [("one dispatch", "0ms"), ("at least 2 ms", "2ms"), ("at least 10 ms", "10ms")]]
    cells = [("bunny", "primary"), ("bunny", "diffuse"), ("interior", "primary"), ("ship", "primary")]
    out = []
    for label, path, rows in data:
        row = [label]
        for scene, workload in cells:
            r = pick(rows, path, builder="sah-binned", scene=scene, workload=workload)
            row.append(with_ci(num(r, "frame_ms", path), num(r, "frame_ms_ci_low", path),
                               num(r, "frame_ms_ci_high", path)))
        widths = sorted(half_width_pct(r, path) for r in rows)
        row.append(f"±{widths[-1]:.1f}% (median ±{widths[len(widths) // 2]:.2f}%)")
        disp = sorted(int(num(r, "dispatches_per_sample", path)) for r in rows)
        row.append(str(disp[0]) if disp[0] == disp[-1] else f"{disp[0]}-{disp[-1]}")
        out.append(row)
    runs = sorted({len(rs) for _, _, rs in data})
    header = ["timed sample"] + [f"sah-binned {s} {w}, ms" for s, w in cells] + \
             [f"widest run interval ({'/'.join(map(str, runs))} runs)", "dispatches per sample"]
    return table(header, out) + provenance([(p, rs) for _, p, rs in data], src, commands(GPU, src))


def gpu_builders_trace():
    path, rows = read_csv(GPU, "builders-gpu.csv")
    src = source(GPU)
    out = []
    for b in BUILDERS:
        row = [f"`{b}`"]
        for scene, workload in GPU_SCENES:
            r = pick(rows, path, builder=b, scene=scene, workload=workload)
            ref = pick(rows, path, builder="sah-binned", scene=scene, workload=workload)
            if b == "sah-binned":
                row.append(f"**{sig(num(r, 'frame_ms', path))} ms**")
            else:
                t = num(r, "frame_ms", path) / num(ref, "frame_ms", path)
                c = num(r, "ray_cost", path) / num(ref, "ray_cost", path)
                row.append(f"{f3(t)} ({c:.2f})")
        out.append(row)
    embree = ["Embree `rtcIntersect1`, 16 threads"]
    for scene, workload in GPU_SCENES:
        ref = pick(rows, path, builder="sah-binned", scene=scene, workload=workload)
        embree.append(f"{sig(num(ref, 'embree_ms', path))} ms")
    out.append(embree)
    traced = [r for r in rows if r.get("workload")]
    widths = sorted(half_width_pct(r, path) for r in traced)
    header = ["builder"] + [f"{s} {w}" for s, w in GPU_SCENES]
    lines = table(header, out)
    lines += ["", f"Each cell: the builder's median time x sah-binned's (ray cost x sah-binned's in brackets); "
                  f"sah-binned's row gives its median. Every run's own 95% interval is within "
                  f"±{widths[0]:.2f}% to ±{widths[-1]:.2f}% of its median. {NO_PAIRED}"]
    return lines + provenance([(path, rows)], src, commands(GPU, src))


def gpu_builders_frames():
    path, rows = read_csv(GPU, "builders-gpu.csv")
    src = source(GPU)
    out = []
    for b in BUILDERS:
        row = [f"`{b}`"]
        for scene in ["interior", "report"]:
            r = pick(rows, path, builder=b, scene=scene, workload="")
            ref = pick(rows, path, builder="sah-binned", scene=scene, workload="")
            row.append(with_ci(num(r, "frame_ms", path), num(r, "frame_ms_ci_low", path),
                               num(r, "frame_ms_ci_high", path)))
            t = num(r, "frame_ms", path) / num(ref, "frame_ms", path)
            c = num(r, "ray_cost", path) / num(ref, "ray_cost", path)
            row.append(f"{f3(t)} ({c:.2f})")
        out.append(row)
    header = ["builder", "interior, ms", "x sah-binned (ray cost)", "report scene, ms", "x sah-binned (ray cost)"]
    r0 = rows[[r.get("workload") for r in rows].index("")]
    lines = table(header, out)
    lines += ["", f"Frames of {r0['width']}x{r0['height']}, every effect the scene calls for. {NO_PAIRED}"]
    return lines + provenance([(path, rows)], src, commands(GPU, src))


def gpu_kernels():
    path, rows = read_csv(GPU, "kernels-gpu.csv")
    src = source(GPU)
    out = []
    for k in ["stack-unordered", "stack-ordered", "stackless"]:
        row = [f"`{k}`"]
        for scene, workload in GPU_SCENES:
            r = pick(rows, path, kernel=k, scene=scene, workload=workload)
            row.append(f"{sig(num(r, 'frame_ms', path))} ({num(r, 'node_visits_per_ray', path):.1f})")
        r = pick(rows, path, kernel=k, scene="report", workload="")
        row.append(with_ci(num(r, "frame_ms", path), num(r, "frame_ms_ci_low", path),
                           num(r, "frame_ms_ci_high", path)))
        out.append(row)
    header = ["kernel"] + [f"{s} {w}, ms (visits/ray)" for s, w in GPU_SCENES] + ["report scene frame, ms"]
    lines = table(header, out)
    rays = sorted({int(num(r, "rays", path)) for r in rows if r.get("workload")})
    lines += ["", f"sah-binned, leaf 4, v1 layout; {'/'.join(f'{n:,}' for n in rays)} rays per workload. Medians; "
                  "the frame column with its 95% interval. Node visits per ray are exact counts."]
    return lines + provenance([(path, rows)], src, commands(GPU, src))


def gpu_layouts():
    path, rows = read_csv(GPU, "layouts-gpu.csv")
    src = source(GPU)
    cells = [("bunny", "primary"), ("bunny", "diffuse"), ("stadium", "primary"), ("stadium", "diffuse"),
             ("interior", "primary"), ("interior", "diffuse")]
    out = []
    for lay in ["v1", "bvh2-cb", "bvh4", "bvh8", "cwbvh"]:
        row = [f"`{lay}`"]
        for scene, workload in cells:
            r = pick(rows, path, layout=lay, scene=scene, workload=workload)
            ref = pick(rows, path, layout="v1", scene=scene, workload=workload)
            if lay == "v1":
                row.append(f"**{sig(num(r, 'frame_ms', path))} ms** ({num(r, 'node_visits_per_ray', path):.1f})")
            else:
                t = num(r, "frame_ms", path) / num(ref, "frame_ms", path)
                v = num(r, "node_visits_per_ray", path) / num(ref, "node_visits_per_ray", path)
                row.append(f"{f3(t)} ({v:.2f})")
        r = pick(rows, path, layout=lay, scene="bunny", workload="primary")
        row.append(f"{num(r, 'bytes_per_triangle', path):.1f}")
        out.append(row)
    header = ["layout"] + [f"{s} {w}" for s, w in cells] + ["bytes/triangle (bunny)"]
    lines = table(header, out)
    lines += ["", "Each cell: the layout's median time with its default kernel x v1's (node visits per ray x v1's "
                  "in brackets); v1's row gives its median and visits. sah-binned, leaf 4. " + NO_PAIRED]
    return lines + provenance([(path, rows)], src, commands(GPU, src))


# ---- GPU builds beside the CPU builders (experiments/remote/gpu-run.sh, step 1b) ---------------------

def gpu_build_time(dirname):
    """The GPU builders' GL-timed builds beside the CPU builders' wall-clock builds on the same host, from
    DIR/gpu-builders.jsonl (one `bvhlab build --json` object a line). Register it in generate.TABLES with
    the result directory of a committed GPU run."""
    path, builds = read_json_lines(dirname, "gpu-builders.jsonl")
    src = source(dirname)
    groups = {}
    for n, b in enumerate(builds, 1):
        mesh = os.path.splitext(os.path.basename(str(b.get("mesh", "?"))))[0]
        # A GPU build packed into another layout than v1 (`--layout cwbvh`) is its own row: the pack is
        # part of its GL-timed build.
        pack = b.get("gpu_pack")
        builder = f"`{b.get('builder', '?')}`" + (f" into {pack}" if pack not in (None, "v1") else "")
        groups.setdefault((mesh, builder), []).append((n, b))
    cells = {}
    for (mesh, builder), bs in groups.items():
        where = f"{rel(path)}: object {bs[0][0]}"
        sah = num(bs[0][1], "sah_cost", where)
        g = bs[0][1].get("gpu_build_ms")
        if isinstance(g, dict):  # GL-timed: the median and interval over the object's builds
            ms, lo, hi = num(g, "median", where), g.get("low"), g.get("high")
            time = with_ci(ms, lo, hi) if lo is not None and hi is not None else f"{sig(ms)} (no interval)"
            how = f"GPU, {int(num(g, 'builds', where))} GL-timed builds"
        else:  # a CPU builder: one wall-clock build per line
            times = sorted(num(b, "build_ms", f"{rel(path)}: object {k}") for k, b in bs)
            ms = times[len(times) // 2]
            time = f"{sig(ms)} [{sig(times[0])}, {sig(times[-1])}]"
            how = f"CPU, median [min, max] of {len(times)} builds"
        cells[(mesh, builder)] = (ms, sah, time, how, g is not None and isinstance(g, dict))
    out = []
    for (mesh, builder), (ms, sah, time, how, gpu) in sorted(cells.items(), key=lambda kv: (kv[0][0], not kv[1][4], kv[1][0])):
        ref = cells.get((mesh, "`sah-binned`"))
        vs_sah = f"{sah / ref[1]:.3f}" if ref else "–"
        speedup = "–"
        if gpu:
            # The fastest CPU build of this mesh whose SAH is the same or better (a relative 1e-9 covers the
            # rounding of equal trees' costs summed in another order).
            cpu = [c[0] for (m, _), c in cells.items() if m == mesh and not c[4] and c[1] <= sah * (1 + 1e-9)]
            speedup = f"{sig(min(cpu) / ms)}x" if cpu else "no CPU builder as good"
        out.append([mesh, builder, how, time, f"{sah:.2f}", vs_sah, speedup])
    header = ["mesh", "builder", "timed as", "build ms", "SAH cost", "SAH / sah-binned's",
              "fastest CPU build of the same or better SAH / this build"]
    lines = table(header, out)
    lines += ["", "GPU builders: the median of `build --json --gpu-builds` GL-timed builds after an untimed warm-up, "
                  "with its 95% order-statistic interval; the times cover the passes from the uploaded boxes to the "
                  "packed streams (`gpu_phases_ms`; v1 unless the row names another layout), not the upload or the "
                  "download. CPU builders: `build --json`'s "
                  "wall-clock `build_ms` of one build on every host core, repeated."]
    renderers = sorted({b.get("gpu_renderer") for b in builds if b.get("gpu_renderer")})
    rows = [{"git_commit": src.get("git_commit", ""), "gl_renderer": r} for r in renderers]
    return lines + provenance([(path, rows)], src, commands(dirname, src))
