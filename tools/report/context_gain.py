#!/usr/bin/env python3
"""What richer coefficient contexts could save on a coded scene (issue #31, item 2).

Recovers each plane tensor's quantized block-DCT levels from the decoded grids (the float DCT of
the decoded values over the stream's step; exact inside the tensor, approximate in blocks that the
encoder padded) and measures the adaptive code length of their magnitude classes (0..15, signs and
remainders left out: they are the same in every variant) under nested context sets:

  band+inner  frequency band (k0+k1+k2) and the capped magnitudes at the three lower frequencies
              of the same block (what the in-block contexts of SPEC.md 6.4 see)
  +spatial    the co-located coefficient of the blocks above and to the left (the 1.4 neighbour set)
  +channel    the co-located coefficient of the previous channel block: the other components
  both        +spatial and +channel, each its own context dimension (4 x 4 values)
  merged      the larger of the spatial and channel neighbours in one dimension (4 values): the
              channel's information without more contexts to learn

The code length of an adaptive Krichevsky-Trofimov coder depends only on each context's final
counts, so the estimate includes the cost of learning every context (dilution), as a real adaptive
coder pays it.

  python3 tools/report/context_gain.py SCENE.ecrf [--module build/python] [--ecrf build/tools/ecrf]
"""
import argparse
import re
import subprocess
import sys
from math import log

import numpy as np
from scipy.special import gammaln

N = 16  # plane block length along each axis (the default 16x16x16; other shapes are refused)
K = 16  # magnitude classes


def kt_bits(ctx, sym, nctx):
    counts = np.zeros((nctx, K))
    np.add.at(counts, (ctx, sym), 1)
    total = counts.sum(1)
    nats = (gammaln(total + K / 2) - gammaln(K / 2) -
            (gammaln(counts + 0.5) - gammaln(0.5)).sum(1)).sum()
    return nats / log(2)


def dct_matrix(n):
    k = np.arange(n)[:, None]
    i = np.arange(n)[None, :]
    return np.sqrt(np.where(k == 0, 1.0 / n, 2.0 / n)) * np.cos(np.pi * (2 * i + 1) * k / (2 * n))


def block_levels(tensor, step):
    """tensor [rows][columns][rank] -> levels [B0][k0][B1][k1][B2][k2] of channel x row x column
    blocks, edge-padded as the encoder pads (SPEC.md 6.8)."""
    x = np.transpose(np.asarray(tensor, np.float64), (2, 0, 1))
    x = np.pad(x, [(0, (-d) % N) for d in x.shape], mode='edge')
    b = [d // N for d in x.shape]
    x = x.reshape(b[0], N, b[1], N, b[2], N)
    d = dct_matrix(N)
    for axis in (1, 3, 5):
        x = np.moveaxis(np.tensordot(d, x, axes=([1], [axis])), 0, axis)
    return np.round(x / step).astype(np.int64)


def shifted(x, axis):
    """x moved one step along axis: y[.., i, ..] = x[.., i-1, ..], zero at i = 0."""
    y = np.zeros_like(x)
    dst = [slice(None)] * x.ndim
    src = [slice(None)] * x.ndim
    dst[axis] = slice(1, None)
    src[axis] = slice(0, -1)
    y[tuple(dst)] = x[tuple(src)]
    return y


def main():
    p = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    p.add_argument('scene')
    p.add_argument('--module', default='build/python', help='directory of the ecrf Python module')
    p.add_argument('--ecrf', default='build/tools/ecrf', help='the ecrf tool (for the steps)')
    a = p.parse_args()
    sys.path.insert(0, a.module)
    import ecrf

    info = subprocess.run([a.ecrf, 'info', a.scene], capture_output=True, text=True,
                          check=True).stdout
    chunks = {}
    for m in re.finditer(r'^(density|appearance)\.plane\.(\d)\s+(\d+)\s+\d+\s+(\S+)\s+(\S+)',
                         info, re.M):
        chunks[(m.group(1), int(m.group(2)))] = (m.group(4), float(m.group(5)), int(m.group(3)))
    scene = ecrf.decode(a.scene)
    kk = np.arange(N)
    totals = {}
    print(f'{a.scene}: magnitude-class bytes of the plane coefficients per context set')
    print(f'{"tensor":20s} {"blocks":>9s} {"file":>8s} {"band+inner":>11s} {"+spatial":>16s} '
          f'{"+channel":>16s} {"both":>16s} {"merged":>16s}')
    for g, gname in ((0, 'density'), (1, 'appearance')):
        for t in range(3):
            if (gname, t) not in chunks:
                continue
            shape, step, coded = chunks[(gname, t)]
            if shape != f'{N}x{N}x{N}':
                sys.exit(f'{gname}.plane.{t}: block {shape}, this estimate reads {N}x{N}x{N} only')
            mag = np.minimum(np.abs(block_levels(scene.tensor(g, t), step)), K - 1)
            band = np.broadcast_to(
                np.minimum(kk[:, None, None] + kk[None, :, None] + kk[None, None, :],
                           23)[None, :, None, :, None, :], mag.shape)
            inner = np.minimum(shifted(mag, 1) + shifted(mag, 3) + shifted(mag, 5), 6)
            spatial = np.minimum(np.maximum(shifted(mag, 2), shifted(mag, 4)), 3)
            channel = np.minimum(shifted(mag, 0), 3)
            merged = np.maximum(spatial, channel)

            def cost(*fields):
                ctx = np.zeros(mag.shape, np.int64)
                n = 1
                for f, m in fields:
                    ctx = ctx * m + f
                    n *= m
                return kt_bits(ctx.ravel(), mag.ravel(), n) / 8

            row = {'file': coded,
                   'base': cost((band, 24), (inner, 7)),
                   'spatial': cost((band, 24), (inner, 7), (spatial, 4)),
                   'channel': cost((band, 24), (inner, 7), (channel, 4)),
                   'both': cost((band, 24), (inner, 7), (spatial, 4), (channel, 4)),
                   'merged': cost((band, 24), (inner, 7), (merged, 4))}
            for key, v in row.items():
                totals[key] = totals.get(key, 0) + v
            rel = lambda key: f'{row[key]:8.0f} ({100 * (row[key] / row["base"] - 1):+5.1f}%)'
            blocks = 'x'.join(str(d) for d in mag.shape[0::2])
            print(f'{gname + ".plane." + str(t):20s} {blocks:>9s} {coded:8d} {row["base"]:11.0f} '
                  f'{rel("spatial")} {rel("channel")} {rel("both")} {rel("merged")}')
    rel = lambda key: f'{totals[key]:8.0f} ({100 * (totals[key] / totals["base"] - 1):+5.1f}%)'
    print(f'{"all planes":20s} {"":>9s} {totals["file"]:8.0f} {totals["base"]:11.0f} '
          f'{rel("spatial")} {rel("channel")} {rel("both")} {rel("merged")}')
    best = min(totals['both'], totals['merged'])
    print(f'the channel context on top of the spatial one (the better of both and merged): '
          f'{100 * (best / totals["spatial"] - 1):+.2f}% of the magnitude classes, '
          f'{100 * (best - totals["spatial"]) / totals["file"]:+.2f}% of the plane bytes')


if __name__ == '__main__':
    main()
