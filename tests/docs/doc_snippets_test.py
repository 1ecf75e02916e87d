#!/usr/bin/env python3
"""The snippet runner's own rules: what it refuses and how it compares output (no sandbox)."""

import os
import signal
import subprocess
import sys
import tempfile
import time
import unittest
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import doc_snippets  # noqa: E402


def tree(readme: str, **docs: str) -> Path:
    root = Path(tempfile.mkdtemp(prefix="doc-snippets-test-"))
    (root / "README.md").write_text(readme)
    (root / "docs").mkdir()
    for name, text in docs.items():
        (root / "docs" / f"{name}.md").write_text(text)
    return root


class Annotations(unittest.TestCase):
    def test_a_block_without_an_annotation_is_a_problem_naming_its_line(self):
        root = tree("# t\n\n<!-- snippet: a run=sh -->\n```sh\ntrue\n```\n\ntext\n\n```sh\nfalse\n```\n")
        snippets, problems = doc_snippets.load(root)
        self.assertEqual([s.name for s in snippets], ["a"])
        self.assertEqual(len(problems), 1)
        self.assertIn("README.md:10:", problems[0])

    def test_a_skip_needs_its_reason_and_one_kind_only(self):
        root = tree("<!-- snippet: a skip -->\n```\nx\n```\n<!-- snippet: b run=sh shows=\"y\" -->\n```\ny\n```\n")
        _, problems = doc_snippets.load(root)
        self.assertTrue(any("skip= needs a reason" in p for p in problems), problems)
        self.assertTrue(any("exactly one of" in p for p in problems), problems)

    def test_an_unknown_attribute_and_a_dangling_expect_are_problems(self):
        root = tree("<!-- snippet: a run=sh expect=nowhere colour=red -->\n```sh\ntrue\n```\n")
        _, problems = doc_snippets.load(root)
        self.assertTrue(any("unknown attribute 'colour'" in p for p in problems), problems)
        self.assertTrue(any("expect=nowhere" in p for p in problems), problems)

    def test_an_output_nobody_expects_is_a_problem(self):
        root = tree("<!-- snippet: out output -->\n```\nx\n```\n")
        _, problems = doc_snippets.load(root)
        self.assertTrue(any("no snippet expects" in p for p in problems), problems)

    def test_groups_keep_document_order_and_after_moves_one(self):
        root = tree("<!-- snippet: a run=sh group=g -->\n```sh\n1\n```\n"
                    "<!-- snippet: b output group=g after=c from=\"true\" -->\n```\nx\n```\n"
                    "<!-- snippet: c run=sh group=g -->\n```sh\n2\n```\n")
        snippets, problems = doc_snippets.load(root)
        self.assertEqual(problems, [])
        members = doc_snippets.groups(snippets)[("README.md", "g")]
        self.assertEqual([m.name for m in members], ["a", "c", "b"])


class Compare(unittest.TestCase):
    def test_runs_between_gaps_must_appear_in_order_anchored_at_the_ends(self):
        doc_snippets.compare("a\n...\nc\n", "a\nb\nc\n", "t")
        doc_snippets.compare("...\nb\n...\n", "a\nb\nc\n", "t")
        with self.assertRaises(doc_snippets.SnippetError):
            doc_snippets.compare("b\n...\n", "a\nb\nc\n", "t")      # not at the start
        with self.assertRaises(doc_snippets.SnippetError):
            doc_snippets.compare("...\nb\n", "a\nb\nc\n", "t")      # not at the end
        with self.assertRaises(doc_snippets.SnippetError):
            doc_snippets.compare("c\n...\na\n", "c\nb\na\nx\n", "t")  # out of order / unanchored end

    def test_a_changed_digit_fails(self):
        with self.assertRaises(doc_snippets.SnippetError) as raised:
            doc_snippets.compare("  0.060  19.386\n...\n", "  0.060  19.384\nrest\n", "t")
        self.assertIn("19.384", str(raised.exception))

    def test_log_lines_compare_without_their_stamp(self):
        doc_snippets.compare("...\nhapticd: viewer at x\n...\n",
                             "[2026-12-03 16:06:24.754] [info] hapticd: viewer at x\n", "t")

    def test_expectations_from_comments(self):
        code = 'x = 1\nprint(x)   # 1 (a note)\nprint(2)\n'
        self.assertEqual(doc_snippets.python_expectations(code), ["1"])
        self.assertEqual(doc_snippets.sh_comment_expectations("# intro\ncmd\n# out line\n"), ["out line"])


class Programs(unittest.TestCase):
    def test_wrap_main_puts_statements_in_main_and_fields_in_a_client_config(self):
        root = tree("<!-- snippet: m run=cpp wrap=main -->\n```cpp\n#include <vector>\nint x = 1;\n```\n"
                    "<!-- snippet: f run=cpp wrap=fields -->\n```cpp\n.server_address = \"h:1\",\n```\n")
        snippets, problems = doc_snippets.load(root)
        self.assertEqual(problems, [])
        main = doc_snippets.cpp_program(snippets[0], snippets)
        self.assertIn("#include <vector>", main.split("int main()")[0])
        self.assertIn("int x = 1;", main.split("int main()")[1])
        fields = doc_snippets.cpp_program(snippets[1], snippets)
        self.assertIn("haptic::ClientConfig config{", fields)


class Streams(unittest.TestCase):
    def start(self, script: str) -> subprocess.Popen:
        return subprocess.Popen(["bash", "-c", script], text=True, stdout=subprocess.PIPE,
                                stderr=subprocess.STDOUT, start_new_session=True)

    def test_the_window_counts_from_the_first_output(self):
        # A line that is slow to start (a TLS connection on a loaded machine) still gets its window.
        process = self.start("sleep 0.6; echo first; sleep 0.1; echo second; sleep 30")
        started = time.monotonic()
        out, exited = doc_snippets.read_until_quiet(process, window_s=0.4, first_within_s=10)
        waited = time.monotonic() - started
        os.killpg(process.pid, signal.SIGKILL)
        process.communicate()
        self.assertFalse(exited)
        self.assertEqual(out, "first\nsecond\n")
        self.assertGreater(waited, 0.9)
        self.assertLess(waited, 10)

    def test_a_line_that_ends_is_read_to_its_end(self):
        process = self.start("echo one; echo two")
        out, exited = doc_snippets.read_until_quiet(process, window_s=5, first_within_s=10)
        process.communicate()
        self.assertTrue(exited)
        self.assertEqual(out, "one\ntwo\n")

    def test_a_silent_line_gives_up_after_the_first_output_wait(self):
        process = self.start("sleep 30")
        out, exited = doc_snippets.read_until_quiet(process, window_s=0.1, first_within_s=0.3)
        os.killpg(process.pid, signal.SIGKILL)
        process.communicate()
        self.assertFalse(exited)
        self.assertEqual(out, "")

    def test_a_passed_snippets_long_output_is_cut_to_its_head(self):
        text = "".join(f"line {i}\n" for i in range(30))
        cut = doc_snippets.head(text, lines=5)
        self.assertEqual(cut.splitlines()[:5], [f"line {i}" for i in range(5)])
        self.assertIn("25 more lines", cut)
        self.assertEqual(doc_snippets.head("a\nb\n", lines=5), "a\nb\n")


if __name__ == "__main__":
    unittest.main()
