#!/usr/bin/env python3
"""Writes the result tables of README.md and docs/*.md from the committed result directories.

Every table in the documentation that holds a measured figure is generated here from a directory under
docs/results/ and carries, below it, the command, commit, machine and GL renderer that produced its
data. A table lives in a Markdown file between two markers:

    <!-- generated:NAME -->
    ... (written by this script) ...
    <!-- end generated -->

Usage (Python 3's standard library only):
    python3 docs/results/generate.py            # rewrite every table in place
    python3 docs/results/generate.py --check    # exit 1 naming each table that is stale

A result directory holds what its run wrote (results.csv, findings.json, JSON lines of `bvhlab build`)
and a source.json with the command that made it and a note on the machine's state; the commit, machine
and renderer are read from the rows themselves where the rows record them (results.csv's git_commit,
hostname, cpu, cores and gl_renderer columns), and from source.json otherwise.
"""

import argparse
import csv
import json
import math
import os
import re
import sys
import textwrap

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
BEGIN = re.compile(r"^<!-- generated:([a-z0-9-]+) -->$")
END = "<!-- end generated -->"


class DataError(Exception):
    """A result file is missing or does not hold what a table needs."""


# ---- reading result directories -------------------------------------------------------------------

def result_path(*parts):
    return os.path.join(HERE, *parts)


def rel(path):
    return os.path.relpath(path, ROOT)


def read_csv(dirname, filename):
    path = result_path(dirname, filename)
    try:
        with open(path, newline="") as f:
            rows = list(csv.DictReader(f))
    except OSError as e:
        raise DataError(f"{rel(path)}: {e.strerror}") from None
    if not rows:
        raise DataError(f"{rel(path)}: no rows")
    return path, rows


def read_json(dirname, filename):
    path = result_path(dirname, filename)
    try:
        with open(path) as f:
            return path, json.load(f)
    except OSError as e:
        raise DataError(f"{rel(path)}: {e.strerror}") from None
    except json.JSONDecodeError as e:
        raise DataError(f"{rel(path)}: line {e.lineno}: {e.msg}") from None


def read_json_lines(dirname, filename):
    path = result_path(dirname, filename)
    out = []
    try:
        with open(path) as f:
            for n, line in enumerate(f, 1):
                if line.strip():
                    try:
                        out.append(json.loads(line))
                    except json.JSONDecodeError as e:
                        raise DataError(f"{rel(path)}: line {n}: {e.msg}") from None
    except OSError as e:
        raise DataError(f"{rel(path)}: {e.strerror}") from None
    return path, out


def source(dirname):
    """source.json of a result directory: {"commands": {file: command}, "note": ..., and, for data
    that does not record them itself, "git_commit", "machine", "gl_renderer"}."""
    return read_json(dirname, "source.json")[1]


def num(row, key, path=""):
    """A finite number from a row, or a DataError naming the file and the key."""
    value = row.get(key)
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise DataError(f"{rel(path)}: key '{key}' is {value!r}, not a number") from None
    if not math.isfinite(x):
        raise DataError(f"{rel(path)}: key '{key}' is not finite")
    return x


def pick(rows, path, **match):
    """The one row whose columns equal `match`."""
    found = [r for r in rows if all(r.get(k) == v for k, v in match.items())]
    if len(found) != 1:
        raise DataError(f"{rel(path)}: {len(found)} rows match {match}, expected 1")
    return found[0]


# ---- formatting ----------------------------------------------------------------------------------

def f3(x):
    return f"{x:.3f}"


def sig(x, digits=3):
    """x to `digits` significant figures, without exponent notation."""
    if x == 0:
        return "0"
    decimals = max(0, digits - 1 - int(math.floor(math.log10(abs(x)))))
    return f"{x:.{decimals}f}"


def with_ci(x, lo, hi, fmt=sig):
    return f"{fmt(x)} [{fmt(lo)}, {fmt(hi)}]"


def table(header, rows):
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(r) + " |" for r in rows]
    return lines


def provenance(paths_rows, src, command_of):
    """The lines below a table: data files, command, commit, machine, renderer, note."""
    commits, machines, renderers = set(), set(), set()
    for _, rows in paths_rows:
        for r in rows:
            c = r.get("git_commit")
            if c:
                commits.add(c[:12])
            if r.get("hostname"):
                machines.add(f"{r['hostname']}, {r.get('cpu', '?')}, {r.get('cores', '?')} cores")
            g = r.get("gl_renderer") or r.get("renderer")
            if g:
                renderers.add(g)
    commits = commits or {src.get("git_commit", "not recorded")[:12]}
    machines = machines or {src.get("machine", "not recorded")}
    renderers = renderers or {src.get("gl_renderer", "not recorded")}
    files = ", ".join(f"`{rel(p)}`" for p, _ in paths_rows)
    cmds = "; ".join(f"`{c}`" for c in dict.fromkeys(command_of(p) for p, _ in paths_rows))
    lines = ["", f"Data: {files}. Command: {cmds}. Commit: {', '.join(sorted(commits))}. "
                 f"Machine: {'; '.join(sorted(machines))}. GL renderer: {'; '.join(sorted(renderers))}."]
    if src.get("note"):
        lines.append(f"{src['note']}")
    return lines


