#!/usr/bin/env python3
"""Would colour tell packed objects apart where convexity joins them? (BENCHMARKS.md, "Colour
across packed boxes"). Reads build/bench/patch_study's files and the scenes' colours (the rgb or
rgba field of a PCD: ascii, binary or binary_compressed) and compares the colour difference
(CIE76 dE of the patches' mean CIELAB colours) of adjacent patches that convexity grouping left
in one segment: pairs across two objects against pairs inside one.

    build/bench/patch_study /tmp/patches $ESF_DATA/real/scenes/mosd_test*.pcd
    bench/patch_colour_study.py /tmp/patches $ESF_DATA/real/scenes/mosd_test*.pcd
"""
import argparse
import csv
import os
import struct
import sys

import numpy as np


def lzf_decompress(data, size):
    out = bytearray(size)
    ip = op = 0
    while ip < len(data):
        ctrl = data[ip]
        ip += 1
        if ctrl < 32:
            n = ctrl + 1
            out[op:op + n] = data[ip:ip + n]
            ip += n
            op += n
            continue
        n = ctrl >> 5
        ref = op - ((ctrl & 0x1F) << 8) - 1
        if n == 7:
            n += data[ip]
            ip += 1
        ref -= data[ip]
        ip += 1
        n += 2
        for k in range(n):  # may overlap its own output
            out[op + k] = out[ref + k]
        op += n
    if op != size:
        raise ValueError("LZF block decompresses to %d bytes, header says %d" % (op, size))
    return bytes(out)


def pcd_colours(path):
    """The packed 0x00RRGGBB colour of every point of a PCD file."""
    raw = open(path, "rb").read()
    start = raw.index(b"\nDATA ") + 1
    end = raw.index(b"\n", start)
    header = {}
    for line in raw[:end].decode("ascii").splitlines():
        if line and not line.startswith("#"):
            key, *values = line.split()
            header[key] = values
    fields, sizes, types = header["FIELDS"], list(map(int, header["SIZE"])), header["TYPE"]
    counts = list(map(int, header.get("COUNT", ["1"] * len(fields))))
    points = int(header["POINTS"][0])
    name = "rgba" if "rgba" in fields else "rgb"
    if name not in fields:
        raise ValueError("%s: no rgb or rgba field" % path)
    f = fields.index(name)
    body = raw[end + 1:]
    kind = header["DATA"][0]
    if kind == "ascii":
        rows = body.decode("ascii").split("\n")[:points]
        column = sum(counts[:f])
        values = np.array([float(r.split()[column]) for r in rows], np.float32)
        return values.view(np.uint32) & 0xFFFFFF
    if kind == "binary_compressed":
        packed, size = struct.unpack("<II", body[:8])
        data = lzf_decompress(body[8:8 + packed], size)
        offset = sum(s * c * points for s, c in zip(sizes[:f], counts[:f]))
        return np.frombuffer(data, np.uint32, points, offset) & 0xFFFFFF
    record = sum(s * c for s, c in zip(sizes, counts))
    offset = sum(s * c for s, c in zip(sizes[:f], counts[:f]))
    block = np.frombuffer(body, np.uint8, points * record).reshape(points, record)
    return block[:, offset:offset + 4].copy().view(np.uint32).ravel() & 0xFFFFFF


def cielab(packed):
    rgb = np.stack([(packed >> 16) & 255, (packed >> 8) & 255, packed & 255], 1) / 255.0
    linear = np.where(rgb > 0.04045, ((rgb + 0.055) / 1.055) ** 2.4, rgb / 12.92)
    xyz = linear @ np.array([[0.4124, 0.3576, 0.1805], [0.2126, 0.7152, 0.0722],
                             [0.0193, 0.1192, 0.9505]]).T / np.array([0.9505, 1.0, 1.089])
    f = np.where(xyz > 0.008856, np.cbrt(xyz), 7.787 * xyz + 16.0 / 116.0)
    return np.stack([116 * f[:, 1] - 16, 500 * (f[:, 0] - f[:, 1]), 200 * (f[:, 1] - f[:, 2])], 1)


def read_csv(path):
    with open(path) as f:
        rows = list(csv.reader(f))
    return np.array(rows[1:], dtype=np.int64).reshape(-1, len(rows[0]))


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("patches", help="patch_study's output folder")
    parser.add_argument("scenes", nargs="+", help="the scenes given to patch_study")
    args = parser.parse_args()
    across, inside = [], []
    for scene in args.scenes:
        name = os.path.splitext(os.path.basename(scene))[0]
        points = read_csv(os.path.join(args.patches, name + ".points.csv"))
        edges = read_csv(os.path.join(args.patches, name + ".edges.csv"))
        lab = cielab(pcd_colours(scene))
        patches = points[:, 1].max() + 1
        sums = np.zeros((patches, 3))
        np.add.at(sums, points[:, 1], lab[points[:, 0]])
        mean = sums / np.maximum(np.bincount(points[:, 1], minlength=patches), 1)[:, None]
        joined = edges[edges[:, 2] == 1]
        d = np.linalg.norm(mean[joined[:, 0]] - mean[joined[:, 1]], axis=1)
        cross = joined[:, 3] != joined[:, 4]
        across.append(d[cross])
        inside.append(d[~cross])
        print("%s: %d joined pairs across two objects (dE %s)" %
              (name, cross.sum(), " ".join("%.0f" % v for v in np.sort(d[cross]))))
    across, inside = np.concatenate(across), np.concatenate(inside)
    print("joined pairs: %d across two objects, %d inside one" % (len(across), len(inside)))
    for t in (10, 15, 20, 30, 40):
        print("dE > %2d: across %4d (%5.1f %%)  inside %6d (%5.1f %%)" %
              (t, (across > t).sum(), 100.0 * (across > t).mean() if len(across) else 0,
               (inside > t).sum(), 100.0 * (inside > t).mean() if len(inside) else 0))


if __name__ == "__main__":
    sys.exit(main())
