"""Tests of the Python module ecrf against the conformance vectors (python3 -m unittest).

The module is found on PYTHONPATH (scripts/test-install.sh points it at an installed tree);
ECRF_SOURCE_DIR overrides where tests/conformance is looked for.
"""
import json
import math
import os
import struct
import threading
import time
import unittest
import zlib

import numpy as np

import ecrf

SOURCE_DIR = os.environ.get(
    "ECRF_SOURCE_DIR", os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))
CONFORMANCE = os.path.join(SOURCE_DIR, "tests", "conformance")
SCENE = os.path.join(CONFORMANCE, "scene_builtin.ecrf")


def read_png(path):
    """8-bit RGB/RGBA PNG -> uint8 [height][width][channels], zlib and the five filters only."""
    with open(path, "rb") as f:
        data = f.read()
    if data[:8] != b"\x89PNG\r\n\x1a\n":
        raise ValueError(path + ": not a PNG")
    pos, idat = 8, b""
    while pos < len(data):
        length, kind = struct.unpack(">I4s", data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + length]
        if kind == b"IHDR":
            width, height, depth, colour, _, _, interlace = struct.unpack(">IIBBBBB", body)
            if depth != 8 or colour not in (2, 6) or interlace:
                raise ValueError(path + ": only 8-bit RGB/RGBA, not interlaced")
        elif kind == b"IDAT":
            idat += body
        pos += 12 + length
    bpp = 3 if colour == 2 else 4
    stride = width * bpp
    raw = zlib.decompress(idat)
    out = bytearray(height * stride)
    prev = bytearray(stride)
    for y in range(height):
        filt = raw[y * (stride + 1)]
        line = bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for i in range(stride):
            a = line[i - bpp] if i >= bpp else 0
            b = prev[i]
            c = prev[i - bpp] if i >= bpp else 0
            if filt == 1:
                line[i] = (line[i] + a) & 255
            elif filt == 2:
                line[i] = (line[i] + b) & 255
            elif filt == 3:
                line[i] = (line[i] + (a + b) // 2) & 255
            elif filt == 4:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                line[i] = (line[i] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
        out[y * stride:(y + 1) * stride] = line
        prev = line
    return np.frombuffer(bytes(out), dtype=np.uint8).reshape(height, width, bpp)


def read_bytes(path):
    with open(path, "rb") as f:
        return f.read()


def manifest_camera(name):
    with open(os.path.join(CONFORMANCE, "manifest.json")) as f:
        manifest = json.load(f)
    vector = next(v for v in manifest["scene_vectors"] if v["file"] == name)
    cam = vector["render"]["camera"]
    c2w = np.array([float.fromhex(v) for v in cam["c2w"]], dtype=np.float32).reshape(3, 4)
    intrinsics = [float.fromhex(cam[k]) for k in ("fx", "fy", "cx", "cy")]
    return vector, c2w, intrinsics, cam["width"], cam["height"]


class DecodeTest(unittest.TestCase):
    def test_info_and_tensors(self):
        vector = manifest_camera("scene_builtin.ecrf")[0]
        s = ecrf.decode(SCENE)
        info = s.info
        self.assertEqual(list(info["grid_res"]), vector["grid"])
        self.assertEqual(list(info["density_ranks"]), vector["ranks"]["density"])
        self.assertEqual(list(info["appearance_ranks"]), vector["ranks"]["appearance"])
        self.assertEqual(info["stream_bytes"], vector["bytes"])
        self.assertTrue(info["has_occupancy"])
        nx, ny, nz = info["grid_res"]
        plane = s.tensor(0, 0)
        self.assertEqual(plane.dtype, np.float32)
        self.assertEqual(plane.ndim, 3)
        self.assertEqual(plane.shape[2], info["density_ranks"][0])
        self.assertIn(plane.shape[0] * plane.shape[1], (nx * ny, ny * nz, nx * nz))
        line = s.tensor(1, 3)
        self.assertEqual(line.ndim, 2)
        self.assertEqual(line.shape[1], info["appearance_ranks"][0])
        self.assertFalse(plane.flags.writeable)
        with self.assertRaises(ValueError):
            plane[0, 0, 0] = 1.0
        self.assertTrue(np.isfinite(plane).all())

    def test_versions_read_as_the_cli_prints_them(self):
        # One version story (#61): the library's version, and bitstream major.minor as
        # `ecrf --version` prints it ("reads bitstream 1.0 to 1.7").
        self.assertRegex(ecrf.__version__, r"^\d+\.\d+\.\d+$")
        self.assertEqual(ecrf.bitstream_version, 1)
        self.assertGreaterEqual(ecrf.bitstream_version_minor, 7)

    def test_views_keep_the_scene_alive(self):
        plane = ecrf.decode(SCENE).tensor(1, 0)
        copy = plane.copy()
        for _ in range(3):
            ecrf.decode(SCENE)  # reuses freed memory if the first scene were gone
        np.testing.assert_array_equal(plane, copy)

    def test_field_occupancy_mlp(self):
        s = ecrf.decode(read_bytes(SCENE))
        field = s.field
        self.assertEqual(field["mlp_inputs"], field["mlp_features"] + 3 + 2 * field["mlp_features"] *
                         field["mlp_feature_freqs"] + 6 * field["mlp_viewdir_freqs"])
        params = s.mlp_params()
        self.assertEqual(params.shape, (field["mlp_params"],))
        self.assertTrue(np.isfinite(params).all())
        mask = s.occupancy()
        res = s.info["occupancy_res"]
        self.assertEqual(mask.shape, (res[2], res[1], res[0]))
        self.assertEqual(mask.dtype, np.bool_)
        self.assertTrue(0 < mask.sum() < mask.size)
        packed = s.occupancy(packed=True)
        self.assertEqual(packed.dtype, np.uint8)
        self.assertEqual(mask.sum(), np.unpackbits(packed, bitorder="little")[:mask.size].sum())

    def test_int16_storage(self):
        s = ecrf.decode(SCENE, storage="int16")
        self.assertLess(s.info["grid_bytes"], ecrf.decode(SCENE).info["grid_bytes"])
        with self.assertRaises(ecrf.Error):
            s.tensor(0, 0)

    def test_bad_bytes_raise_with_the_message(self):
        with self.assertRaises(ecrf.DecodeError) as cm:
            ecrf.decode(b"not an ecrf stream at all")
        self.assertIsInstance(cm.exception, ValueError)
        self.assertLess(cm.exception.code, 0)
        self.assertTrue(str(cm.exception).startswith("decode: "))
        self.assertGreater(len(str(cm.exception)), len("decode: "))
        data = read_bytes(SCENE)
        with self.assertRaises(ecrf.DecodeError) as cm:
            ecrf.decode(data[:len(data) // 2])
        self.assertEqual(cm.exception.code, ecrf.ERR_TRUNCATED)
        self.assertEqual(cm.exception.code_name, "truncated")
        with self.assertRaises(ecrf.DecodeError) as cm:
            ecrf.decode(data, memory_budget=1024)
        self.assertEqual(cm.exception.code, ecrf.ERR_LIMIT)
        with self.assertRaises(ValueError):
            ecrf.decode(data, storage="float64")
        with self.assertRaises(OSError):
            ecrf.decode(os.path.join(CONFORMANCE, "no_such_file.ecrf"))


class RenderTest(unittest.TestCase):
    def test_matches_the_reference_render(self):
        # An object scene, an unbounded one (SPEC.md 7.2.1), a forward-facing one (7.2.2), one
        # with the deferred head (7.6) and one with ReLU density (7.4).
        for name, model in (("scene_builtin", "object"), ("scene_unbounded", "unbounded"),
                            ("scene_forward", "forward"), ("scene_deferred_head", "object"),
                            ("scene_sh_deferred", "object"), ("scene_one_hidden_layer", "object"),
                            ("scene_relu_density", "forward")):
            with self.subTest(name):
                _, c2w, (fx, fy, cx, cy), width, height = manifest_camera(name + ".ecrf")
                reference = read_png(os.path.join(CONFORMANCE, name + ".png"))[:, :, :3].astype(int)
                scene = ecrf.decode(os.path.join(CONFORMANCE, name + ".ecrf"))
                self.assertEqual(scene.info["scene_model"], model)
                self.assertEqual(scene.info["head"],
                                 "mlp" if name in ("scene_builtin", "scene_unbounded",
                                                   "scene_forward", "scene_relu_density")
                                 else "deferred")
                # Hidden width 0: spherical-harmonics colour, no MLP (SPEC.md 7.6.2).
                self.assertEqual(scene.field["mlp_hidden"] == 0, name == "scene_sh_deferred")
                # One hidden layer (SPEC.md 6.6 layers 1, bitstream 1.8).
                self.assertEqual(scene.field["mlp_layers"], 1 if name == "scene_one_hidden_layer" else 2)
                self.assertEqual(scene.field["density_activation"],
                                 "relu" if name == "scene_relu_density" else "softplus")
                # The file header's version (SPEC.md 2.1), as `ecrf info` prints it.
                self.assertEqual(scene.info["version"],
                                 {"scene_builtin": "1.0", "scene_unbounded": "1.2",
                                  "scene_forward": "1.3", "scene_deferred_head": "1.6",
                                  "scene_sh_deferred": "1.7", "scene_one_hidden_layer": "1.8",
                                  "scene_relu_density": "1.9"}[name])
                self.assertEqual("ndc_near_plane" in scene.info, model == "forward")
                if model == "forward":
                    self.assertEqual(scene.info["ndc_near_plane"], 1.5)  # the vector's NDCP chunk
                    self.assertEqual(len(scene.info["ndc_world_to_ref"]), 12)
                rgba = scene.render(c2w, fx, fy, cx, cy, width, height)
                self.assertEqual(rgba.shape, (height, width, 4))
                self.assertEqual(rgba.dtype, np.uint8)
                diff = np.abs(rgba[:, :, :3].astype(int) - reference)
                mse = np.mean((diff / 255.0) ** 2)
                psnr = float("inf") if mse == 0 else -10 * np.log10(mse)
                within = np.mean(diff.max(axis=2) <= 2)  # SPEC.md 7.7
                self.assertTrue(psnr >= 40 or within >= 0.99, "PSNR %.2f dB, %.4f within 2" % (psnr, within))

    def test_orbit_camera_is_the_reference_one(self):
        # The manifest camera of scene_builtin is OrbitCamera(64, 64, 0.3f, 0.45f, 4) (radians, in
        # float32). orbit_camera takes degrees, as `ecrf render` and the viewer do; these degrees
        # convert back to exactly those float32 radians, and the camera must match to the last bit.
        _, c2w, (fx, fy, cx, cy), width, height = manifest_camera("scene_builtin.ecrf")
        az, el = (math.degrees(float(np.float32(r))) for r in (0.3, 0.45))
        m, ofx, ofy, ocx, ocy = ecrf.orbit_camera(width, height, az, el, 4.0)
        self.assertEqual(m.shape, (3, 4))
        self.assertEqual(m.dtype, np.float32)
        self.assertEqual((ofx, ofy, ocx, ocy), (fx, fy, cx, cy))
        self.assertTrue(np.array_equal(m, c2w), "%r\n%r" % (m, c2w))

    def test_orbit_camera_matches_the_cli_bit_for_bit(self):
        # Frame 5 of `ecrf render --orbit 7 --elevation 33.3 --radius 4.2 -W 40 -H 30` as the tool
        # computes it (dec::OrbitCamera in binary32 without fused multiply-adds, SPEC.md 7.1). A
        # module built with FMA contraction gets c2w[2][1] one unit in the last place off.
        expected = ["0x1.f329cp-1", "0x1.f4679ap-4", "-0x1.7ce58cp-3", "-0x1.8ff104p-1",
                    "-0x1.c7b91ap-3", "0x1.120d4ap-1", "-0x1.a13444p-1", "-0x1.b6107ap+1",
                    "0x0p+0", "0x1.abeef2p-1", "0x1.191984p-1", "0x1.272796p+1"]
        m, fx, fy, cx, cy = ecrf.orbit_camera(40, 30, 360.0 * 5 / 7, 33.3, 4.2)
        self.assertEqual([float(v).hex() for v in m.flatten()], [float.fromhex(v).hex() for v in expected])
        self.assertEqual((fx, fy, cx, cy), (float.fromhex("0x1.bc71c6p+5"),) * 2 + (20.0, 15.0))

    def test_orbit_camera_takes_degrees(self):
        # Azimuth 90, elevation 30 degrees at radius 2: on the +y side, 1 above the xy plane.
        m = ecrf.orbit_camera(width=32, height=32, azimuth_deg=90.0, elevation_deg=30.0, radius=2.0)[0]
        np.testing.assert_allclose(m[:, 3], [0.0, math.sqrt(3.0), 1.0], atol=1e-6)
        self.assertIn("degrees", ecrf.orbit_camera.__doc__)

    def test_rgb_and_options(self):
        s = ecrf.decode(SCENE)
        cam = ecrf.orbit_camera(32, 24, 17.0, 29.0, 4.0)
        rgb = s.render(*cam, 32, 24, rgb=True, threads=2)
        self.assertEqual(rgb.shape, (24, 32, 3))
        self.assertEqual(rgb.dtype, np.float32)
        rgba = s.render(*cam, 32, 24)
        self.assertLessEqual(np.abs(np.round(rgb * 255) - rgba[:, :, :3]).max(), 1)
        with self.assertRaises(ecrf.Error) as cm:
            s.render(*cam, 32, 24, sample_budget=1)
        self.assertEqual(cm.exception.code, ecrf.ERR_LIMIT)
        with self.assertRaises(ValueError):
            s.render(np.eye(3), 1, 1, 1, 1, 8, 8)

    def test_work_and_decode_budgets(self):
        # SPEC.md 8: a work budget below one sample's cost refuses the scene, 0 lifts the limit
        # and leaves the image unchanged; the decode budget is per byte of the stream.
        s = ecrf.decode(SCENE)
        cam = ecrf.orbit_camera(24, 24, 17.0, 29.0, 4.0)
        with self.assertRaises(ecrf.Error) as cm:
            s.render(*cam, 24, 24, work_budget=1)
        self.assertEqual(cm.exception.code, ecrf.ERR_LIMIT)
        self.assertIn("work budget", str(cm.exception))
        np.testing.assert_array_equal(s.render(*cam, 24, 24, work_budget=0), s.render(*cam, 24, 24))
        unlimited = ecrf.decode(SCENE, decode_budget=0)
        np.testing.assert_array_equal(unlimited.tensor(0, 0), s.tensor(0, 0))
        with self.assertRaises(ValueError):
            ecrf.decode(SCENE, decode_budget=-1)

    def test_render_releases_the_gil(self):
        s = ecrf.decode(SCENE)
        cam = ecrf.orbit_camera(128, 128, 17.0, 29.0, 4.0)
        done = threading.Event()
        ticks = [0]

        def render():
            for _ in range(2):
                s.render(*cam, 128, 128)
            done.set()

        thread = threading.Thread(target=render)
        start = time.perf_counter()
        thread.start()
        # Python code on this thread keeps running only if the render let go of the GIL.
        while not done.is_set():
            ticks[0] += 1
            time.sleep(0.001)
        thread.join()
        elapsed = time.perf_counter() - start
        self.assertGreater(ticks[0], max(2, int(elapsed / 0.001) // 10),
                           "%d ticks in %.3f s" % (ticks[0], elapsed))


if __name__ == "__main__":
    unittest.main()
