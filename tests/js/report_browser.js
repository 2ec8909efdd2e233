// ctest report_browser: a springy report opened in headless Chromium (Debian's chromium, driven by
// playwright-core), as a reader would open it: from the folder (file://), no network.
//   every page: no console error, no page error, no failed request; every image decoded
//   (naturalWidth > 0); every link to a page opens it
//   a scene's page: the video plays past 6 s and its frame is drawn (not one colour); the 3D
//   replay draws a canvas that is not empty, and seeking it to the last frame changes the picture;
//   where a collider moves (the press's plate), seeking moves its mesh as its poses say; at least
//   one page has one
// usage: node report_browser.js REPORT_DIR
"use strict";
const fs = require("fs");
const path = require("path");
const { chromium } = require("playwright-core");

const root = path.resolve(process.argv[2]);
const failures = [];
function check(ok, what) {
  if (!ok) failures.push(what);
  console.log(`${ok ? "ok  " : "FAIL"} ${what}`);
}

// Pixels of an element as the page shows it on the screen (a screenshot: a video from a file://
// page may not be read back by the page itself): how many differ from the corner's colour, and
// a hash of them all.
async function pixelStats(page, selector) {
  const png = await page.locator(selector).screenshot();
  return page.evaluate(async (base64) => {
    const image = new Image();
    image.src = "data:image/png;base64," + base64;
    await image.decode();
    const c = document.createElement("canvas");
    c.width = image.naturalWidth, c.height = image.naturalHeight;
    const g = c.getContext("2d");
    g.drawImage(image, 0, 0);
    const d = g.getImageData(0, 0, c.width, c.height).data;
    let differing = 0, hash = 0;
    for (let i = 0; i < d.length; i += 4) {
      if (Math.abs(d[i] - d[0]) + Math.abs(d[i + 1] - d[1]) + Math.abs(d[i + 2] - d[2]) > 24) differing++;
      hash = (hash * 31 + d[i] + 7 * d[i + 1] + 13 * d[i + 2]) % 1000000007;
    }
    return { pixels: c.width * c.height, differing, hash };
  }, png.toString("base64"));
}

// The 3D view's own pixels (its WebGL canvas, read back: transparent where nothing was drawn, the
// sky being the page's background behind it): how many are drawn.
async function canvasDrawn(page) {
  return page.evaluate(() => {
    const el = document.querySelector(".springy-replay-canvas canvas");
    const c = document.createElement("canvas");
    c.width = el.width, c.height = el.height;
    const g = c.getContext("2d");
    g.drawImage(el, 0, 0);
    const d = g.getImageData(0, 0, c.width, c.height).data;
    let drawn = 0;
    for (let i = 3; i < d.length; i += 4) drawn += d[i] > 0 ? 1 : 0;
    return { pixels: c.width * c.height, drawn };
  });
}

async function openPage(browser, file) {
  const page = await browser.newPage({ viewport: { width: 1280, height: 900 } });
  const problems = [];
  page.on("console", (m) => { if (m.type() === "error") problems.push(`console error: ${m.text()}`); });
  page.on("pageerror", (e) => problems.push(`page error: ${e.message}`));
  page.on("requestfailed", (r) => problems.push(`failed to load ${r.url()}: ${r.failure().errorText}`));
  await page.goto("file://" + file, { waitUntil: "load" });
  return { page, problems };
}

async function checkImages(page, name) {
  const images = await page.evaluate(() =>
    [...document.images].map((i) => ({ src: i.getAttribute("src"), ok: i.complete && i.naturalWidth > 0 })));
  for (const i of images) check(i.ok, `${name}: image ${i.src} decoded`);
  return images.length;
}

async function checkLinks(page, file, name) {
  const links = await page.evaluate(() => [...document.querySelectorAll("a[href]")].map((a) => a.getAttribute("href")));
  const pages = [];
  for (const href of links) {
    if (href.startsWith("#")) continue;
    const target = path.resolve(path.dirname(file), decodeURIComponent(href.split("#")[0]));
    check(target.startsWith(root) && fs.existsSync(target), `${name}: link ${href} resolves in the report`);
    if (target.endsWith(".html")) pages.push(target);
  }
  return pages;
}

