#!/usr/bin/env python3
"""Checks a springy report folder without a browser (ctest report_browser runs it first).

  references  every src and href of every page names a file inside the report (no network, no
              path outside the folder, nothing missing); anchors (#...) name an id on the page
  markup      every page starts with <!doctype html>, has <html lang>, a <title>, a charset, and its
              elements nest: each closes the one opened last (void elements excepted)
  replay      with --replay REPLAY.js PC2 FPS: the 3D replay's frames, decoded as the viewer
              decodes them (base64, zlib, sums of 32-bit changes, times each body's quantum),
              equal the point cache `springy export` wrote of the same run at every kept frame,
              within half a quantum (plus the cache's float32 rounding); a collider or prop that
              moves: its mesh at rest placed by its pose at each kept frame (translation and
              quaternion, as three.js places it) equals its own point cache (PC2's NAME.collider0.pc2
              beside it) within 1e-6 m; --replay may be given more than once
  size        with --max-bytes N: the report's files but its videos (.mp4) take at most N bytes

usage: report_check.py REPORT_DIR [--replay REPLAY.js PC2 FPS]... [--max-bytes N]
"""
import argparse
import base64
import html.parser
import json
import os
import re
import struct
import sys
import urllib.parse
import zlib

VOID = {"area", "base", "br", "col", "embed", "hr", "img", "input", "link", "meta", "source", "track", "wbr"}
# Closed implicitly by the next of their kind or by their parent's end (HTML's optional end tags).
OPTIONAL_END = {"li", "dt", "dd", "p", "tr", "td", "th", "option"}

failures = []


def check(ok, what):
    if not ok:
        failures.append(what)
    print(("ok   " if ok else "FAIL ") + what)


class Page(html.parser.HTMLParser):
    def __init__(self):
        super().__init__(convert_charrefs=True)
        self.refs, self.ids, self.stack, self.problems = [], set(), [], []
        self.doctype = self.title = self.charset = self.lang = False

    def handle_decl(self, decl):
        self.doctype = self.doctype or decl.lower() == "doctype html"

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        if "id" in a:
            self.ids.add(a["id"])
        for key in ("src", "href"):
            if a.get(key) is not None:
                self.refs.append((tag, a[key]))
        self.title = self.title or tag == "title"
        self.charset = self.charset or (tag == "meta" and "charset" in a)
        self.lang = self.lang or (tag == "html" and bool(a.get("lang")))
        if tag in VOID:
            return
        if tag in OPTIONAL_END and self.stack and self.stack[-1] == tag:
            self.stack.pop()
        self.stack.append(tag)

    def handle_startendtag(self, tag, attrs):
        self.handle_starttag(tag, attrs)
        if tag not in VOID:
            self.stack.pop()

    def handle_endtag(self, tag):
        if tag in VOID:
            self.problems.append(f"</{tag}> closes a void element")
            return
        while self.stack and self.stack[-1] != tag and self.stack[-1] in OPTIONAL_END:
            self.stack.pop()
        if not self.stack or self.stack[-1] != tag:
            self.problems.append(f"</{tag}> closes <{self.stack[-1] if self.stack else 'nothing'}>")
            return
        self.stack.pop()


def check_pages(root):
    root = os.path.realpath(root)
    pages = []
    for folder, _, files in os.walk(root):
        pages += [os.path.join(folder, f) for f in files if f.endswith(".html")]
    check(len(pages) > 0, f"{len(pages)} pages in {root}")
    references = 0
    for page in sorted(pages):
        name = os.path.relpath(page, root)
        p = Page()
        with open(page, encoding="utf-8") as f:
            p.feed(f.read())
        p.close()
        check(p.doctype and p.lang and p.title and p.charset, f"{name}: doctype, lang, title and charset")
        open_left = [t for t in p.stack if t not in OPTIONAL_END]
        check(not p.problems and not open_left,
              f"{name}: elements nest ({'; '.join(p.problems[:3]) or 'unclosed: ' + ', '.join(open_left) if p.problems or open_left else 'all closed'})")
        for tag, ref in p.refs:
            references += 1
            url = urllib.parse.urlsplit(ref)
            if url.scheme or url.netloc or ref.startswith("/"):
                check(False, f"{name}: <{tag}> {ref} leaves the folder (the report must open offline)")
                continue
            if not url.path:
                check(url.fragment in p.ids, f"{name}: anchor #{url.fragment} names an id on the page")
                continue
            target = os.path.realpath(os.path.join(os.path.dirname(page), urllib.parse.unquote(url.path)))
            inside = target.startswith(root + os.sep)
            if not (inside and os.path.isfile(target)):
                check(False, f"{name}: <{tag}> {ref} is {'outside the report' if not inside else 'missing'}")
    check(not any("leaves the folder" in f or "missing" in f or "outside" in f for f in failures),
          f"{references} references, every one to a file in the report")


