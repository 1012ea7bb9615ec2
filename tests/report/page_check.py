#!/usr/bin/env python3
"""Checks report pages the way a person opens them: in headless Chromium, offline.

Usage: page_check.py CHROMIUM WORKDIR PAGE...

For every page:
  * it is self-contained: every src= and <image href= is a data: URI, no http(s) resource, and
    it is below 10 MB;
  * every embedded PNG decodes and is not blank (at least 3 distinct colours);
  * Chromium loads it offline (a dead proxy: any network request would fail) and logs no
    console message;
  * its screenshot differs from that of the same page with the pictures taken out in at least
    2,000 pixels showing at least 16 distinct colours: the pictures are on screen.
Prints one line per page (size, pictures, pixels the pictures changed); exits 1 on failure.
"""
import base64
import os
import re
import struct
import subprocess
import sys
import zlib


def decode_png(data):
    """(width, height, channels, rows as bytes) of an 8-bit grey, RGB or RGBA PNG."""
    if data[:8] != b"\x89PNG\r\n\x1a\n":
        raise ValueError("not a PNG")
    pos, idat, header = 8, b"", None
    while pos < len(data):
        length, kind = struct.unpack(">I4s", data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + length]
        if kind == b"IHDR":
            header = struct.unpack(">IIBBBBB", body)
        elif kind == b"IDAT":
            idat += body
        pos += 12 + length
    width, height, depth, colour, _, _, interlace = header
    channels = {0: 1, 2: 3, 6: 4}.get(colour)
    if depth != 8 or channels is None or interlace:
        raise ValueError("unsupported PNG: depth %d colour %d interlace %d" %
                         (depth, colour, interlace))
    raw = zlib.decompress(idat)
    stride = width * channels
    if len(raw) != height * (stride + 1):
        raise ValueError("truncated PNG data")
    rows, previous = [], bytes(stride)
    for y in range(height):
        kind = raw[y * (stride + 1)]
        line = bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        if kind == 2:  # up (the common case: a row like the one above is all zeros)
            line = bytearray(previous) if not any(line) else bytearray(
                (a + b) & 255 for a, b in zip(line, previous))
        elif kind in (1, 3, 4):
            for i in range(stride):
                a = line[i - channels] if i >= channels else 0
                b = previous[i]
                c = previous[i - channels] if i >= channels else 0
                if kind == 1:
                    line[i] = (line[i] + a) & 255
                elif kind == 3:
                    line[i] = (line[i] + (a + b) // 2) & 255
                else:
                    p = a + b - c
                    pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                    line[i] = (line[i] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
        elif kind != 0:
            raise ValueError("bad PNG filter %d" % kind)
        previous = bytes(line)
        rows.append(previous)
    return width, height, channels, rows


def colours(row, channels, xs=None):
    """The set of RGB colours of a decoded row (of the pixels xs, default all)."""
    xs = range(len(row) // channels) if xs is None else xs
    if channels == 1:
        return {(row[x],) * 3 for x in xs}
    return {bytes(row[x * channels:x * channels + 3]) for x in xs}


def screenshot(chromium, workdir, page, name):
    shot = os.path.join(workdir, name)
    if os.path.exists(shot):
        os.remove(shot)
    run = subprocess.run(
        [chromium, "--headless", "--disable-gpu", "--no-sandbox", "--no-first-run",
         "--user-data-dir=" + os.path.join(workdir, "profile"), "--enable-logging=stderr",
         "--v=0", "--proxy-server=127.0.0.1:9", "--hide-scrollbars",
         "--window-size=1280,4000", "--screenshot=" + shot, "file://" + os.path.abspath(page)],
        capture_output=True, text=True, timeout=120)
    console = [l for l in run.stderr.splitlines() if ":CONSOLE" in l]
    if run.returncode != 0 or not os.path.exists(shot):
        raise RuntimeError("chromium failed (%d): %s" % (run.returncode, run.stderr[-2000:]))
    with open(shot, "rb") as f:
        return decode_png(f.read()), console


def check(chromium, workdir, page):
    problems = []
    size = os.path.getsize(page)
    with open(page, encoding="utf-8") as f:
        html = f.read()
    if size > 10 * 1024 * 1024:
        problems.append("%d bytes, over 10 MB" % size)
    for ref in re.findall(r'(?:\ssrc|<image[^>]*\shref)="([^"]*)"', html):
        if not ref.startswith("data:"):
            problems.append("a resource that is not embedded: " + ref[:80])
    if re.search(r'(?:src|href)="https?:', html):
        problems.append("a link to the network")
    uris = re.findall(r'data:image/png;base64,([A-Za-z0-9+/=]*)', html)
    for n, uri in enumerate(uris):
        try:
            _, _, channels, rows = decode_png(base64.b64decode(uri))
        except Exception as e:  # noqa: BLE001 - any decoding problem is a failure
            problems.append("embedded picture %d does not decode: %s" % (n, e))
            continue
        if len(set().union(*(colours(row, channels) for row in rows))) < 3:
            problems.append("embedded picture %d is blank" % n)
    (w, h, channels, with_pictures), console = screenshot(chromium, workdir, page, "with.png")
    problems += ["console: " + l for l in console]
    bare = os.path.join(workdir, "bare.html")
    with open(bare, "w", encoding="utf-8") as f:
        f.write(re.sub(r'data:image/png;base64,[A-Za-z0-9+/=]*', "", html))
    (_, _, bare_channels, without), _ = screenshot(chromium, workdir, bare, "without.png")
    changed, shown = 0, set()
    if bare_channels != channels:
        problems.append("the two screenshots differ in format")
    else:
        for y in range(h):
            if with_pictures[y] == without[y]:
                continue
            xs = [x for x in range(w) if with_pictures[y][x * channels:(x + 1) * channels] !=
                  without[y][x * channels:(x + 1) * channels]]
            changed += len(xs)
            shown |= colours(with_pictures[y], channels, xs)
    if uris and (changed < 2000 or len(shown) < 16):
        problems.append("the pictures are not on screen: %d pixels changed, %d colours" %
                        (changed, len(shown)))
    print("%s: %.1f kB, %d pictures, %d pixels from pictures in %d colours%s" %
          (os.path.basename(page), size / 1024.0, len(uris), changed, len(shown),
           "" if not problems else ", FAILED"))
    for p in problems:
        print("  " + p)
    return not problems


def main():
    chromium, workdir, pages = sys.argv[1], sys.argv[2], sys.argv[3:]
    ok = all([check(chromium, workdir, page) for page in pages])
    sys.exit(0 if ok and pages else 1)


if __name__ == "__main__":
    main()
