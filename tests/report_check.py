#!/usr/bin/env python3
"""Checks a springy report folder without a browser (ctest report_browser runs it first).

  references  every src and href of every page names a file inside the report (no network, no
              path outside the folder, nothing missing); anchors (#...) name an id on the page
  markup      every page starts with <!doctype html>, has <html lang>, a <title>, a charset, and its
              elements nest: each closes the one opened last (void elements excepted)
  replay      with --replay REPLAY.js PC2 FPS: the 3D replay's frames, decoded as the viewer
              decodes them (base64, zlib, sums of 32-bit changes, times each body's quantum),
              equal the point cache `springy export` wrote of the same run at every kept frame,
              within half a quantum (plus the cache's float32 rounding)
  size        with --max-bytes N: the report's files but its videos (.mp4) take at most N bytes

usage: report_check.py REPORT_DIR [--replay REPLAY.js PC2 FPS] [--max-bytes N]
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
    with open(pc2, "rb") as f:
        header = f.read(32)
        _, _, count, _, _, samples = struct.unpack("<12siiffi", header)
        cache = f.read()
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


def check_size(root, most):
    total = 0
    for folder, _, files in os.walk(root):
        total += sum(os.path.getsize(os.path.join(folder, f)) for f in files if not f.endswith(".mp4"))
    check(total <= most, f"the report but its videos takes {total} bytes (at most {most})")


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("report")
    parser.add_argument("--replay", nargs=3, metavar=("REPLAY", "PC2", "FPS"))
    parser.add_argument("--max-bytes", type=int)
    a = parser.parse_args()
    check_pages(a.report)
    if a.replay:
        check_replay(a.replay[0], a.replay[1], float(a.replay[2]))
    if a.max_bytes:
        check_size(a.report, a.max_bytes)
    if failures:
        print(f"report_check: {len(failures)} failed", file=sys.stderr)
        sys.exit(1)


if __name__ == "__main__":
    main()