async function checkScenePage(page, name) {
  // The video: plays (at 4x, muted, so the test waits 1.5 s for 6 s of it) past 6 s, frame drawn.
  const video = await page.evaluate(async () => {
    const v = document.getElementById("video");
    if (!v) return { present: false };
    if (v.readyState < 1) await new Promise((ok, no) => { v.onloadedmetadata = ok; v.onerror = () => no(v.error); });
    v.playbackRate = 4;
    await v.play();
    const deadline = performance.now() + 20000;
    while (v.currentTime < 6.0 && !v.ended && performance.now() < deadline) await new Promise((r) => setTimeout(r, 50));
    // A frame presented at this time (requestVideoFrameCallback fires while playing), then pause.
    await new Promise((r) => { v.requestVideoFrameCallback(() => r()); setTimeout(r, 2000); });
    v.pause();
    return { present: true, duration: v.duration, time: v.currentTime, width: v.videoWidth, error: v.error && v.error.code };
  });
  check(video.present, `${name}: has a video`);
  if (!video.present) return;
  check(video.duration >= 6.0, `${name}: the video lasts ${video.duration} s (at least 6 s)`);
  check(video.time >= 6.0, `${name}: the video played to ${video.time.toFixed(2)} s`);
  const frame = await pixelStats(page, "#video");
  check(frame.pixels > 0 && frame.differing > frame.pixels / 50,
        `${name}: the video's frame at ${video.time.toFixed(2)} s is drawn (${frame.differing} of ${frame.pixels} pixels differ from the corner)`);

  // The 3D replay: ready, drawn, and a different picture at the last frame.
  await page.waitForFunction(() => window.springyViewer && (window.springyViewer.ready || window.springyViewer.error),
                             null, { timeout: 20000 });
  const viewer = await page.evaluate(() => window.springyViewer);
  check(viewer.ready && !viewer.error, `${name}: the 3D replay is ready (${viewer.error || "no error"})`);
  const drawn = await canvasDrawn(page);
  check(drawn.drawn > drawn.pixels / 50 && drawn.drawn < drawn.pixels,
        `${name}: the 3D canvas is not empty (${drawn.drawn} of ${drawn.pixels} pixels drawn, the rest sky)`);
  const first = await pixelStats(page, ".springy-replay-canvas canvas");
  const frames = await page.evaluate(() => {
    const s = document.querySelector(".springy-replay-time");
    s.value = s.max;
    s.dispatchEvent(new Event("input"));
    return Number(s.max) + 1;
  });
  await page.waitForFunction((f) => window.springyViewer.frame === f - 1, frames, { timeout: 5000 });
  const last = await pixelStats(page, ".springy-replay-canvas canvas");
  check(last.hash !== first.hash, `${name}: the 3D replay's last frame (${frames - 1}) differs from its first`);
  return checkMoving(page, name, frames);
}

// Seeks the replay to frame f; the viewer's state then.
async function seek(page, f) {
  await page.evaluate((f) => {
    const s = document.querySelector(".springy-replay-time");
    s.value = String(f);
    s.dispatchEvent(new Event("input"));
  }, f);
  await page.waitForFunction((f) => window.springyViewer.frame === f, f, { timeout: 5000 });
  return page.evaluate(() => window.springyViewer);
}

// The colliders and props that move: at frames 0 and a quarter of the way, each mesh stands where
// the replay's data put it (translation, quaternion), and somewhere the two differ. True when the
// page has one.
async function checkMoving(page, name, frames) {
  const poses = await page.evaluate(() => window.springyReplayData.stills.filter((s) => s.translations).map((s) => {
    const floats = (b) => Array.from(new Float32Array(Uint8Array.from(atob(b), (c) => c.charCodeAt(0)).buffer));
    return { name: s.name, t: floats(s.translations), r: s.rotations ? floats(s.rotations) : null };
  }));
  if (poses.length === 0) return false;
  const at = [0, Math.floor(frames / 4)];
  const seen = [];
  for (const f of at) {
    const viewer = await seek(page, f);
    check(viewer.moving.length === poses.length, `${name}: ${viewer.moving.length} moving meshes in the viewer at frame ${f}`);
    poses.forEach((p, i) => {
      const want = p.t.slice(3 * f, 3 * f + 3).concat(p.r ? p.r.slice(4 * f, 4 * f + 4) : [0, 0, 0, 1]);
      const got = viewer.moving[i] || [];
      check(want.every((v, k) => Math.abs(v - got[k]) < 1e-6), `${name}: ${p.name} at frame ${f} is at [${got.map((v) => v.toFixed(3))}], its pose`);
    });
    seen.push(viewer.moving);
  }
  const moved = seen[0].some((m, i) => m.some((v, k) => Math.abs(v - seen[1][i][k]) > 1e-3));
  check(moved, `${name}: the moving meshes stand elsewhere at frame ${at[1]} than at frame 0`);
  return true;
}

(async () => {
  const browser = await chromium.launch({
    executablePath: process.env.SPRINGY_CHROMIUM || "/usr/bin/chromium",
    args: ["--no-sandbox", "--use-angle=swiftshader", "--enable-unsafe-swiftshader", "--autoplay-policy=no-user-gesture-required"],
  });
  try {
    const queue = [path.join(root, "index.html")];
    const seen = new Set();
    let scenes = 0, moving = 0;
    while (queue.length) {
      const file = queue.shift();
      if (seen.has(file)) continue;
      seen.add(file);
      const name = path.relative(root, file);
      const { page, problems } = await openPage(browser, file);
      await checkImages(page, name);
      for (const p of await checkLinks(page, file, name)) queue.push(p);
      if (await page.$(".springy-replay")) {
        ++scenes;
        if (await checkScenePage(page, name)) ++moving;
      }
      await page.waitForTimeout(100);
      for (const p of problems) check(false, `${name}: ${p}`);
      if (problems.length === 0) check(true, `${name}: no console errors`);
      await page.close();
    }
    check(scenes > 0, `${scenes} scene pages with a video and a 3D replay`);
    check(moving > 0, `${moving} scene pages whose replay moves a collider (report_test.sh reports the press)`);
    console.log(`${seen.size} pages opened`);
  } finally {
    await browser.close();
  }
  if (failures.length) {
    console.error(`report_browser: ${failures.length} failed:\n  ${failures.join("\n  ")}`);
    process.exit(1);
  }
})().catch((e) => {
  console.error(`report_browser: ${e.stack || e}`);
  process.exit(1);
});
