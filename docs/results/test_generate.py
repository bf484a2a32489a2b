#!/usr/bin/env python3
"""Tests of docs/results/generate.py (CTest: doc_tables_generator). Python 3's standard library only.

They check that the committed tables are current, that --check fails naming a table whose text no
longer matches its data, that a bad marker is an error naming the file and line. That the intervals quoted
from findings.json follow from the per-round times is checked by `bvhlab findings DIR --check`
(test_findings), the C++ that computes them."""

import contextlib
import io
import os
import shutil
import sys
import tempfile
import unittest

sys.dont_write_bytecode = True
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import generate  # noqa: E402
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


if __name__ == "__main__":
    unittest.main()
