"""The tables of the committed GPU run (docs/results/gpu-h200), for docs/results/generate.py."""

from tables_io import num, pick, read_csv, read_json, source, commands, provenance, table, sig, f3, with_ci

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
