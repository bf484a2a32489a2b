#!/usr/bin/env python3
"""Tests of docs/results/generate.py (CTest: doc_tables_generator). Python 3's standard library only.

They check that the committed tables are current, that --check fails naming a table whose text no
longer matches its data, that a bad marker is an error naming the file and line. That the intervals quoted
from findings.json follow from the per-round times is checked by `bvhlab findings DIR --check`
(test_findings), the C++ that computes them."""

import contextlib
import io
import json
import os
import shutil
import sys
import tempfile
import unittest

sys.dont_write_bytecode = True
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import generate  # noqa: E402
import tables_gpu  # noqa: E402
import tables_io  # noqa: E402


def run(*argv):
    """generate.main's exit status and what it wrote to stderr."""
    err = io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
        status = generate.main(list(argv))
    return status, err.getvalue()


class CopiedDocs(unittest.TestCase):
    """README.md and docs/*.md copied into a temporary tree, so the tests may change them."""

    def setUp(self):
        self.root = tempfile.mkdtemp(prefix="doc_tables_")
        shutil.copy(os.path.join(tables_io.ROOT, "README.md"), self.root)
        shutil.copytree(os.path.join(tables_io.ROOT, "docs"), os.path.join(self.root, "docs"),
                        ignore=lambda d, names: [n for n in names
                                                 if not n.endswith(".md") and not os.path.isdir(os.path.join(d, n))])

    def tearDown(self):
        shutil.rmtree(self.root)

    def test_copied_tables_are_current(self):
        self.assertEqual(run("--check", "--root", self.root), (0, ""))

    def type_over_a_cell(self, relpath):
        """Changes the first data row of the first generated table in a file; returns the table's name."""
        path = os.path.join(self.root, relpath)
        with open(path) as f:
            lines = f.read().split("\n")
        start = next(i for i, line in enumerate(lines) if generate.BEGIN.match(line))
        row = start + 3  # the marker, the header, the |---| line, then the first row
        self.assertTrue(lines[row].startswith("| "), lines[row])
        lines[row] = lines[row].replace(" | ", " | 9", 1)
        with open(path, "w") as f:
            f.write("\n".join(lines))
        return generate.BEGIN.match(lines[start]).group(1)

    def test_a_changed_cell_is_stale(self):
        # A figure typed over inside a generated block: --check names the file and the table.
        for relpath in ["docs/gpu.md", "docs/builders.md", "docs/robustness.md"]:
            name = self.type_over_a_cell(relpath)
            status, err = run("--check", "--root", self.root)
            self.assertEqual(status, 1)
            self.assertIn(f"{relpath}: table '{name}'", err)

    def test_writing_makes_it_current_again(self):
        self.type_over_a_cell("docs/layouts.md")
        self.assertEqual(run("--root", self.root)[0], 0)
        self.assertEqual(run("--check", "--root", self.root), (0, ""))

    def test_unknown_table_names_file_and_line(self):
        with open(os.path.join(self.root, "docs", "extra.md"), "w") as f:
            f.write("# x\n\n<!-- generated:no-such-table -->\n<!-- end generated -->\n")
        status, err = run("--check", "--root", self.root)
        self.assertEqual(status, 2)
        self.assertIn("docs/extra.md:3: unknown table 'no-such-table'", err)

    def test_unclosed_block_names_file_and_line(self):
        with open(os.path.join(self.root, "docs", "extra.md"), "w") as f:
            f.write("<!-- generated:gpu-render -->\n| stale |\n")
        status, err = run("--check", "--root", self.root)
        self.assertEqual(status, 2)
        self.assertIn("docs/extra.md:1: table 'gpu-render' has no", err)


class GpuBuildTime(unittest.TestCase):
    """tables_gpu.gpu_build_time over a made-up step-1b file (no GPU run of the GPU builders is committed)."""

    def setUp(self):
        self.dir = tempfile.mkdtemp(prefix="gpu_build_time_")
        with open(os.path.join(self.dir, "source.json"), "w") as f:
            json.dump({"commands": {"gpu-builders.jsonl": "bash experiments/remote/gpu-run.sh installed OUT"},
                       "git_commit": "0123456789abcdef", "machine": "test host"}, f)

    def tearDown(self):
        shutil.rmtree(self.dir)

    def write(self, builds):
        with open(os.path.join(self.dir, "gpu-builders.jsonl"), "w") as f:
            for b in builds:
                f.write(json.dumps(b) + "\n")

    def rows(self):
        lines = tables_gpu.gpu_build_time(self.dir)
        return {tuple(c.strip() for c in line.strip("|").split("|"))[1]: [c.strip() for c in line.strip("|").split("|")]
                for line in lines if line.startswith("| ") and "`" in line}

    def test_speedups_are_over_the_fastest_cpu_build_of_the_same_or_better_sah(self):
        gpu = lambda name, ms, sah: {"mesh": "m/scaling_1M.toml", "builder": name, "sah_cost": sah, "build_ms": 900.0,
                                     "gpu_build_ms": {"median": ms, "low": ms * 0.9, "high": ms * 1.1, "builds": 11},
                                     "gpu_renderer": "NVIDIA H100"}
        cpu = lambda name, ms, sah: {"mesh": "m/scaling_1M.toml", "builder": name, "sah_cost": sah, "build_ms": ms}
        wide = dict(gpu("ploc-gpu", 8.0, 50.0), gpu_pack="cwbvh")
        self.write([gpu("lbvh-gpu", 2.0, 60.0), gpu("ploc-gpu", 5.0, 50.0), gpu("odd-gpu", 1.0, 10.0), wide,
                    cpu("lbvh", 30.0, 60.0), cpu("lbvh", 50.0, 60.0), cpu("lbvh", 40.0, 60.0),
                    cpu("ploc", 100.0, 50.0), cpu("sah-binned", 80.0, 45.0)])
        rows = self.rows()
        self.assertEqual(rows["`lbvh-gpu`"][6], "20.0x")   # lbvh's median 40 ms (sah-binned's 80 is better, slower)
        self.assertEqual(rows["`ploc-gpu`"][6], "16.0x")   # min(ploc 100, sah-binned 80) / 5
        self.assertEqual(rows["`odd-gpu`"][6], "no CPU builder as good")
        self.assertEqual(rows["`lbvh`"][3], "40.0 [30.0, 50.0]")
        self.assertEqual(rows["`ploc-gpu`"][5], f"{50 / 45:.3f}")
        self.assertEqual(rows["`lbvh`"][6], "–")
        self.assertEqual(rows["`ploc-gpu` into cwbvh"][6], "10.0x")  # its own row, not merged with v1's
        self.assertEqual(rows["`ploc-gpu`"][3], "5.00 [4.50, 5.50]")

    def test_a_missing_key_names_the_file_and_object(self):
        self.write([{"mesh": "a.off", "builder": "lbvh", "build_ms": 3.0}])
        with self.assertRaises(tables_io.DataError) as e:
            tables_gpu.gpu_build_time(self.dir)
        self.assertIn("gpu-builders.jsonl: object 1", str(e.exception))
        self.assertIn("sah_cost", str(e.exception))


if __name__ == "__main__":
    unittest.main()
