#!/usr/bin/env python3
"""How far estimated cameras are from the true ones, up to the similarity structure from motion
cannot know: camera centres after the best similarity (Umeyama), as RMS of the true centres'
spread, and the orientation error after the same rotation.

usage: camera_error.py TRUE_TRANSFORMS.json ESTIMATED.json [...]

The files are transforms.json-style (frames with file_path and transform_matrix): the truth from
ecrf_export_capture, the estimates from `ecrf prepare` (DATA/transforms.json) or from training
(RUN/cameras_refined.json). Frames are matched by file name without folder and extension; frame
names ending in a number divisible by 8 are the held-out ones. Needs numpy.
"""
import json
import os
import sys

import numpy as np


def load(path):
    with open(path) as f:
        data = json.load(f)
    cameras = {}
    for frame in data["frames"]:
        name = os.path.splitext(os.path.basename(frame["file_path"]))[0]
        cameras[name] = np.array(frame["transform_matrix"], float)[:3]
    return cameras, data


def similarity(src, dst):
    """Scale, rotation and translation carrying src points onto dst (Umeyama 1991)."""
    mu_s, mu_d = src.mean(0), dst.mean(0)
    s, d = src - mu_s, dst - mu_d
    u, sv, vt = np.linalg.svd(d.T @ s / len(src))
    fix = np.eye(3)
    fix[2, 2] = np.sign(np.linalg.det(u @ vt))
    rotation = u @ fix @ vt
    scale = np.trace(np.diag(sv) @ fix) / (s**2).sum(1).mean()
    return scale, rotation, mu_d - scale * rotation @ mu_s


def main():
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    truth, _ = load(sys.argv[1])
    for path in sys.argv[2:]:
        estimate, data = load(path)
        names = sorted(set(truth) & set(estimate))
        if len(names) < 3:
            sys.exit(f"{path}: fewer than 3 frames in common with {sys.argv[1]}")
        src = np.array([estimate[n][:, 3] for n in names])
        dst = np.array([truth[n][:, 3] for n in names])
        scale, rotation, shift = similarity(src, dst)
        spread = np.sqrt(((dst - dst.mean(0)) ** 2).sum(1).mean())
        for subset in ("all", "train", "test"):
            chosen = [n for n in names
                      if subset == "all" or (int(n[-3:]) % 8 == 0) == (subset == "test")]
            if not chosen:
                continue
            centre_error, angle = [], []
            for n in chosen:
                centre = scale * rotation @ estimate[n][:, 3] + shift
                centre_error.append(np.linalg.norm(centre - truth[n][:, 3]))
                turned = rotation @ estimate[n][:, :3]
                cos = (np.trace(turned.T @ truth[n][:, :3]) - 1) / 2
                angle.append(np.degrees(np.arccos(np.clip(cos, -1, 1))))
            rms = np.sqrt(np.mean(np.square(centre_error)))
            print(f"{path} {subset}: centres {100 * rms / spread:.2f} % of the spread (RMS), "
                  f"orientation {np.mean(angle):.3f} deg mean, {np.max(angle):.3f} max")
        first = data["frames"][0]
        lens = {k: data.get(k, first.get(k)) for k in
                ("w", "fl_x", "fl_y", "cx", "cy", "k1", "k2", "p1", "p2")}
        print(f"{path} intrinsics: " +
              ", ".join(f"{k} {v:.4g}" for k, v in lens.items() if v is not None))


if __name__ == "__main__":
    main()
