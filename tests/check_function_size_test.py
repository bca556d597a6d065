#!/usr/bin/env python3
"""tests/check_function_size.py on small made-up trees: a function of 120 lines passes and one of
121 fails with its PATH:LINE: NAME is N lines message, in C++ sources, C files and headers; an
exempted function passes, an exemption that names no function over the limit (stale) or has no
reason fails; without Universal Ctags the check skips (exit 77), as does this test.

    python3 tests/check_function_size_test.py"""
import os
import shutil
import subprocess
import sys
import tempfile
import unittest

CHECKER = os.path.join(os.path.dirname(os.path.abspath(__file__)), 'check_function_size.py')
EXEMPTIONS = 'tests/function_size_exemptions.txt'
LIMIT = 120
SKIP = 77


def function(name, lines):
    """A C function `name` of exactly `lines` lines, from its signature to its closing brace."""
    body = ''.join(f'  x += {i};\n' for i in range(lines - 3))
    return f'int {name}(int x) {{\n{body}  return x;\n}}\n'


def run_checker(files, path=None):
    """Runs the checker on a tree of `files` (path -> text), with PATH `path` if given; returns
    (exit code, stdout)."""
    env = dict(os.environ, PATH=path) if path is not None else None
    with tempfile.TemporaryDirectory() as root:
        for name, text in files.items():
            os.makedirs(os.path.join(root, os.path.dirname(name)), exist_ok=True)
            with open(os.path.join(root, name), 'w', encoding='utf-8') as f:
                f.write(text)
        run = subprocess.run([sys.executable, CHECKER, root], capture_output=True, text=True,
                             env=env)
        return run.returncode, run.stdout


def ctags_is_universal():
    if shutil.which('ctags') is None:
        return False
    return 'Universal Ctags' in subprocess.run(['ctags', '--version'], capture_output=True,
                                               text=True).stdout


# Every checked kind of file, each holding a function exactly at the limit after a small one.
AT_LIMIT = {path: function('Small', 5) + '\n' + function('Long', LIMIT) for path in [
    'tools/cmd_encode.cc', 'decoder/ray_march.h', 'benchmarks/decoder_speed.c',
    'examples/viewer.cpp', 'conformance/vectors.hpp', 'format/fields.inc']}


class CheckFunctionSizeTest(unittest.TestCase):
    def setUp(self):
        if not ctags_is_universal():
            self.skipTest('Universal Ctags is not installed')

    def test_functions_at_the_limit_pass(self):
        rc, out = run_checker(AT_LIMIT)
        self.assertEqual(rc, 0, out)
        self.assertIn(f'every function within {LIMIT} lines', out)

    def test_one_line_over_fails_in_every_kind_of_file(self):
        for path in AT_LIMIT:
            with self.subTest(path=path):
                text = function('Small', 5) + '\n' + function('Long', LIMIT + 1)
                rc, out = run_checker({**AT_LIMIT, path: text})
                self.assertEqual(rc, 1, out)
                self.assertIn(f'{path}:7: Long is {LIMIT + 1} lines (limit {LIMIT})\n', out)
                self.assertIn('1 problem(s)', out)

    def test_a_long_lambda_fails(self):
        body = ''.join(f'  x += {i};\n' for i in range(LIMIT - 2))
        text = f'auto kTable = [](int x) {{\n{body}  return x;\n}};\n'  # 121 lines
        rc, out = run_checker({'tools/table.cc': text})
        self.assertEqual(rc, 1, out)
        self.assertIn(f'tools/table.cc:1: lambda in file scope is {LIMIT + 1} lines', out)

    def test_an_exempted_function_passes(self):
        rc, out = run_checker({'conformance/vectors.h': function('Vectors', 3 * LIMIT),
                               EXEMPTIONS: '# table code only\n'
                                           'conformance/vectors.h Vectors  # a vector table\n'})
        self.assertEqual(rc, 0, out)

    def test_an_exemption_covers_only_its_file_and_function(self):
        rc, out = run_checker({'conformance/vectors.h': function('Vectors', LIMIT + 1),
                               'conformance/other.h': function('Vectors', LIMIT + 1) + '\n' +
                                                      function('Other', LIMIT + 1),
                               EXEMPTIONS: 'conformance/vectors.h Vectors  # a vector table\n'})
        self.assertEqual(rc, 1, out)
        self.assertIn('conformance/other.h:1: Vectors is', out)
        self.assertIn(f'conformance/other.h:{LIMIT + 3}: Other is', out)
        self.assertNotIn('conformance/vectors.h:', out)

    def test_a_stale_exemption_fails(self):
        for tree in [{'conformance/vectors.h': function('Vectors', LIMIT)}, {}]:
            with self.subTest(files=list(tree)):
                rc, out = run_checker({**tree, EXEMPTIONS:
                                       'conformance/vectors.h Vectors  # a vector table\n'})
                self.assertEqual(rc, 1, out)
                self.assertIn(f'conformance/vectors.h Vectors is not over {LIMIT} lines '
                              '(stale exemption: remove it)', out)

    def test_an_exemption_without_a_reason_fails(self):
        rc, out = run_checker({'conformance/vectors.h': function('Vectors', LIMIT + 1),
                               EXEMPTIONS: 'conformance/vectors.h Vectors\n'})
        self.assertEqual(rc, 1, out)
        self.assertIn(f'{EXEMPTIONS}:1: expected `PATH FUNCTION  # why`', out)

    def test_other_files_and_build_outputs_are_not_read(self):
        rc, out = run_checker({'tests/check_layers.py': function('Long', 2 * LIMIT),
                               'build/gen.cc': function('Long', 2 * LIMIT),
                               'examples/cmake/CMakeCache.txt': '',
                               'examples/cmake/gen.cc': function('Long', 2 * LIMIT)})
        self.assertEqual(rc, 0, out)


class WithoutCtagsTest(unittest.TestCase):
    def test_the_check_skips_and_says_why(self):
        with tempfile.TemporaryDirectory() as empty:
            rc, out = run_checker(AT_LIMIT, path=empty)
        self.assertEqual(rc, SKIP, out)
        self.assertIn('skipped: ctags is not installed', out)


if __name__ == '__main__':
    # Where Universal Ctags is missing the test is a skip for ctest too (SKIP_RETURN_CODE 77).
    result = unittest.main(exit=False).result
    if not result.wasSuccessful():
        sys.exit(1)
    sys.exit(0 if ctags_is_universal() else SKIP)
