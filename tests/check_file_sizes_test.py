#!/usr/bin/env python3
"""tests/check_file_sizes.py on small made-up trees: files at the limit pass, a file of any
checked language one line over it fails with its FILE: N lines message, build outputs are not
read (so the check over the real tree can fail).

    python3 tests/check_file_sizes_test.py"""
import os
import subprocess
import sys
import tempfile
import unittest

CHECKER = os.path.join(os.path.dirname(os.path.abspath(__file__)), 'check_file_sizes.py')
LIMIT = 600


def lines(n):
    return ''.join(f'// line {i}\n' for i in range(n))


def run_checker(files):
    """Runs the checker on a tree of `files` (path -> text); returns (exit code, stdout)."""
    with tempfile.TemporaryDirectory() as root:
        for path, text in files.items():
            os.makedirs(os.path.join(root, os.path.dirname(path)), exist_ok=True)
            with open(os.path.join(root, path), 'w', encoding='utf-8') as f:
                f.write(text)
        run = subprocess.run([sys.executable, CHECKER, root], capture_output=True, text=True)
        return run.returncode, run.stdout


# Every checked language, each exactly at the limit.
AT_LIMIT = {path: lines(LIMIT) for path in [
    'decoder/ray_march.cc', 'decoder/ray_march.h', 'benchmarks/decoder_speed.c',
    'web/viewer.js', 'web/test/viewer_test.mjs', 'tests/check_layers.py', 'scripts/test.sh']}


class CheckFileSizesTest(unittest.TestCase):
    def test_files_at_the_limit_pass(self):
        rc, out = run_checker(AT_LIMIT)
        self.assertEqual(rc, 0, out)
        self.assertIn(f'every source file within {LIMIT} lines', out)

    def test_one_line_over_fails_in_every_language(self):
        for path in AT_LIMIT:
            with self.subTest(path=path):
                rc, out = run_checker({**AT_LIMIT, path: lines(LIMIT + 1)})
                self.assertEqual(rc, 1, out)
                self.assertIn(f'{path}: {LIMIT + 1} lines (limit {LIMIT})\n', out)
                self.assertIn('1 file(s) over', out)

    def test_last_line_without_newline_counts(self):
        rc, out = run_checker({'format/x.h': lines(LIMIT) + 'int x;'})
        self.assertEqual(rc, 1, out)
        self.assertIn(f'format/x.h: {LIMIT + 1} lines', out)

    def test_other_files_and_build_outputs_are_not_read(self):
        rc, out = run_checker({'tests/conformance/manifest.json': lines(2 * LIMIT),
                               'build-wasm/ecrf_decoder.js': lines(2 * LIMIT),
                               'examples/cmake/CMakeCache.txt': '',
                               'examples/cmake/gen.cc': lines(2 * LIMIT)})
        self.assertEqual(rc, 0, out)


if __name__ == '__main__':
    unittest.main()
