#!/usr/bin/env python3
"""tests/check_layers.py on small made-up trees: a clean tree passes, and each kind of violation
fails with its FILE:LINE message (so the check over the real tree can fail).

    python3 tests/check_layers_test.py"""
import os
import subprocess
import sys
import tempfile
import unittest

CHECKER = os.path.join(os.path.dirname(os.path.abspath(__file__)), 'check_layers.py')

# A tree whose includes all follow the rules, in the shapes the real tree has.
CLEAN = {
    'include/ecrf/decoder.h': '',
    'format/container.h': '#include <cstdint>\n',
    'decoder/scene_decoder.h': '#include <ecrf/decoder.h>\n#include "format/container.h"\n',
    'conformance/scene_vectors.h': '#include "decoder/scene_decoder.h"\n',
    'trainer/model/tensorf_model.h': '#include "format/container.h"\n',
    'encoder/scene_encoder.h': '#include "format/container.h"\n',
    'trainer/train/trainer.h': ('#include "encoder/scene_encoder.h"\n'
                                '#include "trainer/model/tensorf_model.h"\n'),
    'tools/cmd_conformance.cc': ('#include <vector>\n#include <CLI/CLI.hpp>\n'
                                 '#include "conformance/scene_vectors.h"\n'
                                 '#include "trainer/train/trainer.h"\n'),
    'examples/example_util.h': '#include <ecrf/decoder.h>\n',
    'examples/decode_render.c': '#include <ecrf/decoder.h>\n#include "example_util.h"\n',
    'benchmarks/decoder_speed.c': '#include "examples/example_util.h"\n',
    'tests/common/md5.h': '',
    'tests/tools/cli_test.cc': '#include "tests/common/md5.h"\n#include "tools/cli.h"\n',
}


def run_checker(extra):
    """Runs the checker on CLEAN plus `extra` (path -> text); returns (exit code, stdout)."""
    with tempfile.TemporaryDirectory() as root:
        for path, text in {**CLEAN, **extra}.items():
            os.makedirs(os.path.join(root, os.path.dirname(path)), exist_ok=True)
            with open(os.path.join(root, path), 'w', encoding='utf-8') as f:
                f.write(text)
        run = subprocess.run([sys.executable, CHECKER, root], capture_output=True, text=True)
        return run.returncode, run.stdout


class CheckLayersTest(unittest.TestCase):
    def assertFails(self, extra, message):
        rc, out = run_checker(extra)
        self.assertEqual(rc, 1, out)
        self.assertIn(message + '\n', out)
        self.assertIn('1 layering violation(s)', out)

    def test_clean_tree_passes(self):
        rc, out = run_checker({})
        self.assertEqual(rc, 0, out)
        self.assertIn('layers respected', out)

    def test_encoder_including_the_trainer_fails(self):
        self.assertFails({'encoder/grid_dct.h': '// grids\n#include "trainer/model/vm_grid.h"\n'},
                         'encoder/grid_dct.h:2: encoder/ may not include trainer/model/vm_grid.h')

    def test_tools_including_tests_fails(self):
        self.assertFails({'tools/cmd_info.cc': '#include "tests/common/md5.h"\n'},
                         'tools/cmd_info.cc:1: tools/ may not include tests/common/md5.h')

    def test_c_file_including_examples_fails(self):
        self.assertFails({'tools/speed.c': '#include <stdio.h>\n\n#include "examples/example_util.h"\n'},
                         'tools/speed.c:3: tools/ may not include examples/example_util.h')

    def test_include_relative_to_the_file_is_resolved(self):
        self.assertFails({'decoder/fast.c': '#include "../examples/example_util.h"\n'},
                         'decoder/fast.c:1: decoder/ may not include ../examples/example_util.h')

    def test_angle_bracket_project_include_counts(self):
        self.assertFails({'format/io.h': '#include <vector>\n#include <decoder/scene_decoder.h>\n'},
                         'format/io.h:2: format/ may not include decoder/scene_decoder.h')

    def test_decoder_including_the_encoder_fails(self):
        self.assertFails({'decoder/ray_marcher.cc': '#include "encoder/scene_encoder.h"\n'},
                         'decoder/ray_marcher.cc:1: decoder/ may not include '
                         'encoder/scene_encoder.h')

    def test_folder_without_a_rule_fails(self):
        self.assertFails({'viewer/viewer.cc': '#include "format/container.h"\n'},
                         'viewer/viewer.cc:1: viewer/ has no layer rule in tests/check_layers.py')

    def test_build_outputs_are_not_read(self):
        rc, out = run_checker({
            'build-asan/decoder/x.cc': '#include "trainer/train/trainer.h"\n',
            'examples/cmake/CMakeCache.txt': '',
            'examples/cmake/gen/x.cc': '#include "trainer/train/trainer.h"\n'})
        self.assertEqual(rc, 0, out)


if __name__ == '__main__':
    unittest.main()