def read_replay(path):
    with open(path, encoding="utf-8") as f:
        text = f.read()
    data = json.loads(re.search(r"window\.springyReplayData = (\{.*?\});\n", text).group(1))
    motion = re.search(r'window\.springyReplayMotion = "([A-Za-z0-9+/=]*)";', text).group(1)
    deltas = zlib.decompress(base64.b64decode(motion))
    return data, struct.unpack(f"<{len(deltas) // 4}i", deltas)


def check_replay(replay, pc2, fps):
    data, deltas = read_replay(replay)
    points = sum(b["vertices"] for b in data["bodies"])
    frames = data["frames"]
    check(len(deltas) == 3 * points * frames, f"replay: {frames} frames of {points} points")
    count, samples, cache = read_pc2(pc2)
    check(count == points, f"replay: the point cache has the same {count} points")
    stride = round(fps / data["fps"])
    check(stride >= 1 and abs(fps / stride - data["fps"]) < 1e-9 and (frames - 1) * stride < samples,
          f"replay: every {stride}. frame of the run's {samples} ({data['fps']:g} frames/s)")
    quanta = []
    for b in data["bodies"]:
        quanta += [b["quantum"]] * (3 * b["vertices"])
    sums = [0] * (3 * points)
    worst = 0.0
    for k in range(frames):
        row = struct.unpack_from(f"<{3 * points}f", cache, 4 * 3 * points * k * stride)
        for i in range(3 * points):
            sums[i] += deltas[3 * points * k + i]
            x = sums[i] * quanta[i]
            err = abs(x - row[i]) / (0.5 * quanta[i] + 2.0 ** -22 * abs(row[i]))
            worst = max(worst, err)
    check(worst <= 1.0, f"replay: every position within half a quantum of the point cache (worst {worst:.3f} of the bound)")
    check_moving(data, pc2, stride)


def read_pc2(path):
    """(points, samples, the floats of every sample)"""
    with open(path, "rb") as f:
        _, _, count, _, _, samples = struct.unpack("<12siiffi", f.read(32))
        cache = f.read()
    return count, samples, cache


def rotated(q, v):
    """v turned by the unit quaternion q = (x, y, z, w)."""
    x, y, z, w = q
    # v + 2 w (u x v) + 2 u x (u x v), u = (x, y, z)
    c = (y * v[2] - z * v[1], z * v[0] - x * v[2], x * v[1] - y * v[0])
    cc = (y * c[2] - z * c[1], z * c[0] - x * c[2], x * c[1] - y * c[0])
    return [v[i] + 2 * w * c[i] + 2 * cc[i] for i in range(3)]


def check_moving(data, pc2, stride):
    """Each moving collider's or prop's mesh, placed by its poses, against its own point cache."""
    moving = [s for s in data["stills"] if "translations" in s]
    for s in moving:
        name = s["name"].replace(" ", "")
        frames = data["frames"]
        xyz = struct.unpack(f"<{len(base64.b64decode(s['xyz'])) // 4}f", base64.b64decode(s["xyz"]))
        t = struct.unpack(f"<{3 * frames}f", base64.b64decode(s["translations"]))
        r = struct.unpack(f"<{4 * frames}f", base64.b64decode(s["rotations"])) if "rotations" in s else None
        count, samples, cache = read_pc2(pc2[:-len(".pc2")] + "." + name + ".pc2")
        check(count == len(xyz) // 3, f"replay: {s['name']} has {count} points, as its point cache")
        worst, moved = 0.0, 0.0
        for k in range(frames):
            row = struct.unpack_from(f"<{3 * count}f", cache, 12 * count * k * stride)
            q = r[4 * k:4 * k + 4] if r else (0.0, 0.0, 0.0, 1.0)
            for i in range(count):
                p = rotated(q, xyz[3 * i:3 * i + 3])
                for c in range(3):
                    worst = max(worst, abs(p[c] + t[3 * k + c] - row[3 * i + c]))
                    moved = max(moved, abs(row[3 * i + c] - xyz[3 * i + c]))
        check(worst <= 1e-6, f"replay: {s['name']} placed by its poses at {frames} frames equals its point cache "
              f"(worst {worst:.2g} m)")
        check(moved > 0.01, f"replay: {s['name']} moves ({moved:.3g} m at most)")


def check_size(root, most):
    total = 0
    for folder, _, files in os.walk(root):
        total += sum(os.path.getsize(os.path.join(folder, f)) for f in files if not f.endswith(".mp4"))
    check(total <= most, f"the report but its videos takes {total} bytes (at most {most})")


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("report")
    parser.add_argument("--replay", nargs=3, metavar=("REPLAY", "PC2", "FPS"), action="append", default=[])
    parser.add_argument("--max-bytes", type=int)
    a = parser.parse_args()
    check_pages(a.report)
    for replay, pc2, fps in a.replay:
        check_replay(replay, pc2, float(fps))
    if a.max_bytes:
        check_size(a.report, a.max_bytes)
    if failures:
        print(f"report_check: {len(failures)} failed", file=sys.stderr)
        sys.exit(1)


if __name__ == "__main__":
    main()