def commands(dirname, src):
    cmds = src.get("commands", {})

    def command_of(path):
        name = os.path.basename(path)
        if name not in cmds:
            raise DataError(f"{rel(result_path(dirname, 'source.json'))}: no command for '{name}'")
        return cmds[name]
    return command_of


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
    out = []
    for c in findings.get("comparisons") or []:
        if c.get("kind") != "axis" or c.get("axis") != "robust":
            continue
        lo, hi = c.get("ci_low"), c.get("ci_high")
        ratio = num(c, "ratio", fpath)
        cell = with_ci(ratio, num(c, "ci_low", fpath), num(c, "ci_high", fpath), f3) \
            if lo is not None and hi is not None else f3(ratio)
        band = float(c.get("band") or 0)
        out.append([str(c.get("scene")), f"`{c.get('a_label')}`", f"`{c.get('b_label')}`", cell,
                    str(c.get("verdict")), f"±{100 * (math.exp(band) - 1):.1f}%"])
    if not out:
        raise DataError(f"{rel(fpath)}: no comparison along the robust axis")
    r0 = rows[0]
    header = ["scene", "a", "b (reference)", "frame time a/b [95%]", "verdict", "noise band"]
    lines = table(header, out)
    lines += ["", f"{r0.get('width')}x{r0.get('height')} frames, {r0.get('builder')}, {r0.get('kernel')}, leaf "
                  f"{r0.get('leaf_size')}; every variant of a scene interleaved in one process. Every ratio, interval, "
                  f"band and verdict is findings.json's (docs/measurement.md)."]
    return lines + provenance([(cpath, rows), (fpath, [])], src, commands(RB, src))


KNOBS = "sbvh-knobs"


def cpu_sbvh_knobs():
    fpath, findings = read_json(KNOBS, "findings.json")
    cpath, rows = read_csv(KNOBS, "results.csv")
    src = source(KNOBS)
    comps = findings.get("comparisons")
    if not isinstance(comps, list):
        raise DataError(f"{rel(fpath)}: key 'comparisons' is not a list")
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
        band = float(c.get("band") or 0)
        out.append([str(c.get("scene", "?")), f"`{c.get('a_label')}`", f"`{c.get('b_label')}`", cell,
                    str(c.get("verdict", "?")), f"±{100 * (math.exp(band) - 1):.1f}%",
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
                  f"SAH and ray cost are exact counts from results.csv."]
    return lines + provenance([(cpath, rows), (fpath, [])], src, commands(KNOBS, src))


TABLES = {
    "gpu-render": gpu_render,
    "gpu-sample-length": gpu_sample_length,
    "gpu-builders-trace": gpu_builders_trace,
    "gpu-builders-frames": gpu_builders_frames,
    "gpu-kernels": gpu_kernels,
    "gpu-layouts": gpu_layouts,
    "cpu-build-quality": cpu_build_quality,
    "cpu-layout-bytes": cpu_layout_bytes,
    "cpu-build-time": cpu_build_time,
    "cpu-hard-cases": cpu_hard_cases,
    "cpu-robust-cost": cpu_robust_cost,
    "cpu-sbvh-knobs": cpu_sbvh_knobs,
}


# ---- the Markdown files ------------------------------------------------------------------------

def wrap(lines):
    """Prose lines wrapped at 110 characters; table rows kept whole."""
    out = []
    for line in lines:
        if line.startswith("|") or len(line) <= 110:
            out.append(line)
        else:
            out += textwrap.wrap(line, 110, break_long_words=False, break_on_hyphens=False)
    return out


def markdown_files():
    files = [os.path.join(ROOT, "README.md")]
    for dirpath, _, names in os.walk(os.path.join(ROOT, "docs")):
        files += [os.path.join(dirpath, n) for n in sorted(names) if n.endswith(".md")]
    return [f for f in files if os.path.isfile(f)]


def render_file(path, cache):
    """The file's text with every generated block rewritten, and the names of its blocks.
    Raises DataError naming the file and line on an unknown name or an unclosed block."""
    with open(path) as f:
        lines = f.read().split("\n")
    out, names, i = [], [], 0
    while i < len(lines):
        m = BEGIN.match(lines[i].strip())
        out.append(lines[i])
        if not m:
            i += 1
            continue
        name, start = m.group(1), i + 1
        if name not in TABLES:
            raise DataError(f"{rel(path)}:{start}: unknown table '{name}' (known: {', '.join(TABLES)})")
        j = i + 1
        while j < len(lines) and lines[j].strip() != END:
            if BEGIN.match(lines[j].strip()):
                raise DataError(f"{rel(path)}:{j + 1}: table '{name}' opened on line {start} is not closed")
            j += 1
        if j == len(lines):
            raise DataError(f"{rel(path)}:{start}: table '{name}' has no '{END}'")
        if name not in cache:
            cache[name] = wrap(TABLES[name]())
        out += cache[name]
        out.append(END)
        names.append((name, lines[i + 1:j] != cache[name]))
        i = j + 1
    return "\n".join(out), names


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--check", action="store_true", help="exit 1 if any table differs from its data")
    args = ap.parse_args()
    cache, stale, count = {}, [], 0
    try:
        for path in markdown_files():
            text, names = render_file(path, cache)
            count += len(names)
            for name, differs in names:
                if differs:
                    stale.append(f"{rel(path)}: table '{name}'")
            if names and not args.check:
                with open(path) as f:
                    old = f.read()
                if text != old:
                    with open(path, "w") as f:
                        f.write(text)
    except DataError as e:
        print(f"generate.py: error: {e}", file=sys.stderr)
        return 2
    if args.check:
        for s in stale:
            print(f"generate.py: stale: {s} (run python3 docs/results/generate.py)", file=sys.stderr)
        print(f"generate.py: {count} tables checked, {len(stale)} stale")
        return 1 if stale else 0
    print(f"generate.py: {count} tables written ({len(stale)} changed)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
