#!/usr/bin/env python3
"""PSNR of an ecrf_gl_replay image (PPM) against a reference render (PNG or PPM): the check of
web/test/gpu_test.mjs (PSNR over RGB, >= 40 dB) plus the SPEC 7.7 pixel criterion (the fraction of
pixels whose largest channel difference is <= 2 codes). Needs python3 and numpy (PNGs are read
with Pillow where installed, else with zlib: fast for the unfiltered PNGs make-devbench stores).

  gl_replay_compare.py IMAGE.ppm REF.png [--min-psnr 40] [--merge REPLAY_LINE.json] [--png OUT.png]

Prints one JSON line: the replay's line (--merge: a file holding ecrf_gl_replay's JSON line) with
psnr, max_diff, within2, reference and pass added. Exit status 1 when the PSNR is below --min-psnr
or an image cannot be read.
"""
import argparse
import json
import math
import struct
import sys
import zlib

import numpy as np


def read_ppm(data):
    # P6, maxval 255; comments are not written by ecrf_gl_replay and not supported.
    fields, pos = [], 2
    while len(fields) < 3:
        while data[pos:pos + 1].isspace():
            pos += 1
        start = pos
        while not data[pos:pos + 1].isspace():
            pos += 1
        fields.append(int(data[start:pos]))
    w, h, maxval = fields
    if maxval != 255:
        raise ValueError("PPM maxval %d" % maxval)
    pos += 1
    px = np.frombuffer(data, dtype=np.uint8, count=w * h * 3, offset=pos)
    return px.reshape(h, w, 3)


def read_png(data):
    pos, w, h, channels, idat = 8, 0, 0, 0, []
    while pos + 8 <= len(data):
        n, kind = struct.unpack(">I4s", data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + n]
        if kind == b"IHDR":
            w, h, depth, ctype, _, _, interlace = struct.unpack(">IIBBBBB", body)
            channels = {0: 1, 2: 3, 4: 2, 6: 4}.get(ctype, 0)
            if depth != 8 or not channels or interlace:
                raise ValueError("unsupported PNG (8-bit grey/RGB/RGBA, not interlaced only)")
        elif kind == b"IDAT":
            idat.append(body)
        elif kind == b"IEND":
            break
        pos += 12 + n
    raw = np.frombuffer(zlib.decompress(b"".join(idat)), dtype=np.uint8)
    stride = w * channels
    raw = raw.reshape(h, stride + 1)
    out = np.zeros((h, stride), dtype=np.int32)
    prev = np.zeros(stride, dtype=np.int32)
    for y in range(h):
        f, row = raw[y, 0], raw[y, 1:].astype(np.int32)
        if f == 0:
            cur = row
        elif f == 1:
            cur = (np.cumsum(row.reshape(w, channels), axis=0) & 255).reshape(stride)
        elif f == 2:
            cur = (row + prev) & 255
        else:  # 3 (average), 4 (Paeth): byte by byte (slow; Pillow is used when installed)
            cur = np.zeros(stride, dtype=np.int32)
            for i in range(stride):
                a = int(cur[i - channels]) if i >= channels else 0
                b = int(prev[i])
                c = int(prev[i - channels]) if i >= channels else 0
                if f == 1:
                    p = a
                elif f == 3:
                    p = (a + b) >> 1
                elif f == 4:
                    pa, pb, pc = abs(b - c), abs(a - c), abs(a + b - 2 * c)
                    p = a if pa <= pb and pa <= pc else (b if pb <= pc else c)
                else:
                    raise ValueError("bad PNG filter %d" % f)
                cur[i] = (int(row[i]) + p) & 255
        out[y] = cur
        prev = cur
    img = out.astype(np.uint8).reshape(h, w, channels)
    if channels == 1 or channels == 2:
        img = np.repeat(img[:, :, :1], 3, axis=2)
    return img[:, :, :3]


def read_image(path):
    with open(path, "rb") as f:
        data = f.read()
    if data[:2] == b"P6":
        return read_ppm(data)
    if data[:8] == b"\x89PNG\r\n\x1a\n":
        try:
            from PIL import Image  # fast, where installed
            with Image.open(path) as im:
                return np.asarray(im.convert("RGB"))
        except ImportError:
            return read_png(data)
    raise ValueError("%s: neither a P6 PPM nor a PNG" % path)


def write_png(path, rgb):
    h, w, _ = rgb.shape
    raw = b"".join(b"\x00" + rgb[y].tobytes() for y in range(h))

    def chunk(kind, body):
        return struct.pack(">I", len(body)) + kind + body + struct.pack(">I", zlib.crc32(kind + body))

    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0)) +
                chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b""))


def compare(img, ref):
    d = img.astype(np.int32) - ref.astype(np.int32)
    mse = float(np.mean(d * d))
    per_pixel = np.abs(d).max(axis=2)
    return {
        "psnr": math.inf if mse == 0 else 10 * math.log10(255 * 255 / mse),
        "max_diff": int(per_pixel.max()),
        "within2": float(np.mean(per_pixel <= 2)),
    }


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("image")
    ap.add_argument("reference")
    ap.add_argument("--min-psnr", type=float, default=40.0)
    ap.add_argument("--merge", help="a file with ecrf_gl_replay's JSON line for this image")
    ap.add_argument("--png", help="also write the image as this PNG")
    a = ap.parse_args()
    line = {}
    if a.merge:
        with open(a.merge) as f:
            text = f.read().strip()
        line = json.loads(text.splitlines()[-1]) if text else {}
    try:
        img, ref = read_image(a.image), read_image(a.reference)
        if img.shape != ref.shape:
            raise ValueError("image %s vs reference %s" % (img.shape, ref.shape))
        c = compare(img, ref)
        if a.png:
            write_png(a.png, img)
    except (OSError, ValueError) as e:
        line.update({"reference": a.reference, "pass": False, "compare_error": str(e)})
        print(json.dumps(line))
        return 1
    ok = c["psnr"] >= a.min_psnr
    line.update({"reference": a.reference, "psnr": round(c["psnr"], 3) if c["psnr"] != math.inf else "inf",
                 "max_diff": c["max_diff"], "within2": round(c["within2"], 6), "min_psnr": a.min_psnr,
                 "pass": ok})
    print(json.dumps(line))
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
